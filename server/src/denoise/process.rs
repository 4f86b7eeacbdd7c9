//! OIDN's processing around the network, for its `RT` filter: the input
//! scale, sanitising, the transfer function into the space the network was
//! trained in, normals to [0, 1], zero padding to the network's alignment;
//! and back: sanitising, the inverse transfer, cropping, the output scale.
//!
//! Sources (OIDN, github.com/RenderKit/oidn): `core/color.h` and
//! `core/color.cpp` (transfer functions and their constants),
//! `core/rt_filter.cpp` (`newTransferFunc`: which one), `core/unet_filter.cpp`
//! (`execute`: the input scale; `init`: padding to 16 at the bottom and
//! right), `devices/cpu/cpu_input_process.isph`,
//! `devices/cpu/cpu_output_process.isph` and `devices/cpu/cpu_autoexposure.*`.

use super::cpu::Tensor;
use super::image::Image;
pub use crate::denoise_options::Mode;

/// The curve from the colour's encoding into the network's space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transfer {
    Linear,
    Srgb,
    /// The PU curve, normalised so that 65504 (the largest f16) maps to 1.
    Pu,
}

/// The largest value OIDN's HDR mode expects (`TransferFunction::yMax`).
const Y_MAX: f32 = 65504.0;

/// sRGB's constants as OIDN writes them (`TransferFunction::SRGB`).
mod srgb {
    pub const A: f32 = 12.92;
    pub const B: f32 = 1.055;
    pub const C: f32 = 1.0 / 2.4;
    pub const D: f32 = -0.055;
    pub const Y0: f32 = 0.0031308;
    pub const X0: f32 = 0.04045;
}

/// The PU curve's fit (`TransferFunction::PU`), digit for digit as OIDN
/// writes it, so that it can be checked against the source.
#[allow(clippy::excessive_precision)]
mod pu {
    pub const A: f32 = 1.41283765e+03;
    pub const B: f32 = 1.64593172e+00;
    pub const C: f32 = 4.31384981e-01;
    pub const D: f32 = -2.94139609e-03;
    pub const E: f32 = 1.92653254e-01;
    pub const F: f32 = 6.26026094e-03;
    pub const G: f32 = 9.98620152e-01;
    pub const Y0: f32 = 1.57945760e-06;
    pub const Y1: f32 = 3.22087631e-02;
    pub const X0: f32 = 2.23151711e-03;
    pub const X1: f32 = 3.70974749e-01;

    pub fn forward(y: f32) -> f32 {
        if y <= Y0 {
            A * y
        } else if y <= Y1 {
            B * y.powf(C) + D
        } else {
            E * (y + F).ln() + G
        }
    }

    pub fn inverse(x: f32) -> f32 {
        if x <= X0 {
            x / A
        } else if x <= X1 {
            ((x - D) / B).powf(1.0 / C)
        } else {
            ((x - G) / E).exp() - F
        }
    }
}

impl Mode {
    /// The transfer function OIDN picks (`RTFilter::newTransferFunc`).
    pub fn transfer(self) -> Transfer {
        match self {
            Mode::Ldr => Transfer::Srgb,
            Mode::LdrSrgb => Transfer::Linear,
            Mode::Hdr => Transfer::Pu,
        }
    }

    pub fn hdr(self) -> bool {
        self == Mode::Hdr
    }
}

impl Transfer {
    pub fn forward(self, y: f32) -> f32 {
        match self {
            Transfer::Linear => y,
            Transfer::Srgb => {
                if y <= srgb::Y0 {
                    srgb::A * y
                } else {
                    srgb::B * y.powf(srgb::C) + srgb::D
                }
            }
            Transfer::Pu => pu::forward(y) * (1.0 / pu::forward(Y_MAX)),
        }
    }

    pub fn inverse(self, x: f32) -> f32 {
        match self {
            Transfer::Linear => x,
            Transfer::Srgb => {
                if x <= srgb::X0 {
                    x / srgb::A
                } else {
                    ((x - srgb::D) / srgb::B).powf(1.0 / srgb::C)
                }
            }
            Transfer::Pu => pu::inverse(x * pu::forward(Y_MAX)),
        }
    }
}

