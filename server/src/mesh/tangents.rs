//! Tangents for meshes that come without them: MikkTSpace over the UVs (the
//! algorithm glTF prescribes, so a normal map baked by another tool reads
//! back as it was baked), and a unit vector perpendicular to the normal
//! where there are no UVs to follow.
//!
//! Whatever the input (zero-area UV triangles, collapsed positions), every
//! tangent comes out unit length and perpendicular to its normal: a NaN or
//! zero tangent would poison a normal map's shading.

use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};

use super::math::{Vec3, add, cross, dot, normalize_or_up, scale, sub};

/// `t` made perpendicular to the unit normal `n` and unit length
/// (Gram–Schmidt), or any unit vector perpendicular to `n` when `t` has no
/// part off the normal (zero, NaN, parallel).
pub fn orthonormal(t: Vec3, n: Vec3) -> Vec3 {
    let off = sub(t, scale(n, dot(n, t)));
    let len = dot(off, off).sqrt();
    // Below 1e-6 of the tangent's own length the direction is rounding.
    if len.is_finite() && len > 1e-6 * dot(t, t).sqrt() { scale(off, 1.0 / len) } else { perpendicular(n) }
}

/// A unit vector perpendicular to the unit vector `n`: `n` crossed with the
/// axis it is least aligned with.
pub fn perpendicular(n: Vec3) -> Vec3 {
    let a = n.map(f32::abs);
    let axis = if a[0] <= a[1] && a[0] <= a[2] {
        [1.0, 0.0, 0.0]
    } else if a[1] <= a[2] {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    normalize_or_up(cross(n, axis))
}

/// Tangents of a mesh without UVs: nothing to follow, so any perpendicular,
/// right-handed.
pub fn without_uvs(normals: &[Vec3]) -> Vec<[f32; 4]> {
    normals.iter().map(|&n| with_sign(perpendicular(n), 1.0)).collect()
}

/// MikkTSpace tangents of an indexed triangle mesh. A vertex shared by
/// triangles whose tangent spaces MikkTSpace splits keeps the last one
/// written (it welds vertices by position, normal and UV, so that happens
/// only where the UV mapping mirrors within one vertex).
pub fn mikktspace(positions: &[Vec3], normals: &[Vec3], uvs: &[[f32; 2]], indices: &[u32]) -> Vec<[f32; 4]> {
    let mut mesh = Mikk { positions, normals, uvs, indices, tangents: vec![None; positions.len()] };
    // The crate's error type has no variants yet; were one to come, the
    // vertices it left without a tangent get the fallback below.
    generate_tangents(&mut mesh).ok();
    mesh.tangents.iter().zip(normals).map(|(t, &n)| t.unwrap_or_else(|| with_sign(perpendicular(n), 1.0))).collect()
}

/// A tangent a file gives: made unit and perpendicular to the normal (as
/// exporters round them), w read by its sign (glTF says ±1).
pub fn given(t: [f32; 4], n: Vec3) -> [f32; 4] {
    with_sign(orthonormal([t[0], t[1], t[2]], n), if t[3] < 0.0 { -1.0 } else { 1.0 })
}

fn with_sign(t: Vec3, w: f32) -> [f32; 4] {
    [t[0], t[1], t[2], w]
}

struct Mikk<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [[f32; 2]],
    indices: &'a [u32],
    /// Per vertex, what MikkTSpace gave it (none for a vertex only on
    /// degenerate triangles with no neighbour to inherit from).
    tangents: Vec<Option<[f32; 4]>>,
}

impl Mikk<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face * 3 + vert] as usize
    }
}

impl Geometry for Mikk<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)]
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)]
    }

    /// v flipped: MikkTSpace's bitangent follows increasing v, and glTF's
    /// (up the image) follows decreasing v, as exporters that run
    /// MikkTSpace in a v-up space write it.
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let [u, v] = self.uvs[self.vertex(face, vert)];
        [u, 1.0 - v]
    }

    fn set_tangent(&mut self, space: Option<TangentSpace>, face: usize, vert: usize) {
        let i = self.vertex(face, vert);
        if let Some(space) = space {
            let [x, y, z, w] = space.tangent_encoded();
            self.tangents[i] = Some(with_sign(orthonormal([x, y, z], self.normals[i]), w));
        }
    }
}

/// A tangent carried through a node transform: xyz by the transform's
/// upper 3×3 (`column` k is its k-th column), renormalised against the
/// transformed normal `n`; handedness flipped by a mirroring transform.
pub fn transform(t: [f32; 4], columns: &[Vec3; 3], mirrors: bool, n: Vec3) -> [f32; 4] {
    let xyz = add(add(scale(columns[0], t[0]), scale(columns[1], t[1])), scale(columns[2], t[2]));
    with_sign(orthonormal(xyz, n), if mirrors { -t[3] } else { t[3] })
}
