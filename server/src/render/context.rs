//! What a pass sees while it records its commands: its resources by
//! handle, the scene's buffers, its pipelines, and helpers that draw,
//! dispatch and bind by name. Every render or compute pass it begins
//! carries the pass's GPU timestamps.

use std::collections::BTreeMap;
use std::sync::Arc;

use wgpu::util::DeviceExt;

use super::debug_print::PrintBinding;
use super::quads::{Faces, PendingDepth, PendingDraw, PendingTarget, QuadRecorder, depth_state};
use super::readback::copy_texture;
use super::resource::{Handle, Physical, PipelineKey};
use super::scene_gpu::SceneGpu;
use super::vertex_capture::{self, Vertices};
use crate::gpu::pipeline::{self, Pipeline};

/// What a cleared depth target holds: the far plane, as the pipelines'
/// `Less` compare expects (reversed depth would clear to 0 and compare
/// `Greater`). Viewers leave it out of depth's range.
pub const DEPTH_CLEAR: f32 = 1.0;

/// The depth target of a draw: one layer of a depth texture, cleared first
/// or tested against what it holds.
#[derive(Debug, Clone, Copy)]
pub struct DepthTarget {
    pub texture: Handle,
    pub layer: u32,
    pub clear: bool,
}

/// Bindings by the names the pipeline spec gives them.
pub type Bindings<'b> = [(&'static str, wgpu::BindingResource<'b>)];

pub struct PassContext<'a> {
    pub device: &'a wgpu::Device,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub pass: &'a str,
    pub scene: &'a SceneGpu,
    /// The frame's number, counting from 1.
    pub frame: u64,
    /// Samples per pixel the path tracer holds after this frame.
    pub samples: u32,
    /// Seconds since the previous frame (0 for the first): what temporal
    /// passes adapt by.
    pub dt: f32,
    /// Physical resources, by handle index (`None`: not used this frame).
    pub(super) resources: Vec<Option<&'a Physical>>,
    pub(super) pipelines: &'a BTreeMap<PipelineKey, Pipeline>,
    /// The query slots of this pass's begin and end timestamps.
    pub(super) timestamps: Option<(&'a wgpu::QuerySet, u32)>,
    /// Render and compute passes recorded so far; the first writes the
    /// begin stamp.
    pub(super) recorded: u32,
    /// Set when the pass drew nothing because a pipeline never built.
    pub skipped: bool,
    /// Where each render pass counts its fragment-shader invocations
    /// (pipeline statistics), when the frame asked for them.
    pub(super) statistics: Option<Statistics<'a>>,
    /// Where draws are recorded for quad statistics, when the frame asked.
    pub(super) quads: Option<QuadRecorder<'a>>,
    /// The print buffer, when a pixel is selected.
    pub(super) prints: Option<PrintBinding<'a>>,
}

/// The frame's pipeline-statistics queries: one per render pass recorded.
pub(super) struct Statistics<'a> {
    pub set: &'a wgpu::QuerySet,
    /// The next free query.
    pub next: u32,
    /// The queries this pass used.
    pub used: Vec<u32>,
}

/// How many pipeline-statistics queries one frame may make; render passes
/// beyond them go uncounted (and their pass reports no count).
pub(super) const MAX_STATISTICS: u32 = 256;

