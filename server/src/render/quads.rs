//! Quad statistics of a frame, renderer side: while a frame is asked for
//! them, every draw of every raster pass is recorded with the clip-space
//! positions its own vertex stage produced (read back from the GPU) and
//! the depth its render pass started from; once the frame has landed they
//! are replayed, in submission order, through the exact CPU model in
//! [`crate::quads`], a render target only when its inputs differ from the
//! last frame's ([`ReplayCache`]). The same records answer for one pixel:
//! every fragment each draw made there ([`trace`]).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use serde::Serialize;

use super::readback::{Readback, Rows};
use super::resource::PipelineKey;
use super::vertex_capture::{PendingPositions, VertexCapture};
use crate::quads::{self, Compare, DepthState, Draw, DrawStats, Face, FrontFace, QuadMaps, Scissor};

/// What a frame records for quad statistics while it is recorded: the
/// vertex captures of its pipelines, and the render passes drawn so far.
pub struct QuadRecorder<'a> {
    pub captures: &'a BTreeMap<PipelineKey, VertexCapture>,
    pub targets: Vec<PendingTarget>,
    /// Record only render passes whose targets are this size (`None`:
    /// all): a pixel's history alone needs no shadow map.
    pub only: Option<(u32, u32)>,
}

impl QuadRecorder<'_> {
    /// Whether a render pass into targets of `size` is recorded.
    pub fn wants(&self, size: wgpu::Extent3d) -> bool {
        self.only.is_none_or(|only| only == (size.width, size.height))
    }
}

/// A render pass recorded, its readbacks on their way.
pub struct PendingTarget {
    pub pass: String,
    pub width: u32,
    pub height: u32,
    pub depth: Option<PendingDepth>,
    pub draws: Vec<PendingDraw>,
    pub fullscreen: Option<bool>,
}

pub enum PendingDepth {
    Clear(f32),
    /// The depth layer copied out before the pass.
    Loaded {
        readback: Readback,
        rows: Rows,
    },
}

pub struct PendingDraw {
    pub name: String,
    pub positions: PendingPositions,
    pub depth: Option<DepthState>,
    pub faces: Faces,
}

/// The face culling of a draw's pipeline, as the model takes it: wgpu's
/// `PrimitiveState::cull_mode` and `front_face`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Faces {
    pub cull: Option<Face>,
    pub front_face: FrontFace,
}

impl Faces {
    /// The culling of a pipeline created with `primitive`.
    pub fn of(primitive: &wgpu::PrimitiveState) -> Faces {
        let cull = primitive.cull_mode.map(|f| match f {
            wgpu::Face::Front => Face::Front,
            wgpu::Face::Back => Face::Back,
        });
        let front_face = match primitive.front_face {
            wgpu::FrontFace::Ccw => FrontFace::Ccw,
            wgpu::FrontFace::Cw => FrontFace::Cw,
        };
        Faces { cull, front_face }
    }

    /// The cull mode as reports name it: `none`, `back` or `front`.
    pub fn cull_mode(self) -> &'static str {
        match self.cull {
            None => "none",
            Some(Face::Back) => "back",
            Some(Face::Front) => "front",
        }
    }
}

impl PendingTarget {
    /// Starts the readbacks: after the frame is submitted.
    pub fn map(&self) {
        if let Some(PendingDepth::Loaded { readback, .. }) = &self.depth {
            readback.map();
        }
        for d in &self.draws {
            d.positions.map();
        }
    }

    pub fn landed(&self) -> bool {
        let depth = match &self.depth {
            Some(PendingDepth::Loaded { readback, .. }) => readback.landed(),
            _ => true,
        };
        depth && self.draws.iter().all(|d| d.positions.ready())
    }

