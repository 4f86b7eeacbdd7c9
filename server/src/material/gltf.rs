//! glTF materials to material trees: a second front end beside `front/`,
//! building the IR (`tree`) straight from a glTF document's JSON, no
//! material text in between.
//!
//! One `Definition` per glTF material: a base slab from
//! `pbrMetallicRoughness` (factor × texture for each value), with the
//! `KHR_materials_*` extensions loupe represents as slab fields, and a coat
//! slab `layer`ed over it for `KHR_materials_clearcoat`. Every factor and
//! texture is a parameter whose default is the file's value, so the
//! browser's controls move it like a `.mat` file's. What cannot be
//! represented is a located warning (at the glTF element), never dropped
//! silently; docs/materials.md ("glTF materials") lists the mapping.

use std::path::Path;

use serde_json::Value as Json;

use super::tree::{
    BinOp, Builtin, ColorSpace, Definition, Expr, ExprId, ExprKind, Field, Node, NodeId, NodeKind, Param, Slab, TextureSource, Type, Value,
};
use crate::diag::{Code, Diagnostic, Location, Severity};
use crate::mesh::Doc;
use crate::mesh::json_path::JsonPath;
use crate::mesh::uri::{self, Uri};

/// The material extensions loupe maps into the tree.
pub const SUPPORTED: [&str; 9] = [
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
];

/// Extensions that change nothing a material shows here: the geometry's
/// (the mesh importer reads or refuses them) and the texture formats it
/// would refuse by name.
const NOT_MATERIAL: [&str; 3] = ["KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization"];

/// A glTF document's materials as the compiler sees them.
pub struct Document<'a> {
    pub json: &'a Json,
    /// Places diagnostics (at the element in a .gltf, at the file in a .glb).
    pub doc: &'a Doc<'a>,
    /// The directory image URIs are relative to.
    pub dir: &'a Path,
}

/// One glTF material as a definition, with what it names and what it
/// could not represent.
pub struct Imported {
    pub definition: Definition,
    /// The images its texture params' defaults index (`Value::Texture`).
    pub textures: Vec<TextureSource>,
    pub warnings: Vec<Diagnostic>,
}

/// Warnings for the document as a whole: every extension in
/// `extensionsUsed` that loupe does not represent, by name.
pub fn document_warnings(d: &Document) -> Vec<Diagnostic> {
    let used = d.json.get("extensionsUsed").and_then(Json::as_array).map(Vec::as_slice).unwrap_or_default();
    used.iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let name = name.as_str()?;
            if SUPPORTED.contains(&name) || NOT_MATERIAL.contains(&name) {
                return None;
            }
            let why = format!("loupe cannot represent {name}: it is ignored, and the asset may look different than intended");
            Some(warning(d, &JsonPath::top("extensionsUsed").index(i), format!("{name}: {why}")))
        })
        .collect()
}

/// glTF material `index` (`None`: glTF's default material, for primitives
/// that name none) as a definition called `name`.
pub fn definition(d: &Document, index: Option<usize>, name: &str) -> Imported {
    let (json, path) = match index {
        Some(i) => (d.json.get("materials").and_then(|m| m.get(i)).unwrap_or(&Json::Null), JsonPath::element("materials", i)),
        None => (&Json::Null, JsonPath::top("materials")),
    };
    let at = if index.is_some() { d.doc.at(&path) } else { Location::file_start(d.doc.display) };
    let mut b = Builder {
        d,
        def: Definition {
            name: name.to_owned(),
            location: at.clone(),
            params: Vec::new(),
            nodes: Vec::new(),
            exprs: Vec::new(),
            root: NodeId(0),
            energy_compensation: true,
        },
        at,
        textures: Vec::new(),
        warnings: Vec::new(),
    };
    b.material(json, &path);
    Imported { definition: b.def, textures: b.textures, warnings: b.warnings }
}

fn warning(d: &Document, path: &JsonPath, message: String) -> Diagnostic {
    Diagnostic::warning(Code::Material, message).at(d.doc.at(path))
}

/// A colour's channel `k` as a float, with the IR's operations only:
/// `luminance(c * w_k⁻¹ e_k)` is exactly `c[k]`'s share, scaled back.
const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

