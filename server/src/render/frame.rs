//! Running a built graph on the GPU: transient textures, per-pass GPU
//! timestamps, and captures copied out right after the pass that wrote them
//! and read back asynchronously.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::Instant;

use wgpu::util::DeviceExt;

use super::capture::{CapturedImage, Layout};
use super::graph::{Graph, Handle, PipelineKey, TextureDesc};
use crate::gpu::pipeline::Pipeline;

/// What a pass sees while it records its commands.
pub struct PassContext<'a> {
    pub device: &'a wgpu::Device,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub pass: &'a str,
    pub inputs: Vec<&'a wgpu::TextureView>,
    pub outputs: Vec<&'a wgpu::TextureView>,
    pub output_descs: Vec<&'a TextureDesc>,
    pipelines: &'a BTreeMap<PipelineKey, Pipeline>,
    timestamps: Option<wgpu::RenderPassTimestampWrites<'a>>,
    /// Set when the pass drew nothing because its pipeline never built.
    pub skipped: bool,
}

impl PassContext<'_> {
    pub fn pipeline(&self, key: &PipelineKey) -> Option<&Pipeline> {
        self.pipelines.get(key)
    }

    /// A uniform buffer holding `data`, for this frame only.
    pub fn uniform(&self, data: &[u8]) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(self.pass),
            contents: data,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }

    /// Draws one fullscreen pass into the pass's outputs: one triangle, or
    /// two when the pipeline was built with TWO_TRIANGLES. Resources bind to
    /// group 0 in order of `bindings` (binding index = position).
    pub fn fullscreen(&mut self, key: &PipelineKey, bindings: &[wgpu::BindingResource<'_>]) {
        let Some(Pipeline::Render(pipeline)) = self.pipelines.get(key).cloned() else {
            self.skipped = true;
            return;
        };
        let layout = pipeline.get_bind_group_layout(0);
        let entries: Vec<wgpu::BindGroupEntry> = bindings
            .iter()
            .enumerate()
            .map(|(i, r)| wgpu::BindGroupEntry { binding: i as u32, resource: r.clone() })
            .collect();
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(self.pass), layout: &layout, entries: &entries });
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = self
            .outputs
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
                })
            })
            .collect();
        let mut rp = self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.pass),
            color_attachments: &attachments,
            depth_stencil_attachment: None,
            timestamp_writes: self.timestamps.take(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&pipeline);
        rp.set_bind_group(0, &group, &[]);
        let vertices = if key.defs.contains("TWO_TRIANGLES") { 6 } else { 3 };
        rp.draw(0..vertices, 0..1);
    }
}

/// Textures kept between frames, reused while the graph's descriptions match.
#[derive(Default)]
pub struct TexturePool {
    textures: BTreeMap<(String, u32, u32, String), (wgpu::Texture, wgpu::TextureView)>,
}

impl TexturePool {
    fn get(&mut self, device: &wgpu::Device, desc: &TextureDesc) -> &wgpu::TextureView {
        let key = (desc.name.clone(), desc.width, desc.height, format!("{:?}", desc.format));
        &self
            .textures
            .entry(key)
            .or_insert_with(|| {
                let t = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&desc.name),
                    size: wgpu::Extent3d { width: desc.width, height: desc.height, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: desc.format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                });
                let v = t.create_view(&Default::default());
                (t, v)
            })
            .1
    }

    /// Drops textures the current graph no longer uses.
    pub fn retain(&mut self, graph: &Graph) {
        let live: BTreeSet<_> = graph
            .textures
            .iter()
            .map(|d| (d.name.clone(), d.width, d.height, format!("{:?}", d.format)))
            .collect();
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
}

/// Records and submits one frame of `graph`. `capture` names the textures
/// (`pass/output`) to copy out; `None` captures everything.
pub fn submit(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    features: wgpu::Features,
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
    let views: Vec<&wgpu::TextureView> = graph
        .textures
        .iter()
        .map(|d| {
            let key = (d.name.clone(), d.width, d.height, format!("{:?}", d.format));
            &pool.textures[&key].1
        })
        .collect();
    let textures: Vec<&wgpu::Texture> = graph
        .textures
        .iter()
        .map(|d| &pool.textures[&(d.name.clone(), d.width, d.height, format!("{:?}", d.format))].0)
        .collect();

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
            inputs: pass.reads.iter().map(|h| views[h.0]).collect(),
            outputs: pass.writes.iter().map(|h| views[h.0]).collect(),
            output_descs: pass.writes.iter().map(|h| graph.texture(*h)).collect(),
            pipelines,
            timestamps: query_set.as_ref().map(|qs| wgpu::RenderPassTimestampWrites {
                query_set: qs,
                beginning_of_pass_write_index: Some(i as u32 * 2),
                end_of_pass_write_index: Some(i as u32 * 2 + 1),
            }),
            skipped: false,
        };
        (pass.execute)(&mut ctx);
        if ctx.skipped {
            skipped.push(pass.name.clone());
        }
        if let Some(qs) = &query_set {
            if ctx.timestamps.is_some() {
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
        size: u64::from(padded_row) * u64::from(desc.height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded_row), rows_per_image: None },
        },
        wgpu::Extent3d { width: desc.width, height: desc.height, depth_or_array_layers: 1 },
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
            let mut tight = Vec::with_capacity(row * c.desc.height as usize);
            for r in mapped.chunks(c.padded_row as usize).take(c.desc.height as usize) {
                tight.extend_from_slice(&r[..row]);
            }
            drop(mapped);
            c.buffer.unmap();
            let data = layout.to_rgba_f32(&tight);
            captures.push(CapturedImage::new(&c.pass, &c.output, self.frame, c.desc.width, c.desc.height, c.desc.format, data));
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
        FrameResult { frame: self.frame, timings, timing, captures, skipped: self.skipped }
    }
}

/// The handle's capture name, for building capture sets.
pub fn capture_name(graph: &Graph, h: Handle) -> String {
    graph.texture(h).name.clone()
}