    /// The recorded pass with its data read; `None`, with a warning, when a
    /// readback failed.
    pub fn read(self) -> Option<RecordedTarget> {
        let depth = match self.depth {
            None => None,
            Some(PendingDepth::Clear(v)) => Some(InitialDepth::Clear(v)),
            Some(PendingDepth::Loaded { readback, rows }) => {
                let depths = readback.read(|bytes| {
                    rows.of(bytes).flat_map(|r| r.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))).collect()
                });
                Some(InitialDepth::Loaded(depths.or_else(|| warn_none(&self.pass, "its depth"))?))
            }
        };
        let mut draws = Vec::new();
        for d in self.draws {
            let positions = d.positions.read().map_err(|e| log::warn!("quad statistics of `{}`: {e}", self.pass)).ok()?;
            draws.push(RecordedDraw { name: d.name, positions, depth: d.depth, faces: d.faces });
        }
        Some(RecordedTarget { pass: self.pass, width: self.width, height: self.height, depth, draws, fullscreen: self.fullscreen })
    }
}

fn warn_none<T>(pass: &str, what: &str) -> Option<T> {
    log::warn!("quad statistics of `{pass}`: the readback of {what} failed");
    None
}

/// One render pass recorded for replay (a shadow pass records one per
/// layer).
#[derive(Clone)]
pub struct RecordedTarget {
    pub pass: String,
    pub width: u32,
    pub height: u32,
    pub depth: Option<InitialDepth>,
    pub draws: Vec<RecordedDraw>,
    /// For a fullscreen pass: whether it drew two triangles, so the other
    /// mode can be modelled beside it.
    pub fullscreen: Option<bool>,
}

/// What a render pass's depth buffer held before its first draw.
#[derive(Clone)]
pub enum InitialDepth {
    /// Cleared to this value.
    Clear(f32),
    /// Loaded: the depths, rows top first, copied out before the pass.
    Loaded(Vec<f32>),
}

/// One draw: its name in the report, its positions (one per vertex
/// invocation, in index order: every three make a triangle), its depth
/// state and its pipeline's face culling.
#[derive(Clone)]
pub struct RecordedDraw {
    pub name: String,
    pub positions: Vec<[f32; 4]>,
    pub depth: Option<DepthState>,
    pub faces: Faces,
}

/// One draw's figures as reports and the API show them: the keys of what
/// ran the fragment shader at the top, and, for a pipeline that tests
/// depth, everything rasterized before the test.
#[derive(Debug, Clone, Serialize)]
pub struct DrawReport {
    pub name: String,
    /// The face the draw's pipeline culls (`none`, `back` or `front`); for
    /// a total, the mode its draws share, `null` when they differ.
    pub cull_mode: Option<&'static str>,
    #[serde(flatten)]
    pub shaded: quads::QuadStats,
    /// Before the depth test; `null` when the pipeline tests no depth.
    pub rasterized: Option<quads::QuadStats>,
}

impl DrawReport {
    fn new(name: &str, cull_mode: Option<&'static str>, s: &DrawStats) -> Self {
        DrawReport { name: name.to_owned(), cull_mode, shaded: s.shaded_or_rasterized(), rasterized: s.shaded.map(|_| s.rasterized) }
    }

    /// The draws summed, named `total`.
    fn total(draws: &[DrawReport], s: &DrawStats) -> Self {
        let shared = draws.iter().map(|d| d.cull_mode).reduce(|a, b| if a == b { a } else { None }).flatten();
        DrawReport::new("total", shared, s)
    }
}

/// A fullscreen pass drawn the other way.
#[derive(Debug, Clone, Serialize)]
pub struct WhatIf {
    /// `one_triangle` or `two_triangles`: the mode modelled.
    pub mode: &'static str,
    #[serde(flatten)]
    pub quads: quads::QuadStats,
}

/// One raster pass's quad statistics.
#[derive(Debug, Clone, Serialize)]
pub struct PassQuads {
    pub pass: String,
    pub draws: Vec<DrawReport>,
    /// The draws summed.
    pub quads: DrawReport,
    /// Fullscreen passes: the other mode modelled; else `null`.
    pub what_if: Option<WhatIf>,
    /// The maps of each render target of the pass, in order (a shadow
    /// map's layers one under another); shared, as reports are cloned for
    /// every client and a target not replayed again keeps its maps.
    #[serde(skip)]
    pub maps: Vec<Arc<QuadMaps>>,
}

