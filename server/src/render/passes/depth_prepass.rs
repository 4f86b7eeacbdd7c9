//! Depth of the nearest surface per pixel, so the G-buffer pass shades
//! each pixel once.

use super::VIEW;
use crate::gpu::pipeline::{DEPTH, Depth, Group, PipelineSpec, Stages, VERT, storage};
use crate::render::context::DepthTarget;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Handle, Meaning, PipelineKey, Projection, TextureDesc};
use crate::scene::Scene;

pub static DEPTH_ONLY: PipelineSpec = PipelineSpec {
    name: "geometry.depth",
    shader: "geometry/depth.wgsl",
    stages: Stages::Mesh { vertex: "vs_main", fragment: None, targets: &[], depth: Depth::Write },
    groups: &[Group::always(0, &[VIEW, storage("objects", 1, VERT)])],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&DEPTH_ONLY];

pub fn depth_prepass(g: &mut GraphBuilder, scene: &Scene) -> Handle {
    let mut p = g.pass("depth_prepass", PassKind::Raster);
    let key = p.pipeline(PipelineKey::new(&DEPTH_ONLY, &[]));
    let depth = p.create("depth", Meaning::Depth(Projection::Camera), TextureDesc::d2(DEPTH, scene.width, scene.height), Access::DepthTarget);
    p.execute(move |ctx| {
        let s = ctx.scene;
        let target = DepthTarget { texture: depth, layer: 0, clear: true };
        ctx.draw_objects(&key, &[("view", s.view.as_entire_binding()), ("objects", s.objects.as_entire_binding())], &[], Some(target));
    });
    depth
}
