//! Direct light from every light on the G-buffer, with shadows, rect
//! lights through LTC, and the media's transmittance toward each light; the
//! environment's light (its irradiance and split-sum specular, with the
//! GGX table of `render/dfg.rs`); the environment behind the geometry.
//!
//! A compute pass per tile class (`classify.rs`), each over its class's
//! tiles by an indirect dispatch, all writing the one `lighting/color`:
//! `lighting` (created there) lights the empty tiles with the environment
//! alone, `lighting_simple` against `loupe::material_simple` (one closure,
//! no optional field), `lighting_single` against `loupe::material_single`
//! (one closure, the one-closure materials' features) and
//! `lighting_complex` against the program's `loupe::material`. Each tile is in exactly one list, so each
//! pixel is written once. A class no material of the scene makes is
//! culled with its reason. With `quality.tile_classification` off, the
//! classify pass lists every tile as complex and `lighting` alone lights
//! them all through the complex pipeline.

use super::classify::{self, Classes, Tiles};
use super::gbuffer::{GBuffer, WORDS_BINDING};
use super::{LIGHTS, MEDIA, SHADOW_GROUP, SHADOWS, VIEW};
use crate::gpu::pipeline::{COMPUTE, Group, HDR, PipelineSpec, Stages, depth_texture, sizes, storage, storage_texture, texture, uniform};
use crate::render::context::PassContext;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Handle, Meaning, PipelineKey, TextureDesc};
use crate::scene::Scene;
use crate::scene::settings::RectLights;

/// Rect lights, shaded with the LTC tables.
pub const LIGHT_RECT: &str = "LIGHT_RECT";
/// Rect lights integrated by sampling their area (`quality.rect_lights`).
pub const RECT_SAMPLED: &str = "RECT_SAMPLED";
/// Shadows cast by the participating media onto surfaces.
pub const MEDIA_SHADOWS: &str = "MEDIA_SHADOWS";
/// Compiled against `loupe::material_simple`: the simple tiles'.
pub const SIMPLE_CLASS: &str = "SIMPLE_CLASS";
/// Compiled against `loupe::material_single`: the single tiles'.
pub const SINGLE_CLASS: &str = "SINGLE_CLASS";

/// Where the lit colour is stored.
const LIT: u32 = 15;

pub static DEFERRED: PipelineSpec = PipelineSpec {
    name: "lighting.deferred",
    shader: "passes/lighting.wgsl",
    stages: Stages::Compute { entry: "light" },
    groups: &[
        // Depth and the material buffer: the G-buffer's other targets are
        // for the inspector and the debug views.
        Group::always(
            0,
            &[
                VIEW,
                LIGHTS,
                depth_texture("depth", 5),
                texture("dfg", 6),
                storage("material_words", WORDS_BINDING, COMPUTE),
                storage_texture("lit", LIT, HDR),
            ],
        ),
        SHADOW_GROUP,
        Group::when(2, LIGHT_RECT, &[texture("ltc_matrix", 0), texture("ltc_amplitude", 1)]),
        Group::when(3, MEDIA_SHADOWS, MEDIA),
        Group::always(4, &[storage("tile_lists", 0, COMPUTE), storage("tile_stats", 1, COMPUTE), uniform("tile_class", 2, COMPUTE, sizes::VEC4)]),
    ],
    defs: &[SHADOWS, LIGHT_RECT, RECT_SAMPLED, MEDIA_SHADOWS, SIMPLE_CLASS, SINGLE_CLASS],
};
/// The empty tiles: the environment only.
pub static ENVIRONMENT: PipelineSpec = PipelineSpec {
    name: "lighting.environment",
    shader: "passes/lighting_environment.wgsl",
    stages: Stages::Compute { entry: "environment" },
    groups: &[Group::always(
        0,
        &[VIEW, storage_texture("lit", LIT, HDR), storage("tile_lists", 16, COMPUTE), storage("tile_stats", 17, COMPUTE)],
    )],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&DEFERRED, &ENVIRONMENT];

/// The lit colour's inputs, bound alike by every lighting pass.
#[derive(Clone, Copy)]
struct Inputs {
    depth: Handle,
    words: Handle,
    shadows: Option<Handle>,
    ltc: Option<[Handle; 2]>,
    color: Handle,
}

impl Inputs {
    fn bind<'a>(&self, ctx: &PassContext<'a>) -> Vec<(&'static str, wgpu::BindingResource<'a>)> {
        let s = ctx.scene;
        let mut b = vec![
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("media", s.media.as_entire_binding()),
            ("dfg", wgpu::BindingResource::TextureView(&s.dfg)),
            ("depth", ctx.bind(self.depth)),
            ("material_words", ctx.bind(self.words)),
            ("lit", ctx.bind(self.color)),
        ];
        if let Some(h) = self.shadows {
            b.extend([("shadow_maps", ctx.bind(h)), ("shadow_views", s.shadow_views.as_entire_binding())]);
        }
        if let Some([m, a]) = self.ltc {
            b.extend([("ltc_matrix", ctx.bind(m)), ("ltc_amplitude", ctx.bind(a))]);
        }
        b
    }
}

