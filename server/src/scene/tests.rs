use super::*;

fn err(text: &str) -> Diagnostic {
    parse("s.toml", text).expect_err("the scene is invalid")
}

fn at(d: &Diagnostic) -> (u32, u32) {
    let l = d.location.as_ref().expect("located");
    (l.line, l.column)
}

const BASE: &str = "[[materials]]\nname = \"m\"\n\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n";

#[test]
fn defaults_apply() {
    let s = parse("s.toml", "# nothing\n").unwrap();
    assert_eq!((s.width, s.height, s.post.tonemap), (1280, 720, Tonemap::Aces));
    assert!(s.is_empty());
}

#[test]
fn every_bundled_scene_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            load(&p).unwrap_or_else(|d| panic!("{}: {d}", p.display()));
            n += 1;
        }
    }
    assert!(n >= 4, "default, showcase, minimal, volume");
}

#[test]
fn output_size_errors_are_located() {
    let e = err("[output]\nwidth = 0\nheight = 10\n");
    assert_eq!(at(&e), (2, 9));
    let e = err("[output]\nwidth = 16384\nheight = 16384\n");
    assert!(e.message.contains("8192"), "{}", e.message);
    assert_eq!(at(&e), (2, 9));
}

#[test]
fn unknown_fields_are_errors_at_their_line() {
    let e = err("[post]\nexposure = 1\n");
    assert_eq!(at(&e).0, 2);
    let e = err(&format!("{BASE}colour = [1, 0, 0]\n"));
    assert_eq!(at(&e).0, 7);
    assert!(e.message.contains("colour"), "{}", e.message);
}

#[test]
fn nan_and_negative_values_are_located_at_the_value() {
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = nan\n"));
    assert!(e.message.starts_with("lights[0].intensity"), "{}", e.message);
    assert_eq!(at(&e), (11, 13));
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = -2.0\n"));
    assert!(e.message.contains("negative"), "{}", e.message);
    assert_eq!(at(&e), (11, 13));
    let e = err("[[materials]]\nname = \"m\"\nroughness = 1.5\n");
    assert_eq!(at(&e), (3, 13));
    let e = err("[[media]]\nabsorption = [0.1, -0.1, 0.1]\nscattering = [1, 1, 1]\nshapes = [{ type = \"sphere\", center = [0, 0, 0], radius = 1 }]\n");
    assert!(e.message.starts_with("media[0].absorption[1]"), "{}", e.message);
    assert_eq!(at(&e), (2, 20));
    let e = err("[[media]]\nabsorption = [0, 0, 0]\nscattering = [1, 1, 1]\nshapes = [{ type = \"sphere\", center = [0, 0, 0], radius = inf }]\n");
    assert!(e.message.contains("radius"), "{}", e.message);
    assert_eq!(at(&e).0, 4);
}

#[test]
fn references_and_light_fields_are_checked() {
    let e = err("[[objects]]\nshape = \"sphere\"\nmaterial = \"nope\"\n");
    assert!(e.message.contains("no material named `nope`"), "{}", e.message);
    assert_eq!(at(&e), (3, 12));
    let e = err(&BASE.replace("sphere", "teapot"));
    assert!(e.message.contains("unknown shape `teapot`"), "{}", e.message);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nsize = [1, 1]\n"));
    assert!(e.message.contains("does not apply for a point light"), "{}", e.message);
    assert_eq!(at(&e).0, 11);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"rect\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n"));
    assert!(e.message.contains("lights[0].size: is required for a rect light"), "{}", e.message);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\n"));
    assert!(e.message.contains("zero vector"), "{}", e.message);
    assert_eq!(at(&e), (10, 13));
}

#[test]
fn missing_and_malformed_meshes_are_diagnosed_at_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"gone.gltf\"\nmaterial = \"m\"\n").unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.message.contains("gone.gltf") && e.message.contains("does not exist"), "{}", e.message);
    assert_eq!(at(&e), (4, 8));
    std::fs::write(dir.path().join("bad.gltf"), "{ \"asset\": { \"version\": \"2.0\" }, \n  \"meshes\": [ oops ] }").unwrap();
    std::fs::write(&scene, "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"bad.gltf\"\nmaterial = \"m\"\n").unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.file().is_some_and(|f| f.ends_with("bad.gltf")), "located in the glTF: {e}");
    assert!(e.labels.iter().any(|l| l.location.file.ends_with("s.toml") && l.location.line == 4), "and at the reference: {e:?}");
}
