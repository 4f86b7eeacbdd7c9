//! HDR-FLIP (Andersson et al., "Visualizing Errors in Rendered High
//! Dynamic Range Images", Eurographics 2021) over the binding's LDR-FLIP:
//! both images are exposed at a range of exposures, tonemapped with ACES,
//! clamped, and compared with LDR-FLIP; a pixel's error is its largest over
//! the exposures. The range comes from the reference's luminance, as in
//! FLIP's `computeExposures`: the first exposure maps its brightest pixel,
//! the last its median, to where the tonemapper reaches 0.85.
//!
//! The binding reads 8-bit sRGB only, so each tonemapped image is encoded
//! to 8 bits before the comparison; FLIP's own tool compares the floats.
//! That quantisation is the one difference (measured in docs/images.md).

use super::{ErrorMap, Linear, Srgb8, encode_srgb8, ldr};

/// FLIP's ACES fit, `(a·x² + b·x + c) / (d·x² + e·x + f)`, with its 0.6
/// pre-exposure folded in.
const ACES: [f32; 6] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// The exposures (in stops) HDR-FLIP evaluates, evenly spaced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: u32,
}

impl Exposures {
    fn each(&self) -> impl Iterator<Item = f32> + '_ {
        let step = if self.count > 1 { (self.stop - self.start) / (self.count - 1) as f32 } else { 0.0 };
        (0..self.count).map(move |i| self.start + i as f32 * step)
    }
}

/// The exposure range `reference` calls for. A black reference (or one
/// whose median is black) has no range to speak of: its exposure 0 is
/// used, twice as FLIP's minimum count asks.
pub fn exposures(reference: Linear) -> Exposures {
    let t = 0.85f32;
    let (a, b, c) = (ACES[0] - t * ACES[3], ACES[1] - t * ACES[4], ACES[2] - t * ACES[5]);
    // The larger root of a·x² + b·x + c = 0: the input the tonemapper
    // maps to t.
    let d1 = -0.5 * (b / a);
    let x_max = d1 + (d1 * d1 - c / a).sqrt();
    let mut luminance: Vec<f32> =
        reference.rgba.chunks_exact(4).map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]).filter(|y| y.is_finite()).collect();
    if luminance.is_empty() {
        return Exposures { start: 0.0, stop: 0.0, count: 2 };
    }
    let y_max = luminance.iter().copied().fold(f32::MIN, f32::max);
    let middle = luminance.len() / 2;
    let y_median = *luminance.select_nth_unstable_by(middle, f32::total_cmp).1;
    let start = if y_max > 0.0 { (x_max / y_max).log2() } else { 0.0 };
    let stop = if y_median > 0.0 { (x_max / y_median).log2() } else { start };
    Exposures { start, stop, count: (stop - start).ceil().max(2.0) as u32 }
}

/// The per-pixel largest LDR-FLIP error over `exposures`.
pub(super) fn flip(reference: Linear, test: Linear, exposures: Exposures) -> ErrorMap {
    let (w, h) = (reference.width, reference.height);
    let mut out = ErrorMap { width: w, height: h, values: vec![0.0; w as usize * h as usize] };
    for exposure in exposures.each() {
        let (r, t) = (tonemapped(reference.rgba, exposure), tonemapped(test.rgba, exposure));
        let map = ldr(Srgb8 { width: w, height: h, rgb: &r }, Srgb8 { width: w, height: h, rgb: &t }).expect("sizes checked by the caller");
        for (o, v) in out.values.iter_mut().zip(map.values) {
            *o = o.max(v);
        }
    }
    out
}

/// `rgba` scaled by 2^exposure, through ACES, as 8-bit sRGB.
fn tonemapped(rgba: &[f32], exposure: f32) -> Vec<u8> {
    let m = exposure.exp2();
    let aces = |x: f32| {
        let x = x * m;
        (x * x * ACES[0] + x * ACES[1] + ACES[2]) / (x * x * ACES[3] + x * ACES[4] + ACES[5])
    };
    let mapped: Vec<f32> = rgba.chunks_exact(4).flat_map(|p| [aces(p[0]), aces(p[1]), aces(p[2]), p[3]]).collect();
    encode_srgb8(&mapped)
}
