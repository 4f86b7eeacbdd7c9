//! Triangle meshes the renderer draws: built-in shapes and meshes loaded
//! from glTF 2.0 files (`import`), all as one `MeshData` layout.
//!
//! Every failure to load a mesh is a `Diagnostic` pointing into the file the
//! user wrote (the .gltf, at the element at fault), and no input, however
//! broken or large, panics or exhausts memory: sizes are capped.

mod dependencies;
mod glb;
mod import;
mod json_path;
mod math;
mod shapes;
mod uri;

#[cfg(test)]
mod tests;

pub use dependencies::external_buffers;
pub use import::load_gltf;
pub use shapes::{cube, plane, sphere};

/// The most triangles a mesh may have: 16 Mi, an index buffer of 192 MiB,
/// under wgpu's default 256 MiB `max_buffer_size`.
pub const MAX_TRIANGLES: usize = 16 << 20;

/// The most vertices a mesh may have: 8 Mi, a vertex buffer of 192 MiB
/// (`VERTEX_STRIDE` bytes each), under the same limit.
pub const MAX_VERTICES: usize = 8 << 20;

/// The largest file loupe reads for a mesh (.gltf, .glb), and the most all
/// its buffers may hold together.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// Bytes per vertex in `MeshData::vertex_bytes`: position then normal, each
/// three f32.
pub const VERTEX_STRIDE: usize = 24;

/// The names `shape` knows, for "unknown shape" messages.
pub const SHAPES: [&str; 3] = ["sphere", "cube", "plane"];

/// Indexed triangles in object space, counter-clockwise front faces
/// (right-handed, +Y up). Normals are unit length, one per position.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

impl MeshData {
    /// Axis-aligned (min, max) corners; both zero for an empty mesh.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let Some(&first) = self.positions.first() else {
            return ([0.0; 3], [0.0; 3]);
        };
        self.positions.iter().fold((first, first), |(mut lo, mut hi), p| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            (lo, hi)
        })
    }

    /// The vertex buffer's contents: per vertex, position then normal as
    /// f32x3 each (`VERTEX_STRIDE` bytes), in the machine's byte order as
    /// `queue.write_buffer` expects.
    pub fn vertex_bytes(&self) -> Vec<u8> {
        let interleaved: Vec<[[f32; 3]; 2]> = self.positions.iter().zip(&self.normals).map(|(&p, &n)| [p, n]).collect();
        bytemuck::cast_slice(&interleaved).to_vec()
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// A built-in shape by name (see `SHAPES`).
pub fn shape(name: &str) -> Option<MeshData> {
    match name {
        "sphere" => Some(sphere()),
        "cube" => Some(cube()),
        "plane" => Some(plane()),
        _ => None,
    }
}