impl PassQuads {
    /// The maps stacked as one image: (width, height, quads launched per
    /// 2×2 block spread over its pixels, helper-lane count per pixel).
    pub fn stacked_maps(&self) -> Option<(u32, u32, Vec<f32>, Vec<f32>)> {
        let width = self.maps.first()?.size().0;
        let (mut height, mut quads, mut helpers) = (0, Vec::new(), Vec::new());
        for m in self.maps.iter().filter(|m| m.size().0 == width) {
            let (_, h, q, l) = per_pixel(m);
            quads.extend(q);
            helpers.extend(l);
            height += h;
        }
        Some((width, height, quads, helpers))
    }

    /// The first render target's maps alone (a shadow map's first layer),
    /// as [`Self::stacked_maps`] lays each out.
    pub fn first_maps(&self) -> Option<(u32, u32, Vec<f32>, Vec<f32>)> {
        Some(per_pixel(self.maps.first()?))
    }
}

/// One target's maps per pixel: (width, height, quads launched over the
/// pixel's 2×2 block, helper-lane count).
fn per_pixel(m: &QuadMaps) -> (u32, u32, Vec<f32>, Vec<f32>) {
    let (w, h) = m.size();
    let bw = m.blocks().0 as usize;
    let quads = (0..h as usize).flat_map(|y| (0..w as usize).map(move |x| m.quads()[(y / 2) * bw + x / 2] as f32)).collect();
    let helpers = m.helper_lanes().iter().map(|&n| n as f32).collect();
    (w, h, quads, helpers)
}

/// The model's replays kept from frame to frame, render target by render
/// target in frame order: each one's inputs, its `quads::Pass` (started
/// over, not allocated again) and its figures. A target recorded exactly as
/// the last frame recorded it (the same pass, size and initial depth, the
/// same draws with their positions bit for bit, depth state and culling)
/// is not replayed: its figures and maps are the last frame's. Cloning
/// shares it: the session keeps it, each frame replays through it on the
/// thread that converts the frame.
#[derive(Clone, Default)]
pub struct ReplayCache(Arc<Mutex<Replays>>);

#[derive(Default)]
struct Replays {
    targets: Vec<Option<Replayed>>,
    /// Targets replayed so far, not counting those reused.
    replayed: u64,
}

struct Replayed {
    inputs: RecordedTarget,
    pass: quads::Pass,
    draws: Vec<DrawStats>,
    maps: Arc<QuadMaps>,
    what_if: Option<WhatIf>,
}

impl ReplayCache {
    /// The quad statistics of a frame's recorded render passes: one entry
    /// per raster pass that drew, in frame order. A target the model
    /// refuses (a size over its limit, a non-finite depth) is left out
    /// with a warning.
    pub fn replay(&self, targets: &[RecordedTarget]) -> Vec<PassQuads> {
        self.lock().replay(targets)
    }

    /// How many render targets were replayed so far (those reused from the
    /// frame before not counted).
    pub fn replayed(&self) -> u64 {
        self.lock().replayed
    }

    /// Lets every kept target go: the next frame replays them all.
    pub fn clear(&self) {
        self.lock().targets = Vec::new();
    }

    fn lock(&self) -> MutexGuard<'_, Replays> {
        // A replay that panicked left its target empty (see `replay`).
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Replays {
    fn replay(&mut self, targets: &[RecordedTarget]) -> Vec<PassQuads> {
        self.targets.resize_with(targets.len(), || None);
        let mut out: Vec<PassQuads> = Vec::new();
        for (t, slot) in targets.iter().zip(&mut self.targets) {
            if !slot.as_ref().is_some_and(|r| r.inputs.same_as(t)) {
                // Taken before replaying: a replay that fails leaves no
                // figures of other inputs behind.
                let kept = slot.take().map(|r| r.pass);
                *slot = Replayed::new(t, kept).map_err(|e| log::warn!("quad statistics of `{}`: {e}", t.pass)).ok();
                self.replayed += 1;
            }
            if let Some(r) = slot {
                r.report(t, &mut out);
            }
        }
        out
    }
}

impl Replayed {
    /// Replays `t` into `kept` when it is the target's size, else into a
    /// new pass.
    fn new(t: &RecordedTarget, kept: Option<quads::Pass>) -> Result<Replayed, quads::QuadError> {
        let mut pass = match kept {
            Some(pass) if pass.size() == (t.width, t.height) => pass,
            _ => quads::Pass::new(t.width, t.height)?,
        };
        start(&mut pass, &t.depth)?;
        let draws = t.draws.iter().map(|d| pass.draw(&d.model())).collect::<Result<Vec<_>, _>>()?;
        let what_if = t.fullscreen.and_then(|two| fullscreen_what_if(t.width, t.height, !two).ok());
        Ok(Replayed { inputs: t.clone(), maps: Arc::new(pass.maps().clone()), pass, draws, what_if })
    }

