use super::*;
use crate::denoise::testing;
use crate::denoise_options::Mode;

/// A sphere and its material: a scene with something to denoise.
const BASE: &str = "[[materials]]\nname = \"m\"\n\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n";

fn at(d: &Diagnostic) -> (u32, u32) {
    let l = d.location.as_ref().expect("located");
    (l.line, l.column)
}

#[test]
fn missing_and_malformed_weights_are_diagnosed_at_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, format!("{BASE}\n[denoiser]\nweights = \"gone.tza\"\n")).unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.message.contains("gone.tza") && e.message.contains("does not exist"), "{}", e.message);
    assert_eq!(at(&e), (9, 11));
    // A file that is not a .tza: the weights diagnostic, in the file, with the reference.
    std::fs::write(dir.path().join("bad.tza"), b"not a tensor archive").unwrap();
    std::fs::write(&scene, format!("{BASE}\n[denoiser]\nweights = \"bad.tza\"\n")).unwrap();
    let e = load(&scene).unwrap_err();
    assert_eq!(e.code, Code::Weights);
    assert!(e.file().is_some_and(|f| f.ends_with("bad.tza")), "located in the weights file: {e}");
    assert!(e.labels.iter().any(|l| l.location.file.ends_with("s.toml") && l.location.line == 9), "and at the reference: {e:?}");
    // A well-formed archive that is not a U-Net: the network's diagnostic.
    let not_a_unet = testing::archive(&testing::small_unet(9)[..3], 1);
    std::fs::write(dir.path().join("bad.tza"), not_a_unet).unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.code == Code::Weights && e.message.contains("layer"), "{e}");
    // Good weights: the network is built, and the file is one the scene depends on.
    let good = dir.path().join("sub/good.tza");
    std::fs::create_dir_all(good.parent().unwrap()).unwrap();
    std::fs::write(&good, testing::archive(&testing::small_unet(9), 1)).unwrap();
    std::fs::write(&scene, format!("{BASE}\n[denoiser]\nweights = \"sub/good.tza\"\n")).unwrap();
    let loaded = load(&scene).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(loaded.denoiser.expect("the network").inputs, Inputs::ColorAlbedoNormal);
    assert!(loaded.files.iter().any(|f| f.ends_with("sub/good.tza")), "{:?}", loaded.files);
}

/// `[denoiser]` without weights: the bundled network trained for its mode,
/// taking colour, albedo and normal; no weights file to watch.
#[test]
fn a_denoiser_without_weights_gets_the_bundled_network_for_its_mode() {
    let network = |mode| bundled::weights(mode, Inputs::ColorAlbedoNormal).and_then(bundled::Bundled::network).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    for (section, mode) in
        [("", Mode::Hdr), ("mode = \"hdr\"\n", Mode::Hdr), ("mode = \"ldr\"\n", Mode::Ldr), ("mode = \"ldr_srgb\"\n", Mode::Ldr)]
    {
        std::fs::write(&scene, format!("{BASE}\n[denoiser]\n{section}")).unwrap();
        let loaded = load(&scene).unwrap_or_else(|d| panic!("{d}"));
        assert!(*loaded.denoiser.expect("a network") == network(mode), "{section}: the bundled {mode:?} network");
        assert_eq!(loaded.files, std::slice::from_ref(&scene), "nothing but the scene to watch");
    }
    // The two ranges are different networks: the choice is seen.
    assert!(network(Mode::Hdr) != network(Mode::Ldr));
}

