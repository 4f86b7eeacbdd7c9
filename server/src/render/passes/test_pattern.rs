//! A pattern of known values: the frame of a scene with nothing in it.

use super::{TWO_TRIANGLES, fullscreen_key, vec4_bytes};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, sizes, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::Scene;

pub static PATTERN: PipelineSpec = PipelineSpec {
    name: "debug.test_pattern",
    shader: "passes/test_pattern.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR] },
    groups: &[Group::always(0, &[uniform("frame", 0, FRAG, sizes::VEC4)])],
    defs: &[TWO_TRIANGLES],
};
pub const SPECS: &[&PipelineSpec] = &[&PATTERN];

pub fn test_pattern(g: &mut GraphBuilder, scene: &Scene) -> Handle {
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("test_pattern", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&PATTERN, scene, &[]));
    let color = p.create("color", Meaning::Color, TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    p.execute(move |ctx| {
        let mut u = vec4_bytes([w as f32, h as f32, 0.0, 0.0]);
        u[12..16].copy_from_slice(&(ctx.frame as u32).to_le_bytes());
        let frame = ctx.uniform(&u);
        ctx.fullscreen(&key, &[color], &[("frame", frame.as_entire_binding())]);
    });
    color
}
