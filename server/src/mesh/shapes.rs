//! Built-in shapes, generated: nothing to load, nothing to fail. Each has
//! UVs and its analytic tangents (along dP/du, glTF's handedness).

use super::MeshData;
use super::math::{Vec3, add, cross, dot, normalize_or_up, scale, sub};

/// Longitude segments and latitude bands of `sphere`: at 48 × 24 the outline
/// of a sphere filling a 1080p frame shows no visible facets under smooth
/// shading.
const SEGMENTS: u32 = 48;
const BANDS: u32 = 24;

/// Unit sphere (radius 1) with smooth normals, UVs by longitude (u = φ/2π,
/// φ from +X towards −Z) and latitude (v = θ/π, 0 at the north pole, so the
/// image's top is north). The seam at φ = 0 is two columns of vertices at
/// the same positions (u = 0 and u = 1), and each pole is one vertex per
/// segment, at the segment's middle u, so no triangle's UVs wrap or
/// collapse.
pub fn sphere() -> MeshData {
    let mut m = MeshData::default();
    // Seam vertices take segment 0's angle, so their positions are bit for
    // bit those of segment 0 and the mesh stays closed.
    let angle = |seg: u32| std::f32::consts::TAU * (seg % SEGMENTS) as f32 / SEGMENTS as f32;
    // dP/dφ, towards growing u; at a pole the limit along its segment.
    let east = |phi: f32| [-phi.sin(), 0.0, -phi.cos()];
    let mut push = |p: Vec3, uv: [f32; 2], t: Vec3| {
        m.positions.push(p);
        m.normals.push(p);
        m.uvs.push(uv);
        // cross(n, east) points north, up the image: right-handed.
        m.tangents.push([t[0], t[1], t[2], 1.0]);
    };
    let middle = |seg: u32| (seg as f32 + 0.5) / SEGMENTS as f32;
    for seg in 0..SEGMENTS {
        push([0.0, 1.0, 0.0], [middle(seg), 0.0], east(std::f32::consts::TAU * middle(seg)));
    }
    for band in 1..BANDS {
        let theta = std::f32::consts::PI * band as f32 / BANDS as f32;
        for seg in 0..=SEGMENTS {
            let phi = angle(seg);
            // sin/cos are within an ulp of unit length; normalise so the
            // radius is exactly 1 to f32 precision.
            let p = [theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()];
            push(normalize_or_up(p), [seg as f32 / SEGMENTS as f32, band as f32 / BANDS as f32], east(phi));
        }
    }
    for seg in 0..SEGMENTS {
        push([0.0, -1.0, 0.0], [middle(seg), 1.0], east(std::f32::consts::TAU * middle(seg)));
    }
    let north = |seg: u32| seg;
    // Vertex `seg` (0 to SEGMENTS) of ring `ring` (1-based).
    let v = |ring: u32, seg: u32| SEGMENTS + (ring - 1) * (SEGMENTS + 1) + seg;
    let south = |seg: u32| v(BANDS, 0) + seg;
    for seg in 0..SEGMENTS {
        // Longitude grows counter-clockwise seen from +Y (phi from +X
        // towards −Z), so ring order (seg, seg+1) runs counter-clockwise.
        m.indices.extend([north(seg), v(1, seg), v(1, seg + 1)]);
        for ring in 1..BANDS - 1 {
            let (a, b, c, d) = (v(ring, seg), v(ring + 1, seg), v(ring + 1, seg + 1), v(ring, seg + 1));
            m.indices.extend([a, b, c, a, c, d]);
        }
        m.indices.extend([v(BANDS - 1, seg), south(seg), v(BANDS - 1, seg + 1)]);
    }
    m
}

/// Cube from −1 to 1 on every axis, 4 vertices per face so each face has its
/// own flat normal. Each face's UVs run 0 to 1 along its own axes.
pub fn cube() -> MeshData {
    let e = |k: usize| {
        let mut v = [0.0; 3];
        v[k % 3] = 1.0;
        v
    };
    let mut m = MeshData::default();
    for k in 0..3 {
        // u × v = n for both faces of axis k: e(k+1) × e(k+2) = e(k), and
        // e(k+2) × e(k+1) = −e(k).
        face(&mut m, e(k), [e(k + 1), e(k + 2)], [e(k + 1), e(k + 2)]);
        face(&mut m, scale(e(k), -1.0), [e(k + 2), e(k + 1)], [e(k + 2), e(k + 1)]);
    }
    m
}

/// The XZ square from −1 to 1, facing +Y. Its UVs run 0 to 1 with u along
/// +X and the image's top towards −Z: upright seen from +Z.
pub fn plane() -> MeshData {
    let mut m = MeshData::default();
    // (0, 0, 1) × (1, 0, 0) = (0, 1, 0)
    face(&mut m, [0.0; 3], [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]);
    m
}

/// A square centred on `center`, spanned by `span` = [u, v] (each from −1
/// to 1), facing `u × v`, counter-clockwise seen from that side. Its UVs
/// run from 0 to 1 along `texture` = [the axis u grows along, the axis the
/// image's top lies towards] (unit, in the square's plane).
fn face(m: &mut MeshData, center: Vec3, span: [Vec3; 2], texture: [Vec3; 2]) {
    let base = m.positions.len() as u32;
    let [u, v] = span;
    let normal = cross(u, v);
    let [right, up] = texture;
    let w = if dot(cross(normal, right), up) > 0.0 { 1.0 } else { -1.0 };
    for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let p = add(center, add(scale(u, su), scale(v, sv)));
        let d = sub(p, center);
        m.positions.push(p);
        m.normals.push(normal);
        m.uvs.push([(dot(d, right) + 1.0) * 0.5, (1.0 - dot(d, up)) * 0.5]);
        m.tangents.push([right[0], right[1], right[2], w]);
    }
    m.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
}