/// A scene naming a material file: its definition and the instance's
/// values (defaults, replaced by `params`); the file and what it imports
/// are dependencies; each way the reference can be wrong is an error at
/// the scene's line.
#[test]
fn material_files_are_compiled_and_their_references_checked() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(dir.path().join("lib.mat"), "param r: float = 0.5 in [0, 1]\nmaterial base = slab { specular_roughness: r }\n").unwrap();
    std::fs::write(
        dir.path().join("paint.mat"),
        "import \"lib.mat\"\nparam colour: color = rgb(0.5, 0.5, 0.5) in [0, 1]\nmaterial paint = layer(slab { base_color: grey(0.0) }, slab { base_color: colour })\nmaterial other = lib.base(r: 0.2)\n",
    )
    .unwrap();
    let entry = |extra: &str| {
        format!("[[materials]]\nname = \"m\"\nfile = \"paint.mat\"\n{extra}\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n")
    };
    let write = |text: String| std::fs::write(&scene, text).unwrap();

    write(entry("material = \"paint\"\nparams = { colour = [0.1, 0.2, 0.3] }"));
    let loaded = load(&scene).unwrap_or_else(|d| panic!("{d}"));
    let p = &loaded.materials;
    assert_eq!(p.definitions.len(), 1);
    assert_eq!(p.definitions[0].name, "paint");
    assert_eq!(p.instances[0].values, vec![Value::Vec3([0.1, 0.2, 0.3])]);
    for f in ["paint.mat", "lib.mat"] {
        assert!(loaded.files.iter().any(|x| x.ends_with(f)), "{f} is a dependency: {:?}", loaded.files);
    }

    let error = |extra: &str| load_error(&scene, entry(extra));
    let e = error("");
    assert!(e.message.contains("defines 2 materials") && e.message.contains("paint, other"), "{e}");
    assert_eq!(at(&e), (3, 8));
    let e = error("material = \"nope\"");
    assert!(e.message.contains("no material `nope`"), "{e}");
    let e = error("material = \"paint\"\nparams = { color = [0.1, 0.2, 0.3] }");
    assert!(e.message.contains("no parameter `color`") && e.message.contains("colour"), "{e}");
    assert_eq!(at(&e), (5, 20));
    let e = error("material = \"paint\"\nparams = { colour = 0.5 }");
    assert!(e.message.contains("is a colour"), "{e}");
    let e = error("material = \"paint\"\nparams = { colour = [0.1, 2.0, 0.3] }");
    assert!(e.message.contains("[0, 1]") && e.message.contains('2'), "{e}");

    // A broken material file: its own diagnostic, with the reference.
    std::fs::write(dir.path().join("paint.mat"), "material paint = slab { base_color: 1 + }\n").unwrap();
    let e = error("");
    assert_eq!(e.code, Code::Material);
    assert!(e.file().is_some_and(|f| f.ends_with("paint.mat")), "{e}");
    assert!(e.labels.iter().any(|l| l.location.file.ends_with("s.toml") && l.location.line == 3), "{e:?}");
    // A missing one: at the reference.
    std::fs::remove_file(dir.path().join("paint.mat")).unwrap();
    let e = error("");
    assert!(e.message.contains("does not exist"), "{e}");
    assert_eq!(at(&e), (3, 8));
}

/// Textures of different sizes share the array at the largest: each other
/// one is resampled, a warning at the param naming it (the scene's
/// diagnostics, not only the log); textures of one size warn nothing.
#[test]
fn a_resampled_texture_is_a_warning_at_its_param() {
    let dir = tempfile::tempdir().unwrap();
    let png = |name: &str, w: u32, h: u32| image::RgbImage::new(w, h).save(dir.path().join(name)).unwrap();
    png("big.png", 4, 4);
    png("small.png", 2, 2);
    png("also_big.png", 4, 4);
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "[[materials]]\nname = \"m\"\nfile = \"t.mat\"\n\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n").unwrap();
    let mat = |second: &str| {
        let text = format!(
            "param a: texture = \"big.png\"\nparam b: texture = \"{second}\"\nmaterial t = slab {{ base_color: sample(a) * sample(b) }}\n"
        );
        std::fs::write(dir.path().join("t.mat"), text).unwrap();
        load(&scene).unwrap_or_else(|d| panic!("{d}")).warnings
    };
    let warnings = mat("small.png");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let w = &warnings[0];
    assert_eq!(w.severity, crate::diag::Severity::Warning);
    assert!(w.message.contains("small.png") && w.message.contains("2×2") && w.message.contains("4×4"), "{w}");
    assert!(w.file().is_some_and(|f| f.ends_with("t.mat")) && at(w).0 == 2, "at the param naming it: {w:?}");
    assert!(mat("also_big.png").is_empty(), "one size: nothing resampled");
}

fn load_error(scene: &Path, text: String) -> Diagnostic {
    std::fs::write(scene, text).unwrap();
    load(scene).unwrap_err()
}

