//! Running a built graph on the GPU: transient textures, per-pass GPU
//! timestamps, and captures copied out right after the pass that wrote them
//! and read back asynchronously.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::Instant;

use wgpu::util::DeviceExt;

use super::capture::{CapturedImage, Layout};
use super::graph::{Graph, Handle, PipelineKey, TextureDesc};
use super::scene_gpu::SceneGpu;
use crate::gpu::pipeline::Pipeline;

/// What a pass sees while it records its commands.
pub struct PassContext<'a> {
    pub device: &'a wgpu::Device,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub pass: &'a str,
    pub scene: &'a SceneGpu,
    pub inputs: Vec<&'a wgpu::TextureView>,
    pub outputs: Vec<&'a wgpu::TextureView>,
    pub output_textures: Vec<&'a wgpu::Texture>,
    pipelines: &'a BTreeMap<PipelineKey, Pipeline>,
    /// The query slots of this pass's begin and end timestamps.
    timestamps: Option<(&'a wgpu::QuerySet, u32)>,
    /// Render passes recorded so far; the first writes the begin stamp.
    recorded: u32,
    /// Set when the pass drew nothing because its pipeline never built.
    pub skipped: bool,
}

impl PassContext<'_> {
    /// A uniform buffer holding `data`, for this frame only.
    pub fn uniform(&self, data: &[u8]) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(self.pass),
            contents: data,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }

    /// A view of one array layer of output `index`, to render into.
    pub fn output_layer(&self, index: usize, layer: u32) -> wgpu::TextureView {
        self.output_textures[index].create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..Default::default()
        })
    }

    /// The render pipeline for `key` and its bind groups: `groups[i]` binds
    /// group i, resource j at binding j; an empty slice leaves the group out.
    /// `None` (and the pass marked skipped) when the pipeline never built.
    fn prepare(&mut self, key: &PipelineKey, groups: &[&[wgpu::BindingResource<'_>]]) -> Option<(Arc<wgpu::RenderPipeline>, Vec<(u32, wgpu::BindGroup)>)> {
        let Some(Pipeline::Render(pipeline)) = self.pipelines.get(key).cloned() else {
            self.skipped = true;
            return None;
        };
        let bind_groups = groups
            .iter()
            .enumerate()
            .filter(|(_, g)| !g.is_empty())
            .map(|(i, g)| {
                let entries: Vec<wgpu::BindGroupEntry> =
                    g.iter().enumerate().map(|(b, r)| wgpu::BindGroupEntry { binding: b as u32, resource: r.clone() }).collect();
                let layout = pipeline.get_bind_group_layout(i as u32);
                (i as u32, self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(self.pass), layout: &layout, entries: &entries }))
            })
            .collect();
        Some((pipeline, bind_groups))
    }

    fn begin<'p>(
        &'p mut self,
        colors: &'p [Option<wgpu::RenderPassColorAttachment<'p>>],
        depth: Option<wgpu::RenderPassDepthStencilAttachment<'p>>,
    ) -> wgpu::RenderPass<'p> {
        // One pass may record several render passes (a shadow map layer
        // each): the begin stamp goes on the first, the end stamp is
        // rewritten by each, so the last one's end counts.
        let timestamp_writes = self.timestamps.map(|(qs, base)| wgpu::RenderPassTimestampWrites {
            query_set: qs,
            beginning_of_pass_write_index: (self.recorded == 0).then_some(base),
            end_of_pass_write_index: Some(base + 1),
        });
        self.recorded += 1;
        self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.pass),
            color_attachments: colors,
            depth_stencil_attachment: depth,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// Draws one fullscreen pass into the pass's outputs: one triangle, or
    /// two when the pipeline was built with TWO_TRIANGLES.
    pub fn fullscreen(&mut self, key: &PipelineKey, groups: &[&[wgpu::BindingResource<'_>]]) {
        let Some((pipeline, bind_groups)) = self.prepare(key, groups) else { return };
        let outputs = self.outputs.clone();
        let attachments = color_attachments(&outputs);
        let mut rp = self.begin(&attachments, None);
        rp.set_pipeline(&pipeline);
        for (i, g) in &bind_groups {
            rp.set_bind_group(*i, g, &[]);
        }
        let vertices = if key.defs.contains("TWO_TRIANGLES") { 6 } else { 3 };
        rp.draw(0..vertices, 0..1);
    }

    /// Draws every object of the scene, each with its index as the instance
    /// index, into `colors` and the depth target (cleared when `clear`).
    pub fn draw_objects(
        &mut self,
        key: &PipelineKey,
        groups: &[&[wgpu::BindingResource<'_>]],
        colors: &[&wgpu::TextureView],
        depth: Option<(&wgpu::TextureView, bool)>,
    ) {
        let Some((pipeline, bind_groups)) = self.prepare(key, groups) else { return };
        let attachments = color_attachments(colors);
        let depth = depth.map(|(view, clear)| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: if clear { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load },
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        });
        let scene = self.scene;
        let mut rp = self.begin(&attachments, depth);
        rp.set_pipeline(&pipeline);
        for (i, g) in &bind_groups {
            rp.set_bind_group(*i, g, &[]);
        }
        for (object, &mesh) in scene.draws.iter().enumerate() {
            let m = &scene.meshes[mesh];
            rp.set_vertex_buffer(0, m.vertices.slice(..));
            rp.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
            rp.draw_indexed(0..m.index_count, 0, object as u32..object as u32 + 1);
        }
    }
}

fn color_attachments<'v>(views: &[&'v wgpu::TextureView]) -> Vec<Option<wgpu::RenderPassColorAttachment<'v>>> {
    views
        .iter()
        .map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store },
            })
        })
        .collect()
}

