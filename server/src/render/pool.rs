//! GPU memory behind the graph's handles. Frame resources are reused while
//! the next graph describes them the same way; history resources are kept
//! by name across frames and dropped only when their description changes,
//! the graph stops using them, or `reset_history` is called.

use std::collections::HashMap;

use super::graph::{Graph, Resource};
use super::resource::{Handle, Lifetime, Physical, ResourceDesc, TextureKind};

#[derive(Default)]
pub struct ResourcePool {
    /// Keyed by the whole description (name, shape, usage, lifetime).
    entries: HashMap<Resource, Physical>,
}

impl ResourcePool {
    /// Allocates whatever the graph's used resources lack, and drops what
    /// it no longer uses.
    pub fn prepare(&mut self, device: &wgpu::Device, graph: &Graph) {
        let used: Vec<&Resource> = graph.used().into_iter().map(|h| graph.resource(h)).collect();
        self.entries.retain(|k, _| used.contains(&k));
        for r in used {
            if !self.entries.contains_key(r) {
                self.entries.insert(r.clone(), allocate(device, r));
            }
        }
    }

    /// The memory of `h`; `prepare` must have seen this graph.
    pub fn get<'p>(&'p self, graph: &Graph, h: Handle) -> &'p Physical {
        &self.entries[graph.resource(h)]
    }

    /// The memory of `h`, when the pool holds it (a culled resource has none).
    pub fn try_get<'p>(&'p self, graph: &Graph, h: Handle) -> Option<&'p Physical> {
        self.entries.get(graph.resource(h))
    }

    /// Forgets every history resource: the next frame starts from zeros.
    pub fn reset_history(&mut self) {
        self.entries.retain(|k, _| k.lifetime != Lifetime::History);
    }

    /// Forgets the history resources pass `pass` keeps.
    pub fn reset_history_of(&mut self, pass: &str) {
        self.entries.retain(|k, _| k.lifetime != Lifetime::History || k.name.split_once('/').is_none_or(|(p, _)| p != pass));
    }
}

fn allocate(device: &wgpu::Device, r: &Resource) -> Physical {
    match &r.desc {
        ResourceDesc::Texture(d) => {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&r.name),
                size: wgpu::Extent3d { width: d.width, height: d.height, depth_or_array_layers: d.layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: if d.kind == TextureKind::D3 { wgpu::TextureDimension::D3 } else { wgpu::TextureDimension::D2 },
                format: d.format,
                usage: r.texture_usage,
                view_formats: &[],
            });
            let dimension = match d.kind {
                TextureKind::D2 => wgpu::TextureViewDimension::D2,
                TextureKind::D2Array => wgpu::TextureViewDimension::D2Array,
                TextureKind::D3 => wgpu::TextureViewDimension::D3,
            };
            let view = texture.create_view(&wgpu::TextureViewDescriptor { dimension: Some(dimension), ..Default::default() });
            Physical::Texture { texture, view }
        }
        // wgpu zeroes new buffers: a new history buffer reads as "no
        // history yet".
        ResourceDesc::Buffer(t) => Physical::Buffer(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&r.name),
            size: t.bytes().max(4).next_multiple_of(4),
            usage: r.buffer_usage,
            mapped_at_creation: false,
        })),
    }
}
