//! The depth test, run in primitive order over the pass's depth buffer:
//! which covered pixels of a block pass (and so which lanes of a launched
//! quad shade rather than help), and the depth they write.
//!
//! A primitive's NDC depth z/w is affine in screen space, so its depth at a
//! pixel centre is a plane through its snapped vertices, mapped to the
//! viewport's depth range, offset by the depth bias and clamped to the
//! range. The GPU computes the same plane in its own precision; depths
//! closer than the tolerance compare as equal (see `DEPTH_TOLERANCE`).

use std::cmp::Ordering;

use super::input::{Compare, DepthState, Viewport};
use super::raster;

/// A primitive's depth over the screen, bias included: `c + dx·x + dy·y`
/// at the centre (x + 0.5, y + 0.5) of pixel (x, y).
pub(super) struct Surface {
    c: f64,
    dx: f64,
    dy: f64,
}

pub(super) struct DepthTest<'a> {
    /// The depth buffer's rows from `first_row` on.
    buffer: &'a mut [f32],
    first_row: usize,
    width: usize,
    state: DepthState,
    range: [f64; 2],
    /// Whether a fragment passes when it is less than, equal to (within the
    /// tolerance) or greater than the stored depth.
    passes: [bool; 3],
}

impl<'a> DepthTest<'a> {
    /// `buffer` holds rows `first_row` on of the pass's depth buffer,
    /// `width` pixels a row.
    pub fn new(buffer: &'a mut [f32], first_row: u32, width: u32, state: DepthState, viewport: &Viewport) -> DepthTest<'a> {
        let range = [f64::from(viewport.min_depth), f64::from(viewport.max_depth)];
        let passes = [Ordering::Less, Ordering::Equal, Ordering::Greater].map(|o| passes(state.compare, o));
        DepthTest { buffer, first_row: first_row as usize, width: width as usize, state, range, passes }
    }

    /// The depth range value of an NDC depth.
    pub fn depth(&self, ndc: f64) -> f64 {
        self.range[0] + ndc * (self.range[1] - self.range[0])
    }

    /// The surface of a triangle (snapped vertices, their depths from
    /// `depth`) belonging to a primitive whose largest vertex depth is
    /// `max_depth`: that depth sets the unit of the constant bias.
    pub fn surface(&self, v: &[[i64; 2]; 3], z: [f64; 3], max_depth: f64) -> Surface {
        let [x0, x1, x2] = v.map(|p| raster::pixels(p[0]));
        let [y0, y1, y2] = v.map(|p| raster::pixels(p[1]));
        let area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
        let dx = ((z[1] - z[0]) * (y2 - y0) - (z[2] - z[0]) * (y1 - y0)) / area;
        let dy = ((x1 - x0) * (z[2] - z[0]) - (x2 - x0) * (z[1] - z[0])) / area;
        let b = self.state.bias;
        let mut bias = f64::from(b.constant) * unit(max_depth) + f64::from(b.slope_scale) * dx.abs().max(dy.abs());
        let clamp = f64::from(b.clamp);
        if clamp > 0.0 {
            bias = bias.min(clamp);
        } else if clamp < 0.0 {
            bias = bias.max(clamp);
        }
        Surface { c: z[0] + bias - dx * (x0 - 0.5) - dy * (y0 - 0.5), dx, dy }
    }

    /// The lanes of `mask` in block (bx, by) whose fragments pass, writing
    /// their depth when the pipeline writes depth.
    pub fn shade(&mut self, s: &Surface, bx: u32, by: u32, mask: u8) -> u8 {
        let (x, y) = (2 * bx as usize, 2 * by as usize);
        let at = (y - self.first_row) * self.width + x;
        let mut passed = 0;
        let ats = [at, at + 1, at + self.width, at + self.width + 1];
        for (lane, (z, at)) in lanes(s, bx, by).into_iter().zip(ats).enumerate() {
            // An uncovered lane may lie outside the target.
            if mask & 1 << lane != 0 && self.test(z, at) {
                passed |= 1 << lane;
            }
        }
        passed
    }

    /// The depth `shade` tests lane `lane` (bit of its mask) of block
    /// (bx, by) at.
    pub fn fragment(&self, s: &Surface, bx: u32, by: u32, lane: usize) -> f32 {
        self.stored(lanes(s, bx, by)[lane])
    }

    /// The fragment's depth is an f32, as a Depth32Float buffer stores it.
    fn stored(&self, z: f64) -> f32 {
        z.clamp(self.range[0], self.range[1]) as f32
    }

    /// Tests (and writes) the fragment at depth `z` of buffer entry `at`.
    fn test(&mut self, z: f64, at: usize) -> bool {
        let fragment = self.stored(z);
        let stored = &mut self.buffer[at];
        let d = f64::from(fragment) - f64::from(*stored);
        let tolerance = f64::from(self.state.tolerance);
        // 0: less, 1: equal within the tolerance, 2: greater.
        let class = usize::from(d >= -tolerance) + usize::from(d > tolerance);
        let pass = self.passes[class];
        if pass && self.state.write {
            *stored = fragment;
        }
        pass
    }
}

/// The surface's depth at the centres of block (bx, by)'s lanes, in order:
/// (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1).
fn lanes(s: &Surface, bx: u32, by: u32) -> [f64; 4] {
    let top_left = s.c + s.dx * f64::from(2 * bx) + s.dy * f64::from(2 * by);
    [top_left, top_left + s.dx, top_left + s.dy, top_left + s.dx + s.dy]
}

/// The minimum resolvable difference r of a Depth32Float buffer around
/// `depth`: 2^(e - 23), e its exponent (that of the smallest normal f32 at 0).
fn unit(depth: f64) -> f64 {
    let exponent = (((depth.abs() as f32).to_bits() >> 23) as i32 - 127).max(-126);
    2f64.powi(exponent - 23)
}

/// Whether `f` passes a fragment that compares `o` to the stored depth.
fn passes(f: Compare, o: Ordering) -> bool {
    match f {
        Compare::Never => false,
        Compare::Less => o.is_lt(),
        Compare::Equal => o.is_eq(),
        Compare::LessEqual => o.is_le(),
        Compare::Greater => o.is_gt(),
        Compare::NotEqual => o.is_ne(),
        Compare::GreaterEqual => o.is_ge(),
        Compare::Always => true,
    }
}
