//! The passes of the frame, one module each: its pipeline spec(s), the
//! defs and settings it reads, why it is culled, and its builder — a free
//! function taking the graph builder and input handles and returning
//! output handles. `render::build_graph` assembles them into a frame.

use crate::gpu::pipeline::{ALL, Binding, COMPUTE, FRAG, Group, PipelineSpec, sizes, storage, uniform};
use crate::scene::Scene;

use super::resource::PipelineKey;

pub use crate::gpu::pipeline::TWO_TRIANGLES;

/// Lists the pass modules; every spec they declare lands in `SPECS`.
macro_rules! passes {
    ($($pass:ident),* $(,)?) => {
        $(pub mod $pass;)*

        /// Every pipeline any pass can build: what `loupe check` creates.
        pub fn specs() -> impl Iterator<Item = &'static PipelineSpec> {
            [$($pass::SPECS),*].into_iter().flatten().copied()
        }
    };
}

passes![
    test_pattern,
    shadows,
    depth_prepass,
    gbuffer,
    ltc_tables,
    lighting,
    volume_shadows,
    volume_march,
    volumes,
    path_trace,
    images,
    denoise,
    auto_exposure,
    exposure,
    tonemap,
    debug_view,
    nan_watch,
];

/// The spec named `name`.
pub fn spec(name: &str) -> Option<&'static PipelineSpec> {
    specs().find(|s| s.name == name)
}

/// The def that turns on shadow-map lookups (`lib/shadows.wgsl`).
pub const SHADOWS: &str = "SHADOWS";

/// The camera, as `lib/view.wgsl` declares it.
pub const VIEW: Binding = uniform("view", 0, ALL, sizes::VIEW);
/// The scene's lights, as `lib/lights.wgsl` declares them: read by raster
/// and compute passes (the path tracer).
pub const LIGHTS: Binding = storage("lights", 1, FRAG.union(COMPUTE));
/// Shadow maps and their views (`lib/shadows.wgsl`), with SHADOWS on.
pub const SHADOW_GROUP: Group =
    Group::when(1, SHADOWS, &[crate::gpu::pipeline::depth_array("shadow_maps", 0), storage("shadow_views", 1, FRAG)]);
/// The participating media (`lib/media.wgsl`), for raster and compute passes.
pub const MEDIA: &[Binding] = &[storage("media", 0, FRAG.union(COMPUTE))];

/// A fullscreen pass's key: TWO_TRIANGLES as the scene says, plus `defs`.
pub fn fullscreen_key(spec: &'static PipelineSpec, scene: &Scene, defs: &[(&'static str, bool)]) -> PipelineKey {
    let mut all = vec![(TWO_TRIANGLES, scene.post.two_triangles)];
    all.extend_from_slice(defs);
    PipelineKey::new(spec, &all)
}

pub fn vec4_bytes(v: [f32; 4]) -> Vec<u8> {
    bytemuck::cast_slice(&v).to_vec()
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::scene::overrides::{Overrides, Value};

    /// Every pipeline a frame can use is one `loupe check` creates: the
    /// graphs of every bundled scene under every switch that changes the
    /// pass list or a permutation only name specs in `specs()`, and every
    /// spec there is used by some frame.
    #[test]
    fn every_pipeline_a_frame_uses_is_enumerated_for_loupe_check() {
        let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let switches: &[(&str, &[Value])] = &[
            ("post.auto_exposure", &[Value::Bool(false), Value::Bool(true)]),
            ("post.two_triangles", &[Value::Bool(false), Value::Bool(true)]),
            ("post.tonemap", &[Value::Text("aces".into()), Value::Text("reinhard".into())]),
            ("post.debug_view", &[Value::Text("none".into()), Value::Text("normal".into()), Value::Text("depth".into())]),
            ("post.exposure_ev", &[Value::Float(0.0), Value::Float(1.0)]),
            ("quality.shadows", &[Value::Bool(true), Value::Bool(false)]),
            ("quality.volume_estimator", &[Value::Text("constant".into()), Value::Text("analytic".into())]),
            ("quality.renderer", &[Value::Text("raster".into()), Value::Text("path".into())]),
        ];
        let mut used = BTreeSet::new();
        let mut scenes_seen = 0;
        for entry in std::fs::read_dir(&scenes).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            scenes_seen += 1;
            for (key, values) in switches {
                for v in *values {
                    let overrides = Overrides::from([((*key).to_owned(), v.clone())]);
                    let loaded = crate::loaded::load_with(&path, &overrides).unwrap_or_else(|d| panic!("{d}"));
                    for nan_watch in [false, true] {
                        let options = crate::render::FrameOptions { nan_watch, ..Default::default() };
                        for k in crate::render::build_graph(&loaded.scene, loaded.denoiser.as_deref(), options).pipelines() {
                            assert!(
                                specs().any(|s| std::ptr::eq(s, k.spec)),
                                "{} is built by a frame but not listed for loupe check",
                                k.label()
                            );
                            used.insert(k.spec.name);
                        }
                    }
                }
            }
        }
        assert!(scenes_seen >= 4, "the bundled scenes are found");
        // No bundled scene names weights (they are not in the repository):
        // a denoised frame on a small random network, in each of its modes.
        let network = crate::denoise::testing::network(&crate::denoise::testing::small_unet(9), 1);
        let modes = [
            ("f32", "hdr", true, "direct", ""),
            ("f16", "ldr", false, "tiled", ""),
            ("f16", "hdr", true, "tiled", ""),
            ("f32", "ldr", false, "direct", ""),
            ("f32", "ldr_srgb", true, "direct", ""),
            ("f32", "hdr", true, "tiled", "input_scale = 0.5"),
        ];
        for (precision, mode, fused, kernel, scale) in modes {
            let text = format!(
                "[quality]\nrenderer = \"path\"\ndenoiser_fused = {fused}\ndenoiser_kernel = \"{kernel}\"\n[denoiser]\nweights = \"w.tza\"\nprecision = \"{precision}\"\nmode = \"{mode}\"\n{scale}\n\
                 [[materials]]\nname = \"m\"\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n"
            );
            let scene = crate::scene::parse("denoised.toml", &text).unwrap_or_else(|d| panic!("{d}"));
            for k in crate::render::build_graph(&scene, Some(&network), Default::default()).pipelines() {
                assert!(specs().any(|s| std::ptr::eq(s, k.spec)), "{} is built by a frame but not listed for loupe check", k.label());
                used.insert(k.spec.name);
            }
        }
        let listed: BTreeSet<&str> = specs().map(|s| s.name).collect();
        assert_eq!(listed, used, "every listed spec is used by some frame");
    }
}
