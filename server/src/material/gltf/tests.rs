use super::*;
use crate::diag::LineIndex;

/// `text`'s material `index` imported, with the document's warnings.
fn import(text: &str, index: Option<usize>) -> (Imported, Vec<Diagnostic>) {
    let json: Json = serde_json::from_str(text).unwrap();
    let doc = Doc { display: "a.gltf", text: Some((text, LineIndex::new(text))) };
    let d = Document { json: &json, doc: &doc, dir: Path::new("assets") };
    (definition(&d, index, "a.gltf::m"), document_warnings(&d))
}

fn slab(def: &Definition, node: NodeId) -> &Slab {
    match &def.node(node).kind {
        NodeKind::Slab(s) => s,
        other => panic!("not a slab: {other:?}"),
    }
}

fn param_name(def: &Definition, e: ExprId) -> &str {
    match def.expr(e).kind {
        ExprKind::Param(i) => &def.params[i as usize].name,
        ref other => panic!("not a param: {other:?}"),
    }
}

/// `factor × texture`: the factor's and the texture's param names, and the
/// colour mask picking the texture's channel (`None`: its whole colour).
fn factor_times_texture(def: &Definition, e: ExprId) -> (&str, &str, Option<[f32; 3]>) {
    let ExprKind::Binary(BinOp::Mul, factor, texel) = def.expr(e).kind else { panic!("not a product: {:?}", def.expr(e)) };
    let sampled = |e: ExprId| match &def.expr(e).kind {
        ExprKind::Call(Builtin::Sample, args) => param_name(def, args[0]),
        other => panic!("not a sample: {other:?}"),
    };
    match &def.expr(texel).kind {
        ExprKind::Call(Builtin::Sample, _) => (param_name(def, factor), sampled(texel), None),
        ExprKind::Call(Builtin::Luminance, args) => {
            let ExprKind::Binary(BinOp::Mul, t, mask) = def.expr(args[0]).kind else { panic!("not a channel pick") };
            let ExprKind::Const(Value::Vec3(mask)) = def.expr(mask).kind else { panic!("not a mask") };
            (param_name(def, factor), sampled(t), Some(mask))
        }
        other => panic!("not a texel: {other:?}"),
    }
}

const TEXTURED: &str = r#"{
  "asset": {"version": "2.0"},
  "materials": [{
    "pbrMetallicRoughness": {
      "baseColorFactor": [0.5, 0.25, 1.0, 1.0],
      "baseColorTexture": {"index": 0},
      "metallicFactor": 0.75,
      "roughnessFactor": 0.5,
      "metallicRoughnessTexture": {"index": 1}
    },
    "normalTexture": {"index": 0, "scale": 0.5}
  }],
  "textures": [{"source": 0}, {"source": 1}],
  "images": [{"uri": "colour.png"}, {"uri": "mr%20map.png"}]
}"#;

