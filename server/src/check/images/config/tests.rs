use super::*;
use crate::check::project;
use crate::diag::Code;

fn cases(text: &str) -> Result<Vec<Case>, Diagnostic> {
    project::parse("loupe.toml", text, Path::new("/proj")).map(|d| d.images)
}

/// The refusal's line, column and message.
fn refused(text: &str) -> (u32, u32, String) {
    let d = cases(text).expect_err("must be refused");
    assert_eq!(d.code, Code::ProjectFile);
    let l = d.location.clone().expect("located");
    (l.line, l.column, d.message)
}

#[test]
fn every_key_and_the_defaults() {
    let c = cases(
        "[[images]]\nscene = \"scenes/minimal.toml\"\n\n[[images]]\nscene = \"scenes/showcase.toml\"\nname = \"show\"\nsize = \"64x36\"\n\
         outputs = [\"tonemap/color\", \"lighting/color\"]\nset = { \"quality.volume_steps\" = 32, \"post.tonemap\" = \"reinhard\" }\n\
         renderer = \"path\"\nspp = 4\nthreshold = { flip_mean = 0.02 }\n[images.adapter.\"llvmpipe\"]\nflip_p99 = 0.5\n\
         [images.adapter.cpu]\nflip_mean = 0\n",
    )
    .unwrap();
    assert_eq!(c.len(), 2);
    assert_eq!(c[0].name, "minimal-320x180");
    assert_eq!((c[0].size, c[0].threshold, c[0].outputs.len()), (DEFAULT_SIZE, DEFAULT_THRESHOLD, 0));
    assert_eq!(c[0].scene, PathBuf::from("/proj/scenes/minimal.toml"));
    assert_eq!((c[0].at.line, c[0].at.column), (1, 1));
    let s = &c[1];
    assert_eq!((s.name.as_str(), s.size, s.at.line), ("show", (64, 36), 4));
    assert_eq!(s.outputs.iter().map(|(o, l)| (o.as_str(), l.line)).collect::<Vec<_>>(), [("tonemap/color", 8), ("lighting/color", 8)]);
    assert_eq!(s.overrides["quality.volume_steps"], Setting::Int(32));
    assert_eq!(s.overrides["post.tonemap"], Setting::Text("reinhard".into()));
    assert_eq!(s.overrides["quality.renderer"], Setting::Text("path".into()));
    assert_eq!(s.overrides["quality.path_spp"], Setting::Int(4));
    assert_eq!(s.threshold, Threshold { flip_mean: 0.02, flip_p99: DEFAULT_THRESHOLD.flip_p99 });
    // The first adapter key the name holds wins, field by field over the case's.
    let lavapipe = "llvmpipe (LLVM 19.1.7, 256 bits) (Vulkan, Cpu)";
    assert_eq!(s.threshold_on(lavapipe), (Threshold { flip_mean: 0.02, flip_p99: 0.5 }, Some("llvmpipe")));
    assert_eq!(s.threshold_on("SwiftShader (Vulkan, Cpu)"), (Threshold { flip_mean: 0.0, flip_p99: 0.1 }, Some("cpu")));
    assert_eq!(s.threshold_on("NVIDIA GeForce RTX 4090 (Vulkan, DiscreteGpu)"), (s.threshold, None));
    // The default name carries the renderer when the case names one.
    let c = cases("[[images]]\nscene = \"a/b.toml\"\nrenderer = \"raster\"\nsize = \"8x4\"\n").unwrap();
    assert_eq!(c[0].name, "b-raster-8x4");
}

#[test]
fn bad_cases_are_located() {
    let (line, col, msg) = refused("[[images]]\nscene = \"s.toml\"\nscnee = 1\n");
    assert_eq!((line, col), (3, 1));
    assert!(msg.contains("unknown key `scnee`") && msg.contains("threshold"), "{msg}");
    let (line, col, msg) = refused("[[images]]\nscene = \"s.toml\"\nthreshold = { flip_mean = 1.5 }\n");
    assert_eq!((line, col), (3, 27));
    assert!(msg.contains("from 0 to 1"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nthreshold = { flip_p99 = -0.1 }\n");
    assert!(line == 3 && msg.contains("flip_p99"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nthreshold = { flip_max = 0.1 }\n");
    assert!(line == 3 && msg.contains("unknown threshold `flip_max`"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\n[images.adapter.llvmpipe]\nflip_mean = \"big\"\n");
    assert!(line == 4 && msg.contains("flip_mean"), "{msg}");
    let (line, col, msg) = refused("[[images]]\nscene = \"s.toml\"\nsize = \"320by180\"\n");
    assert!((line, col) == (3, 8) && msg.contains("WIDTHxHEIGHT"), "{msg}");
    let (line, col, msg) = refused("[[images]]\nscene = \"s.toml\"\noutputs = [\"tonemap/color\", \"color\"]\n");
    assert!((line, col) == (3, 29) && msg.contains("`color` is not a `pass/output` name"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nspp = 4\n");
    assert!(line == 3 && msg.contains("renderer = \\\"path\\\"") || msg.contains("renderer = \"path\""), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nrenderer = \"ray\"\n");
    assert!(line == 3 && msg.contains("\"raster\" or \"path\""), "{msg}");
    let (line, _, msg) = refused("[[images]]\nname = \"x\"\n");
    assert!(line == 1 && msg.contains("needs a `scene`"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nname = \"../up\"\n");
    assert!(line == 3 && msg.contains("`name` must be"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"a/s.toml\"\n[[images]]\nscene = \"b/s.toml\"\n");
    assert!(line == 3 && msg.contains("a second image case named `s-320x180`"), "{msg}");
    let (line, _, msg) = refused("images = 3\n");
    assert!(line == 1 && msg.contains("[[images]]"), "{msg}");
    let (line, _, msg) = refused("[[images]]\nscene = \"s.toml\"\nset = { \"a.b\" = { c = 1 } }\n");
    assert!(line == 3 && msg.contains("`a.b` must be"), "{msg}");
}
