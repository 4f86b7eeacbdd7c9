//! RGB float images and the files `loupe denoise` reads and writes: PFM
//! (what OIDN's own tools use), OpenEXR and PNG.
//!
//! Values are stored as they are in the file: PNG's 8 or 16 bits become
//! [0, 1] with no transfer function (whether they are sRGB-encoded is the
//! caller's choice, as in OIDN's `oidnDenoise`). One-channel images become
//! grey RGB; alpha is dropped.

use std::path::Path;

use crate::diag::{Code, Diagnostic, Location};
use crate::files::read_capped;

/// The largest side of an image loupe reads: a file's header may ask for no
/// more than 8192² pixels (768 MiB as RGB f32), whatever its size claims.
pub const MAX_SIDE: usize = 8192;

/// The largest image file loupe reads: a PFM of 8192² RGB f32 plus a header.
pub const MAX_FILE_BYTES: u64 = (MAX_SIDE * MAX_SIDE * 12 + 4096) as u64;

#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    /// RGB per pixel, rows top first.
    pub data: Vec<f32>,
}

impl Image {
    pub fn pixel(&self, x: usize, y: usize) -> [f32; 3] {
        let at = (y * self.width + x) * 3;
        [self.data[at], self.data[at + 1], self.data[at + 2]]
    }
}

/// The file formats, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Pfm,
    Exr,
    Png,
}

impl Format {
    pub fn of(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "pfm" => Some(Format::Pfm),
            "exr" => Some(Format::Exr),
            "png" => Some(Format::Png),
            _ => None,
        }
    }
}

fn unknown_format(display: &str) -> Diagnostic {
    Diagnostic::error(Code::Image, "unknown image format: the file name must end in .pfm, .exr or .png").at(Location::file_start(display))
}

/// Reads an image; `display` names it in diagnostics.
pub fn read(path: &Path, display: &str) -> Result<Image, Diagnostic> {
    let format = Format::of(path).ok_or_else(|| unknown_format(display))?;
    let bytes =
        read_capped(path, MAX_FILE_BYTES).map_err(|e| e.diagnostic("the image", MAX_FILE_BYTES).at(Location::file_start(display)))?;
    let error = |message: String| Diagnostic::error(Code::Image, message).at(Location::file_start(display));
    let image = match format {
        Format::Pfm => pfm::parse(&bytes).map_err(|e| error(e.to_string()))?,
        Format::Exr => read_exr(bytes).map_err(error)?,
        Format::Png => read_png(&bytes).map_err(error)?,
    };
    if image.width == 0 || image.height == 0 {
        return Err(error(format!("the image is {}×{}: it has no pixels", image.width, image.height)));
    }
    Ok(image)
}

/// Writes `image` in the format its extension names.
pub fn write(path: &Path, image: &Image) -> Result<(), Diagnostic> {
    let display = path.display().to_string();
    let bytes = match Format::of(path).ok_or_else(|| unknown_format(&display))? {
        Format::Pfm => pfm::encode(image),
        Format::Exr => encode_exr(image),
        Format::Png => encode_png(image),
    };
    std::fs::write(path, bytes)
        .map_err(|e| Diagnostic::error(Code::Io, format!("cannot write the image: {e}")).at(Location::file_start(&display)))
}

fn too_large(width: usize, height: usize) -> Option<String> {
    (width > MAX_SIDE || height > MAX_SIDE).then(|| format!("the image is {width}×{height}: the largest side loupe reads is {MAX_SIDE}"))
}

fn read_exr(bytes: Vec<u8>) -> Result<Image, String> {
    use exr::prelude::*;
    // Nothing is allocated for a size beyond the limit: the pixels stay
    // empty and the size is refused after.
    let read = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| {
                let (w, h) = (size.width(), size.height());
                let data = if too_large(w, h).is_none() { vec![0.0; w * h * 3] } else { Vec::new() };
                crate::denoise::image::Image { width: w, height: h, data }
            },
            |img: &mut crate::denoise::image::Image, Vec2(x, y), (r, g, b): (f32, f32, f32)| {
                let at = (y * img.width + x) * 3;
                if let Some(px) = img.data.get_mut(at..at + 3) {
                    px.copy_from_slice(&[r, g, b]);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("cannot read the OpenEXR file (it needs a layer with R, G and B channels): {e}"))?;
    let image = read.layer_data.channel_data.pixels;
    match too_large(image.width, image.height) {
        Some(m) => Err(m),
        None => Ok(image),
    }
}

fn encode_exr(image: &Image) -> Vec<u8> {
    use exr::prelude::*;
    let w = image.width;
    let pixels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b] = image.pixel(x, y);
        (r, g, b)
    });
    let mut out = std::io::Cursor::new(Vec::new());
    exr::image::Image::from_channels((w, image.height), pixels)
        .write()
        .to_buffered(&mut out)
        .expect("an in-memory OpenEXR of matching size cannot fail");
    out.into_inner()
}

fn read_png(bytes: &[u8]) -> Result<Image, String> {
    let decoder = image::codecs::png::PngDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| format!("cannot read the PNG file: {e}"))?;
    let (w, h) = image::ImageDecoder::dimensions(&decoder);
    let (w, h) = (w as usize, h as usize);
    if let Some(m) = too_large(w, h) {
        return Err(m);
    }
    let rgb = image::DynamicImage::from_decoder(decoder).map_err(|e| format!("cannot read the PNG file: {e}"))?.into_rgb32f();
    Ok(Image { width: w, height: h, data: rgb.into_raw() })
}

/// 8-bit RGB: each value clamped to [0, 1] and rounded.
fn encode_png(image: &Image) -> Vec<u8> {
    let bytes: Vec<u8> = image.data.iter().map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(encoder, &bytes, image.width as u32, image.height as u32, image::ExtendedColorType::Rgb8)
        .expect("an in-memory PNG of matching size cannot fail");
    out
}

pub mod pfm;

#[cfg(test)]
mod tests;
