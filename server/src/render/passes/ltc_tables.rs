//! The LTC tables as textures the lighting pass reads; only for scenes
//! with a rect light. Copied in each frame from tables uploaded once, so
//! the inspector can show them like any other output.

use crate::gpu::pipeline::PipelineSpec;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::ltc;
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::Scene;
use crate::scene::settings::RectLights;

pub const SPECS: &[&PipelineSpec] = &[];

pub fn ltc_tables(g: &mut GraphBuilder, scene: &Scene) -> Option<[Handle; 2]> {
    if !scene.has_rect_lights() {
        g.cull("ltc_tables", "no rectangular area light");
        return None;
    }
    if scene.quality.rect_lights == RectLights::Sampled {
        g.cull("ltc_tables", "quality.rect_lights is sampled");
        return None;
    }
    let d = TextureDesc::d2(ltc::FORMAT, ltc::SIZE, ltc::SIZE);
    let mut p = g.pass("ltc_tables", PassKind::Copy);
    let out = [p.create("matrix", Meaning::Data, d.clone(), Access::CopyDst), p.create("amplitude", Meaning::Data, d, Access::CopyDst)];
    p.execute(move |ctx| {
        let Some(tables) = &ctx.scene.ltc else { return };
        for (t, h) in tables.iter().zip(out) {
            let target = ctx.texture(h);
            ctx.encoder.copy_texture_to_texture(t.as_image_copy(), target.as_image_copy(), t.size());
        }
    });
    Some(out)
}