#[test]
fn factors_multiply_their_textures_and_metal_roughness_read_blue_and_green() {
    let (m, warnings) = import(TEXTURED, Some(0));
    assert!(warnings.is_empty() && m.warnings.is_empty(), "{warnings:?} {:?}", m.warnings);
    let def = &m.definition;
    let s = slab(def, def.root);
    assert_eq!(factor_times_texture(def, s.get(Field::BaseColor).unwrap()), ("base_color_factor", "base_color_texture", None));
    let blue = [0.0, 0.0, 1.0 / LUMINANCE[2]];
    let green = [0.0, 1.0 / LUMINANCE[1], 0.0];
    let metal = factor_times_texture(def, s.get(Field::BaseMetalness).unwrap());
    assert_eq!(metal, ("metallic_factor", "metallic_roughness_texture", Some(blue)));
    let rough = factor_times_texture(def, s.get(Field::SpecularRoughness).unwrap());
    assert_eq!(rough, ("roughness_factor", "metallic_roughness_texture", Some(green)));
    // The mask picks exactly the channel out of luminance's weights.
    assert!((blue[2] * LUMINANCE[2] - 1.0).abs() < 1e-6 && (green[1] * LUMINANCE[1] - 1.0).abs() < 1e-6);
    // The factors are the params' defaults; colour textures are sRGB, the rest linear.
    let p = |name: &str| def.params.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no param {name}")).default;
    assert_eq!(p("base_color_factor"), Value::Vec3([0.5, 0.25, 1.0]));
    assert_eq!(p("metallic_factor"), Value::Float(0.75));
    assert_eq!(p("normal_scale"), Value::Float(0.5));
    let spaces: Vec<(String, ColorSpace)> = m.textures.iter().map(|t| (t.path.display().to_string(), t.space)).collect();
    assert_eq!(
        spaces,
        [
            ("assets/colour.png".to_owned(), ColorSpace::Srgb),
            ("assets/mr map.png".to_owned(), ColorSpace::Linear),
            ("assets/colour.png".to_owned(), ColorSpace::Normal),
        ]
    );
    let ExprKind::Call(Builtin::NormalMap, args) = &def.expr(s.get(Field::Normal).unwrap()).kind else { panic!("no normal map") };
    assert_eq!((param_name(def, args[0]), param_name(def, args[1])), ("normal_texture", "normal_scale"));
    // It passes the analysis (types, ranges) and the back end writes it.
    let analysed = crate::material::analysed(def).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(crate::material::back::wgsl(&[analysed.def], crate::material::back::Bindings::RENDERER).contains("material_texel"));
}

#[test]
fn clearcoat_is_a_coat_slab_layered_over_the_base_and_the_other_extensions_are_fields() {
    let text = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_ior", "KHR_materials_sheen", "KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_emissive_strength"],
  "materials": [{
    "emissiveFactor": [1, 0.5, 0],
    "extensions": {
      "KHR_materials_clearcoat": {"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.1},
      "KHR_materials_ior": {"ior": 1.33},
      "KHR_materials_sheen": {"sheenColorFactor": [0.2, 0.3, 0.4], "sheenRoughnessFactor": 0.6},
      "KHR_materials_transmission": {"transmissionFactor": 0.9},
      "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationColor": [0.25, 1, 1], "attenuationDistance": 2.0},
      "KHR_materials_emissive_strength": {"emissiveStrength": 4}
    }
  }]
}"#;
    let (m, warnings) = import(text, Some(0));
    assert!(warnings.is_empty() && m.warnings.is_empty(), "{warnings:?} {:?}", m.warnings);
    let def = &m.definition;
    let NodeKind::Layer { top, base } = def.node(def.root).kind else { panic!("the root is no layer: {:?}", def.node(def.root)) };
    let (top, base) = (slab(def, top), slab(def, base));
    assert_eq!(param_name(def, top.get(Field::SpecularWeight).unwrap()), "clearcoat_factor");
    assert_eq!(param_name(def, top.get(Field::SpecularRoughness).unwrap()), "clearcoat_roughness_factor");
    assert_eq!(def.expr(top.get(Field::BaseColor).unwrap()).kind, ExprKind::Const(Value::Vec3([0.0; 3])), "the coat diffuses nothing");
    let p = |name: &str| def.params.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no param {name}")).default;
    assert_eq!(p("clearcoat_factor"), Value::Float(0.8));
    for (field, name) in [
        (Field::SpecularIor, "ior"),
        (Field::FuzzColor, "sheen_color_factor"),
        (Field::FuzzRoughness, "sheen_roughness_factor"),
        (Field::TransmissionWeight, "transmission_factor"),
        (Field::EmissionColor, "emissive_factor"),
        (Field::EmissionLuminance, "emissive_strength"),
    ] {
        assert_eq!(param_name(def, base.get(field).unwrap_or_else(|| panic!("{field:?} unset"))), name);
    }
    assert!(base.get(Field::ThinWalled).is_none(), "a volume with thickness is a solid");
    // A mean free path keeping 0.25 of the red after 2 units: 0.5 per unit.
    let path = base.get(Field::MeanFreePath).expect("the volume's mean free path");
    let ExprKind::Call(Builtin::TransmittanceToMfp, args) = &def.expr(path).kind else { panic!("{:?}", def.expr(path)) };
    assert_eq!((param_name(def, args[0]), param_name(def, args[1])), ("attenuation_color", "attenuation_distance"));
    let values: Vec<Value> = def.params.iter().map(|p| p.default).collect();
    let Value::Vec3(mfp) = crate::material::analysis::eval(def, path, &values) else { panic!("not a colour") };
    assert!(((-1.0 / mfp[0]).exp() - 0.5).abs() < 1e-6 && mfp[1] > 1e5, "{mfp:?}");
    assert_eq!(p("emissive_strength"), Value::Float(4.0));
    crate::material::analysed(def).unwrap_or_else(|d| panic!("{d:?}"));
    // Without a volume, transmission is thin-walled; without a coat factor, no layer.
    let thin = text.replace("\"thicknessFactor\": 1.0, ", "").replace("\"clearcoatFactor\": 0.8, ", "");
    let (m, _) = import(&thin, Some(0));
    let s = slab(&m.definition, m.definition.root);
    assert_eq!(m.definition.expr(s.get(Field::ThinWalled).unwrap()).kind, ExprKind::Const(Value::Float(1.0)));
}

