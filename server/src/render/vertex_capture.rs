//! Vertex capture: the clip-space positions a draw's vertex stage produces,
//! computed on the device by the pass's own vertex shader instrumented
//! into a compute kernel (`shader::instrument`), then read back. Quad
//! statistics rasterize them on the CPU.
//!
//! A capture is recorded into the pass's encoder next to the draw, with the
//! resources the pass binds by name: the kernel is built with an automatic
//! layout, so its bind groups are made here, not taken from the render
//! pipeline. Vertex and index buffers are read as storage buffers and need
//! `STORAGE` usage besides `VERTEX` / `INDEX`.

use std::sync::{Arc, OnceLock};

use wgpu::util::DeviceExt;

use crate::gpu::pipeline::Binding;
use crate::shader::instrument::{self, DrawParams, InstrumentError, binding};

/// Why a capture could not be built, recorded or read. Never a panic.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    #[error(transparent)]
    Instrument(#[from] InstrumentError),
    #[error("the instrumented pipeline was rejected: {0}")]
    Pipeline(String),
    #[error("the vertex stage reads @group({group}) @binding({binding}), which the pipeline layout does not name")]
    Unnamed { group: u32, binding: u32 },
    #[error("the vertex stage reads `{0}`, which the pass did not bind")]
    Unbound(&'static str),
    #[error("the draw: {0}")]
    Draw(String),
    #[error("reading the positions back: {0}")]
    Readback(String),
}

/// Which vertices a draw runs.
#[derive(Debug, Clone, Copy)]
pub enum Vertices<'a> {
    /// Vertex `first + i` for invocation `i` (`draw`).
    Direct { first: u32 },
    /// Vertex `indices[first + i] + base_vertex` (`draw_indexed`, u32
    /// indices).
    Indexed { indices: &'a wgpu::Buffer, first: u32, base_vertex: i32 },
}

/// One draw as the pass issues it, for one instance.
#[derive(Debug, Clone, Copy)]
pub struct Draw<'a> {
    /// The vertex buffer (slot 0), when the stage has `@location` inputs.
    pub buffer: Option<&'a wgpu::Buffer>,
    pub vertices: Vertices<'a>,
    /// Vertices (or indices) drawn: one position each, in draw order.
    pub count: u32,
    /// `@builtin(instance_index)`.
    pub instance: u32,
}

/// The compute pipeline that captures positions for one vertex stage.
pub struct VertexCapture {
    pipeline: wgpu::ComputePipeline,
    group: u32,
    reads_vertices: bool,
    /// The shader's own bindings the vertex stage reads.
    resources: Vec<naga::ResourceBinding>,
    /// Bound as the indices of direct draws, which read none.
    no_indices: wgpu::Buffer,
}