/// A browser control's override of a material parameter: the path
/// `materials[I].params.NAME` reaches the instance's values whether the
/// entry has an inline `params` table, a `[materials.params]` sub-table or
/// none yet, and a value of the wrong type or out of range is refused with
/// the parameter named. Each definition has its compile report.
#[test]
fn material_parameter_overrides_reach_the_instance_and_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        dir.path().join("m.mat"),
        "param tint: color = rgb(0.5, 0.5, 0.5) in [0, 1]\nparam rough: float = 0.5 in [0, 1]\nmaterial m = slab { base_color: tint, specular_roughness: rough }\n",
    )
    .unwrap();
    let entry = |params: &str| {
        format!("[[materials]]\nname = \"m\"\nfile = \"m.mat\"\n{params}\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n")
    };
    let set = |path: &str, value: crate::scene::settings::Value| Overrides::from([(path.to_owned(), value)]);
    let rough = |v: f64| set("materials[0].params.rough", crate::scene::settings::Value::Float(v));
    for params in ["params = { tint = [0.1, 0.2, 0.3] }", "[materials.params]\ntint = [0.1, 0.2, 0.3]", ""] {
        std::fs::write(&scene, entry(params)).unwrap();
        let loaded = load_with(&scene, &rough(0.25)).unwrap_or_else(|d| panic!("{params}: {d}"));
        assert_eq!(loaded.materials.instances[0].values[1], Value::Float(0.25), "{params}");
        let tint = set("materials[0].params.tint", crate::scene::settings::Value::List(vec![0.0, 1.0, 0.5]));
        let loaded = load_with(&scene, &tint).unwrap_or_else(|d| panic!("{params}: {d}"));
        assert_eq!(loaded.materials.instances[0].values[0], Value::Vec3([0.0, 1.0, 0.5]), "{params}");
        let e = load_with(&scene, &rough(1.5)).unwrap_err();
        assert!(e.message.contains("`rough` must lie in [0, 1], not 1.5"), "{params}: {e}");
        let e = load_with(&scene, &set("materials[0].params.tint", crate::scene::settings::Value::Float(0.5))).unwrap_err();
        assert!(e.message.contains("`tint` is a colour"), "{params}: {e}");
    }
    let report = &load(&scene).unwrap().reports[0];
    assert_eq!(report.material, "m");
    assert_eq!(report.closures, [0]);
    assert!(report.wgsl_bytes.is_some_and(|b| b > 1000) && report.compile_ms.is_some_and(|ms| ms > 0.0), "{report:?}");
}

/// The repository's scenes directory.
fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

