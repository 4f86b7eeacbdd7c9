//! Running a built graph on the GPU: per-pass GPU timestamps for raster,
//! compute and copy passes alike, and captures (textures and buffers)
//! copied out right after the pass that wrote them and read back
//! asynchronously.

use super::debug_print::{PendingPrints, Printed};
use super::pixel_history::{AtPass, HistoryRecorder, PendingHistory, PixelHistory};
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use super::capture::{CapturedImage, CapturedTensor, Layout};
use super::context::{MAX_STATISTICS, PassContext, Statistics};
use super::graph::{Graph, PassKind, Resource};
use super::pool::ResourcePool;
use super::quads::{PendingTarget, QuadRecorder, ReplayCache};
use super::readback::{Readback, Rows, copy_texture};
use super::resource::{Physical, PipelineKey, ResourceDesc, TensorLayout, TextureDesc};
use super::scene_gpu::SceneGpu;
use super::vertex_capture::VertexCapture;
use crate::gpu::pipeline::Pipeline;

/// Everything one frame's recording needs from its owner.
pub struct FrameInputs<'a> {
    pub device: &'a wgpu::Device,
    pub queue: &'a wgpu::Queue,
    pub features: wgpu::Features,
    pub scene: &'a SceneGpu,
    pub graph: &'a Graph,
    pub pipelines: &'a BTreeMap<PipelineKey, Pipeline>,
    /// `pass/output` names to copy out; `None` captures everything.
    pub capture: Option<&'a BTreeSet<String>>,
    /// Count each raster pass's fragment-shader invocations (pipeline
    /// statistics), where the adapter can.
    pub statistics: bool,
    /// Record every draw, capturing positions with these (one per raster
    /// pipeline), for quad statistics or a pixel's history; `None`: do not.
    pub vertex_captures: Option<&'a BTreeMap<PipelineKey, VertexCapture>>,
    /// Where the recorded draws are replayed for quad statistics, kept
    /// across frames; `None`: no statistics.
    pub quad_replays: Option<ReplayCache>,
    /// The selected pixel and the frame's size: its history is recorded.
    pub pixel: Option<([u32; 2], (u32, u32))>,
    pub frame: u64,
    /// Samples per pixel the path tracer holds after this frame (frames
    /// since its history was last forgotten).
    pub samples: u32,
    /// Seconds since the previous frame.
    pub dt: f32,
    /// Submit each pass on its own and wait for it, timing it by the wall
    /// clock: for adapters whose timestamps do not bracket compute work
    /// (llvmpipe's), at the cost of the overlap between passes.
    pub serial: bool,
    /// The print buffer and the pipelines instrumented to write it.
    pub prints: Option<super::debug_print::PrintBinding<'a>>,
}

/// A submitted frame whose captures and timings are still on their way back.
pub struct PendingFrame {
    pub frame: u64,
    pub submitted: Instant,
    pub cpu_record_ms: f64,
    captures: Vec<PendingCapture>,
    /// The timestamps and the timestamp period.
    timestamps: Option<(Readback, f32)>,
    /// The pipeline statistics and, per pass, the queries it used.
    statistics: Option<(Readback, Vec<Vec<u32>>)>,
    /// Per pass, the wall-clock milliseconds of its own submission (serial
    /// frames only).
    serial: Option<Vec<(String, f64)>>,
    /// Render passes recorded for quad statistics, and where to replay them.
    quad_targets: Vec<PendingTarget>,
    quad_replays: Option<ReplayCache>,
    pub skipped: Vec<String>,
    passes: Vec<String>,
    /// Per pass: the capture names it read and wrote, for the NaN report.
    io: Vec<(Vec<String>, Vec<String>)>,
    /// The selected pixel's prints, when one is selected.
    prints: Option<PendingPrints>,
    history: Option<PendingHistory>,
}

/// What a capture copied.
enum Copied {
    Texture { desc: TextureDesc, rows: Rows },
    Buffer(TensorLayout),
}

