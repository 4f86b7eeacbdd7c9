//! The NaN watch (`loupe serve` only): a compute pass counting the texels
//! of the HDR frame that hold a NaN or an Inf, into a two-element buffer
//! the daemon reads every frame. The final image cannot say: an 8-bit
//! unorm target stores NaN as 0.

use crate::gpu::pipeline::{Group, PipelineSpec, Stages, storage_rw, texture};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Element, Handle, PipelineKey, TensorLayout};
use crate::scene::Scene;

pub static COUNT: PipelineSpec = PipelineSpec {
    name: "debug.nan_watch",
    shader: "debug/nan_watch.wgsl",
    stages: Stages::Compute { entry: "count" },
    groups: &[Group::always(0, &[texture("hdr", 0), storage_rw("counts", 1)])],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&COUNT];

/// The pass's output: `[texels with a NaN, texels with an Inf]`.
pub const OUTPUT: &str = "nan_watch/counts";

/// Counts the non-finite texels of `hdr`; the counts are a frame output.
pub fn nan_watch(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Handle {
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("nan_watch", PassKind::Compute);
    let key = p.pipeline(PipelineKey::new(&COUNT, &[]));
    p.sample(hdr);
    let counts = p.create("counts", Meaning::Data, TensorLayout::new(&[("kind", 2)], Element::U32), Access::StorageWrite);
    p.access(counts, Access::CopyDst);
    p.execute(move |ctx| {
        ctx.encoder.clear_buffer(ctx.buffer(counts), 0, None);
        let b = [("hdr", ctx.bind(hdr)), ("counts", ctx.bind(counts))];
        ctx.dispatch(&key, &b, [w.div_ceil(16), h.div_ceil(16), 1]);
    });
    counts
}