impl<'a> PassContext<'a> {
    fn physical(&self, h: Handle) -> &'a Physical {
        self.resources[h.0].expect("a pass only uses resources it declared")
    }

    pub fn texture(&self, h: Handle) -> &'a wgpu::Texture {
        match self.physical(h) {
            Physical::Texture { texture, .. } => texture,
            Physical::Buffer(_) => panic!("handle {h:?} is a buffer, not a texture"),
        }
    }

    pub fn view(&self, h: Handle) -> &'a wgpu::TextureView {
        match self.physical(h) {
            Physical::Texture { view, .. } => view,
            Physical::Buffer(_) => panic!("handle {h:?} is a buffer, not a texture"),
        }
    }

    pub fn buffer(&self, h: Handle) -> &'a wgpu::Buffer {
        match self.physical(h) {
            Physical::Buffer(b) => b,
            Physical::Texture { .. } => panic!("handle {h:?} is a texture, not a buffer"),
        }
    }

    /// `h` as a binding: its whole view or whole buffer.
    pub fn bind(&self, h: Handle) -> wgpu::BindingResource<'a> {
        match self.physical(h) {
            Physical::Texture { view, .. } => wgpu::BindingResource::TextureView(view),
            Physical::Buffer(b) => b.as_entire_binding(),
        }
    }

    /// A uniform buffer holding `data`, for this frame only.
    pub fn uniform(&self, data: &[u8]) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(self.pass),
            contents: data,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }

    /// A view of one array layer of texture `h`, to render into.
    pub fn layer(&self, h: Handle, layer: u32) -> wgpu::TextureView {
        self.texture(h).create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..Default::default()
        })
    }

    /// The bind groups of `key`'s layout, each entry found by name in
    /// `bindings` (extra names are ignored: a permutation may leave a
    /// group out). `None`, with the pass marked skipped, when the pipeline
    /// never built or a binding is missing.
    fn bind_groups(
        &mut self,
        key: &PipelineKey,
        layout_of: impl Fn(u32) -> wgpu::BindGroupLayout,
        bindings: &Bindings<'_>,
    ) -> Option<Vec<(u32, wgpu::BindGroup)>> {
        let mut groups = Vec::new();
        for (i, group) in key.spec.layout(&key.defs).into_iter().enumerate() {
            let Some(group) = group else { continue };
            let mut entries = Vec::new();
            for b in group {
                let Some((_, resource)) = bindings.iter().find(|(name, _)| *name == b.name) else {
                    log::error!("pass `{}` binds no `{}` for pipeline {}", self.pass, b.name, key.label());
                    self.skipped = true;
                    return None;
                };
                entries.push(wgpu::BindGroupEntry { binding: b.entry.binding, resource: resource.clone() });
            }
            let layout = layout_of(i as u32);
            groups.push((
                i as u32,
                self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(self.pass), layout: &layout, entries: &entries }),
            ));
        }
        if let Some(p) = self.prints
            && let Some(&group) = p.groups.get(key)
        {
            let entries = [wgpu::BindGroupEntry { binding: 0, resource: p.buffer.binding() }];
            let layout = layout_of(group);
            groups.push((
                group,
                self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("debug prints"),
                    layout: &layout,
                    entries: &entries,
                }),
            ));
        }
        Some(groups)
    }

    fn render_pipeline(&mut self, key: &PipelineKey) -> Option<Arc<wgpu::RenderPipeline>> {
        match self.pipelines.get(key) {
            Some(Pipeline::Render(p)) => Some(p.clone()),
            _ => {
                self.skipped = true;
                None
            }
        }
    }

    /// One pass may record several render or compute passes (a shadow map
    /// layer each): the begin stamp goes on the first, the end stamp is
    /// rewritten by each, so the last one's end counts.
    fn stamps(&mut self) -> Option<(&'a wgpu::QuerySet, Option<u32>, Option<u32>)> {
        let first = self.recorded == 0;
        self.recorded += 1;
        self.timestamps.map(|(qs, base)| (qs, first.then_some(base), Some(base + 1)))
    }

    /// A render pass carrying this pass's stamps, counting fragment-shader
    /// invocations when asked (then the flag is set): end it with
    /// `end_render`.
    fn begin_render<'p>(
        &'p mut self,
        colors: &'p [Option<wgpu::RenderPassColorAttachment<'p>>],
        depth: Option<wgpu::RenderPassDepthStencilAttachment<'p>>,
    ) -> (wgpu::RenderPass<'p>, bool) {
        let timestamp_writes = self.stamps().map(|(query_set, beginning_of_pass_write_index, end_of_pass_write_index)| {
            wgpu::RenderPassTimestampWrites { query_set, beginning_of_pass_write_index, end_of_pass_write_index }
        });
        let counted = self.statistics.as_mut().filter(|s| s.next < MAX_STATISTICS).map(|s| {
            s.used.push(s.next);
            s.next += 1;
            (s.set, s.next - 1)
        });
        let mut rp = self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.pass),
            color_attachments: colors,
            depth_stencil_attachment: depth,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let Some((set, query)) = counted {
            rp.begin_pipeline_statistics_query(set, query);
        }
        (rp, counted.is_some())
    }

    /// Ends a render pass from `begin_render`.
    fn end_render(counted: bool, mut rp: wgpu::RenderPass<'_>) {
        if counted {
            rp.end_pipeline_statistics_query();
        }
    }

    /// A compute pass carrying this pass's stamps.
    fn begin_compute(&mut self) -> wgpu::ComputePass<'_> {
        let timestamp_writes = self.stamps().map(|(query_set, beginning_of_pass_write_index, end_of_pass_write_index)| {
            wgpu::ComputePassTimestampWrites { query_set, beginning_of_pass_write_index, end_of_pass_write_index }
        });
        self.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(self.pass), timestamp_writes })
    }

    /// An empty compute pass that only writes a stamp: how copy passes, and
    /// passes that recorded nothing, are timed without
    /// TIMESTAMP_QUERY_INSIDE_ENCODERS.
    pub(super) fn stamp_only(&mut self) {
        if self.timestamps.is_some() {
            drop(self.begin_compute());
        }
    }

    /// Draws one fullscreen pass into `targets`: one triangle, or two when
    /// the pipeline was built with TWO_TRIANGLES.
    pub fn fullscreen(&mut self, key: &PipelineKey, targets: &[Handle], bindings: &Bindings<'_>) {
        let Some(pipeline) = self.render_pipeline(key) else { return };
        let Some(groups) = self.bind_groups(key, |i| pipeline.get_bind_group_layout(i), bindings) else { return };
        let views: Vec<&wgpu::TextureView> = targets.iter().map(|h| self.view(*h)).collect();
        let attachments = color_attachments(&views);
        let (mut rp, counted) = self.begin_render(&attachments, None);
        rp.set_pipeline(&pipeline);
        for (i, g) in &groups {
            rp.set_bind_group(*i, g, &[]);
        }
        let two = key.defs.contains(pipeline::TWO_TRIANGLES);
        let vertices = if two { 6 } else { 3 };
        rp.draw(0..vertices, 0..1);
        Self::end_render(counted, rp);
        let size = self.texture(targets[0]).size();
        if self.records(size) {
            let draw = vertex_capture::Draw { buffer: None, vertices: Vertices::Direct { first: 0 }, count: vertices, instance: 0 };
            let name = if two { "two triangles" } else { "fullscreen triangle" };
            let draws = self.capture_positions(key, bindings, &[(name.to_owned(), draw)], None);
            self.record_target(size, None, draws, Some(two));
        }
    }

    /// Whether the frame records the draws of a render pass into targets
    /// of `size`.
    fn records(&self, size: wgpu::Extent3d) -> bool {
        self.quads.as_ref().is_some_and(|r| r.wants(size))
    }

    /// Records the positions of `draws` (named) for quad statistics; `None`
    /// with a warning when the vertex stage cannot be captured.
    fn capture_positions(
        &mut self,
        key: &PipelineKey,
        bindings: &Bindings<'_>,
        draws: &[(String, vertex_capture::Draw<'_>)],
        depth: Option<crate::quads::DepthState>,
    ) -> Option<Vec<PendingDraw>> {
        let rec = self.quads.as_ref()?;
        let Some(capture) = rec.captures.get(key) else {
            log::warn!("quad statistics of `{}`: no vertex capture for pipeline {}", self.pass, key.label());
            return None;
        };
        let layout = key.spec.layout(&key.defs);
        let faces = Faces::of(&pipeline::primitive());
        let mut out = Vec::new();
        for (name, draw) in draws {
            match capture.record(self.device, self.encoder, &layout, bindings, draw) {
                Ok(positions) => out.push(PendingDraw { name: name.clone(), positions, depth, faces }),
                Err(e) => {
                    log::warn!("quad statistics of `{}`: {e}", self.pass);
                    return None;
                }
            }
        }
        Some(out)
    }

    /// Adds one render pass's recorded draws (`None`: not capturable, so the
    /// pass is left out rather than counted short).
    fn record_target(
        &mut self,
        size: wgpu::Extent3d,
        depth: Option<PendingDepth>,
        draws: Option<Vec<PendingDraw>>,
        fullscreen: Option<bool>,
    ) {
        let pass = self.pass.to_owned();
        let Some(rec) = self.quads.as_mut() else { return };
        match draws {
            Some(draws) => rec.targets.push(PendingTarget { pass, width: size.width, height: size.height, depth, draws, fullscreen }),
            // One layer short would misstate the pass: drop all of it.
            None => rec.targets.retain(|t| t.pass != pass),
        }
    }

    /// Copies layer `layer` of depth texture `h` out, before a pass that
    /// tests against it changes nothing but still must be replayed from it.
    fn copy_depth(&mut self, h: Handle, layer: u32) -> PendingDepth {
        let (readback, rows) = copy_texture(self.device, self.encoder, "quad statistics: depth", self.texture(h), layer, 1, 4);
        PendingDepth::Loaded { readback, rows }
    }

    /// Draws every object of the scene, each with its index as the instance
    /// index, into `colors` and the depth target (cleared when `clear`).
    pub fn draw_objects(&mut self, key: &PipelineKey, bindings: &Bindings<'_>, colors: &[Handle], depth: Option<DepthTarget>) {
        let Some(pipeline) = self.render_pipeline(key) else { return };
        let Some(groups) = self.bind_groups(key, |i| pipeline.get_bind_group_layout(i), bindings) else { return };
        let views: Vec<&wgpu::TextureView> = colors.iter().map(|h| self.view(*h)).collect();
        let attachments = color_attachments(&views);
        let depth_target = depth;
        let size = match (depth_target, colors.first()) {
            (_, Some(c)) => Some(self.texture(*c).size()),
            (Some(d), None) => Some(self.texture(d.texture).size()),
            (None, None) => None,
        };
        let record = size.is_some_and(|s| self.records(s));
        // What the depth buffer holds before the pass, for quad statistics.
        let initial = match depth {
            Some(d) if record => Some(if d.clear { PendingDepth::Clear(DEPTH_CLEAR) } else { self.copy_depth(d.texture, d.layer) }),
            _ => None,
        };
        let depth_view = depth.map(|d| self.layer(d.texture, d.layer));
        let depth = depth.zip(depth_view.as_ref()).map(|(d, view)| wgpu::RenderPassDepthStencilAttachment {
            view,
            // Tested against only: read-only, so the pass may also read it
            // (the G-buffer does, to write its storage words from the
            // visible fragment alone).
            depth_ops: d.clear.then_some(wgpu::Operations { load: wgpu::LoadOp::Clear(DEPTH_CLEAR), store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        });
        let scene = self.scene;
        let (mut rp, counted) = self.begin_render(&attachments, depth);
        rp.set_pipeline(&pipeline);
        for (i, g) in &groups {
            rp.set_bind_group(*i, g, &[]);
        }
        for (object, &mesh) in scene.draws.iter().enumerate() {
            let m = &scene.meshes[mesh];
            rp.set_vertex_buffer(0, m.vertices.slice(..));
            rp.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
            rp.draw_indexed(0..m.index_count, 0, object as u32..object as u32 + 1);
        }
        Self::end_render(counted, rp);
        if let Some(size) = size.filter(|_| record) {
            let draws: Vec<(String, vertex_capture::Draw<'_>)> = scene
                .draws
                .iter()
                .enumerate()
                .map(|(object, &mesh)| {
                    let m = &scene.meshes[mesh];
                    let vertices = Vertices::Indexed { indices: &m.indices, first: 0, base_vertex: 0 };
                    // Layers of one texture are one pass's targets: say which.
                    let name = match depth_target {
                        Some(d) if self.texture(d.texture).size().depth_or_array_layers > 1 => {
                            format!("layer {}: {}", d.layer, scene.names[object])
                        }
                        _ => scene.names[object].clone(),
                    };
                    (name, vertex_capture::Draw { buffer: Some(&m.vertices), vertices, count: m.index_count, instance: object as u32 })
                })
                .collect();
            let state = match key.spec.stages {
                pipeline::Stages::Mesh { depth: mode, .. } if depth_target.is_some() => Some(depth_state(mode)),
                _ => None,
            };
            let recorded = self.capture_positions(key, bindings, &draws, state);
            self.record_target(size, initial, recorded, None);
        }
    }

    /// Dispatches compute pipeline `key` over `workgroups`.
    pub fn dispatch(&mut self, key: &PipelineKey, bindings: &Bindings<'_>, workgroups: [u32; 3]) {
        if let Some(mut cp) = self.compute(key, bindings) {
            cp.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        }
    }

    /// Dispatches compute pipeline `key` over the workgroups the three
    /// `u32`s at byte `offset` of buffer `args` say (written on the GPU).
    pub fn dispatch_indirect(&mut self, key: &PipelineKey, bindings: &Bindings<'_>, args: Handle, offset: u64) {
        let args = self.buffer(args);
        if let Some(mut cp) = self.compute(key, bindings) {
            cp.dispatch_workgroups_indirect(args, offset);
        }
    }

    /// A compute pass with `key`'s pipeline and bind groups set; `None`
    /// (the pass marked skipped) when the pipeline never built.
    fn compute(&mut self, key: &PipelineKey, bindings: &Bindings<'_>) -> Option<wgpu::ComputePass<'_>> {
        let pipeline = match self.pipelines.get(key) {
            Some(Pipeline::Compute(p)) => p.clone(),
            _ => {
                self.skipped = true;
                return None;
            }
        };
        let groups = self.bind_groups(key, |i| pipeline.get_bind_group_layout(i), bindings)?;
        let mut cp = self.begin_compute();
        cp.set_pipeline(&pipeline);
        for (i, g) in &groups {
            cp.set_bind_group(*i, g, &[]);
        }
        Some(cp)
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