/// What multiplies the colour before the network (and divides its output):
/// the user's, else in HDR the autoexposure, else 1 (`UNetFilter::execute`).
pub fn input_scale(mode: Mode, user: Option<f32>, color: &Image) -> f32 {
    match user {
        Some(s) => s,
        None if mode.hdr() => autoexposure(color),
        None => 1.0,
    }
}

/// OIDN's autoexposure: the image cut into bins of at most 16×16 pixels,
/// the mean luminance of each, and 0.18 over the geometric mean of those
/// above 1e-8 (1 when none is).
pub fn autoexposure(color: &Image) -> f32 {
    const MAX_BIN: usize = 16;
    const KEY: f32 = 0.18;
    const EPS: f32 = 1e-8;
    let (w, h) = (color.width, color.height);
    let (bins_h, bins_w) = (h.div_ceil(MAX_BIN), w.div_ceil(MAX_BIN));
    let (mut sum, mut count) = (0.0f32, 0u32);
    for i in 0..bins_h {
        for j in 0..bins_w {
            let (y0, y1) = (i * h / bins_h, (i + 1) * h / bins_h);
            let (x0, x1) = (j * w / bins_w, (j + 1) * w / bins_w);
            let mut l = 0.0f32;
            for y in y0..y1 {
                for x in x0..x1 {
                    let [r, g, b] = color.pixel(x, y).map(|v| sanitize(v, 0.0, f32::MAX));
                    l += 0.212671 * r + 0.715160 * g + 0.072169 * b;
                }
            }
            let l = l / ((y1 - y0) * (x1 - x0)) as f32;
            if l > EPS {
                sum += l.log2();
                count += 1;
            }
        }
    }
    if count > 0 { KEY / (sum / count as f32).exp2() } else { 1.0 }
}

/// NaN to 0, then clamped (OIDN's `clamp(nan_to_zero(v), lo, hi)`).
fn sanitize(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_nan() { 0.0 } else { v.clamp(lo, hi) }
}

/// The network's input: colour (scaled, sanitised, through the transfer
/// function), then albedo (clamped to [0, 1]) and normal (clamped to
/// [-1, 1], mapped to [0, 1]) when given, zero-padded at the right and
/// bottom to a multiple of `alignment` (OIDN's single tile puts the image
/// at the top left).
pub fn input(color: &Image, albedo: Option<&Image>, normal: Option<&Image>, mode: Mode, scale: f32, alignment: usize) -> Tensor {
    let transfer = mode.transfer();
    let hi = if mode.hdr() { f32::MAX } else { 1.0 };
    let channels = 3 * (1 + usize::from(albedo.is_some()) + usize::from(normal.is_some()));
    let (w, h) = (color.width, color.height);
    let mut t = Tensor::zeros(w.next_multiple_of(alignment), h.next_multiple_of(alignment), channels);
    for y in 0..h {
        for x in 0..w {
            let at = (y * t.width + x) * channels;
            let px = &mut t.data[at..at + channels];
            let c = color.pixel(x, y).map(|v| transfer.forward(sanitize(v * scale, 0.0, hi)));
            px[..3].copy_from_slice(&c);
            let mut k = 3;
            if let Some(a) = albedo {
                px[k..k + 3].copy_from_slice(&a.pixel(x, y).map(|v| sanitize(v, 0.0, 1.0)));
                k += 3;
            }
            if let Some(n) = normal {
                px[k..k + 3].copy_from_slice(&n.pixel(x, y).map(|v| sanitize(v, -1.0, 1.0) * 0.5 + 0.5));
            }
        }
    }
    t
}

/// The denoised colour from the network's output: its top-left `width` ×
/// `height`, NaN and negatives to 0, through the inverse transfer, clamped
/// to 1 unless HDR, divided by the input scale (0 for a scale of 0).
pub fn output(t: &Tensor, width: usize, height: usize, mode: Mode, scale: f32) -> Image {
    let transfer = mode.transfer();
    let out_scale = if scale != 0.0 { 1.0 / scale } else { 0.0 };
    let mut data = Vec::with_capacity(width * height * 3);
    for y in 0..height {
        for x in 0..width {
            for &v in &t.pixel(x, y)[..3] {
                let v = transfer.inverse(sanitize(v, 0.0, f32::MAX));
                let v = if mode.hdr() { v } else { v.min(1.0) };
                data.push(v * out_scale);
            }
        }
    }
    Image { width, height, data }
}

#[cfg(test)]
mod tests;
