//! Single scattering through the scene's media, composited over the lit
//! frame: a ray march whose self-shadowing comes from the volume grid
//! (`volume_shadows`).

use super::volume_shadows::{GRID_UNIFORM, VolumeGrid};
use super::{LIGHTS, MEDIA, SHADOW_GROUP, SHADOWS, TWO_TRIANGLES, VIEW, fullscreen_key};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, depth_texture, storage, texture};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Handle, TextureDesc};
use crate::scene::{Estimator, Scene};

/// The exact per-step in-scattering integral instead of the constant one.
pub const VOLUME_ANALYTIC: &str = "VOLUME_ANALYTIC";

pub static RAYMARCH: PipelineSpec = PipelineSpec {
    name: "volumes.raymarch",
    shader: "passes/volumes.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR, HDR] },
    groups: &[
        Group::always(0, &[VIEW, LIGHTS, texture("opaque", 2), depth_texture("depth", 3), GRID_UNIFORM, storage("cells", 5, FRAG)]),
        SHADOW_GROUP,
        Group::always(3, MEDIA),
    ],
    defs: &[TWO_TRIANGLES, SHADOWS, VOLUME_ANALYTIC],
};
pub const SPECS: &[&PipelineSpec] = &[&RAYMARCH];

/// Returns the composited colour, or `color` itself when culled (no media,
/// so no `grid`).
pub fn volumes(g: &mut GraphBuilder, scene: &Scene, color: Handle, depth: Handle, shadows: Option<Handle>, grid: Option<VolumeGrid>) -> Handle {
    let Some(grid) = grid else {
        g.cull("volumes", "the scene has no participating media");
        return color;
    };
    let analytic = scene.quality.volume_estimator == Estimator::Analytic;
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("volumes", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&RAYMARCH, scene, &[(SHADOWS, shadows.is_some()), (VOLUME_ANALYTIC, analytic)]));
    let opaque = p.sample(color);
    p.sample(depth);
    let shadow_maps = shadows.map(|h| p.sample(h));
    let cells = p.access(grid.cells, Access::StorageRead);
    let grid_params = grid.layout.uniform_bytes();
    let out = p.create("color", TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    let transmittance = p.create("transmittance", TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    p.execute(move |ctx| {
        let s = ctx.scene;
        let u = ctx.uniform(&grid_params);
        let mut b = vec![
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("opaque", ctx.bind(opaque)),
            ("depth", ctx.bind(depth)),
            ("grid", u.as_entire_binding()),
            ("cells", ctx.bind(cells)),
            ("media", s.media.as_entire_binding()),
        ];
        if let Some(h) = shadow_maps {
            b.extend([("shadow_maps", ctx.bind(h)), ("shadow_views", s.shadow_views.as_entire_binding())]);
        }
        ctx.fullscreen(&key, &[out, transmittance], &b);
    });
    out
}

#[cfg(test)]
mod tests;
