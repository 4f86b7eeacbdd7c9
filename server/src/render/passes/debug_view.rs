//! One G-buffer channel or the depth as the displayed image; or, from the
//! material buffer and the classify pass, each tile's class, each pixel's
//! closures or its material bytes (`post/debug_tiles.wgsl`).

use super::classify::Tiles;
use super::gbuffer::GBuffer;
use super::{TWO_TRIANGLES, fullscreen_key, vec4_bytes};
use crate::gpu::pipeline::{FRAG, Group, LDR, PipelineSpec, Stages, depth_texture, sizes, storage, texture, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, TextureDesc};
use crate::scene::{DebugView, Scene};

/// The source is the depth buffer, linearised for display.
pub const DEBUG_DEPTH: &str = "DEBUG_DEPTH";

pub static DEBUG_VIEW: PipelineSpec = PipelineSpec {
    name: "post.debug_view",
    shader: "post/debug_view.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[LDR] },
    groups: &[
        Group::always(0, &[uniform("debug", 0, FRAG, sizes::VEC4)]),
        Group::unless(1, DEBUG_DEPTH, &[texture("source", 0)]),
        Group::when(1, DEBUG_DEPTH, &[depth_texture("source", 0)]),
    ],
    defs: &[TWO_TRIANGLES, DEBUG_DEPTH],
};
/// The tile-class view: binds the classify pass's classes.
pub const TILE_CLASS_VIEW: &str = "TILE_CLASS_VIEW";

pub static DEBUG_TILES: PipelineSpec = PipelineSpec {
    name: "post.debug_tiles",
    shader: "post/debug_tiles.wgsl",
    stages: Stages::Fullscreen { fragment: "fs_main", targets: &[LDR] },
    groups: &[
        Group::always(0, &[uniform("debug", 0, FRAG, sizes::VEC4), depth_texture("depth", 1), storage("material_words", 2, FRAG)]),
        Group::when(1, TILE_CLASS_VIEW, &[storage("tile_classes", 0, FRAG)]),
    ],
    defs: &[TWO_TRIANGLES, TILE_CLASS_VIEW],
};
pub const SPECS: &[&PipelineSpec] = &[&DEBUG_VIEW, &DEBUG_TILES];

/// The material views: closures, bytes, tile classes (`None`).
fn material_view(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle, tiles: Tiles, mode: Option<u32>) -> Handle {
    let classes = mode.is_none().then_some(tiles.classes);
    let mut p = g.pass("debug_view", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&DEBUG_TILES, scene, &[(TILE_CLASS_VIEW, classes.is_some())]));
    p.sample(depth);
    let words = p.access(gb.words, Access::StorageRead);
    let classes = classes.map(|h| p.access(h, Access::StorageRead));
    let color = p.create("color", Meaning::Color, TextureDesc::d2(LDR, scene.width, scene.height), Access::ColorTarget);
    p.execute(move |ctx| {
        let debug = ctx.uniform(bytemuck::cast_slice(&[mode.unwrap_or(0), 0, 0, 0]));
        let mut b = vec![("debug", debug.as_entire_binding()), ("depth", ctx.bind(depth)), ("material_words", ctx.bind(words))];
        b.extend(classes.map(|h| ("tile_classes", ctx.bind(h))));
        ctx.fullscreen(&key, &[color], &b);
    });
    color
}

pub fn debug_view(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle, tiles: Tiles) -> Option<Handle> {
    let (source, mode) = match scene.post.debug_view {
        DebugView::TileClass => return Some(material_view(g, scene, gb, depth, tiles, None)),
        DebugView::Closures => return Some(material_view(g, scene, gb, depth, tiles, Some(0))),
        DebugView::Bytes => return Some(material_view(g, scene, gb, depth, tiles, Some(1))),
        DebugView::None => {
            g.cull("debug_view", "post.debug_view is none");
            return None;
        }
        DebugView::Normal => (gb.normal, 0u32),
        DebugView::Albedo => (gb.albedo, 1),
        DebugView::Roughness => (gb.material, 2),
        DebugView::Metallic => (gb.material, 3),
        DebugView::Uv => (gb.uv, 4),
        DebugView::Depth => (depth, 0),
    };
    let (near, far) = (scene.camera.near, scene.camera.far);
    let mut p = g.pass("debug_view", PassKind::Raster);
    let key = p.pipeline(fullscreen_key(&DEBUG_VIEW, scene, &[(DEBUG_DEPTH, scene.post.debug_view == DebugView::Depth)]));
    p.sample(source);
    let color = p.create("color", Meaning::Color, TextureDesc::d2(LDR, scene.width, scene.height), Access::ColorTarget);
    p.execute(move |ctx| {
        let mut u = vec4_bytes([0.0, near, far, 0.0]);
        u[0..4].copy_from_slice(&mode.to_le_bytes());
        let debug = ctx.uniform(&u);
        ctx.fullscreen(&key, &[color], &[("debug", debug.as_entire_binding()), ("source", ctx.bind(source))]);
    });
    Some(color)
}
