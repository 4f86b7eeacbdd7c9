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

/// A primitive's depth over the screen: depth at a pixel centre (x, y) is
/// `z0 + dx·(x - x0) + dy·(y - y0)`, plus `bias`.
pub(super) struct Surface {
    x0: f64,
    y0: f64,
    z0: f64,
    dx: f64,
    dy: f64,
    bias: f64,
}

pub(super) struct DepthTest<'a> {
    buffer: &'a mut [f32],
    width: usize,
    state: DepthState,
    range: [f64; 2],
}

impl<'a> DepthTest<'a> {
    /// `buffer` is the pass's depth buffer, `width` pixels a row.
    pub fn new(
        buffer: &'a mut [f32],
        width: u32,
        state: DepthState,
        viewport: &Viewport,
    ) -> DepthTest<'a> {
        let range = [f64::from(viewport.min_depth), f64::from(viewport.max_depth)];
        DepthTest {
            buffer,
            width: width as usize,
            state,
            range,
        }
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
        let mut bias = f64::from(b.constant) * unit(max_depth)
            + f64::from(b.slope_scale) * dx.abs().max(dy.abs());
        let clamp = f64::from(b.clamp);
        if clamp > 0.0 {
            bias = bias.min(clamp);
        } else if clamp < 0.0 {
            bias = bias.max(clamp);
        }
        Surface {
            x0,
            y0,
            z0: z[0],
            dx,
            dy,
            bias,
        }
    }

    /// The lanes of `mask` in block (bx, by) whose fragments pass, writing
    /// their depth when the pipeline writes depth.
    pub fn shade(&mut self, s: &Surface, bx: u32, by: u32, mask: u8) -> u8 {
        let mut passed = 0;
        for lane in (0..4).filter(|l| mask & 1 << l != 0) {
            let (x, y) = (
                (2 * bx + (lane & 1)) as usize,
                (2 * by + (lane >> 1)) as usize,
            );
            let at =
                s.z0 + s.dx * (x as f64 + 0.5 - s.x0) + s.dy * (y as f64 + 0.5 - s.y0) + s.bias;
            // The fragment's depth is an f32, as a Depth32Float buffer stores it.
            let fragment = at.clamp(self.range[0], self.range[1]) as f32;
            let stored = &mut self.buffer[y * self.width + x];
            if passes(
                self.state.compare,
                compare(fragment, *stored, self.state.tolerance),
            ) {
                passed |= 1 << lane;
                if self.state.write {
                    *stored = fragment;
                }
            }
        }
        passed
    }
}

/// The minimum resolvable difference r of a Depth32Float buffer around
/// `depth`: 2^(e - 23), e its exponent (that of the smallest normal f32 at 0).
fn unit(depth: f64) -> f64 {
    let exponent = (((depth.abs() as f32).to_bits() >> 23) as i32 - 127).max(-126);
    2f64.powi(exponent - 23)
}

/// Fragment against stored depth, equal within `tolerance`.
fn compare(fragment: f32, stored: f32, tolerance: f32) -> Ordering {
    let d = f64::from(fragment) - f64::from(stored);
    if d.abs() <= f64::from(tolerance) {
        Ordering::Equal
    } else {
        d.total_cmp(&0.0)
    }
}

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