struct PendingCapture {
    pass: String,
    output: String,
    what: Copied,
    readback: Readback,
}

/// A frame's results once every readback has landed.
pub struct FrameResult {
    pub frame: u64,
    /// Per pass, in execution order: (name, milliseconds). Empty without
    /// timestamp queries: one clock around the whole frame cannot say how
    /// it splits between passes.
    pub timings: Vec<(String, f64)>,
    /// The whole frame: the passes' sum (`gpu`, `serial`), or the wall
    /// clock from recording to the readbacks landing (`cpu`).
    pub total_ms: f64,
    /// `gpu` when from timestamp queries, `serial` when each pass was
    /// submitted and waited for alone, `cpu` otherwise.
    pub timing: &'static str,
    pub captures: Vec<CapturedImage>,
    pub tensors: Vec<CapturedTensor>,
    /// Passes that drew nothing because their pipeline never built.
    pub skipped: Vec<String>,
    /// Per raster pass, the fragment-shader invocations the adapter counted
    /// (pipeline statistics); empty unless asked for and supported.
    pub fragment_invocations: Vec<(String, u64)>,
    /// Per raster pass that drew, its quad statistics; empty unless asked.
    pub quads: Vec<super::quads::PassQuads>,
    /// What the selected pixel printed; `None` without a selection (or
    /// when its readback failed).
    pub prints: Option<Printed>,
    /// The selected pixel's history; `None` without a selection.
    pub history: Option<PixelHistory>,
    /// Where a NaN or Inf first appeared, when any output holds one.
    pub nan: Option<NanOrigin>,
}

/// The first pass, in graph order, whose output holds a NaN or Inf that
/// none of its inputs held: where the bad value was made, not where it
/// merely travelled to.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NanOrigin {
    pub pass: String,
    pub output: String,
    /// The first bad pixel in row order (for a buffer: its flat index, 0).
    pub pixel: [u32; 2],
    pub value: [f32; 4],
    pub nan: u64,
    pub inf: u64,
    /// False when some input was not captured, so an inherited value
    /// cannot be ruled out.
    pub inputs_checked: bool,
}

/// Where a capture holds its first non-finite value, if it does.
fn first_bad(name: &str, images: &[CapturedImage], tensors: &[CapturedTensor]) -> Option<Option<NanOrigin>> {
    if let Some(c) = images.iter().find(|c| c.key() == name) {
        return Some(c.stats.has_non_finite().then(|| {
            let pixel = c.stats.first_nan.expect("non-finite values have a first pixel");
            NanOrigin {
                pass: c.pass.clone(),
                output: c.output.clone(),
                pixel,
                value: c.pixel(pixel[0], pixel[1]),
                nan: c.stats.nan,
                inf: c.stats.inf,
                inputs_checked: true,
            }
        }));
    }
    let t = tensors.iter().find(|t| t.key() == name)?;
    Some(t.stats.has_non_finite().then(|| {
        let i = t.stats.first_nan.expect("non-finite values have a first index");
        let v = t.data[i as usize];
        NanOrigin {
            pass: t.pass.clone(),
            output: t.output.clone(),
            pixel: [i as u32, 0],
            value: [v, 0.0, 0.0, 0.0],
            nan: t.stats.nan,
            inf: t.stats.inf,
            inputs_checked: true,
        }
    }))
}

fn nan_origin(
    passes: &[String],
    io: &[(Vec<String>, Vec<String>)],
    images: &[CapturedImage],
    tensors: &[CapturedTensor],
) -> Option<NanOrigin> {
    for (_, (reads, writes)) in passes.iter().zip(io) {
        let inputs: Vec<Option<Option<NanOrigin>>> = reads.iter().map(|r| first_bad(r, images, tensors)).collect();
        if inputs.iter().flatten().any(Option::is_some) {
            continue; // it inherited bad values; an earlier pass made them
        }
        if let Some(origin) = writes.iter().find_map(|w| first_bad(w, images, tensors).flatten()) {
            return Some(NanOrigin { inputs_checked: inputs.iter().all(Option::is_some), ..origin });
        }
    }
    None
}