/// Textures kept between frames, reused while the graph's descriptions match.
#[derive(Default)]
pub struct TexturePool {
    textures: HashMap<TextureDesc, (wgpu::Texture, wgpu::TextureView)>,
}

impl TexturePool {
    fn get(&mut self, device: &wgpu::Device, desc: &TextureDesc) -> &(wgpu::Texture, wgpu::TextureView) {
        self.textures.entry(desc.clone()).or_insert_with(|| {
            let t = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&desc.name),
                size: wgpu::Extent3d { width: desc.width, height: desc.height, depth_or_array_layers: desc.layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: desc.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let dimension = if desc.array { wgpu::TextureViewDimension::D2Array } else { wgpu::TextureViewDimension::D2 };
            let v = t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(dimension), ..Default::default() });
            (t, v)
        })
    }

    /// Drops textures the current graph no longer uses.
    pub fn retain(&mut self, graph: &Graph) {
        let live: HashSet<&TextureDesc> = graph.textures.iter().collect();
        self.textures.retain(|k, _| live.contains(k));
    }
}

/// A submitted frame whose captures and timings are still on their way back.
pub struct PendingFrame {
    pub frame: u64,
    pub submitted: Instant,
    pub cpu_record_ms: f64,
    captures: Vec<PendingCapture>,
    timestamps: Option<(wgpu::Buffer, Arc<AtomicU8>, Vec<String>, f32)>,
    pub skipped: Vec<String>,
    passes: Vec<String>,
    /// Per pass: the capture names it read and wrote, for the NaN report.
    io: Vec<(Vec<String>, Vec<String>)>,
}

struct PendingCapture {
    pass: String,
    output: String,
    desc: TextureDesc,
    buffer: wgpu::Buffer,
    padded_row: u32,
    state: Arc<AtomicU8>,
}

const MAP_PENDING: u8 = 0;
const MAP_OK: u8 = 1;
const MAP_FAILED: u8 = 2;

/// A frame's results once every readback has landed.
pub struct FrameResult {
    pub frame: u64,
    /// Per pass, in execution order: (name, milliseconds).
    pub timings: Vec<(String, f64)>,
    /// `gpu` when from timestamp queries, `cpu` otherwise.
    pub timing: &'static str,
    pub captures: Vec<CapturedImage>,
    /// Passes that drew nothing because their pipeline never built.
    pub skipped: Vec<String>,
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
    /// The first bad pixel in row order.
    pub pixel: [u32; 2],
    pub value: [f32; 4],
    pub nan: u64,
    pub inf: u64,
    /// False when some input was not captured, so an inherited value
    /// cannot be ruled out.
    pub inputs_checked: bool,
}

