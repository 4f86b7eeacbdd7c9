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