#[test]
fn a_gltf_object_without_a_material_gets_one_instance_per_gltf_material_and_a_named_one_overrides() {
    let dir = tempfile::tempdir_in(scenes()).unwrap();
    let scene = dir.path().join("s.toml");
    let crate_ = "[[materials]]\nname = \"m\"\n\n[[objects]]\nname = \"box\"\nmesh = \"../meshes/crate/crate.gltf\"\n";
    std::fs::write(&scene, crate_).unwrap();
    let l = load(&scene).unwrap_or_else(|d| panic!("{d}"));
    let names: Vec<(&str, usize)> = l.scene.objects.iter().map(|o| (o.name.as_str(), o.material)).collect();
    assert_eq!(names, [("box/wood", 1), ("box/felt", 2)], "instances after the scene's own");
    let defs: Vec<&str> = l.materials.instances[1..].iter().map(|i| l.materials.definitions[i.definition as usize].name.as_str()).collect();
    assert!(defs[0].ends_with("crate.gltf::wood") && defs[1].ends_with("crate.gltf::felt"), "{defs:?}");
    // Each part draws its primitive: four sides, then top and bottom.
    let triangles: Vec<usize> = l
        .scene
        .objects
        .iter()
        .map(|o| match &o.geometry {
            scene::Geometry::Mesh { file, .. } => l.meshes[file].triangle_count(),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(triangles, [8, 4]);
    assert_eq!(l.materials.textures.len(), 2, "the wood's colour and normal map");
    assert!(l.files.iter().any(|f| f.ends_with("crate_wood.png")), "textures are watched");
    // The felt's anisotropy is read into its slab, not warned about.
    assert!(l.warnings.iter().all(|w| !w.message.contains("KHR_materials_anisotropy")), "{:?}", l.warnings);
    let felt = &l.materials.definitions[l.materials.instances[2].definition as usize];
    let stretched = |n: &crate::material::tree::Node| matches!(&n.kind, crate::material::tree::NodeKind::Slab(s) if s.get(crate::material::tree::Field::SpecularAnisotropy).is_some());
    assert!(felt.nodes.iter().any(stretched), "{felt:?}");
    // Naming a material overrides them all.
    std::fs::write(&scene, format!("{crate_}material = \"m\"\n")).unwrap();
    let l = load(&scene).unwrap_or_else(|d| panic!("{d}"));
    let names: Vec<(&str, usize)> = l.scene.objects.iter().map(|o| (o.name.as_str(), o.material)).collect();
    assert_eq!(names, [("box", 0)]);
    assert_eq!(l.materials.instances.len(), 1);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    // A shape has no materials of its own.
    std::fs::write(&scene, "[[objects]]\nshape = \"cube\"\n").unwrap();
    assert!(load(&scene).unwrap_err().message.contains("needs a `material`"));
}

#[test]
fn the_showcase_uses_six_library_materials_and_a_gltf_asset_with_its_own() {
    let l = load(&scenes().join("showcase.toml")).unwrap_or_else(|d| panic!("{d}"));
    let library: std::collections::BTreeSet<&str> = l
        .scene
        .materials
        .iter()
        .filter_map(|m| match &m.source {
            MaterialSource::File { file, .. } => Some(file.as_str()),
            MaterialSource::Shorthand { .. } => None,
        })
        .collect();
    let gltf: Vec<&str> = l.materials.definitions.iter().map(|d| d.name.as_str()).filter(|n| n.contains(".gltf::")).collect();
    assert!(library.len() + gltf.len() >= 6 && library.len() >= 5, "{library:?} {gltf:?}");
    assert_eq!(gltf.len(), 2, "the crate's wood and felt: {gltf:?}");
    assert!(l.materials.definitions.iter().any(|d| d.name.contains(".gltf::") && d.params.iter().any(|p| p.ty == Type::Texture)));
}

/// A reload keeps the previous load's meshes, texture layers and network
/// when none of their files changed (a material edit, an override), and
/// reads again exactly those whose files did.
#[test]
fn a_reload_keeps_what_did_not_change_and_reads_what_did() {
    let path = scenes().join("showcase.toml");
    let first = load(&path).unwrap_or_else(|d| panic!("{d}"));
    assert!(first.denoiser.is_some() && !first.materials.textures.is_empty() && !first.meshes.is_empty());
    let reload = |changed: &dyn Fn(&Path) -> bool| {
        load_keeping(&path, &Overrides::new(), Some(&Keep { previous: &first, changed })).unwrap_or_else(|d| panic!("{d}"))
    };
    let same = |a: &Loaded, b: &Loaded, name: &str| Arc::ptr_eq(&a.meshes[name], &b.meshes[name]);
    let nothing = reload(&|_| false);
    // (A glTF's own materials split its mesh into `FILE#materialK` parts,
    // made again each load.)
    let named = |l: &Loaded| l.meshes.keys().filter(|m| !m.contains('#')).cloned().collect::<Vec<_>>();
    assert!(!named(&first).is_empty() && named(&first).iter().all(|m| same(&first, &nothing, m)));
    assert!(Arc::ptr_eq(&first.materials.layers, &nothing.materials.layers));
    assert!(Arc::ptr_eq(first.denoiser.as_ref().unwrap(), nothing.denoiser.as_ref().unwrap()));
    assert_eq!(nothing.files, first.files, "the same files are watched");

    // One mesh file changed: that mesh alone is read again.
    let name = &named(&first)[0];
    let mesh_path = scenes().join(name);
    let edited = reload(&|p| p == mesh_path);
    assert!(!same(&first, &edited, name), "{name} read again");
    assert!(named(&first).iter().filter(|m| *m != name).all(|m| same(&first, &edited, m)));
    assert!(Arc::ptr_eq(&first.materials.layers, &edited.materials.layers));

    // One texture changed: the layers are made again.
    let texture = first.materials.textures[0].path.clone();
    let retextured = reload(&|p| p == texture);
    assert!(!Arc::ptr_eq(&first.materials.layers, &retextured.materials.layers));
    assert_eq!(*first.materials.layers, *retextured.materials.layers, "from the same bytes");
}