fn nan_origin(passes: &[String], io: &[(Vec<String>, Vec<String>)], captures: &[CapturedImage]) -> Option<NanOrigin> {
    let find = |name: &str| captures.iter().find(|c| c.key() == name);
    for (pass, (reads, writes)) in passes.iter().zip(io) {
        let inputs: Vec<Option<&CapturedImage>> = reads.iter().map(|r| find(r)).collect();
        if inputs.iter().flatten().any(|c| c.stats.has_non_finite()) {
            continue; // it inherited bad values; an earlier pass made them
        }
        for w in writes {
            let Some(c) = find(w).filter(|c| c.stats.has_non_finite()) else { continue };
            let pixel = c.stats.first_nan.expect("non-finite values have a first pixel");
            return Some(NanOrigin {
                pass: pass.clone(),
                output: c.output.clone(),
                pixel,
                value: c.pixel(pixel[0], pixel[1]),
                nan: c.stats.nan,
                inf: c.stats.inf,
                inputs_checked: inputs.iter().all(Option::is_some),
            });
        }
    }
    None
}

/// Records and submits one frame of `graph`. `capture` names the textures
/// (`pass/output`) to copy out; `None` captures everything.
pub fn submit(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    features: wgpu::Features,
    scene: &SceneGpu,
    graph: &Graph,
    pool: &mut TexturePool,
    pipelines: &BTreeMap<PipelineKey, Pipeline>,
    capture: Option<&BTreeSet<String>>,
    frame: u64,
) -> PendingFrame {
    let start = Instant::now();
    // Create every texture first so views can be borrowed together.
    for d in &graph.textures {
        pool.get(device, d);
    }
    let views: Vec<&wgpu::TextureView> = graph.textures.iter().map(|d| &pool.textures[d].1).collect();
    let textures: Vec<&wgpu::Texture> = graph.textures.iter().map(|d| &pool.textures[d].0).collect();

    let gpu_timing = features.contains(wgpu::Features::TIMESTAMP_QUERY) && !graph.passes.is_empty();
    let query_set = gpu_timing.then(|| {
        device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timings"),
            ty: wgpu::QueryType::Timestamp,
            count: graph.passes.len() as u32 * 2,
        })
    });

    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
    let mut captures = Vec::new();
    let mut skipped = Vec::new();
    for (i, pass) in graph.passes.iter().enumerate() {
        let mut ctx = PassContext {
            device,
            encoder: &mut encoder,
            pass: &pass.name,
            scene,
            inputs: pass.reads.iter().map(|h| views[h.0]).collect(),
            outputs: pass.writes.iter().map(|h| views[h.0]).collect(),
            output_textures: pass.writes.iter().map(|h| textures[h.0]).collect(),
            pipelines,
            timestamps: query_set.as_ref().map(|qs| (qs, i as u32 * 2)),
            recorded: 0,
            skipped: false,
        };
        (pass.execute)(&mut ctx);
        if ctx.skipped {
            skipped.push(pass.name.clone());
        }
        if let Some(qs) = &query_set {
            if ctx.recorded == 0 {
                // The pass recorded no render pass: write both stamps here so
                // its time reads as zero rather than garbage.
                encoder.write_timestamp(qs, i as u32 * 2);
                encoder.write_timestamp(qs, i as u32 * 2 + 1);
            }
        }
        for h in &pass.writes {
            let desc = graph.texture(*h);
            if capture.is_some_and(|c| !c.contains(&desc.name)) {
                continue;
            }
            if let Some(c) = copy_out(device, &mut encoder, textures[h.0], desc, &pass.name) {
                captures.push(c);
            }
        }
    }
    let timestamps = query_set.map(|qs| {
        let n = graph.passes.len() as u64 * 2;
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: n * 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps readback"),
            size: n * 8,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.resolve_query_set(&qs, 0..n as u32, &resolve, 0);
        encoder.copy_buffer_to_buffer(&resolve, 0, &read, 0, n * 8);
        (read, Arc::new(AtomicU8::new(MAP_PENDING)), graph.passes.iter().map(|p| p.name.clone()).collect(), queue.get_timestamp_period())
    });
    queue.submit([encoder.finish()]);
    for c in &captures {
        map(&c.buffer, c.state.clone());
    }
    if let Some((buf, state, _, _)) = &timestamps {
        map(buf, state.clone());
    }
    PendingFrame {
        frame,
        submitted: Instant::now(),
        cpu_record_ms: start.elapsed().as_secs_f64() * 1e3,
        captures,
        timestamps,
        skipped,
        passes: graph.passes.iter().map(|p| p.name.clone()).collect(),
        io: graph
            .passes
            .iter()
            .map(|p| {
                let names = |hs: &[Handle]| hs.iter().map(|h| graph.texture(*h).name.clone()).collect();
                (names(&p.reads), names(&p.writes))
            })
            .collect(),
    }
}

