//! Triangle meshes the renderer draws: built-in shapes and meshes loaded
//! from glTF 2.0 files (`import`), all as one `MeshData` layout.
//!
//! Every failure to load a mesh is a `Diagnostic` pointing into the file the
//! user wrote (the .gltf, at the element at fault), and no input, however
//! broken or large, panics or exhausts memory: sizes are capped.

mod dependencies;
mod glb;
mod import;
pub(crate) mod json_path;
mod math;
mod shapes;
mod tangents;
pub(crate) mod uri;

#[cfg(test)]
mod tests;

pub use dependencies::external_buffers;
pub use import::Doc;
pub use import::{Parts, load_gltf, load_gltf_parts};
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

/// Bytes per vertex in `MeshData::vertex_bytes`: position and normal (three
/// f32 each), UV (two) and tangent (four).
pub const VERTEX_STRIDE: usize = 48;

/// The names `shape` knows, for "unknown shape" messages.
pub const SHAPES: [&str; 3] = ["sphere", "cube", "plane"];

/// Indexed triangles in object space, counter-clockwise front faces
/// (right-handed, +Y up). Per position: a unit normal, a UV (glTF's: origin
/// at the image's top left, v down) and a tangent.
///
/// Tangents follow glTF: xyz is a unit vector along increasing u,
/// perpendicular to the normal; w = ±1 is the handedness, so that the
/// bitangent `cross(normal, tangent.xyz) * w` points up the image
/// (decreasing v), where a tangent-space normal map's +Y (green) points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub tangents: Vec<[f32; 4]>,
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

    /// The vertex buffer's contents: per vertex, position (f32x3), normal
    /// (f32x3), UV (f32x2) and tangent (f32x4), `VERTEX_STRIDE` bytes, in
    /// the machine's byte order as `queue.write_buffer` expects.
    pub fn vertex_bytes(&self) -> Vec<u8> {
        let mut out: Vec<f32> = Vec::with_capacity(self.positions.len() * VERTEX_STRIDE / 4);
        for (((p, n), uv), t) in self.positions.iter().zip(&self.normals).zip(&self.uvs).zip(&self.tangents) {
            out.extend_from_slice(p);
            out.extend_from_slice(n);
            out.extend_from_slice(uv);
            out.extend_from_slice(t);
        }
        bytemuck::cast_slice(&out).to_vec()
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