/// Records and submits one frame.
pub fn submit(f: FrameInputs<'_>, pool: &mut ResourcePool) -> PendingFrame {
    let start = Instant::now();
    let graph = f.graph;
    pool.prepare(f.device, graph);
    let used = graph.used();
    let physical: Vec<Option<&Physical>> =
        (0..graph.resources.len()).map(|i| used.iter().find(|h| h.0 == i).map(|h| pool.get(graph, *h))).collect();

    let gpu_timing = f.features.contains(wgpu::Features::TIMESTAMP_QUERY) && !graph.passes.is_empty();
    let query_set = gpu_timing.then(|| {
        f.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timings"),
            ty: wgpu::QueryType::Timestamp,
            count: graph.passes.len() as u32 * 2,
        })
    });

    let statistics_set = (f.statistics && f.features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY)).then(|| {
        f.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("fragment invocations"),
            ty: wgpu::QueryType::PipelineStatistics(wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS),
            count: MAX_STATISTICS,
        })
    });
    let (mut next_query, mut queries) = (0, Vec::new());
    let mut quad_targets = Vec::new();

    let mut encoder = f.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
    if let Some(p) = f.prints {
        p.buffer.clear(&mut encoder);
    }
    let mut history = f.pixel.map(|(pixel, size)| HistoryRecorder::new(f.device, graph, pixel, size));
    let mut captures = Vec::new();
    let mut skipped = Vec::new();
    let mut serial = f.serial.then(Vec::new);
    for (i, pass) in graph.passes.iter().enumerate() {
        let started = Instant::now();
        let at = AtPass { device: f.device, graph, physical: &physical, pass: i };
        if let Some(h) = history.as_mut() {
            h.before(&mut encoder, &at);
        }
        let mut ctx = PassContext {
            device: f.device,
            encoder: &mut encoder,
            pass: &pass.name,
            scene: f.scene,
            frame: f.frame,
            samples: f.samples,
            dt: f.dt,
            resources: physical.clone(),
            pipelines: f.pipelines,
            timestamps: query_set.as_ref().map(|qs| (qs, i as u32 * 2)),
            recorded: 0,
            skipped: false,
            statistics: statistics_set.as_ref().map(|set| Statistics { set, next: next_query, used: Vec::new() }),
            quads: f.vertex_captures.map(|captures| QuadRecorder {
                captures,
                targets: Vec::new(),
                // Without statistics, the draws serve the pixel's history.
                only: f.quad_replays.is_none().then(|| f.pixel.map(|(_, size)| size)).flatten(),
            }),
            prints: f.prints,
        };
        // A copy pass records no render or compute pass of its own: empty
        // compute passes around it carry its stamps.
        if pass.kind == PassKind::Copy {
            ctx.stamp_only();
        }
        (pass.execute)(&mut ctx);
        // After a copy, the end stamp; after a pass that recorded nothing
        // (its pipeline never built), both stamps on one empty pass: zero.
        if pass.kind == PassKind::Copy || ctx.recorded == 0 {
            ctx.stamp_only();
        }
        if ctx.skipped {
            skipped.push(pass.name.clone());
        }
        if let Some(st) = ctx.statistics.take() {
            next_query = st.next;
            queries.push(st.used);
        }
        if let Some(rec) = ctx.quads.take() {
            quad_targets.extend(rec.targets);
        }
        if let Some(h) = history.as_mut() {
            h.after(&mut encoder, &at);
        }
        for h in pass.writes() {
            let r = graph.resource(h);
            if f.capture.is_some_and(|c| !c.contains(&r.name)) {
                continue;
            }
            // A resource several passes write (the lighting's classes) is
            // captured once, complete, after the last, under its own name.
            if graph.passes[i + 1..].iter().any(|later| later.writes().any(|w| w == h)) {
                continue;
            }
            let owner = r.name.rsplit_once('/').map_or(pass.name.as_str(), |(p, _)| p);
            if let Some(c) = copy_out(f.device, &mut encoder, physical[h.0].expect("written resources are allocated"), r, owner) {
                captures.push(c);
            }
        }
        if let Some(times) = serial.as_mut() {
            let done =
                std::mem::replace(&mut encoder, f.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") }));
            f.queue.submit([done.finish()]);
            let _ = f.device.poll(wgpu::PollType::wait_indefinitely());
            times.push((pass.name.clone(), started.elapsed().as_secs_f64() * 1e3));
        }
    }
    let timestamps = query_set
        .map(|qs| (resolve(f.device, &mut encoder, &qs, graph.passes.len() as u32 * 2, "timestamps"), f.queue.get_timestamp_period()));
    let statistics = statistics_set.map(|set| (resolve(f.device, &mut encoder, &set, next_query, "fragment invocations"), queries));
    let prints = f.prints.map(|p| p.buffer.copy_out(f.device, &mut encoder, &p));
    f.queue.submit([encoder.finish()]);
    if let Some(p) = &prints {
        p.map();
    }
    let history = history.map(HistoryRecorder::finish);
    if let Some(h) = &history {
        h.map();
    }
    for c in &captures {
        c.readback.map();
    }
    if let Some((r, _)) = &timestamps {
        r.map();
    }
    if let Some((r, _)) = &statistics {
        r.map();
    }
    for t in &quad_targets {
        t.map();
    }
    PendingFrame {
        prints,
        history,
        frame: f.frame,
        submitted: Instant::now(),
        cpu_record_ms: start.elapsed().as_secs_f64() * 1e3,
        captures,
        timestamps,
        statistics,
        serial,
        quad_targets,
        quad_replays: f.quad_replays,
        skipped,
        passes: graph.passes.iter().map(|p| p.name.clone()).collect(),
        io: graph
            .passes
            .iter()
            .map(|p| {
                let names = |hs: &mut dyn Iterator<Item = super::resource::Handle>| hs.map(|h| graph.resource(h).name.clone()).collect();
                (names(&mut p.reads()), names(&mut p.writes()))
            })
            .collect(),
    }
}