    /// Adds the target's figures to `out`: a pass of its own, or the last
    /// one when it is another render target (layer) of that pass.
    fn report(&self, t: &RecordedTarget, out: &mut Vec<PassQuads>) {
        let total: DrawStats = self.draws.iter().copied().sum();
        let reports = self.draws.iter().zip(&t.draws).map(|(s, d)| DrawReport::new(&d.name, Some(d.faces.cull_mode()), s));
        match out.last_mut().filter(|p| p.pass == t.pass) {
            Some(p) => {
                p.draws.extend(reports);
                let sum = total + stats_of(&p.quads);
                p.quads = DrawReport::total(&p.draws, &sum);
                p.maps.push(self.maps.clone());
            }
            None => {
                let draws: Vec<DrawReport> = reports.collect();
                out.push(PassQuads {
                    pass: t.pass.clone(),
                    quads: DrawReport::total(&draws, &total),
                    draws,
                    what_if: self.what_if.clone(),
                    maps: vec![self.maps.clone()],
                });
            }
        }
    }
}

impl RecordedTarget {
    /// Whether the model replays `other` exactly as this.
    fn same_as(&self, other: &RecordedTarget) -> bool {
        let depth = match (&self.depth, &other.depth) {
            (None, None) => true,
            (Some(InitialDepth::Clear(a)), Some(InitialDepth::Clear(b))) => a.to_bits() == b.to_bits(),
            (Some(InitialDepth::Loaded(a)), Some(InitialDepth::Loaded(b))) => bytes(a) == bytes(b),
            _ => false,
        };
        let same_draw = |(a, b): (&RecordedDraw, &RecordedDraw)| {
            a.name == b.name && a.depth == b.depth && a.faces == b.faces && bytes(&a.positions) == bytes(&b.positions)
        };
        self.pass == other.pass
            && (self.width, self.height, self.fullscreen) == (other.width, other.height, other.fullscreen)
            && depth
            && self.draws.len() == other.draws.len()
            && self.draws.iter().zip(&other.draws).all(same_draw)
    }
}

/// Floats compared bit for bit: a NaN equals itself, -0 differs from 0.
fn bytes<T: bytemuck::Pod>(values: &[T]) -> &[u8] {
    bytemuck::cast_slice(values)
}

/// A report's figures back as the model's, for summing across targets.
fn stats_of(r: &DrawReport) -> DrawStats {
    match r.rasterized {
        Some(rasterized) => DrawStats { rasterized, shaded: Some(r.shaded) },
        None => DrawStats { rasterized: r.shaded, shaded: None },
    }
}

/// Starts `pass` over with the depth buffer a render pass started from.
fn start(pass: &mut quads::Pass, depth: &Option<InitialDepth>) -> Result<(), quads::QuadError> {
    match depth {
        Some(InitialDepth::Clear(v)) => pass.reset_cleared(*v),
        Some(InitialDepth::Loaded(d)) => pass.reset(Some(d)),
        None => pass.reset(None),
    }
}

/// The model's pass for a recorded target, its depth buffer as the render
/// pass started.
fn model_pass(t: &RecordedTarget) -> Result<quads::Pass, quads::QuadError> {
    let mut pass = quads::Pass::new(t.width, t.height)?;
    start(&mut pass, &t.depth)?;
    Ok(pass)
}

impl RecordedDraw {
    /// The draw as the model takes it (loupe sets no viewport or scissor).
    fn model(&self) -> Draw<'_> {
        Draw { positions: &self.positions, depth: self.depth, cull: self.faces.cull, front_face: self.faces.front_face, ..Draw::default() }
    }
}