struct Builder<'a> {
    d: &'a Document<'a>,
    def: Definition,
    /// Where the material is written: every node and expression points there.
    at: Location,
    textures: Vec<TextureSource>,
    warnings: Vec<Diagnostic>,
}

impl Builder<'_> {
    fn expr(&mut self, kind: ExprKind, ty: Type) -> ExprId {
        self.def.exprs.push(Expr { kind, ty, location: self.at.clone() });
        ExprId(self.def.exprs.len() as u32 - 1)
    }

    fn node(&mut self, kind: NodeKind) -> NodeId {
        self.def.nodes.push(Node { kind, location: self.at.clone() });
        NodeId(self.def.nodes.len() as u32 - 1)
    }

    fn warn(&mut self, path: &JsonPath, message: String) {
        self.warnings.push(warning(self.d, path, message));
    }

    /// A parameter whose default is the file's value (clamped into `range`,
    /// with a warning when it had to be).
    fn param(&mut self, name: &str, ty: Type, default: Value, range: Option<(f32, f32)>, path: &JsonPath) -> ExprId {
        let default = match (default, range) {
            (Value::Float(x), Some((lo, hi))) if !(lo..=hi).contains(&x) => {
                self.warn(path, format!("{name} {x} is outside [{lo}, {hi}]: clamped"));
                Value::Float(if x.is_nan() { lo } else { x.clamp(lo, hi) })
            }
            (Value::Vec3(c), Some((lo, hi))) if c.iter().any(|x| !(lo..=hi).contains(x)) => {
                self.warn(path, format!("{name} {c:?} is outside [{lo}, {hi}]: clamped"));
                Value::Vec3(c.map(|x| if x.is_nan() { lo } else { x.clamp(lo, hi) }))
            }
            (v, _) => v,
        };
        self.def.params.push(Param {
            name: name.to_owned(),
            ty,
            default,
            range,
            unit: None,
            doc: Some(format!("glTF {path}")),
            location: self.d.doc.at(path),
        });
        let i = self.def.params.len() as u32 - 1;
        self.expr(ExprKind::Param(i), ty)
    }

    /// A float factor (`key` of `object`, else `default`) as a param feeding
    /// `field`.
    fn float(&mut self, name: &str, object: &Json, key: &'static str, default: f32, field: Field, path: &JsonPath) -> ExprId {
        let x = object.get(key).and_then(Json::as_f64).map_or(default, |x| x as f32);
        self.param(name, Type::Float, Value::Float(x), field.range(), &path.field(key))
    }

    /// A colour factor (the first three numbers of `key`).
    fn color(&mut self, name: &str, object: &Json, key: &'static str, default: [f32; 3], path: &JsonPath) -> ExprId {
        let c = object
            .get(key)
            .and_then(Json::as_array)
            .filter(|a| a.len() >= 3)
            .map_or(default, |a| std::array::from_fn(|k| a[k].as_f64().map_or(default[k], |x| x as f32)));
        self.param(name, Type::Color, Value::Vec3(c), Some((0.0, 1.0)), &path.field(key))
    }

    /// The texture a `textureInfo` (`key` of `object`) names, as a texture
    /// param, or `None` (with a warning) when loupe cannot read it here.
    fn texture(&mut self, name: &str, object: &Json, key: &'static str, space: ColorSpace, path: &JsonPath) -> Option<ExprId> {
        let info = object.get(key)?;
        let path = path.field(key);
        if let Some(set) = info.get("texCoord").and_then(Json::as_u64).filter(|&s| s != 0) {
            self.warn(
                &path.field("texCoord"),
                format!("{path} reads TEXCOORD_{set}: loupe reads TEXCOORD_0 only, so the texture is ignored"),
            );
            return None;
        }
        if info.get("extensions").and_then(|e| e.get("KHR_texture_transform")).is_some() {
            self.warn(&path.field("extensions"), format!("{path}: KHR_texture_transform is not applied (the UVs are used as they are)"));
        }
        let root = self.d.json;
        let index = info.get("index").and_then(Json::as_u64).map(|i| i as usize);
        let image = index.and_then(|i| root.get("textures")?.get(i)?.get("source")?.as_u64()).map(|i| i as usize);
        let Some((t, i)) = index.zip(image) else {
            self.warn(&path.field("index"), format!("{path} names no texture with an image: ignored"));
            return None;
        };
        let image_path = JsonPath::element("images", i);
        let uri = root.get("images").and_then(|im| im.get(i)).and_then(|im| im.get("uri")).and_then(Json::as_str);
        let file = match uri.map(uri::parse) {
            Some(Ok(Uri::Relative(file))) => file,
            Some(Ok(Uri::Data(_))) | None => {
                let why = format!(
                    "{image_path} (textures[{t}]) is embedded in the file: loupe reads image files beside the glTF only, so it is ignored"
                );
                self.warn(&image_path, why);
                return None;
            }
            Some(Err(e)) => {
                self.warn(&image_path.field("uri"), format!("{image_path}.uri: {}: ignored", e.message));
                return None;
            }
        };
        let location = self.d.doc.at(&image_path.field("uri"));
        self.textures.push(TextureSource { path: self.d.dir.join(&file), space, location });
        let layer = Value::Texture(self.textures.len() as u32 - 1);
        Some(self.param(name, Type::Texture, layer, None, &image_path))
    }

    fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let ty = if self.def.expr(a).ty == Type::Float { self.def.expr(b).ty } else { self.def.expr(a).ty };
        self.expr(ExprKind::Binary(BinOp::Mul, a, b), ty)
    }

    fn sample(&mut self, texture: ExprId) -> ExprId {
        self.expr(ExprKind::Call(Builtin::Sample, vec![texture]), Type::Color)
    }

    /// Channel `k` (0 R, 1 G, 2 B) of a texture's colour.
    fn channel(&mut self, texture: ExprId, k: usize) -> ExprId {
        let texel = self.sample(texture);
        let mut pick = [0.0; 3];
        pick[k] = 1.0 / LUMINANCE[k];
        let pick = self.expr(ExprKind::Const(Value::Vec3(pick)), Type::Color);
        let picked = self.mul(texel, pick);
        self.expr(ExprKind::Call(Builtin::Luminance, vec![picked]), Type::Float)
    }

    /// `factor × texture` (its colour, or its channel `k`).
    fn times(&mut self, factor: ExprId, texture: Option<ExprId>, channel: Option<usize>) -> ExprId {
        let Some(t) = texture else { return factor };
        let value = match channel {
            Some(k) => self.channel(t, k),
            None => self.sample(t),
        };
        self.mul(factor, value)
    }

    fn constant(&mut self, v: Value) -> ExprId {
        let ty = if matches!(v, Value::Float(_)) { Type::Float } else { Type::Color };
        self.expr(ExprKind::Const(v), ty)
    }

    /// A tangent-space normal map (`normalTexture`-like `key`) with its scale.
    fn normal(&mut self, prefix: &str, object: &Json, key: &'static str, path: &JsonPath) -> Option<ExprId> {
        let texture = self.texture(&format!("{prefix}normal_texture"), object, key, ColorSpace::Normal, path)?;
        let info = &object[key];
        let scale = info.get("scale").and_then(Json::as_f64).map_or(1.0, |x| x as f32);
        let scale = self.param(&format!("{prefix}normal_scale"), Type::Float, Value::Float(scale), None, &path.field(key).field("scale"));
        Some(self.expr(ExprKind::Call(Builtin::NormalMap, vec![texture, scale]), Type::Vec3))
    }

    fn material(&mut self, m: &Json, path: &JsonPath) {
        let mut base = Vec::new();
        let pbr_path = path.field("pbrMetallicRoughness");
        let pbr = m.get("pbrMetallicRoughness").unwrap_or(&Json::Null);
        let factor = self.color("base_color_factor", pbr, "baseColorFactor", [1.0; 3], &pbr_path);
        let texture = self.texture("base_color_texture", pbr, "baseColorTexture", ColorSpace::Srgb, &pbr_path);
        base.push((Field::BaseColor, self.times(factor, texture, None)));
        let metallic = self.float("metallic_factor", pbr, "metallicFactor", 1.0, Field::BaseMetalness, &pbr_path);
        let roughness = self.float("roughness_factor", pbr, "roughnessFactor", 1.0, Field::SpecularRoughness, &pbr_path);
        let texture = self.texture("metallic_roughness_texture", pbr, "metallicRoughnessTexture", ColorSpace::Linear, &pbr_path);
        // glTF: roughness in green, metalness in blue.
        base.push((Field::BaseMetalness, self.times(metallic, texture, Some(2))));
        base.push((Field::SpecularRoughness, self.times(roughness, texture, Some(1))));
        if let Some(n) = self.normal("", m, "normalTexture", path) {
            base.push((Field::Normal, n));
        }
        if m.get("occlusionTexture").is_some() {
            let mut d = warning(
                self.d,
                &path.field("occlusionTexture"),
                format!(
                    "{path}.occlusionTexture is not used: loupe's lighting computes its own occlusion (shadows, and the path tracer's bounces)"
                ),
            );
            d.severity = Severity::Note;
            self.warnings.push(d);
        }
        if let Some(mode) = m.get("alphaMode").and_then(Json::as_str).filter(|&a| a != "OPAQUE") {
            self.warn(&path.field("alphaMode"), format!("{path}.alphaMode {mode} is not supported: the material is drawn opaque"));
        }
        let ext = m.get("extensions").unwrap_or(&Json::Null);
        let ext_path = path.field("extensions");
        self.emission(m, ext, path, &mut base);
        let mut coat = None;
        for name in ext.as_object().map(|o| o.keys().cloned().collect::<Vec<_>>()).unwrap_or_default() {
            let Some(&known) = SUPPORTED.iter().find(|s| **s == name) else {
                // Named once for the document when it is listed as used.
                let listed =
                    self.d.json.get("extensionsUsed").and_then(Json::as_array).is_some_and(|u| u.iter().any(|x| x == name.as_str()));
                if !listed {
                    self.warn(&ext_path, format!("{path} uses {name}, which loupe cannot represent: it is ignored"));
                }
                continue;
            };
            let (e, at) = (&ext[known], ext_path.field(known));
            match known {
                "KHR_materials_ior" => {
                    let ior = self.float("ior", e, "ior", 1.5, Field::SpecularIor, &at);
                    base.push((Field::SpecularIor, ior));
                }
                "KHR_materials_specular" => {
                    let weight = self.float("specular_factor", e, "specularFactor", 1.0, Field::SpecularWeight, &at);
                    if e.get("specularTexture").is_some() {
                        self.warn(
                            &at.field("specularTexture"),
                            format!("{at}.specularTexture (alpha) is not read: the factor alone applies"),
                        );
                    }
                    base.push((Field::SpecularWeight, weight));
                    let color = self.color("specular_color_factor", e, "specularColorFactor", [1.0; 3], &at);
                    let texture = self.texture("specular_color_texture", e, "specularColorTexture", ColorSpace::Srgb, &at);
                    base.push((Field::SpecularColor, self.times(color, texture, None)));
                }
                "KHR_materials_sheen" => {
                    let color = self.color("sheen_color_factor", e, "sheenColorFactor", [0.0; 3], &at);
                    let texture = self.texture("sheen_color_texture", e, "sheenColorTexture", ColorSpace::Srgb, &at);
                    let roughness = self.float("sheen_roughness_factor", e, "sheenRoughnessFactor", 0.0, Field::FuzzRoughness, &at);
                    if e.get("sheenRoughnessTexture").is_some() {
                        self.warn(
                            &at.field("sheenRoughnessTexture"),
                            format!("{at}.sheenRoughnessTexture (alpha) is not read: the factor alone applies"),
                        );
                    }
                    let one = self.constant(Value::Float(1.0));
                    base.push((Field::FuzzWeight, one));
                    base.push((Field::FuzzColor, self.times(color, texture, None)));
                    base.push((Field::FuzzRoughness, roughness));
                }
                "KHR_materials_transmission" => {
                    let weight = self.float("transmission_factor", e, "transmissionFactor", 0.0, Field::TransmissionWeight, &at);
                    let texture = self.texture("transmission_texture", e, "transmissionTexture", ColorSpace::Linear, &at);
                    base.push((Field::TransmissionWeight, self.times(weight, texture, Some(0))));
                    self.volume(ext, &ext_path, &mut base);
                }
                "KHR_materials_clearcoat" => coat = self.coat(e, &at),
                "KHR_materials_iridescence" => self.iridescence(e, &at, &mut base),
                "KHR_materials_anisotropy" => self.anisotropy(e, &at, &mut base),
                // Read with the emission and the transmission.
                _ => {}
            }
        }
        let base = self.node(NodeKind::Slab(Slab { fields: base }));
        self.def.root = match coat {
            Some(top) => self.node(NodeKind::Layer { top, base }),
            None => base,
        };
    }

    /// `emissiveFactor` × `emissiveTexture`, times
    /// `KHR_materials_emissive_strength`; nothing when the factor is black.
    fn emission(&mut self, m: &Json, ext: &Json, path: &JsonPath, base: &mut Vec<(Field, ExprId)>) {
        let black = m.get("emissiveFactor").and_then(Json::as_array).is_none_or(|a| a.iter().all(|x| x.as_f64() == Some(0.0)));
        if black {
            return;
        }
        let color = self.color("emissive_factor", m, "emissiveFactor", [0.0; 3], path);
        let texture = self.texture("emissive_texture", m, "emissiveTexture", ColorSpace::Srgb, path);
        base.push((Field::EmissionColor, self.times(color, texture, None)));
        let key = "KHR_materials_emissive_strength";
        let strength = ext.get(key).unwrap_or(&Json::Null);
        let at = path.field("extensions").field(key);
        let strength = self.float("emissive_strength", strength, "emissiveStrength", 1.0, Field::EmissionLuminance, &at);
        base.push((Field::EmissionLuminance, strength));
    }

    /// `KHR_materials_iridescence` as the base's thin film: the factor ×
    /// the texture's R as its weight, its IOR, and its thickness in
    /// nanometres made micrometres: the maximum, or the minimum to the
    /// maximum by the thickness texture's G.
    fn iridescence(&mut self, e: &Json, at: &JsonPath, base: &mut Vec<(Field, ExprId)>) {
        let weight = self.float("iridescence_factor", e, "iridescenceFactor", 0.0, Field::ThinFilmWeight, at);
        let texture = self.texture("iridescence_texture", e, "iridescenceTexture", ColorSpace::Linear, at);
        base.push((Field::ThinFilmWeight, self.times(weight, texture, Some(0))));
        let ior = self.float("iridescence_ior", e, "iridescenceIor", 1.3, Field::ThinFilmIor, at);
        base.push((Field::ThinFilmIor, ior));
        let most = self.float("iridescence_thickness_maximum", e, "iridescenceThicknessMaximum", 400.0, Field::ThinFilmThickness, at);
        let nanometres = match self.texture("iridescence_thickness_texture", e, "iridescenceThicknessTexture", ColorSpace::Linear, at) {
            Some(t) => {
                let least =
                    self.float("iridescence_thickness_minimum", e, "iridescenceThicknessMinimum", 100.0, Field::ThinFilmThickness, at);
                let g = self.channel(t, 1);
                self.expr(ExprKind::Call(Builtin::Lerp, vec![least, most, g]), Type::Float)
            }
            None => most,
        };
        let per_micrometre = self.constant(Value::Float(1000.0));
        let thickness = self.expr(ExprKind::Binary(BinOp::Div, nanometres, per_micrometre), Type::Float);
        base.push((Field::ThinFilmThickness, thickness));
    }

    /// `KHR_materials_volume` beside a transmission: thin-walled when its
    /// thickness is 0 (or it is absent); else a mean free path,
    /// `transmittance_to_mfp(attenuationColor, attenuationDistance)`
    /// (Beer–Lambert in the glTF's units; no attenuation distance: none).
    fn volume(&mut self, ext: &Json, ext_path: &JsonPath, base: &mut Vec<(Field, ExprId)>) {
        let key = "KHR_materials_volume";
        let (v, at) = (ext.get(key).unwrap_or(&Json::Null), ext_path.field(key));
        let thickness = v.get("thicknessFactor").and_then(Json::as_f64).unwrap_or(0.0);
        if thickness <= 0.0 {
            let thin = self.constant(Value::Float(1.0));
            base.push((Field::ThinWalled, thin));
            return;
        }
        if v.get("thicknessTexture").is_some() {
            self.warn(
                &at.field("thicknessTexture"),
                format!("{at}.thicknessTexture is not used: the path tracer measures the distance through the mesh itself"),
            );
        }
        let color = v
            .get("attenuationColor")
            .and_then(Json::as_array)
            .filter(|a| a.len() >= 3)
            .map_or([1.0; 3], |a| std::array::from_fn(|k| a[k].as_f64().unwrap_or(1.0) as f32));
        let Some(distance) = v.get("attenuationDistance").and_then(Json::as_f64).filter(|d| *d > 0.0) else { return };
        let kept = self.param("attenuation_color", Type::Color, Value::Vec3(color), Some((0.0, 1.0)), &at.field("attenuationColor"));
        let distance = self.param(
            "attenuation_distance",
            Type::Float,
            Value::Float(distance as f32),
            Some((f32::MIN_POSITIVE, f32::MAX)),
            &at.field("attenuationDistance"),
        );
        let path = self.expr(ExprKind::Call(Builtin::TransmittanceToMfp, vec![kept, distance]), Type::Color);
        base.push((Field::MeanFreePath, path));
    }

    /// `KHR_materials_anisotropy`: the strength as the slab's roughness
    /// anisotropy (OpenPBR's mapping of it, not glTF's: docs/materials.md),
    /// the rotation (radians from the tangent toward the bitangent) in
    /// turns. The texture's per-texel direction and strength are not read.
    fn anisotropy(&mut self, e: &Json, at: &JsonPath, base: &mut Vec<(Field, ExprId)>) {
        let strength = self.float("anisotropy_strength", e, "anisotropyStrength", 0.0, Field::SpecularAnisotropy, at);
        let radians = e.get("anisotropyRotation").and_then(Json::as_f64).unwrap_or(0.0);
        let turns = (radians / std::f64::consts::TAU).rem_euclid(1.0) as f32;
        let range = Field::SpecularRotation.range();
        let rotation = self.param("anisotropy_rotation", Type::Float, Value::Float(turns), range, &at.field("anisotropyRotation"));
        if e.get("anisotropyTexture").is_some() {
            self.warn(
                &at.field("anisotropyTexture"),
                format!("{at}.anisotropyTexture (direction and strength per texel) is not read: the factors alone apply"),
            );
        }
        base.push((Field::SpecularAnisotropy, strength));
        base.push((Field::SpecularRotation, rotation));
    }

    /// `KHR_materials_clearcoat` as a clear dielectric slab (IOR 1.5, black
    /// beneath) whose specular weight is the coat's factor; `None` when the
    /// factor is 0.
    fn coat(&mut self, e: &Json, at: &JsonPath) -> Option<NodeId> {
        if e.get("clearcoatFactor").and_then(Json::as_f64).unwrap_or(0.0) == 0.0 {
            return None;
        }
        let weight = self.float("clearcoat_factor", e, "clearcoatFactor", 0.0, Field::SpecularWeight, at);
        let texture = self.texture("clearcoat_texture", e, "clearcoatTexture", ColorSpace::Linear, at);
        let mut fields = vec![(Field::SpecularWeight, self.times(weight, texture, Some(0)))];
        let roughness = self.float("clearcoat_roughness_factor", e, "clearcoatRoughnessFactor", 0.0, Field::SpecularRoughness, at);
        let texture = self.texture("clearcoat_roughness_texture", e, "clearcoatRoughnessTexture", ColorSpace::Linear, at);
        fields.push((Field::SpecularRoughness, self.times(roughness, texture, Some(1))));
        let black = self.constant(Value::Vec3([0.0; 3]));
        fields.push((Field::BaseColor, black));
        let ior = self.constant(Value::Float(1.5));
        fields.push((Field::SpecularIor, ior));
        if let Some(n) = self.normal("clearcoat_", e, "clearcoatNormalTexture", at) {
            fields.push((Field::Normal, n));
        }
        Some(self.node(NodeKind::Slab(Slab { fields })))
    }
}

#[cfg(test)]
mod tests;
