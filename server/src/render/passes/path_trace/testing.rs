//! Test fixtures of the path tracer: a session from scene text, frames
//! accumulated and captured, the shader's NaN guard taken out. Shared by
//! its tests, the shadow tests and the stability suite (`tests/stability`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::sync::Arc;

use crate::mesh::MeshData;
use crate::render::capture::CapturedImage;
use crate::render::frame::FrameResult;
use crate::render::session::Session;
use crate::loaded::Loaded;

pub const COLOR: &str = "path_trace/color";
pub const ALBEDO: &str = "path_trace/albedo";
pub const NORMAL: &str = "path_trace/normal";
pub const SAMPLES: &str = "path_trace/samples";

/// A scene from TOML text, with `meshes` as if loaded from its files.
pub fn loaded(text: &str, meshes: BTreeMap<String, Arc<MeshData>>) -> Loaded {
    let scene = crate::scene::parse("path_test.toml", text).unwrap_or_else(|d| panic!("{d}"));
    Loaded { materials: crate::loaded::materials_of(&scene), scene, meshes, denoiser: None, files: vec![], reports: Default::default(), warnings: vec![] }
}

/// A session on the test device over the repository's shaders, every
/// pipeline of the frame built.
pub fn session(loaded: &Loaded) -> Session {
    session_patched(loaded, &[])
}

/// `session` over the repository's shaders with each `(file, from, to)`
/// patch applied (file under `shaders/`; `from` must be there).
pub fn session_patched(loaded: &Loaded, patches: &[(&str, &str, &str)]) -> Session {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let mut lib = crate::shader::library::read_tree(&root).unwrap();
    for (file, from, to) in patches {
        patch(&mut lib, crate::diag::display_path(&root.join(file)), from, to);
    }
    let gpu = crate::gpu::testing::device();
    let mut s = Session::new(gpu, &root, lib, loaded);
    assert_eq!(s.install_missing(), vec![], "the frame's shaders build");
    s
}

/// Renders frames from a fresh accumulation until it holds `max(at)`
/// samples per pixel, capturing `outputs` (every output when `None`) after
/// each count in `at`.
pub fn accumulate(s: &mut Session, at: &[u32], outputs: Option<&[&str]>) -> Vec<FrameResult> {
    s.reset_history();
    let wanted: Option<BTreeSet<String>> = outputs.map(|o| o.iter().map(|n| (*n).to_owned()).collect());
    let nothing = BTreeSet::new();
    let mut out = Vec::new();
    for n in 1..=*at.iter().max().unwrap() {
        let captured = at.contains(&n);
        let pending = s.submit(if captured { wanted.as_ref() } else { Some(&nothing) }, 1.0 / 30.0);
        let r = s.wait(pending);
        assert_eq!(s.take_uncaptured(), Vec::<String>::new());
        if captured {
            out.push(r);
        }
    }
    out
}

pub fn image<'a>(r: &'a FrameResult, key: &str) -> &'a CapturedImage {
    r.captures.iter().find(|c| c.key() == key).unwrap_or_else(|| panic!("{key} is captured"))
}

/// The guard at the end of `path_trace.wgsl` that counts a non-finite
/// sample as black. The degenerate-input tests render with it taken out, so a sample
/// that goes NaN or infinite shows in the captures instead of quietly
/// darkening the pixel.
pub const GUARD: &str = "select(vec3(0.0), s.radiance, finite(s.radiance))";

/// Rebuilds the path tracer with `GUARD` taken out.
pub fn without_guard(s: &mut Session) {
    let mut lib = (**s.library()).clone();
    patch(&mut lib, s.shader_display(&super::PATH_TRACE), GUARD, "s.radiance");
    s.apply_sources(lib);
    let keys: Vec<_> = s.wanted().into_iter().collect();
    for key in keys {
        let job = s.compose_job(&key);
        s.install(&key, job());
    }
    assert_eq!(s.pipeline_diagnostics(), vec![]);
}

/// The patches that make both renderers sample the same points the same
/// way: the path tracer's camera rays through pixel centres, as the raster
/// samples (no jitter), and the raster's textures at level 0, as the path
/// tracer reads them (it has no ray differentials). With one point light,
/// no environment and no bounce, one path-traced sample is then the value
/// the raster computes at the same point, with no noise to tolerate.
pub const SAME_SAMPLES: [(&str, &str, &str); 2] = [
    ("passes/path_trace.wgsl", "let jitter = vec2(rand(), rand());", "let jitter = vec2(0.5);"),
    ("geometry/gbuffer.wgsl", "MaterialPoint(in.uv, dpdx(in.uv), dpdy(in.uv), in.tangent)", "MaterialPoint(in.uv, vec2(0.0), vec2(0.0), in.tangent)"),
];

/// Replaces `from` by `to` in `lib`'s file `display`.
fn patch(lib: &mut crate::shader::library::Library, display: String, from: &str, to: &str) {
    let file = lib.get(&display).unwrap();
    assert!(file.text.contains(from), "{display} still has `{from}`");
    let text = file.text.replace(from, to);
    let path = file.path.clone();
    lib.upsert(crate::shader::SourceFile::from_bytes(&path, display, text.into_bytes()).unwrap());
}

/// Renders to each count in `at` with every output captured, and asserts
/// every capture finite; returns the colour at the last count.
pub fn assert_finite(s: &mut Session, what: &str, at: &[u32]) -> CapturedImage {
    let frames = accumulate(s, at, None);
    for (n, r) in at.iter().zip(&frames) {
        for c in &r.captures {
            assert!(!c.stats.has_non_finite(), "{what}, {n} spp: {} holds {} NaN and {} Inf, the first at {:?}", c.key(), c.stats.nan, c.stats.inf, c.stats.first_nan);
        }
        for t in &r.tensors {
            assert!(!t.stats.has_non_finite(), "{what}, {n} spp: {} holds a NaN or Inf: {:?}", t.key(), t.stats);
        }
        assert_eq!(r.nan, None, "{what}, {n} spp");
        let samples = image(r, SAMPLES);
        assert!(samples.data.chunks(4).all(|p| p[0] == *n as f32), "{what}: every pixel holds {n} samples");
    }
    image(frames.last().unwrap(), COLOR).clone()
}

/// The mean of R + G + B over the image.
pub fn mean(c: &CapturedImage) -> f64 {
    c.data.chunks(4).map(|p| f64::from(p[0] + p[1] + p[2])).sum::<f64>() / (c.data.len() / 4) as f64
}