/// The lighting passes' names, by class (`classify::CLASSES`).
pub const PASSES: [&str; 4] = ["lighting", "lighting_simple", "lighting_single", "lighting_complex"];

/// Why a class's pass is culled when no material of the scene makes it.
const CANNOT: [&str; 4] = [
    "",
    "no material of the scene has a single closure",
    "the scene's only one-closure material is the shorthand, whose pixels are all simple",
    "no material of the scene has two or more closures",
];

#[allow(clippy::too_many_arguments)]
pub fn lighting(
    g: &mut GraphBuilder,
    scene: &Scene,
    gb: &GBuffer,
    depth: Handle,
    tiles: Tiles,
    classes: Classes,
    shadows: Option<Handle>,
    ltc: Option<[Handle; 2]>,
) -> Handle {
    let media = !scene.media.is_empty();
    let sampled = scene.has_rect_lights() && scene.quality.rect_lights == RectLights::Sampled;
    let defs = [(SHADOWS, shadows.is_some()), (LIGHT_RECT, ltc.is_some()), (RECT_SAMPLED, sampled), (MEDIA_SHADOWS, media)];
    // The pipeline specialised for `class`'s tiles.
    let key = |class: usize| {
        let mut all = defs.to_vec();
        all.extend([(SIMPLE_CLASS, class == classify::SIMPLE), (SINGLE_CLASS, class == classify::SINGLE)]);
        PipelineKey::new(&DEFERRED, &all)
    };
    let reads = |p: &mut crate::render::graph::PassBuilder<'_>| {
        p.sample(depth);
        p.access(gb.words, Access::StorageRead);
        if let Some(h) = shadows {
            p.sample(h);
        }
        for h in ltc.into_iter().flatten() {
            p.sample(h);
        }
    };
    let desc = TextureDesc::d2(HDR, scene.width, scene.height);
    // The passes over one class's tiles against `key`; the first creates
    // the colour.
    let class_pass = |g: &mut GraphBuilder, name: &str, class: usize, key: PipelineKey, color: Option<Handle>| {
        let mut p = g.pass(name, PassKind::Compute);
        let key = p.pipeline(key);
        reads(&mut p);
        p.access(tiles.lists, Access::StorageRead);
        p.access(tiles.stats, Access::StorageRead);
        p.access(tiles.dispatch, Access::Indirect);
        let color = match color {
            Some(h) => p.access(h, Access::StorageWrite),
            None => p.create("color", Meaning::Color, desc.clone(), Access::StorageWrite),
        };
        let inputs = Inputs { depth, words: gb.words, shadows, ltc, color };
        p.execute(move |ctx| {
            let which = ctx.uniform(bytemuck::cast_slice(&[class as u32, 0, 0, 0]));
            let mut b = inputs.bind(ctx);
            b.extend([
                ("tile_lists", ctx.bind(tiles.lists)),
                ("tile_stats", ctx.bind(tiles.stats)),
                ("tile_class", which.as_entire_binding()),
            ]);
            ctx.dispatch_indirect(&key, &b, tiles.dispatch, class as u64 * 12);
        });
        color
    };
    if !scene.quality.tile_classification {
        for pass in &PASSES[1..] {
            g.cull(pass, "quality.tile_classification is off: `lighting` lights every tile through the complex pipeline");
        }
        return class_pass(g, PASSES[0], classify::COMPLEX, key(classify::COMPLEX), None);
    }
    // The empty tiles: the environment, and the colour every class writes.
    let mut p = g.pass(PASSES[0], PassKind::Compute);
    let env = p.pipeline(PipelineKey::new(&ENVIRONMENT, &[]));
    p.access(tiles.lists, Access::StorageRead);
    p.access(tiles.stats, Access::StorageRead);
    p.access(tiles.dispatch, Access::Indirect);
    let color = p.create("color", Meaning::Color, desc.clone(), Access::StorageWrite);
    p.execute(move |ctx| {
        let b = [
            ("view", ctx.scene.view.as_entire_binding()),
            ("lit", ctx.bind(color)),
            ("tile_lists", ctx.bind(tiles.lists)),
            ("tile_stats", ctx.bind(tiles.stats)),
        ];
        ctx.dispatch_indirect(&env, &b, tiles.dispatch, 0);
    });
    for class in [classify::SIMPLE, classify::SINGLE, classify::COMPLEX] {
        if classes.possible(class) {
            class_pass(g, PASSES[class], class, key(class), Some(color));
        } else {
            g.cull(PASSES[class], CANNOT[class]);
        }
    }
    color
}
