//! Tile classification (Substrate's): a compute pass gives each 8×8 tile
//! the dearest class among its pixels, from the depth (no geometry: empty)
//! and the material buffer's headers (simple, single, complex), and makes
//! each class's tile list and indirect dispatch arguments, so the lighting
//! (`lighting.rs`) runs one specialised pipeline per class over that
//! class's tiles only. It counts pixels and tiles per class and the
//! material bytes each tile's pixels wrote, for the frame's statistics
//! (`Statistics`). Classes no material of the scene can make are known
//! before the frame (`Classes::of`): their lighting passes are culled.
//! Shared terms: `shaders/lib/tiles.wgsl`.

use serde::Serialize;

use super::gbuffer::GBuffer;
use crate::gpu::pipeline::{COMPUTE, Group, PipelineSpec, Stages, depth_texture, sizes, storage, storage_rw, uniform};
use crate::material::tree::{Definition, Field, NodeKind};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Element, Handle, Meaning, PipelineKey, TensorLayout};
use crate::scene::Scene;

pub static CLASSIFY: PipelineSpec = PipelineSpec {
    name: "passes.classify",
    shader: "passes/classify.wgsl",
    stages: Stages::Compute { entry: "classify" },
    groups: &[Group::always(
        0,
        &[
            depth_texture("depth", 0),
            storage("material_words", 1, COMPUTE),
            storage_rw("tile_classes", 2),
            storage_rw("tile_bytes", 3),
            storage_rw("tile_lists", 4),
            storage_rw("dispatch", 5),
            storage_rw("stats", 6),
            uniform("promotion", 7, COMPUTE, sizes::VEC4),
        ],
    )],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&CLASSIFY];

/// Pixels per side of a tile (`loupe::tiles::TILE_SIZE`).
pub const TILE: u32 = 8;
/// The classes, cheapest first: a tile's index in the lists and counters.
pub const CLASSES: [&str; 4] = ["empty", "simple", "single", "complex"];
/// The classes' indices.
pub const EMPTY: usize = 0;
pub const SIMPLE: usize = 1;
pub const SINGLE: usize = 2;
pub const COMPLEX: usize = 3;
/// `classify/stats`: pixels per class, then tiles per class.
pub const STATS: &str = "classify/stats";
/// `classify/bytes`: the material bytes each tile's pixels wrote.
pub const BYTES: &str = "classify/bytes";

/// Which classes the scene's materials can make, known from their
/// definitions: a material of two or more closures makes complex pixels; a
/// one-closure material simple ones, and single ones too unless it is the
/// scene file's shorthand (its closures are simple by construction:
/// `material::pack`). Empty tiles are always possible. Should a pixel
/// still be of a class called impossible, the classify pass lights its
/// tile with the next dearer live class (`promotion`): no tile goes unlit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Classes {
    pub simple: bool,
    pub single: bool,
    pub complex: bool,
}

impl Default for Classes {
    /// Nothing known: every class possible.
    fn default() -> Self {
        Classes { simple: true, single: true, complex: true }
    }
}

impl Classes {
    pub fn of(definitions: &[Definition]) -> Classes {
        let mut c = Classes { simple: false, single: false, complex: false };
        for d in definitions {
            if crate::material::back::closures(d, d.root) > 1 {
                c.complex = true;
            } else {
                c.simple = true;
                c.single |= !(d.name == SHORTHAND && !d.energy_compensation && only_simple_fields(d));
            }
        }
        c
    }

    /// Whether class `i` (of `CLASSES`) can occur.
    pub fn possible(self, i: usize) -> bool {
        match i {
            SIMPLE => self.simple,
            SINGLE => self.single,
            COMPLEX => self.complex,
            _ => true,
        }
    }

    /// Per class, the class whose pass lights its tiles: itself when
    /// possible, else the next dearer possible one, else the dearest.
    pub fn promotion(self) -> [u32; 4] {
        let dearest = (0..4).rev().find(|&i| self.possible(i)).unwrap_or(EMPTY);
        std::array::from_fn(|c| (c..4).find(|&i| self.possible(i)).unwrap_or(dearest) as u32)
    }
}

/// The shorthand's definition name (`material::shorthand`).
const SHORTHAND: &str = "shorthand";

/// Whether every slab of `d` sets only what the simple class stores.
fn only_simple_fields(d: &Definition) -> bool {
    let simple = [Field::BaseColor, Field::BaseMetalness, Field::SpecularRoughness];
    d.nodes.iter().all(|n| match &n.kind {
        NodeKind::Slab(s) => s.fields.iter().all(|(f, _)| simple.contains(f)),
        _ => true,
    })
}

