//! Direct light from every light on the G-buffer, with shadows, rect
//! lights through LTC, and the media's transmittance toward each light; the
//! environment's light (its irradiance and split-sum specular, with the
//! GGX table of `render/dfg.rs`); the environment behind the geometry.

use super::gbuffer::{GBuffer, WORDS_BINDING};
use super::{LIGHTS, MEDIA, SHADOW_GROUP, SHADOWS, TWO_TRIANGLES, VIEW, fullscreen_key};
use crate::gpu::pipeline::{FRAG, Group, HDR, PipelineSpec, Stages, depth_texture, storage, texture};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::Scene;
use crate::scene::settings::RectLights;

/// Rect lights, shaded with the LTC tables.
pub const LIGHT_RECT: &str = "LIGHT_RECT";
/// Rect lights integrated by sampling their area (`quality.rect_lights`).
pub const RECT_SAMPLED: &str = "RECT_SAMPLED";
/// Shadows cast by the participating media onto surfaces.
pub const MEDIA_SHADOWS: &str = "MEDIA_SHADOWS";

pub static DEFERRED: PipelineSpec = PipelineSpec {
    name: "lighting.deferred",
    shader: "passes/lighting.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR] },
    groups: &[
        // Depth and the material buffer: the G-buffer's other targets are
        // for the inspector and the debug views.
        Group::always(0, &[VIEW, LIGHTS, depth_texture("depth", 5), texture("dfg", 6), storage("material_words", WORDS_BINDING, FRAG)]),
        SHADOW_GROUP,
        Group::when(2, LIGHT_RECT, &[texture("ltc_matrix", 0), texture("ltc_amplitude", 1)]),
        Group::when(3, MEDIA_SHADOWS, MEDIA),
    ],
    defs: &[TWO_TRIANGLES, SHADOWS, LIGHT_RECT, RECT_SAMPLED, MEDIA_SHADOWS],
};
pub const SPECS: &[&PipelineSpec] = &[&DEFERRED];

pub fn lighting(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle, shadows: Option<Handle>, ltc: Option<[Handle; 2]>) -> Handle {
    let media = !scene.media.is_empty();
    let mut p = g.pass("lighting", PassKind::Raster);
    let sampled = scene.has_rect_lights() && scene.quality.rect_lights == RectLights::Sampled;
    let defs = [(SHADOWS, shadows.is_some()), (LIGHT_RECT, ltc.is_some()), (RECT_SAMPLED, sampled), (MEDIA_SHADOWS, media)];
    let key = p.pipeline(fullscreen_key(&DEFERRED, scene, &defs));
    p.sample(depth);
    p.access(gb.words, Access::StorageRead);
    let shadow_maps = shadows.map(|h| p.sample(h));
    let ltc = ltc.map(|t| t.map(|h| p.sample(h)));
    let gb_words = gb.words;
    let color = p.create("color", Meaning::Color, TextureDesc::d2(HDR, scene.width, scene.height), Access::ColorTarget);
    p.execute(move |ctx| {
        let s = ctx.scene;
        let mut b = vec![
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("media", s.media.as_entire_binding()),
            ("dfg", wgpu::BindingResource::TextureView(&s.dfg)),
        ];
        b.extend([("depth", ctx.bind(depth)), ("material_words", ctx.bind(gb_words))]);
        if let Some(h) = shadow_maps {
            b.extend([("shadow_maps", ctx.bind(h)), ("shadow_views", s.shadow_views.as_entire_binding())]);
        }
        if let Some([m, a]) = ltc {
            b.extend([("ltc_matrix", ctx.bind(m)), ("ltc_amplitude", ctx.bind(a))]);
        }
        ctx.fullscreen(&key, &[color], &b);
    });
    color
}
