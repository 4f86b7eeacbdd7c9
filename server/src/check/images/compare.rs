//! A rendered output against its reference file: which file, reading it,
//! and the figures. Display-referred outputs (8-bit sRGB textures) are kept
//! as PNG, which holds their bytes exactly, and compared with LDR-FLIP;
//! every other output as OpenEXR (32-bit float, exact) with HDR-FLIP.
//! relMSE, on the linear values, is reported beside.

use std::path::{Path, PathBuf};

use super::config::Threshold;
use crate::diag::{Code, Diagnostic, display_path};
use crate::flip::{self, FlipError, Linear, Summary};
use crate::render::capture::{CapturedImage, srgb_to_linear};
use crate::tradeoffs::metric::{Rgba, relative_mse};

/// How an output is stored and compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    /// 8-bit sRGB: what the display shows.
    Display,
    /// Anything else (float, linear 8-bit): what the renderer computed.
    High,
}

impl Range {
    /// By the captured texture's format name: a PNG's sRGB bytes give back
    /// an sRGB texture's exactly, and a linear one's only approximately.
    pub fn of(format: &str) -> Range {
        if format.ends_with("Srgb") { Range::Display } else { Range::High }
    }

    pub fn extension(self) -> &'static str {
        match self {
            Range::Display => "png",
            Range::High => "exr",
        }
    }
}

/// `references/<case>/<pass>.<output>.<png|exr>`: the naming `loupe
/// render` writes, one folder per case.
pub fn reference_path(references: &Path, case: &str, output: &str, range: Range) -> PathBuf {
    references.join(case).join(format!("{}.{}", output.replace('/', "."), range.extension()))
}

/// An image as linear RGBA f32, rows top first.
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<f32>,
}

impl Image {
    pub fn of(c: &CapturedImage) -> Image {
        Image { width: c.width, height: c.height, rgba: c.data.clone() }
    }

    fn linear(&self) -> Linear<'_> {
        Linear { width: self.width, height: self.height, rgba: &self.rgba }
    }

    fn view(&self) -> Rgba<'_> {
        Rgba { width: self.width as usize, height: self.height as usize, data: &self.rgba }
    }
}

/// Reads a reference; `Ok(None)` when there is none. A PNG holds sRGB
/// bytes, decoded here to linear as captures are.
pub fn read(path: &Path, range: Range) -> Result<Option<Image>, Diagnostic> {
    if !path.exists() {
        return Ok(None);
    }
    let image = crate::denoise::image::read(path, &display_path(path))?;
    let decode = |v: f32| if range == Range::Display { srgb_to_linear(v) } else { v };
    let rgba = image.data.chunks_exact(3).flat_map(|p| [decode(p[0]), decode(p[1]), decode(p[2]), 1.0]).collect();
    Ok(Some(Image { width: image.width as u32, height: image.height as u32, rgba }))
}

/// The figures of `actual` against `reference`, and FLIP's map.
pub struct Compared {
    pub flip: Summary,
    pub relative_mse: f64,
    pub map: flip::ErrorMap,
}

pub fn compare(actual: &Image, reference: &Image, range: Range) -> Result<Compared, FlipError> {
    let map = match range {
        Range::Display => {
            let (a, r) = (flip::encode_srgb8(&actual.rgba), flip::encode_srgb8(&reference.rgba));
            let srgb = |img: &Image, rgb| flip::Srgb8 { width: img.width, height: img.height, rgb };
            flip::ldr(srgb(reference, &r), srgb(actual, &a))?
        }
        Range::High => flip::hdr(reference.linear(), actual.linear())?,
    };
    Ok(Compared { flip: map.summary(), relative_mse: relative_mse(&actual.view(), &reference.view()), map })
}

/// How an output failed its reference, for the notes a caller adds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// No reference file.
    Missing,
    /// A reference that cannot be compared: unreadable, another size.
    Unusable,
    /// Compared, and over a threshold.
    Mismatch,
}

