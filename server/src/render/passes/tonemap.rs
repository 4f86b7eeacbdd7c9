//! Tonemapping to the displayable final image.

use super::{TWO_TRIANGLES, fullscreen_key};
use crate::gpu::pipeline::{Group, LDR, PipelineSpec, Stages, texture};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::{Scene, Tonemap};

pub const TONEMAP_REINHARD: &str = "TONEMAP_REINHARD";

pub static TONEMAP: PipelineSpec = PipelineSpec {
    name: "post.tonemap",
    shader: "post/tonemap.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[LDR] },
    groups: &[Group::always(0, &[texture("hdr", 0)])],
    defs: &[TWO_TRIANGLES, TONEMAP_REINHARD],
};
pub const SPECS: &[&PipelineSpec] = &[&TONEMAP];

pub fn tonemap(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Handle {
    let mut p = g.pass("tonemap", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&TONEMAP, scene, &[(TONEMAP_REINHARD, scene.post.tonemap == Tonemap::Reinhard)]));
    p.sample(hdr);
    let color = p.create("color", Meaning::Color, TextureDesc::d2(LDR, scene.width, scene.height), Access::ColorTarget);
    p.execute(move |ctx| {
        let b = [("hdr", ctx.bind(hdr))];
        ctx.fullscreen(&key, &[color], &b);
    });
    color
}
