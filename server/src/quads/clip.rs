//! From clip space to the framebuffer, and the clipping a rasterizer does
//! before it snaps: against the near and far planes (0 <= z <= w, wgpu's
//! D3D-like clip volume) and w > 0, which decide what is drawn, and against
//! a guard band far outside any target, which changes no covered pixel and
//! only keeps snapped coordinates small enough for exact i64 edge
//! functions. x and y are not clipped to the viewport: coverage is bounded
//! by the pixel rectangle instead, so the fullscreen triangle
//! (-1,-1),(3,-1),(-1,3) is rasterized from its own, exact vertices.

use super::input::Viewport;

/// The guard band's half-width in pixels, around the framebuffer origin:
/// 2^20, 32 times the largest target (2^15), so it never cuts into one.
/// Inside it a position snaps to at most 2^28 sub-pixel units, and edge
/// functions over the target stay below 2^60.
const GUARD_BAND: f64 = (1u64 << 20) as f64;

/// A vertex in framebuffer homogeneous coordinates (X, Y, z, w): X/w and Y/w
/// are its framebuffer position in pixels (y down), z/w its NDC depth.
pub(super) type Homogeneous = [f64; 4];

/// Planes a vertex can lie outside of, one bit each in an outcode.
const NEAR: u8 = 1;
const FAR: u8 = 2;
const W_POSITIVE: u8 = 4;
/// The planes that decide what is drawn: a primitive clipped away by them
/// is culled.
pub(super) const DEPTH_PLANES: u8 = NEAR | FAR | W_POSITIVE;
const PLANES: usize = 7;
/// The most vertices a clipped triangle can have: its own three plus one
/// per plane.
pub(super) const MAX_VERTICES: usize = 3 + PLANES;
/// Set on a vertex with a NaN or infinite coordinate; GPUs drop such
/// primitives, and the model culls them.
pub(super) const NON_FINITE: u8 = 0x80;

/// A primitive being clipped: a convex polygon.
pub(super) struct Polygon {
    pub v: [Homogeneous; MAX_VERTICES],
    pub n: usize,
}

/// The viewport transform, applied before the divide by w so that clipping
/// and snapping see the same numbers for a vertex.
pub(super) struct Framebuffer {
    centre: [f64; 2],
    half: [f64; 2],
}

impl Framebuffer {
    pub fn new(viewport: &Viewport) -> Framebuffer {
        let half = [f64::from(viewport.width) / 2.0, f64::from(viewport.height) / 2.0];
        let centre = [f64::from(viewport.x) + half[0], f64::from(viewport.y) + half[1]];
        Framebuffer { centre, half }
    }

    /// X/w = x0 + (x/w + 1)·width/2; Y/w = y0 + (1 - y/w)·height/2 (NDC y is up).
    pub fn map(&self, [x, y, z, w]: [f32; 4]) -> Homogeneous {
        let [x, y, z, w] = [x, y, z, w].map(f64::from);
        [self.centre[0] * w + self.half[0] * x, self.centre[1] * w - self.half[1] * y, z, w]
    }
}

/// How far inside `plane` a vertex is (inside when >= 0).
fn distance(plane: usize, [x, y, z, w]: &Homogeneous) -> f64 {
    match plane {
        0 => *z,
        1 => w - z,
        // w = 0 passes the near and far planes at the homogeneous origin,
        // where X/w is undefined.
        2 => w - f64::MIN_POSITIVE,
        3 => x + GUARD_BAND * w,
        4 => GUARD_BAND * w - x,
        5 => y + GUARD_BAND * w,
        _ => GUARD_BAND * w - y,
    }
}

/// The planes `v` is outside of, or `NON_FINITE`.
pub(super) fn outcode(v: &Homogeneous) -> u8 {
    if !v.iter().all(|c| c.is_finite()) {
        return NON_FINITE;
    }
    (0..PLANES).filter(|&p| distance(p, v) < 0.0).fold(0, |code, p| code | 1 << p)
}

impl Polygon {
    pub fn triangle(v: [Homogeneous; 3]) -> Polygon {
        let mut p = Polygon { v: [[0.0; 4]; MAX_VERTICES], n: 3 };
        p.v[..3].copy_from_slice(&v);
        p
    }

    /// Sutherland–Hodgman against the planes set in `planes` (an outcode
    /// mask). A vertex inside a plane is kept bit for bit, so a triangle's
    /// unclipped vertices snap exactly as its neighbours' do; a new vertex
    /// is interpolated from the inside end of its edge, so the two
    /// triangles sharing a clipped edge get the same point.
    pub fn clip(&mut self, planes: u8) {
        for plane in (0..PLANES).filter(|p| planes & 1 << p != 0) {
            let input = std::mem::replace(self, Polygon { v: [[0.0; 4]; MAX_VERTICES], n: 0 });
            for i in 0..input.n {
                let (a, b) = (input.v[i], input.v[(i + 1) % input.n]);
                let (da, db) = (distance(plane, &a), distance(plane, &b));
                if da >= 0.0 {
                    self.push(a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    let (inside, di, outside, dout) = if da >= 0.0 { (a, da, b, db) } else { (b, db, a, da) };
                    let t = di / (di - dout);
                    self.push(std::array::from_fn(|k| inside[k] + t * (outside[k] - inside[k])));
                }
            }
        }
    }

    fn push(&mut self, v: Homogeneous) {
        // Each plane adds at most one vertex to a convex polygon; the bound
        // only guards against rounding making a plane look non-convex.
        if self.n < self.v.len() {
            self.v[self.n] = v;
            self.n += 1;
        }
    }
}

/// The sign of the determinant of (X, Y, w) rows: w0·w1·w2 times twice the
/// framebuffer area, and for a triangle crossing w = 0 the orientation of
/// the part in front of the eye. Positive: clockwise on screen (y down).
pub(super) fn orientation([a, b, c]: &[Homogeneous; 3]) -> f64 {
    a[0] * (b[1] * c[3] - c[1] * b[3]) - b[0] * (a[1] * c[3] - c[1] * a[3]) + c[0] * (a[1] * b[3] - b[1] * a[3])
}