/// One render target's fragments at a traced pixel.
#[derive(Debug, Clone, Serialize)]
pub struct PassTrace {
    pub pass: String,
    /// Which of the pass's render targets, in the order it drew them (a
    /// shadow map's layer); 0 for a pass with one.
    pub layer: usize,
    /// The draws with a fragment at the pixel, in order.
    pub draws: Vec<DrawTrace>,
}

/// One draw's fragments at a traced pixel, in primitive order.
#[derive(Debug, Clone, Serialize)]
pub struct DrawTrace {
    pub name: String,
    pub fragments: Vec<quads::Fragment>,
}

/// Every fragment the recorded draws made at `pixel`: one entry per render
/// target of `size` (others, such as shadow maps, are left out), in frame
/// order, even one no draw reached. A pixel outside `size` gives none, and
/// a target the model refuses is left out with a warning.
///
/// Each draw is replayed scissored to the pixel's 2×2 block: the depth at
/// the pixel and whether its quad runs depend on nothing outside it, so
/// the fragments are the whole replay's, for a fraction of its work.
pub fn trace(targets: &[RecordedTarget], pixel: [u32; 2], size: (u32, u32)) -> Vec<PassTrace> {
    let mut out = Vec::new();
    for (i, t) in targets.iter().enumerate() {
        if (t.width, t.height) != size {
            continue;
        }
        let layer = targets[..i].iter().rev().take_while(|earlier| earlier.pass == t.pass).count();
        match trace_target(t, pixel) {
            Ok(draws) => out.push(PassTrace { pass: t.pass.clone(), layer, draws }),
            Err(quads::QuadError::Pixel { .. }) => return Vec::new(),
            Err(e) => log::warn!("pixel history of `{}`: {e}", t.pass),
        }
    }
    out
}

fn trace_target(t: &RecordedTarget, [x, y]: [u32; 2]) -> Result<Vec<DrawTrace>, quads::QuadError> {
    let mut pass = model_pass(t)?;
    pass.probe(x, y)?;
    let (x0, y0) = (x & !1, y & !1);
    let block = Scissor { x: x0, y: y0, width: (t.width - x0).min(2), height: (t.height - y0).min(2) };
    for d in &t.draws {
        pass.draw(&Draw { scissor: Some(block), ..d.model() })?;
    }
    // Fragments come draw by draw.
    let draws = pass.fragments().chunk_by(|a, b| a.draw == b.draw);
    Ok(draws.map(|run| DrawTrace { name: t.draws[run[0].draw].name.clone(), fragments: run.to_vec() }).collect())
}

/// The clip-space corners `shaders/lib/fullscreen.wgsl` draws: one
/// triangle covering the viewport, or two sharing its diagonal.
pub fn fullscreen_positions(two_triangles: bool) -> Vec<[f32; 4]> {
    let corners: &[[f32; 2]] = if two_triangles {
        &[[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]]
    } else {
        &[[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0]]
    };
    corners.iter().map(|[x, y]| [*x, *y, 0.0, 1.0]).collect()
}

/// A fullscreen pass modelled in the other mode, from the corners that
/// mode's shader draws.
fn fullscreen_what_if(width: u32, height: u32, two_triangles: bool) -> Result<WhatIf, quads::QuadError> {
    let mut pass = quads::Pass::new(width, height)?;
    let positions = fullscreen_positions(two_triangles);
    let s = pass.draw(&Draw { positions: &positions, ..Draw::default() })?;
    Ok(WhatIf { mode: if two_triangles { "two_triangles" } else { "one_triangle" }, quads: s.shaded_or_rasterized() })
}

