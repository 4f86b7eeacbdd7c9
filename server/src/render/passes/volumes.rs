//! The volume march brought to the frame's resolution (a depth-aware
//! upsample when `quality.volume_resolution` is half or quarter) and
//! composited over the lit frame: `color`, and the camera-to-surface
//! `transmittance` (alpha: the fraction of the march's steps that ran).

use super::volume_march::Marched;
use super::{TWO_TRIANGLES, VIEW, fullscreen_key};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, depth_texture, sizes, texture, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::Scene;

pub static COMPOSITE: PipelineSpec = PipelineSpec {
    name: "volumes.composite",
    shader: "passes/volumes.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR, HDR] },
    groups: &[Group::always(
        0,
        &[VIEW, uniform("params", 1, FRAG, sizes::VEC4), texture("opaque", 2), depth_texture("depth", 3), texture("scattered", 4), texture("marched", 5)],
    )],
    defs: &[TWO_TRIANGLES],
};
pub const SPECS: &[&PipelineSpec] = &[&COMPOSITE];

/// Returns the composited colour, or `color` itself when culled (no media,
/// so no march).
pub fn volumes(g: &mut GraphBuilder, scene: &Scene, color: Handle, depth: Handle, marched: Option<Marched>) -> Handle {
    let Some(m) = marched else {
        g.cull("volumes", "the scene has no participating media");
        return color;
    };
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("volumes", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&COMPOSITE, scene, &[]));
    let opaque = p.sample(color);
    p.sample(depth);
    p.sample(m.scattered);
    p.sample(m.transmittance);
    let out = p.create("color", Meaning::Color, TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    let transmittance = p.create("transmittance", Meaning::Data, TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    p.execute(move |ctx| {
        let params = ctx.uniform(bytemuck::cast_slice(&[m.scale, 0, 0, 0]));
        let b = [
            ("view", ctx.scene.view.as_entire_binding()),
            ("params", params.as_entire_binding()),
            ("opaque", ctx.bind(opaque)),
            ("depth", ctx.bind(depth)),
            ("scattered", ctx.bind(m.scattered)),
            ("marched", ctx.bind(m.transmittance)),
        ];
        ctx.fullscreen(&key, &[out, transmittance], &b);
    });
    out
}

#[cfg(test)]
mod tests;
