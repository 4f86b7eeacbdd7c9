//! The passes of the frame, one module each: its pipeline spec(s), the
//! defs and settings it reads, why it is culled, and its builder — a free
//! function taking the graph builder and input handles and returning
//! output handles. `render::build_graph` assembles them into a frame.

use crate::gpu::pipeline::{Binding, Group, PipelineSpec, storage, uniform, ALL, FRAG, sizes};
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
    volumes,
    auto_exposure,
    exposure,
    tonemap,
    debug_view,
];

/// The spec named `name`.
pub fn spec(name: &str) -> Option<&'static PipelineSpec> {
    specs().find(|s| s.name == name)
}

/// The def that turns on shadow-map lookups (`lib/shadows.wgsl`).
pub const SHADOWS: &str = "SHADOWS";

/// The camera, as `lib/view.wgsl` declares it.
pub const VIEW: Binding = uniform("view", 0, ALL, sizes::VIEW);
/// The scene's lights, as `lib/lights.wgsl` declares them.
pub const LIGHTS: Binding = storage("lights", 1, FRAG);
/// Shadow maps and their views (`lib/shadows.wgsl`), with SHADOWS on.
pub const SHADOW_GROUP: Group = Group::when(
    1,
    SHADOWS,
    &[crate::gpu::pipeline::depth_array("shadow_maps", 0), storage("shadow_views", 1, FRAG)],
);
/// The participating media (`lib/media.wgsl`).
pub const MEDIA: &[Binding] = &[storage("media", 0, FRAG)];

/// A fullscreen pass's key: TWO_TRIANGLES as the scene says, plus `defs`.
pub fn fullscreen_key(spec: &'static PipelineSpec, scene: &Scene, defs: &[(&'static str, bool)]) -> PipelineKey {
    let mut all = vec![(TWO_TRIANGLES, scene.post.two_triangles)];
    all.extend_from_slice(defs);
    PipelineKey::new(spec, &all)
}

pub fn vec4_bytes(v: [f32; 4]) -> Vec<u8> {
    bytemuck::cast_slice(&v).to_vec()
}
