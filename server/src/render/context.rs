//! What a pass sees while it records its commands: its resources by
//! handle, the scene's buffers, its pipelines, and helpers that draw,
//! dispatch and bind by name. Every render or compute pass it begins
//! carries the pass's GPU timestamps.

use std::collections::BTreeMap;
use std::sync::Arc;

use wgpu::util::DeviceExt;

use super::resource::{Handle, Physical, PipelineKey};
use super::scene_gpu::SceneGpu;
use crate::gpu::pipeline::{self, Pipeline};

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
    fn bind_groups(&mut self, key: &PipelineKey, layout_of: impl Fn(u32) -> wgpu::BindGroupLayout, bindings: &Bindings<'_>) -> Option<Vec<(u32, wgpu::BindGroup)>> {
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
            groups.push((i as u32, self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(self.pass), layout: &layout, entries: &entries })));
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
        let vertices = if key.defs.contains(pipeline::TWO_TRIANGLES) { 6 } else { 3 };
        rp.draw(0..vertices, 0..1);
        Self::end_render(counted, rp);
    }

    /// Draws every object of the scene, each with its index as the instance
    /// index, into `colors` and the depth target (cleared when `clear`).
    pub fn draw_objects(&mut self, key: &PipelineKey, bindings: &Bindings<'_>, colors: &[Handle], depth: Option<DepthTarget>) {
        let Some(pipeline) = self.render_pipeline(key) else { return };
        let Some(groups) = self.bind_groups(key, |i| pipeline.get_bind_group_layout(i), bindings) else { return };
        let views: Vec<&wgpu::TextureView> = colors.iter().map(|h| self.view(*h)).collect();
        let attachments = color_attachments(&views);
        let depth_view = depth.map(|d| self.layer(d.texture, d.layer));
        let depth = depth.zip(depth_view.as_ref()).map(|(d, view)| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: if d.clear { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load },
                store: wgpu::StoreOp::Store,
            }),
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
    }

    /// Dispatches compute pipeline `key` over `workgroups`.
    pub fn dispatch(&mut self, key: &PipelineKey, bindings: &Bindings<'_>, workgroups: [u32; 3]) {
        let pipeline = match self.pipelines.get(key) {
            Some(Pipeline::Compute(p)) => p.clone(),
            _ => {
                self.skipped = true;
                return;
            }
        };
        let Some(groups) = self.bind_groups(key, |i| pipeline.get_bind_group_layout(i), bindings) else { return };
        let mut cp = self.begin_compute();
        cp.set_pipeline(&pipeline);
        for (i, g) in &groups {
            cp.set_bind_group(*i, g, &[]);
        }
        cp.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
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