impl VertexCapture {
    /// Instruments vertex entry point `entry` of `module` (the composed,
    /// validated module the render pipeline was built from), whose vertex
    /// buffer is laid out as `layout` (`None`: it draws without one), and
    /// creates its pipeline.
    pub fn new(
        device: &wgpu::Device,
        module: &naga::Module,
        entry: &str,
        layout: Option<&wgpu::VertexBufferLayout<'_>>,
    ) -> Result<VertexCapture, CaptureError> {
        let instrumented = instrument::instrument(module, entry, layout)?;
        let group = instrumented.group;
        let mut resources: Vec<naga::ResourceBinding> =
            instrumented.module.global_variables.iter().filter_map(|(_, g)| g.binding).filter(|b| b.group != group).collect();
        resources.sort_unstable_by_key(|b| (b.group, b.binding));
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("vertex capture"),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(instrumented.module)),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("vertex capture"),
            layout: None,
            module: &shader,
            entry_point: Some(&instrumented.entry),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(CaptureError::Pipeline(e.to_string()));
        }
        let no_indices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertex capture: no indices"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        Ok(VertexCapture { pipeline, group, reads_vertices: instrumented.reads_vertices, resources, no_indices })
    }

    /// Records the capture of `draw` into `encoder`. `layout` is the render
    /// pipeline's layout (`PipelineSpec::layout`) and `bindings` what the
    /// pass binds, by name; names the vertex stage does not read are
    /// ignored. Call [`PendingPositions::map`] once `encoder` is submitted.
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        layout: &[Option<&[Binding]>],
        bindings: &[(&'static str, wgpu::BindingResource<'_>)],
        draw: &Draw<'_>,
    ) -> Result<PendingPositions, CaptureError> {
        let limits = device.limits();
        let bytes = u64::from(draw.count) * 16;
        if draw.count == 0 {
            return Err(CaptureError::Draw("no vertices to capture".into()));
        }
        if bytes > crate::gpu::largest_binding(&limits) {
            return Err(CaptureError::Draw(format!("{} positions do not fit one storage buffer", draw.count)));
        }
        let workgroups = draw.count.div_ceil(instrument::WORKGROUP_SIZE);
        if workgroups > limits.max_compute_workgroups_per_dimension {
            return Err(CaptureError::Draw(format!("{} vertices need more workgroups than one dispatch has", draw.count)));
        }
        let (indices, first, base_vertex, indexed) = match draw.vertices {
            Vertices::Direct { first } => (&self.no_indices, first, 0, 0),
            Vertices::Indexed { indices, first, base_vertex } => {
                readable("index", indices)?;
                if u64::from(first) + u64::from(draw.count) > indices.size() / 4 {
                    return Err(CaptureError::Draw(format!(
                        "indices {first}..{} run past the index buffer's {}",
                        u64::from(first) + u64::from(draw.count),
                        indices.size() / 4
                    )));
                }
                (indices, first, base_vertex, 1)
            }
        };
        let params = DrawParams { count: draw.count, first, base_vertex, instance: draw.instance, indexed };
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertex capture: draw"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: bytes, usage, mapped_at_creation: false })
        };
        let positions = buffer("vertex capture: positions", wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer("vertex capture: readback", wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);

        let mut groups: Vec<Vec<wgpu::BindGroupEntry<'_>>> = vec![Vec::new(); self.group as usize + 1];
        for rb in &self.resources {
            let name = layout
                .get(rb.group as usize)
                .copied()
                .flatten()
                .and_then(|g| g.iter().find(|b| b.entry.binding == rb.binding))
                .ok_or(CaptureError::Unnamed { group: rb.group, binding: rb.binding })?
                .name;
            let (_, resource) = bindings.iter().find(|(n, _)| *n == name).ok_or(CaptureError::Unbound(name))?;
            groups[rb.group as usize].push(wgpu::BindGroupEntry { binding: rb.binding, resource: resource.clone() });
        }
        let own = &mut groups[self.group as usize];
        own.push(wgpu::BindGroupEntry { binding: binding::DRAW, resource: params.as_entire_binding() });
        own.push(wgpu::BindGroupEntry { binding: binding::INDICES, resource: indices.as_entire_binding() });
        own.push(wgpu::BindGroupEntry { binding: binding::POSITIONS, resource: positions.as_entire_binding() });
        if self.reads_vertices {
            let vertices =
                draw.buffer.ok_or_else(|| CaptureError::Draw("the vertex stage reads a vertex buffer; the draw has none".into()))?;
            readable("vertex", vertices)?;
            own.push(wgpu::BindGroupEntry { binding: binding::VERTICES, resource: vertices.as_entire_binding() });
        }
        // A group the kernel does not read (below its own) stays unset.
        let bind_groups: Vec<(u32, wgpu::BindGroup)> = (0..)
            .zip(&groups)
            .filter(|(_, entries)| !entries.is_empty())
            .map(|(i, entries)| {
                let layout = self.pipeline.get_bind_group_layout(i);
                (i, device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("vertex capture"), layout: &layout, entries }))
            })
            .collect();
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("vertex capture"), timestamp_writes: None });
            pass.set_pipeline(&self.pipeline);
            for (i, g) in &bind_groups {
                pass.set_bind_group(*i, g, &[]);
            }
            pass.dispatch_workgroups(workgroups, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&positions, 0, &readback, 0, bytes);
        Ok(PendingPositions { buffer: readback, mapped: Arc::new(OnceLock::new()) })
    }
}

/// A vertex or index buffer the kernel can bind as `array<u32>`.
fn readable(what: &str, buffer: &wgpu::Buffer) -> Result<(), CaptureError> {
    if !buffer.usage().contains(wgpu::BufferUsages::STORAGE) {
        return Err(CaptureError::Draw(format!("the {what} buffer lacks STORAGE usage, so it cannot be read by the capture")));
    }
    if !buffer.size().is_multiple_of(4) {
        return Err(CaptureError::Draw(format!("the {what} buffer's {} bytes are not whole words", buffer.size())));
    }
    Ok(())
}

/// Positions on their way back from the device.
pub struct PendingPositions {
    buffer: wgpu::Buffer,
    mapped: Arc<OnceLock<Result<(), wgpu::BufferAsyncError>>>,
}

impl PendingPositions {
    /// Starts the readback. Only after the encoder holding the capture is
    /// submitted: a buffer mapped earlier fails the submission.
    pub fn map(&self) {
        let mapped = self.mapped.clone();
        self.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = mapped.set(r);
        });
    }

    /// Whether the readback has completed (poll the device first).
    pub fn ready(&self) -> bool {
        self.mapped.get().is_some()
    }

    /// The clip-space positions, one per vertex invocation in draw order
    /// (an indexed draw's vertex shared by two triangles comes twice).
    pub fn read(self) -> Result<Vec<[f32; 4]>, CaptureError> {
        match self.mapped.get() {
            None => Err(CaptureError::Readback("not mapped yet: call map after submitting, then poll".into())),
            Some(Err(e)) => Err(CaptureError::Readback(e.to_string())),
            Some(Ok(())) => {
                let data = self.buffer.slice(..).get_mapped_range().map_err(|e| CaptureError::Readback(e.to_string()))?;
                Ok(bytemuck::pod_collect_to_vec(&data))
            }
        }
    }
}

#[cfg(test)]
mod tests;