/// Resolves the first `n` queries of `set` (one u64 each) into a buffer to
/// read back.
fn resolve(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, set: &wgpu::QuerySet, n: u32, label: &str) -> Readback {
    // A buffer may not be empty.
    let size = u64::from(n.max(1)) * 8;
    let resolved = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = Readback::new(device, label, size);
    if n > 0 {
        encoder.resolve_query_set(set, 0..n, &resolved, 0);
        encoder.copy_buffer_to_buffer(&resolved, 0, read.buffer(), 0, size);
    }
    read
}

/// The little-endian u64s of a query readback.
fn read_u64s(r: &Readback) -> Option<Vec<u64>> {
    r.read(|bytes| bytes.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes"))).collect())
}

fn copy_out(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    physical: &Physical,
    r: &Resource,
    pass: &str,
) -> Option<PendingCapture> {
    let (what, readback) = match (&r.desc, physical) {
        (ResourceDesc::Texture(desc), Physical::Texture { texture, .. }) => {
            let layout = Layout::of(desc.format)?;
            // Layers land one under another: an array reads back as one tall image.
            let (readback, rows) = copy_texture(device, encoder, &r.name, texture, 0, desc.layers, layout.bytes_per_texel() as u32);
            (Copied::Texture { desc: desc.clone(), rows }, readback)
        }
        (ResourceDesc::Buffer(layout), Physical::Buffer(source)) => {
            let size = source.size();
            let readback = Readback::new(device, &r.name, size);
            encoder.copy_buffer_to_buffer(source, 0, readback.buffer(), 0, size);
            (Copied::Buffer(layout.clone()), readback)
        }
        _ => return None,
    };
    Some(PendingCapture { pass: pass.to_owned(), output: r.output().to_owned(), what, readback })
}

impl PendingFrame {
    /// Whether every readback has completed (call `device.poll` first).
    pub fn ready(&self) -> bool {
        self.captures.iter().all(|c| c.readback.landed())
            && self.timestamps.as_ref().is_none_or(|t| t.0.landed())
            && self.statistics.as_ref().is_none_or(|t| t.0.landed())
            && self.quad_targets.iter().all(PendingTarget::landed)
            && self.prints.as_ref().is_none_or(PendingPrints::landed)
            && self.history.as_ref().is_none_or(PendingHistory::landed)
    }

    /// Converts the mapped readbacks and takes their statistics: the
    /// frame's CPU work, on any thread. Call only when `ready()`.
    pub fn finish(self) -> FrameResult {
        let mut captures = Vec::new();
        let mut tensors = Vec::new();
        for c in &self.captures {
            let converted = c.readback.read(|mapped| match &c.what {
                Copied::Texture { desc, rows } => {
                    let layout = Layout::of(desc.format).expect("checked at copy");
                    let height = desc.height * desc.layers;
                    let mut data = Vec::with_capacity(desc.width as usize * height as usize * 4);
                    for r in rows.of(mapped) {
                        layout.extend_rgba_f32(r, &mut data);
                    }
                    captures.push(CapturedImage::new(&c.pass, &c.output, self.frame, desc.width, height, desc.format, data));
                }
                Copied::Buffer(layout) => tensors.push(CapturedTensor::new(&c.pass, &c.output, self.frame, layout.clone(), mapped)),
            });
            if converted.is_none() {
                log::warn!("the readback of {}/{} failed", c.pass, c.output);
            }
        }
        let stamps = self.timestamps.as_ref().and_then(|(r, period)| Some((read_u64s(r)?, *period)));
        let (timings, total_ms, timing) = match (self.serial, stamps) {
            (Some(t), _) => {
                let total = t.iter().map(|(_, ms)| ms).sum();
                (t, total, "serial")
            }
            (None, Some((stamps, period))) => {
                let t: Vec<(String, f64)> = self
                    .passes
                    .iter()
                    .enumerate()
                    .map(|(i, n)| (n.clone(), stamps[i * 2 + 1].saturating_sub(stamps[i * 2]) as f64 * f64::from(period) / 1e6))
                    .collect();
                let total = t.iter().map(|(_, ms)| ms).sum();
                (t, total, "gpu")
            }
            (None, None) => (Vec::new(), self.submitted.elapsed().as_secs_f64() * 1e3 + self.cpu_record_ms, "cpu"),
        };
        let counts = self.statistics.as_ref().and_then(|(r, queries)| Some((read_u64s(r)?, queries)));
        let fragment_invocations = counts
            .map(|(counts, queries)| {
                self.passes
                    .iter()
                    .zip(queries)
                    .filter(|(_, q)| !q.is_empty())
                    .map(|(n, q)| (n.clone(), q.iter().map(|&i| counts[i as usize]).sum()))
                    .collect()
            })
            .unwrap_or_default();
        let recorded: Vec<_> = self.quad_targets.into_iter().filter_map(PendingTarget::read).collect();
        let quads = self.quad_replays.map(|r| r.replay(&recorded)).unwrap_or_default();
        let history = self.history.map(|h| h.read(self.frame, &recorded));
        let nan = nan_origin(&self.passes, &self.io, &captures, &tensors);
        let prints = self.prints.as_ref().and_then(PendingPrints::read);
        FrameResult {
            frame: self.frame,
            timings,
            total_ms,
            timing,
            captures,
            tensors,
            skipped: self.skipped,
            fragment_invocations,
            quads,
            nan,
            prints,
            history,
        }
    }
}