/// The depth state of a pipeline spec's depth mode, as `gpu::pipeline`
/// creates the pipeline.
pub fn depth_state(depth: crate::gpu::pipeline::Depth) -> DepthState {
    use crate::gpu::pipeline::{Depth, SHADOW_BIAS};
    match depth {
        Depth::Write => DepthState::new(Compare::Less, true),
        Depth::Biased => DepthState {
            bias: quads::DepthBias { constant: SHADOW_BIAS.constant, slope_scale: SHADOW_BIAS.slope_scale, clamp: SHADOW_BIAS.clamp },
            ..DepthState::new(Compare::Less, true)
        },
        Depth::Equal => DepthState::new(Compare::LessEqual, false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle wound clockwise on screen over a 4×4 target, drawn by
    /// a pipeline with `faces`.
    fn replayed(faces: Faces) -> DrawReport {
        let positions = vec![[-1.0, -1.0, 0.5, 1.0], [-1.0, 1.0, 0.5, 1.0], [1.0, -1.0, 0.5, 1.0]];
        let draw = RecordedDraw { name: "tri".into(), positions, depth: None, faces };
        let target = RecordedTarget { pass: "p".into(), width: 4, height: 4, depth: None, draws: vec![draw], fullscreen: None };
        ReplayCache::default().replay(&[target]).remove(0).draws.remove(0)
    }

    /// `n` random triangles over the target, at random depths, as clip
    /// positions (a small xorshift generator, seeded).
    fn random_draw(seed: u64, n: usize, depth: Option<DepthState>, cull: Option<Face>) -> RecordedDraw {
        let mut state = seed;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f32 / (1u64 << 53) as f32
        };
        let positions = (0..3 * n).map(|_| [next() * 2.4 - 1.2, next() * 2.4 - 1.2, next(), 1.0]).collect();
        RecordedDraw { name: format!("draw {seed}"), positions, depth, faces: Faces { cull, front_face: FrontFace::Ccw } }
    }

    fn target(pass: &str, (width, height): (u32, u32), depth: Option<InitialDepth>, draws: Vec<RecordedDraw>) -> RecordedTarget {
        RecordedTarget { pass: pass.into(), width, height, depth, draws, fullscreen: None }
    }

    /// The scissored replay of `trace` finds, at every pixel of an odd-sized
    /// target (blocks cut by its edges), what a whole replay probing that
    /// pixel finds.
    #[test]
    fn a_trace_finds_the_fragments_of_a_whole_replay() {
        let size = (13, 9);
        let less = Some(DepthState::new(Compare::Less, true));
        let equal = Some(depth_state(crate::gpu::pipeline::Depth::Equal));
        let loaded: Vec<f32> = (0..13 * 9).map(|i| 0.3 + (i % 7) as f32 * 0.1).collect();
        let targets = [
            target("shadows", (16, 16), Some(InitialDepth::Clear(1.0)), vec![random_draw(1, 40, less, None)]),
            target(
                "prepass",
                size,
                Some(InitialDepth::Clear(1.0)),
                vec![random_draw(2, 40, less, None), random_draw(3, 40, less, Some(Face::Back))],
            ),
            target(
                "gbuffer",
                size,
                Some(InitialDepth::Loaded(loaded)),
                vec![random_draw(2, 40, equal, None), random_draw(4, 40, less, None)],
            ),
            target("overlay", size, None, vec![random_draw(5, 10, None, None)]),
            target("empty", size, None, vec![]),
        ];
        let mut seen = [0; 4];
        for y in 0..size.1 {
            for x in 0..size.0 {
                let traced = trace(&targets, [x, y], size);
                let names: Vec<&str> = traced.iter().map(|p| p.pass.as_str()).collect();
                assert_eq!(names, ["prepass", "gbuffer", "overlay", "empty"], "the shadow map's size differs");
                for (p, t) in traced.iter().zip(&targets[1..]) {
                    let mut whole = model_pass(t).unwrap();
                    whole.probe(x, y).unwrap();
                    for d in &t.draws {
                        whole.draw(&d.model()).unwrap();
                    }
                    let flat: Vec<quads::Fragment> = p.draws.iter().flat_map(|d| d.fragments.clone()).collect();
                    assert_eq!(flat, whole.fragments(), "{} at ({x}, {y})", t.pass);
                    assert!(p.draws.iter().all(|d| !d.fragments.is_empty() && d.fragments.iter().all(|f| t.draws[f.draw].name == d.name)));
                    for f in &flat {
                        seen[f.verdict as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&n| n > 0), "every verdict occurs: {seen:?}");
        assert!(trace(&targets, [13, 0], size).is_empty(), "a pixel outside the target");
    }

    #[test]
    fn a_trace_numbers_the_layers_of_a_pass() {
        let less = Some(DepthState::new(Compare::Less, true));
        let layer = || target("shadows", (8, 8), Some(InitialDepth::Clear(1.0)), vec![random_draw(6, 20, less, None)]);
        let targets = [layer(), layer(), target("tonemap", (8, 8), None, vec![]), layer()];
        let traced: Vec<(String, usize)> = trace(&targets, [3, 4], (8, 8)).into_iter().map(|p| (p.pass, p.layer)).collect();
        let want = [("shadows", 0), ("shadows", 1), ("tonemap", 0), ("shadows", 0)].map(|(p, l)| (p.to_owned(), l));
        assert_eq!(traced, want);
    }

    /// Reports as they compare: figures and maps.
    fn figures(quads: &[PassQuads]) -> Vec<String> {
        quads.iter().map(|p| format!("{} {:?}", serde_json::to_value(p).unwrap(), p.stacked_maps())).collect()
    }

    /// An edit of a frame's target `.0`.
    type Edit = (usize, fn(&mut RecordedTarget));

    /// A target recorded as the frame before is not replayed, and any
    /// input of a target that changes makes it replay alone, giving what a
    /// fresh cache gives.
    #[test]
    fn the_replay_cache_replays_a_target_only_when_an_input_changed() {
        let less = Some(DepthState::new(Compare::Less, true));
        let loaded: Vec<f32> = (0..16 * 12).map(|i| 0.5 + (i % 5) as f32 * 0.1).collect();
        let frame = vec![
            target("shadows", (16, 16), Some(InitialDepth::Clear(1.0)), vec![random_draw(1, 30, less, None)]),
            target("shadows", (16, 16), Some(InitialDepth::Clear(1.0)), vec![random_draw(2, 30, less, None)]),
            target(
                "gbuffer",
                (16, 12),
                Some(InitialDepth::Loaded(loaded)),
                vec![random_draw(3, 30, less, None), random_draw(4, 30, None, None)],
            ),
        ];
        let cache = ReplayCache::default();
        let first = cache.replay(&frame);
        assert_eq!(cache.replayed(), 3);
        assert!(figures(&cache.replay(&frame)) == figures(&first));
        assert_eq!(cache.replayed(), 3, "nothing changed");

        let edits: [Edit; 6] = [
            (2, |t| t.draws[1].positions[7][2] = 0.01),
            (1, |t| t.draws[0].positions[0][0] = -0.0),
            (2, |t| {
                let Some(InitialDepth::Loaded(d)) = &mut t.depth else { unreachable!() };
                d[20] = 0.0;
            }),
            (0, |t| t.depth = Some(InitialDepth::Clear(0.5))),
            (2, |t| t.draws[0].faces.cull = Some(Face::Back)),
            (1, |t| t.draws[0].depth = Some(DepthState::new(Compare::Greater, true))),
        ];
        for (n, (at, edit)) in edits.into_iter().enumerate() {
            let mut edited = frame.clone();
            edit(&mut edited[at]);
            let replayed = cache.replayed();
            let got = cache.replay(&edited);
            assert_eq!(cache.replayed(), replayed + 1, "edit {n}: that target alone");
            assert!(figures(&got) == figures(&ReplayCache::default().replay(&edited)), "edit {n}: a fresh replay's figures");
            cache.replay(&frame);
        }
        // A frame with fewer targets, then the whole frame again.
        cache.replay(&frame[..1]);
        let replayed = cache.replayed();
        assert!(figures(&cache.replay(&frame)) == figures(&first));
        assert_eq!(cache.replayed(), replayed + 2);
    }

    #[test]
    fn a_draw_is_modelled_and_reported_with_its_pipelines_culling() {
        let loupes = replayed(Faces::of(&crate::gpu::pipeline::primitive()));
        assert_eq!((loupes.cull_mode, loupes.shaded.culled_triangles), (Some("none"), 0), "loupe's pipelines cull nothing");
        let back = replayed(Faces { cull: Some(Face::Back), front_face: FrontFace::Ccw });
        assert_eq!(
            (back.cull_mode, back.shaded.culled_triangles, back.shaded.quads),
            (Some("back"), 1, 0),
            "a clockwise triangle is a back face"
        );
    }
}