/// An output judged against its reference file, as the gate and the live
/// view both judge it.
pub struct Judged {
    /// The reference and the comparison, when the two compared.
    pub compared: Option<(Image, Compared)>,
    /// Why it fails, when it does (its diagnostic carries no notes yet).
    pub failure: Option<(Failure, Diagnostic)>,
}

/// Reads `output`'s reference at `path` and compares `actual` with it
/// against `threshold`; `adapter_key`: the adapter key that chose the
/// threshold, named in a mismatch.
pub fn judge(actual: &Image, range: Range, output: &str, path: &Path, threshold: Threshold, adapter_key: Option<&str>) -> Judged {
    let shown = display_path(path);
    let unusable = |d: Diagnostic| Judged { compared: None, failure: Some((Failure::Unusable, d)) };
    let reference = match read(path, range) {
        Ok(None) => {
            let d = Diagnostic::error(Code::ReferenceMissing, format!("`{output}` has no reference: {shown} does not exist"));
            return Judged { compared: None, failure: Some((Failure::Missing, d)) };
        }
        Err(d) => return unusable(d),
        Ok(Some(r)) if (r.width, r.height) != (actual.width, actual.height) => {
            return unusable(Diagnostic::error(
                Code::Image,
                format!(
                    "the reference {shown} is {}x{}, but the case renders `{output}` at {}x{}",
                    r.width, r.height, actual.width, actual.height
                ),
            ));
        }
        Ok(Some(r)) => r,
    };
    let compared = match compare(actual, &reference, range) {
        Ok(c) => c,
        Err(e) => return unusable(Diagnostic::error(Code::Image, e.to_string())),
    };
    let (f, t) = (compared.flip, threshold);
    let failure = (f.mean > t.flip_mean || f.p99 > t.flip_p99).then(|| {
        let chosen = adapter_key.map(|k| format!(" (the threshold for adapters matching \"{k}\")")).unwrap_or_default();
        let d = Diagnostic::error(
            Code::ImageMismatch,
            format!(
                "`{output}` differs from its reference: FLIP mean {:.4} (at most {}), 99th percentile {:.4} (at most {}){chosen}",
                f.mean, t.flip_mean, f.p99, t.flip_p99
            ),
        );
        (Failure::Mismatch, d)
    });
    Judged { compared: Some((reference, compared)), failure }
}

/// `capture` as the reference file `range` keeps: an sRGB PNG, or a
/// 32-bit float OpenEXR, ZIP-compressed (lossless) to keep the repository
/// small.
pub fn encode(capture: &CapturedImage, range: Range) -> Result<Vec<u8>, String> {
    use exr::prelude::*;
    if range == Range::Display {
        return Ok(capture.to_png());
    }
    let (w, data) = (capture.width as usize, &capture.data);
    let pixels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let i = (y * w + x) * 4;
        (data[i], data[i + 1], data[i + 2], data[i + 3])
    });
    let image = exr::image::Image::from_encoded_channels((w, capture.height as usize), Encoding::SMALL_LOSSLESS, pixels);
    let mut out = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut out).map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_outputs_are_png_and_the_rest_exr_named_as_loupe_render_names_them() {
        assert_eq!(Range::of("Rgba8UnormSrgb"), Range::Display);
        assert_eq!(Range::of("Bgra8UnormSrgb"), Range::Display);
        assert_eq!(Range::of("Rgba8Unorm"), Range::High);
        assert_eq!(Range::of("Rgba16Float"), Range::High);
        let path = reference_path(Path::new("tests/images"), "show-320x180", "tonemap/color", Range::Display);
        assert_eq!(path, Path::new("tests/images/show-320x180/tonemap.color.png"));
        assert_eq!(reference_path(Path::new("r"), "c", "lighting/color", Range::High), Path::new("r/c/lighting.color.exr"));
    }
}