fn map(buffer: &wgpu::Buffer, state: Arc<AtomicU8>) {
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        state.store(if r.is_ok() { MAP_OK } else { MAP_FAILED }, Ordering::Release);
    });
}

fn copy_out(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture, desc: &TextureDesc, pass: &str) -> Option<PendingCapture> {
    let layout = Layout::of(desc.format)?;
    let row = desc.width * layout.bytes_per_texel() as u32;
    let padded_row = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(&desc.name),
        size: u64::from(padded_row) * u64::from(desc.height) * u64::from(desc.layers),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    // Layers land one under another: an array reads back as one tall image.
    let aspect = if desc.format.has_depth_aspect() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { aspect, ..texture.as_image_copy() },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded_row), rows_per_image: Some(desc.height) },
        },
        wgpu::Extent3d { width: desc.width, height: desc.height, depth_or_array_layers: desc.layers },
    );
    let output = desc.name.rsplit('/').next().unwrap_or(&desc.name).to_owned();
    Some(PendingCapture {
        pass: pass.to_owned(),
        output,
        desc: desc.clone(),
        buffer,
        padded_row,
        state: Arc::new(AtomicU8::new(MAP_PENDING)),
    })
}

impl PendingFrame {
    /// Whether every readback has completed (call `device.poll` first).
    pub fn ready(&self) -> bool {
        self.captures.iter().all(|c| c.state.load(Ordering::Acquire) != MAP_PENDING)
            && self.timestamps.as_ref().is_none_or(|t| t.1.load(Ordering::Acquire) != MAP_PENDING)
    }

    /// Converts the mapped readbacks. Call only when `ready()`.
    pub fn finish(self) -> FrameResult {
        let mut captures = Vec::new();
        for c in &self.captures {
            if c.state.load(Ordering::Acquire) != MAP_OK {
                continue;
            }
            let layout = Layout::of(c.desc.format).expect("checked at copy");
            let row = c.desc.width as usize * layout.bytes_per_texel();
            let Ok(mapped) = c.buffer.slice(..).get_mapped_range() else { continue };
            let rows = (c.desc.height * c.desc.layers) as usize;
            let mut tight = Vec::with_capacity(row * rows);
            for r in mapped.chunks(c.padded_row as usize).take(rows) {
                tight.extend_from_slice(&r[..row]);
            }
            drop(mapped);
            c.buffer.unmap();
            let data = layout.to_rgba_f32(&tight);
            captures.push(CapturedImage::new(&c.pass, &c.output, self.frame, c.desc.width, rows as u32, c.desc.format, data));
        }
        let (timings, timing) = match &self.timestamps {
            Some((buf, state, names, period)) if state.load(Ordering::Acquire) == MAP_OK && buf.slice(..).get_mapped_range().is_ok() => {
                let mapped = buf.slice(..).get_mapped_range().expect("checked in the guard");
                let stamps: Vec<u64> = mapped.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes"))).collect();
                drop(mapped);
                buf.unmap();
                let t = names
                    .iter()
                    .enumerate()
                    .map(|(i, n)| (n.clone(), stamps[i * 2 + 1].saturating_sub(stamps[i * 2]) as f64 * f64::from(*period) / 1e6))
                    .collect();
                (t, "gpu")
            }
            _ => {
                // No timestamp queries: only the whole frame's CPU-side time
                // is known; spread evenly it would be a lie, so report the
                // frame total on the first pass and zero elsewhere.
                let total = self.submitted.elapsed().as_secs_f64() * 1e3 + self.cpu_record_ms;
                let t = self.passes.iter().enumerate().map(|(i, n)| (n.clone(), if i == 0 { total } else { 0.0 })).collect();
                (t, "cpu")
            }
        };
        let nan = nan_origin(&self.passes, &self.io, &captures);
        FrameResult { frame: self.frame, timings, timing, captures, skipped: self.skipped, nan }
    }
}

/// The handle's capture name, for building capture sets.
pub fn capture_name(graph: &Graph, h: Handle) -> String {
    graph.texture(h).name.clone()
}
