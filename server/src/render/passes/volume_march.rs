//! Single scattering through the scene's media at `quality.volume_resolution`:
//! a ray march whose self-shadowing comes from the volume grid
//! (`volume_shadows`); `volumes` brings it to the frame's resolution and
//! composites it over the lit frame.

use super::volume_shadows::{GRID_UNIFORM, VolumeGrid};
use super::{LIGHTS, MEDIA, SHADOW_GROUP, SHADOWS, TWO_TRIANGLES, VIEW, fullscreen_key};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, depth_texture, sizes, storage, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::{Estimator, Scene};

/// The exact per-step in-scattering integral instead of the constant one.
pub const VOLUME_ANALYTIC: &str = "VOLUME_ANALYTIC";

pub static RAYMARCH: PipelineSpec = PipelineSpec {
    name: "volume_march",
    shader: "passes/volume_march.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR, HDR] },
    groups: &[
        Group::always(0, &[VIEW, LIGHTS, uniform("params", 2, FRAG, sizes::VEC4), depth_texture("depth", 3), GRID_UNIFORM, storage("cells", 5, FRAG)]),
        SHADOW_GROUP,
        Group::always(3, MEDIA),
    ],
    defs: &[TWO_TRIANGLES, SHADOWS, VOLUME_ANALYTIC],
};
pub const SPECS: &[&PipelineSpec] = &[&RAYMARCH];

/// The march's outputs, one pixel per `scale` × `scale` of the frame.
#[derive(Debug, Clone, Copy)]
pub struct Marched {
    pub scale: u32,
    /// rgb: in-scattered light; a: the distance marched to.
    pub scattered: Handle,
    /// rgb: camera-to-surface transmittance; a: the fraction of steps run.
    pub transmittance: Handle,
}

/// The march, or `None` (culled) without media, so without a `grid`.
pub fn volume_march(g: &mut GraphBuilder, scene: &Scene, depth: Handle, shadows: Option<Handle>, grid: Option<VolumeGrid>) -> Option<Marched> {
    let Some(grid) = grid else {
        g.cull("volume_march", "the scene has no participating media");
        return None;
    };
    let analytic = scene.quality.volume_estimator == Estimator::Analytic;
    let scale = scene.quality.volume_resolution.scale();
    let (w, h) = (scene.width.div_ceil(scale), scene.height.div_ceil(scale));
    let mut p = g.pass("volume_march", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&RAYMARCH, scene, &[(SHADOWS, shadows.is_some()), (VOLUME_ANALYTIC, analytic)]));
    p.sample(depth);
    let shadow_maps = shadows.map(|h| p.sample(h));
    let cells = p.access(grid.cells, Access::StorageRead);
    let grid_params = grid.layout.uniform_bytes();
    let scattered = p.create("scattered", Meaning::Color, TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    let transmittance = p.create("transmittance", Meaning::Data, TextureDesc::d2(HDR, w, h), Access::ColorTarget);
    p.execute(move |ctx| {
        let s = ctx.scene;
        let u = ctx.uniform(&grid_params);
        let params = ctx.uniform(bytemuck::cast_slice(&[scale, 0, 0, 0]));
        let mut b = vec![
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("params", params.as_entire_binding()),
            ("depth", ctx.bind(depth)),
            ("grid", u.as_entire_binding()),
            ("cells", ctx.bind(cells)),
            ("media", s.media.as_entire_binding()),
        ];
        if let Some(h) = shadow_maps {
            b.extend([("shadow_maps", ctx.bind(h)), ("shadow_views", s.shadow_views.as_entire_binding())]);
        }
        ctx.fullscreen(&key, &[scattered, transmittance], &b);
    });
    Some(Marched { scale, scattered, transmittance })
}
