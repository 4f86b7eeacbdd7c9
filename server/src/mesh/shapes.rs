//! Built-in shapes, generated: nothing to load, nothing to fail.

use super::MeshData;
use super::math::{Vec3, add, cross, normalize_or_up, scale};

/// Longitude segments and latitude bands of `sphere`: at 48 × 24 the outline
/// of a sphere filling a 1080p frame shows no visible facets under smooth
/// shading.
const SEGMENTS: u32 = 48;
const BANDS: u32 = 24;

/// Unit sphere (radius 1) with smooth normals. Poles are single vertices:
/// there are no texture coordinates, so nothing needs a seam.
pub fn sphere() -> MeshData {
    let mut m = MeshData::default();
    let mut push = |p: Vec3| {
        m.positions.push(p);
        m.normals.push(p);
    };
    push([0.0, 1.0, 0.0]);
    for band in 1..BANDS {
        let theta = std::f32::consts::PI * band as f32 / BANDS as f32;
        for seg in 0..SEGMENTS {
            let phi = std::f32::consts::TAU * seg as f32 / SEGMENTS as f32;
            // sin/cos are within an ulp of unit length; normalise so the
            // radius is exactly 1 to f32 precision.
            let p = [theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()];
            push(normalize_or_up(p));
        }
    }
    push([0.0, -1.0, 0.0]);
    let south = m.positions.len() as u32 - 1;
    // Vertex `seg` of ring `ring` (1-based ring, wrapping around).
    let v = |ring: u32, seg: u32| 1 + (ring - 1) * SEGMENTS + seg % SEGMENTS;
    for seg in 0..SEGMENTS {
        // Longitude grows counter-clockwise seen from +Y (phi from +X
        // towards −Z), so ring order (seg, seg+1) runs counter-clockwise.
        m.indices.extend([0, v(1, seg), v(1, seg + 1)]);
        for ring in 1..BANDS - 1 {
            let (a, b, c, d) = (v(ring, seg), v(ring + 1, seg), v(ring + 1, seg + 1), v(ring, seg + 1));
            m.indices.extend([a, b, c, a, c, d]);
        }
        m.indices.extend([v(BANDS - 1, seg), south, v(BANDS - 1, seg + 1)]);
    }
    m
}

/// Cube from −1 to 1 on every axis, 4 vertices per face so each face has its
/// own flat normal.
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
        face(&mut m, e(k), e(k + 1), e(k + 2));
        face(&mut m, scale(e(k), -1.0), e(k + 2), e(k + 1));
    }
    m
}

/// The XZ square from −1 to 1, facing +Y.
pub fn plane() -> MeshData {
    let mut m = MeshData::default();
    // (0, 0, 1) × (1, 0, 0) = (0, 1, 0)
    face(&mut m, [0.0; 3], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
    m
}

/// A square centred on `center`, spanned by `u` and `v` (each from −1 to 1),
/// facing `u × v`, counter-clockwise seen from that side.
fn face(m: &mut MeshData, center: Vec3, u: Vec3, v: Vec3) {
    let base = m.positions.len() as u32;
    let normal = cross(u, v);
    for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        m.positions.push(add(center, add(scale(u, su), scale(v, sv))));
        m.normals.push(normal);
    }
    m.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
}