/// What the classify pass hands the lighting.
#[derive(Debug, Clone, Copy)]
pub struct Tiles {
    /// Per class, the tiles in it (`[class][tile]`, row-major tile ids).
    pub lists: Handle,
    /// Per class, its indirect dispatch arguments (`[class][x, y, z]`).
    pub dispatch: Handle,
    /// Pixels per class, then tiles per class.
    pub stats: Handle,
    /// Per tile, the class whose pass lights it.
    pub classes: Handle,
}

/// Tiles across and down a `width` × `height` target.
pub fn tiles(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// Classifies the tiles of the G-buffer. With `quality.tile_classification`
/// off, every tile goes to the complex list (the pixels keep their own
/// classes in the counts).
pub fn classify(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle, possible: Classes) -> Tiles {
    let (across, down) = tiles(scene.width, scene.height);
    let count = across * down;
    let mut p = g.pass("classify", PassKind::Compute);
    let key = p.pipeline(PipelineKey::new(&CLASSIFY, &[]));
    p.sample(depth);
    let words = p.access(gb.words, Access::StorageRead);
    let per_tile = TensorLayout::new(&[("y", down), ("x", across)], Element::U32);
    let classes = p.create("classes", Meaning::Id, per_tile.clone(), Access::StorageWrite);
    let bytes = p.create("bytes", Meaning::Data, per_tile, Access::StorageWrite);
    let lists = p.create("lists", Meaning::Id, TensorLayout::new(&[("class", 4), ("tile", count)], Element::U32), Access::StorageWrite);
    let dispatch = p.create("dispatch", Meaning::Data, TensorLayout::new(&[("class", 4), ("xyz", 3)], Element::U32), Access::StorageWrite);
    let stats = p.create("stats", Meaning::Data, TensorLayout::new(&[("counter", 8)], Element::U32), Access::StorageWrite);
    // The counters start at zero every frame.
    p.access(dispatch, Access::CopyDst);
    p.access(stats, Access::CopyDst);
    let promotion = if scene.quality.tile_classification { possible.promotion() } else { [COMPLEX as u32; 4] };
    p.execute(move |ctx| {
        let promotion = ctx.uniform(bytemuck::cast_slice(&promotion));
        ctx.encoder.clear_buffer(ctx.buffer(dispatch), 0, None);
        ctx.encoder.clear_buffer(ctx.buffer(stats), 0, None);
        let b = [
            ("depth", ctx.bind(depth)),
            ("material_words", ctx.bind(words)),
            ("tile_classes", ctx.bind(classes)),
            ("tile_bytes", ctx.bind(bytes)),
            ("tile_lists", ctx.bind(lists)),
            ("dispatch", ctx.bind(dispatch)),
            ("stats", ctx.bind(stats)),
            ("promotion", promotion.as_entire_binding()),
        ];
        ctx.dispatch(&key, &b, [across, down, 1]);
    });
    Tiles { lists, dispatch, stats, classes }
}

/// Per class (`CLASSES`), a count.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct PerClass {
    pub empty: u64,
    pub simple: u64,
    pub single: u64,
    pub complex: u64,
}

impl PerClass {
    fn of(v: &[f32]) -> PerClass {
        let n = |i: usize| v.get(i).map_or(0, |&x| x as u64);
        PerClass { empty: n(EMPTY), simple: n(SIMPLE), single: n(SINGLE), complex: n(COMPLEX) }
    }
}

/// A frame's tile classification, as `report.json` and the browser show it.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Statistics {
    pub pixels: PerClass,
    pub tiles: PerClass,
    /// Σ over the pixels with geometry of their words × 4.
    pub material_bytes_written: u64,
}

impl Statistics {
    /// From a frame's captured tensors; `None` when it classified nothing
    /// (tile classification off, a path-traced or empty scene).
    pub fn of_frame(tensors: &[crate::render::capture::CapturedTensor]) -> Option<Statistics> {
        let find = |key: &str| tensors.iter().find(|t| t.key() == key);
        Some(Statistics::from_tensors(&find(STATS)?.data, &find(BYTES)?.data))
    }

    /// From the captured `classify/stats` and `classify/bytes` tensors (the
    /// bytes summed here, per tile, so no counter can overflow).
    pub fn from_tensors(stats: &[f32], bytes: &[f32]) -> Statistics {
        Statistics {
            pixels: PerClass::of(&stats[..stats.len().min(4)]),
            tiles: PerClass::of(stats.get(4..).unwrap_or_default()),
            material_bytes_written: bytes.iter().map(|&b| b as u64).sum(),
        }
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod promotion_tests {
    use super::*;

    #[test]
    fn an_impossible_class_is_lit_by_the_next_dearer_possible_one() {
        let c = |simple, single, complex| Classes { simple, single, complex }.promotion();
        assert_eq!(c(true, true, true), [0, 1, 2, 3]);
        assert_eq!(c(true, false, true), [0, 1, 3, 3]);
        assert_eq!(c(true, false, false), [0, 1, 1, 1]);
        assert_eq!(c(false, true, false), [0, 2, 2, 2]);
    }
}