#[test]
fn iridescence_is_the_base_slabs_thin_film_in_micrometres() {
    let text = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_materials_iridescence"],
  "materials": [{
    "extensions": {"KHR_materials_iridescence": {
      "iridescenceFactor": 0.75, "iridescenceIor": 1.8,
      "iridescenceThicknessMinimum": 200, "iridescenceThicknessMaximum": 600,
      "iridescenceTexture": {"index": 0}
    }}
  }],
  "textures": [{"source": 0}],
  "images": [{"uri": "film.png"}]
}"#;
    let (m, warnings) = import(text, Some(0));
    assert!(warnings.is_empty() && m.warnings.is_empty(), "{warnings:?} {:?}", m.warnings);
    let def = &m.definition;
    let base = slab(def, def.root);
    let weight = base.get(Field::ThinFilmWeight).expect("a film weight");
    assert_eq!(factor_times_texture(def, weight), ("iridescence_factor", "iridescence_texture", Some([1.0 / LUMINANCE[0], 0.0, 0.0])));
    assert_eq!(param_name(def, base.get(Field::ThinFilmIor).unwrap()), "iridescence_ior");
    // Without a thickness texture, the maximum: 600 nm is 0.6 µm.
    let values: Vec<Value> = def.params.iter().map(|p| p.default).collect();
    let thickness = base.get(Field::ThinFilmThickness).unwrap();
    assert_eq!(crate::material::analysis::eval(def, thickness, &values), Value::Float(0.6));
    let p = |name: &str| def.params.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no param {name}")).default;
    assert_eq!((p("iridescence_factor"), p("iridescence_ior")), (Value::Float(0.75), Value::Float(1.8)));
    crate::material::analysed(def).unwrap_or_else(|d| panic!("{d:?}"));
    // With one, the minimum to the maximum by its green.
    let textured = text.replace("\"iridescenceTexture\"", "\"iridescenceThicknessTexture\"");
    let (m, _) = import(&textured, Some(0));
    let def = &m.definition;
    let thickness = slab(def, def.root).get(Field::ThinFilmThickness).unwrap();
    let ExprKind::Binary(BinOp::Div, nanometres, _) = def.expr(thickness).kind else { panic!("{:?}", def.expr(thickness)) };
    let ExprKind::Call(Builtin::Lerp, args) = &def.expr(nanometres).kind else { panic!("{:?}", def.expr(nanometres)) };
    assert_eq!((param_name(def, args[0]), param_name(def, args[1])), ("iridescence_thickness_minimum", "iridescence_thickness_maximum"));
}

