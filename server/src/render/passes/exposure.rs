//! Multiplies the HDR frame by 2^EV: the manual `post.exposure_ev`, plus
//! the adapted EV when auto exposure is on. Culled at 0 EV without auto
//! exposure, where it would copy.

use super::{TWO_TRIANGLES, fullscreen_key, vec4_bytes};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, sizes, storage, texture, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::Scene;

/// Adds the adapted EV from the auto-exposure state buffer.
pub const AUTO_EXPOSURE: &str = "AUTO_EXPOSURE";

pub static EXPOSURE: PipelineSpec = PipelineSpec {
    name: "post.exposure",
    shader: "post/exposure.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR] },
    groups: &[
        Group::always(0, &[uniform("exposure", 0, FRAG, sizes::VEC4), texture("hdr", 1)]),
        Group::when(1, AUTO_EXPOSURE, &[storage("adapted", 0, FRAG)]),
    ],
    defs: &[TWO_TRIANGLES, AUTO_EXPOSURE],
};
pub const SPECS: &[&PipelineSpec] = &[&EXPOSURE];

/// `adapted`: the auto-exposure state, when on.
pub fn exposure(g: &mut GraphBuilder, scene: &Scene, hdr: Handle, adapted: Option<Handle>) -> Handle {
    if scene.post.exposure_ev == 0.0 && adapted.is_none() {
        g.cull("exposure", "post.exposure_ev is 0 and auto exposure is off: the frame passes through unchanged");
        return hdr;
    }
    let scale = 2f32.powf(scene.post.exposure_ev);
    let mut p = g.pass("exposure", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&EXPOSURE, scene, &[(AUTO_EXPOSURE, adapted.is_some())]));
    p.sample(hdr);
    let adapted = adapted.map(|h| p.access(h, Access::StorageRead));
    let color = p.create("color", Meaning::Color, TextureDesc::d2(HDR, scene.width, scene.height), Access::ColorTarget);
    p.execute(move |ctx| {
        let u = ctx.uniform(&vec4_bytes([scale, 0.0, 0.0, 0.0]));
        let mut b = vec![("exposure", u.as_entire_binding()), ("hdr", ctx.bind(hdr))];
        b.extend(adapted.map(|h| ("adapted", ctx.bind(h))));
        ctx.fullscreen(&key, &[color], &b);
    });
    color
}
