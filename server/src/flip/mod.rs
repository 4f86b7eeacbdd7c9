//! NVIDIA FLIP (Andersson et al. 2020, 2021): how visible the difference
//! between a test image and its reference is, per pixel, in [0, 1].
//! LDR-FLIP is the `nv-flip` crate's binding of FLIP's own C++ (the one
//! wgpu's image tests use); HDR-FLIP is built on it here as the HDR paper
//! defines it (`hdr`). The image gate (`check::images`), the tradeoffs
//! sweep and the daemon's comparison all read FLIP from here, so this
//! module imports nothing above `color`.

mod hdr;

pub use hdr::{Exposures, exposures};

use crate::color::linear_to_srgb;

/// FLIP's default observer: a 0.7 m wide 4K display seen from 0.7 m.
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// An 8-bit sRGB image, RGB, rows top first: what LDR-FLIP reads.
#[derive(Clone, Copy)]
pub struct Srgb8<'a> {
    pub width: u32,
    pub height: u32,
    pub rgb: &'a [u8],
}

/// A linear RGBA f32 image, rows top first (a capture's layout).
#[derive(Clone, Copy)]
pub struct Linear<'a> {
    pub width: u32,
    pub height: u32,
    pub rgba: &'a [f32],
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlipError {
    #[error("the images differ in size: {test_w}x{test_h} against the reference's {ref_w}x{ref_h}")]
    Size { ref_w: u32, ref_h: u32, test_w: u32, test_h: u32 },
    #[error("an image of {width}x{height} needs {expected} values, not {got}")]
    Data { width: u32, height: u32, expected: usize, got: usize },
}

/// FLIP's error per pixel, rows top first.
#[derive(Debug, Clone)]
pub struct ErrorMap {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

/// The figures a verdict is made of.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Summary {
    /// The mean error, FLIP's recommended single number.
    pub mean: f64,
    /// The 99th percentile of the pixels' errors (nearest rank): a small
    /// region of large error shows here when the mean dilutes it.
    pub p99: f64,
    /// FLIP's weighted median (pixels weighted by their error), as its
    /// tool prints it.
    pub weighted_median: f64,
}

/// LDR-FLIP of two display-referred images.
pub fn ldr(reference: Srgb8, test: Srgb8) -> Result<ErrorMap, FlipError> {
    same_size(reference.width, reference.height, test.width, test.height)?;
    for image in [reference, test] {
        check_len(image.width, image.height, 3, image.rgb.len())?;
    }
    let image = |i: Srgb8| nv_flip::FlipImageRgb8::with_data(i.width, i.height, i.rgb);
    let map = nv_flip::flip(image(reference), image(test), PIXELS_PER_DEGREE);
    Ok(ErrorMap { width: map.width(), height: map.height(), values: map.to_vec() })
}

/// HDR-FLIP of two linear images, over the exposures the reference calls
/// for (see `hdr`).
pub fn hdr(reference: Linear, test: Linear) -> Result<ErrorMap, FlipError> {
    same_size(reference.width, reference.height, test.width, test.height)?;
    for image in [reference, test] {
        check_len(image.width, image.height, 4, image.rgba.len())?;
    }
    Ok(hdr::flip(reference, test, exposures(reference)))
}

/// A linear image as 8-bit sRGB RGB, clamped to [0, 1]; a non-finite
/// pixel becomes magenta, so it counts as an error, never as black.
pub fn encode_srgb8(rgba: &[f32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rgba.len() / 4 * 3);
    for px in rgba.chunks_exact(4) {
        if px[..3].iter().any(|v| !v.is_finite()) {
            out.extend_from_slice(&[255, 0, 255]);
            continue;
        }
        out.extend(px[..3].iter().map(|&v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8));
    }
    out
}

impl ErrorMap {
    pub fn summary(&self) -> Summary {
        let n = self.values.len();
        if n == 0 {
            return Summary { mean: 0.0, p99: 0.0, weighted_median: 0.0 };
        }
        let mean = self.values.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
        let mut sorted = self.values.clone();
        sorted.sort_by(f32::total_cmp);
        let rank = ((0.99 * n as f64).ceil() as usize).clamp(1, n) - 1;
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.values);
        let weighted_median = f64::from(nv_flip::FlipPool::from_image(&map).get_percentile(0.5, true));
        Summary { mean, p99: f64::from(sorted[rank]), weighted_median }
    }

    /// The map in FLIP's magma colours (black: no error, yellow: 1), RGB.
    pub fn magma_rgb8(&self) -> Vec<u8> {
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.values);
        map.apply_color_lut(&nv_flip::magma_lut()).to_vec()
    }

    /// `magma_rgb8` as a PNG file's bytes.
    pub fn magma_png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let encoder = image::codecs::png::PngEncoder::new(&mut out);
        image::ImageEncoder::write_image(encoder, &self.magma_rgb8(), self.width, self.height, image::ExtendedColorType::Rgb8)
            .expect("an in-memory PNG of matching size cannot fail");
        out
    }
}

fn same_size(ref_w: u32, ref_h: u32, test_w: u32, test_h: u32) -> Result<(), FlipError> {
    if (ref_w, ref_h) == (test_w, test_h) { Ok(()) } else { Err(FlipError::Size { ref_w, ref_h, test_w, test_h }) }
}

fn check_len(width: u32, height: u32, channels: usize, got: usize) -> Result<(), FlipError> {
    let expected = width as usize * height as usize * channels;
    if got == expected { Ok(()) } else { Err(FlipError::Data { width, height, expected, got }) }
}

#[cfg(test)]
mod tests;
