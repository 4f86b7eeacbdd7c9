//! What the path tracer traces: the hierarchy over the raster's own
//! triangles (`crate::bvh`) on the GPU, and per triangle the data a hit
//! shades with. Built only for scenes that are path traced, and the
//! hierarchy only when the triangles changed: a scene edit that moves a
//! light or changes a material keeps it.
//!
//! Layouts (mirroring `shaders/lib/bvh.wgsl` and `passes/path_trace.wgsl`):
//! `nodes` and `triangles` as `crate::bvh` documents; `shading` per
//! triangle in leaf order, one `Shading`.

use std::sync::Arc;

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::bvh::{BuildStats, Bvh};

/// One `Shading` of path_trace.wgsl, eight `vec4<f32>`: the three vertices'
/// world-space normals (the material index in the first one's `w`), their
/// world-space tangents (w: handedness), then their UVs (a and b in the
/// seventh, c in the eighth's xy).
pub type Shading = [[f32; 4]; 8];

/// A world-space triangle and its `[object, primitive]`.
pub type SourceTriangle = ([Vec3; 3], [u32; 2]);

/// The hierarchy on the GPU and what it was built from.
struct Hierarchy {
    source: Vec<SourceTriangle>,
    ids: Vec<[u32; 2]>,
    nodes: wgpu::Buffer,
    triangles: wgpu::Buffer,
    stats: BuildStats,
}

pub struct PathGeometry {
    hierarchy: Arc<Hierarchy>,
    pub shading: wgpu::Buffer,
}

impl PathGeometry {
    /// Builds over `source`, or keeps `previous`'s hierarchy when it was
    /// built from the same triangles. `shade(ids)` gives each triangle's
    /// `Shading`, in the hierarchy's order.
    pub fn new(
        device: &wgpu::Device,
        source: Vec<SourceTriangle>,
        previous: Option<&PathGeometry>,
        shade: impl Fn(&[[u32; 2]]) -> Vec<Shading>,
    ) -> Self {
        let hierarchy = match previous {
            Some(p) if p.hierarchy.source == source => p.hierarchy.clone(),
            _ => {
                let bvh = Bvh::build(&source);
                let stats = bvh.stats.clone();
                log::info!("path tracer: built a hierarchy of {} nodes over {} triangles", stats.nodes, stats.triangles);
                Arc::new(Hierarchy {
                    nodes: storage(device, "bvh nodes", bytemuck::cast_slice(&bvh.nodes)),
                    triangles: storage(device, "bvh triangles", bytemuck::cast_slice(&bvh.triangles)),
                    ids: bvh.ids,
                    source,
                    stats,
                })
            }
        };
        let shading = storage(device, "path shading", bytemuck::cast_slice(&shade(&hierarchy.ids)));
        PathGeometry { hierarchy, shading }
    }

    pub fn nodes(&self) -> &wgpu::Buffer {
        &self.hierarchy.nodes
    }

    pub fn triangles(&self) -> &wgpu::Buffer {
        &self.hierarchy.triangles
    }

    pub fn stats(&self) -> &BuildStats {
        &self.hierarchy.stats
    }

    /// Whether `other` shares this one's hierarchy (it was not rebuilt).
    pub fn same_hierarchy(&self, other: &PathGeometry) -> bool {
        Arc::ptr_eq(&self.hierarchy, &other.hierarchy)
    }
}

/// A read-only storage buffer; an empty one gets zeroed room for one
/// element of the largest kind (`Shading`), as bindings may not be empty
/// and a dispatch checks a binding against the shader's element size.
fn storage(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let padded;
    let contents = if bytes.is_empty() {
        padded = vec![0u8; size_of::<Shading>()];
        &padded
    } else {
        bytes
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage: wgpu::BufferUsages::STORAGE })
}

#[cfg(test)]
mod tests;