#[test]
fn what_loupe_cannot_represent_is_a_located_warning_naming_it() {
    let text = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_materials_sheen", "KHR_materials_dispersion", "KHR_materials_diffuse_transmission"],
  "materials": [{
    "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}},
    "occlusionTexture": {"index": 0},
    "extensions": {"KHR_materials_dispersion": {"dispersion": 0.5}}
  }],
  "textures": [{"source": 0}],
  "images": [{"uri": "data:image/png;base64,AAAA"}]
}"#;
    let (m, warnings) = import(text, Some(0));
    let named: Vec<(&str, u32)> = warnings.iter().map(|w| (w.message.as_str(), w.location.as_ref().unwrap().line)).collect();
    assert_eq!(named.len(), 2, "{named:?}");
    assert!(named[0].0.starts_with("KHR_materials_dispersion") && named[0].1 == 3, "{named:?}");
    assert!(named[1].0.starts_with("KHR_materials_diffuse_transmission") && named[1].1 == 3, "{named:?}");
    assert!(warnings.iter().all(|w| w.severity == Severity::Warning && w.file() == Some("a.gltf")));
    // The material's own: a second UV set; occlusion, as a note.
    let own: Vec<&str> = m.warnings.iter().map(|w| w.message.as_str()).collect();
    assert!(own.iter().any(|w| w.contains("TEXCOORD_1")), "{own:?}");
    assert!(m.warnings.iter().any(|w| w.severity == Severity::Note && w.message.contains("occlusionTexture")), "{own:?}");
    assert!(m.textures.is_empty(), "the texture on set 1 is not read");
    // An embedded image is named, not dropped.
    let embedded = text.replace(", \"texCoord\": 1", "");
    let (m, _) = import(&embedded, Some(0));
    assert!(m.warnings.iter().any(|w| w.message.contains("images[0]") && w.message.contains("embedded")), "{:?}", m.warnings);
}

#[test]
fn the_default_material_is_gltfs_white_rough_metal() {
    let (m, _) = import(r#"{"asset": {"version": "2.0"}}"#, None);
    let def = &m.definition;
    let p: Vec<(&str, Value)> = def.params.iter().map(|p| (p.name.as_str(), p.default)).collect();
    assert_eq!(
        p,
        [("base_color_factor", Value::Vec3([1.0; 3])), ("metallic_factor", Value::Float(1.0)), ("roughness_factor", Value::Float(1.0))]
    );
}

#[test]
fn anisotropy_maps_to_the_slabs_anisotropy_and_rotation_in_turns() {
    let text = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_materials_anisotropy"],
  "materials": [{
    "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 0.6, "anisotropyRotation": -1.5707963267948966}}
  }]
}"#;
    let (m, warnings) = import(text, Some(0));
    assert!(warnings.is_empty() && m.warnings.is_empty(), "{warnings:?} {:?}", m.warnings);
    let def = &m.definition;
    let base = slab(def, def.root);
    assert_eq!(param_name(def, base.get(Field::SpecularAnisotropy).unwrap()), "anisotropy_strength");
    assert_eq!(param_name(def, base.get(Field::SpecularRotation).unwrap()), "anisotropy_rotation");
    let p = |name: &str| def.params.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no param {name}")).default;
    assert_eq!(p("anisotropy_strength"), Value::Float(0.6));
    // A quarter turn clockwise is three quarters counter-clockwise.
    assert_eq!(p("anisotropy_rotation"), Value::Float(0.75));
    let a = crate::material::analysed(def).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(a.features().contains(&crate::material::analysis::Feature::Anisotropy), "{:?}", a.features());
    // The texture is named, not dropped.
    let textured = text.replace("\"anisotropyStrength\": 0.6", "\"anisotropyStrength\": 0.6, \"anisotropyTexture\": {\"index\": 0}");
    let (m, _) = import(&textured, Some(0));
    assert!(m.warnings.iter().any(|w| w.message.contains("anisotropyTexture")), "{:?}", m.warnings);
}
