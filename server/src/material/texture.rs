//! Texture images on the CPU: decoding (PNG 8/16-bit grey, grey-alpha, RGB,
//! RGBA; EXR) to linear RGBA, the mip chain (a box filter in linear space),
//! and the scene's layers: every texture at one common size, so the
//! renderer binds one `texture_2d_array` (the GPU side is
//! `render::scene_gpu`). Kept apart from the upload so it is tested without
//! a device.

use std::path::Path;

use super::tree::{ColorSpace, TextureSource};
use crate::diag::{Code, Diagnostic, display_path};
use crate::files::ReadError;

/// The common size's cap, per side: a larger texture is resampled to it.
pub const MAX_SIZE: u32 = 2048;
/// What a file may declare, per side, before it is decoded: beyond this it
/// is refused (the decoded image alone would take gigabytes).
pub const MAX_FILE_SIZE: u32 = 16384;
/// The most bytes an image file may have (a 16384² RGBA half-float EXR,
/// uncompressed, is 2 GiB: far past what a material needs).
pub const MAX_FILE_BYTES: u64 = 512 << 20;

/// A decoded image: linear RGBA, row after row.
#[derive(Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Image({}×{})", self.width, self.height)
    }
}

impl Image {
    fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y.min(self.height - 1) * self.width + x.min(self.width - 1)) as usize]
    }
}

/// The scene's textures as the renderer binds them: one layer each (a 1×1
/// white layer when there is none, so the layout never changes), all at
/// `width`×`height`, each with its whole mip chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Layers {
    pub width: u32,
    pub height: u32,
    /// Per layer, level 0 first.
    pub layers: Vec<Vec<Image>>,
    /// Each image's own size, before it was resampled to the layers'.
    pub sources: Vec<(u32, u32)>,
}

impl Default for Layers {
    fn default() -> Self {
        Layers::of(Vec::new())
    }
}

impl Layers {
    /// `images` at one size: the largest width and height among them,
    /// capped at `MAX_SIZE`.
    pub fn of(images: Vec<Image>) -> Layers {
        let white = Image { width: 1, height: 1, pixels: vec![[1.0; 4]] };
        let images = if images.is_empty() { vec![white] } else { images };
        let width = images.iter().map(|i| i.width).max().unwrap_or(1).min(MAX_SIZE);
        let height = images.iter().map(|i| i.height).max().unwrap_or(1).min(MAX_SIZE);
        let sources = images.iter().map(|i| (i.width, i.height)).collect();
        let layers = images
            .into_iter()
            .map(|img| mips(if (img.width, img.height) == (width, height) { img } else { resample(&img, width, height) }))
            .collect();
        Layers { width, height, layers, sources }
    }

    /// The images (by index) resampled to the layers' size.
    pub fn resampled(&self) -> impl Iterator<Item = usize> + '_ {
        self.sources.iter().enumerate().filter(|(_, s)| **s != (self.width, self.height)).map(|(i, _)| i)
    }
}

/// Reads and decodes `source`: a located diagnostic (at the path as the
/// material file writes it) when the file is missing or cannot be used.
pub fn read(source: &TextureSource) -> Result<Image, Diagnostic> {
    let shown = display_path(&source.path);
    let error = |message: String, label: &str| Diagnostic::error(Code::Material, message).with_label(source.location.clone(), label, true);
    let bytes = crate::files::read_capped(&source.path, MAX_FILE_BYTES).map_err(|e| match e {
        ReadError::Io(e) if e.kind() == std::io::ErrorKind::NotFound => error(format!("texture `{shown}`: {e}"), "no such file"),
        ReadError::Io(e) => error(format!("texture `{shown}`: {e}"), "cannot be read"),
        other => error(other.diagnostic(&format!("texture `{shown}`"), MAX_FILE_BYTES).message, "cannot be read"),
    })?;
    decode(&source.path, &bytes, source.space).map_err(|why| error(format!("texture `{shown}`: {why}"), "this image"))
}

/// Decodes an image file's bytes (the format by the extension) to linear
/// RGBA: grey becomes grey RGB, a missing alpha 1; sRGB colour is decoded
/// when `space` says so.
pub fn decode(path: &Path, bytes: &[u8], space: ColorSpace) -> Result<Image, String> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let mut img = match ext.as_str() {
        "png" => png(bytes)?,
        "exr" => exr(bytes)?,
        _ => return Err(format!("`.{ext}` is not a texture format loupe reads (PNG or EXR)")),
    };
    if img.width == 0 || img.height == 0 {
        return Err("the image is empty (0 pixels)".into());
    }
    if space == ColorSpace::Srgb {
        for p in &mut img.pixels {
            for c in &mut p[..3] {
                *c = srgb_to_linear(*c);
            }
        }
    }
    Ok(img)
}

fn size_ok(width: u32, height: u32) -> Result<(), String> {
    if width > MAX_FILE_SIZE || height > MAX_FILE_SIZE {
        return Err(format!("{width}×{height} is larger than {MAX_FILE_SIZE} pixels a side"));
    }
    Ok(())
}

fn png(bytes: &[u8]) -> Result<Image, String> {
    use image::ImageDecoder;
    let decoder =
        image::codecs::png::PngDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| format!("not a PNG loupe can decode: {e}"))?;
    let (width, height) = decoder.dimensions();
    size_ok(width, height)?;
    use image::ColorType::*;
    match decoder.color_type() {
        L8 | La8 | Rgb8 | Rgba8 | L16 | La16 | Rgb16 | Rgba16 => {}
        other => return Err(format!("{other:?} PNGs are not supported (8 or 16-bit grey, grey-alpha, RGB or RGBA)")),
    }
    let dynamic = image::DynamicImage::from_decoder(decoder).map_err(|e| format!("not a PNG loupe can decode: {e}"))?;
    // u16 / 65535 in f32: a 16-bit channel keeps its precision.
    let rgba = dynamic.to_rgba32f();
    Ok(Image { width, height, pixels: rgba.pixels().map(|p| p.0).collect() })
}

fn exr(bytes: &[u8]) -> Result<Image, String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| self::Image { width: size.width() as u32, height: size.height() as u32, pixels: vec![[0.0; 4]; size.area()] },
            |img: &mut self::Image, at: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                let w = img.width as usize;
                img.pixels[at.y() * w + at.x()] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("not an EXR loupe can decode (RGB or RGBA channels): {e}"))?;
    let img = image.layer_data.channel_data.pixels;
    size_ok(img.width, img.height)?;
    Ok(img)
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// `img` and its mip chain down to 1×1: each level the box-filtered
/// (2×2 average, in linear space) level above; an odd edge repeats its last
/// texel.
pub fn mips(img: Image) -> Vec<Image> {
    let mut chain = vec![img];
    loop {
        let top = chain.last().expect("the chain starts with the image");
        if top.width == 1 && top.height == 1 {
            return chain;
        }
        let (w, h) = ((top.width / 2).max(1), (top.height / 2).max(1));
        let mut pixels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let quad = [top.at(2 * x, 2 * y), top.at(2 * x + 1, 2 * y), top.at(2 * x, 2 * y + 1), top.at(2 * x + 1, 2 * y + 1)];
                pixels.push(std::array::from_fn(|c| quad.iter().map(|p| p[c]).sum::<f32>() * 0.25));
            }
        }
        chain.push(Image { width: w, height: h, pixels });
    }
}

/// `img` at `width`×`height`, bilinear between texel centres.
fn resample(img: &Image, width: u32, height: u32) -> Image {
    let mut pixels = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let u = ((x as f32 + 0.5) * img.width as f32 / width as f32 - 0.5).max(0.0);
            let v = ((y as f32 + 0.5) * img.height as f32 / height as f32 - 0.5).max(0.0);
            let (x0, y0) = (u.floor() as u32, v.floor() as u32);
            let (fx, fy) = (u.fract(), v.fract());
            let lerp = |a: [f32; 4], b: [f32; 4], t: f32| -> [f32; 4] { std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t) };
            let top = lerp(img.at(x0, y0), img.at(x0 + 1, y0), fx);
            let bottom = lerp(img.at(x0, y0 + 1), img.at(x0 + 1, y0 + 1), fx);
            pixels.push(lerp(top, bottom, fy));
        }
    }
    Image { width, height, pixels }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode_png(width: u32, height: u32, color: image::ExtendedColorType, bytes: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        image::ImageEncoder::write_image(image::codecs::png::PngEncoder::new(&mut out), bytes, width, height, color).unwrap();
        out
    }

    #[test]
    fn a_16_bit_png_keeps_its_precision() {
        // Two greys one 16-bit step apart: 8 bits would make them equal.
        let values: [u16; 2] = [30000, 30001];
        // The encoder takes native-endian u16 samples.
        let native: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let png = encode_png(2, 1, image::ExtendedColorType::L16, &native);
        let img = decode(Path::new("a.png"), &png, ColorSpace::Linear).unwrap();
        for (p, v) in img.pixels.iter().zip(values) {
            assert_eq!(p[0], v as f32 / 65535.0);
            assert_eq!((p[1], p[2], p[3]), (p[0], p[0], 1.0), "grey is replicated, alpha is 1");
        }
    }

    #[test]
    fn srgb_pngs_are_decoded_to_linear_and_alpha_is_kept() {
        let png = encode_png(1, 1, image::ExtendedColorType::Rgba8, &[255, 188, 0, 128]);
        let img = decode(Path::new("a.png"), &png, ColorSpace::Srgb).unwrap();
        let p = img.pixels[0];
        assert_eq!(p[0], 1.0);
        assert!((p[1] - 0.5029).abs() < 1e-3, "sRGB 188 is linear 0.503, got {}", p[1]);
        assert_eq!((p[2], p[3]), (0.0, 128.0 / 255.0));
        let linear = decode(Path::new("a.png"), &png, ColorSpace::Normal).unwrap();
        assert_eq!(linear.pixels[0][1], 188.0 / 255.0, "a normal map's values are read as stored");
    }

    #[test]
    fn mip_level_k_of_a_checker_is_its_average() {
        let (w, h) = (8, 4);
        let pixels = (0..w * h).map(|i| if (i % w + i / w) % 2 == 0 { [1.0, 0.0, 0.25, 1.0] } else { [0.0, 1.0, 0.75, 1.0] }).collect();
        let chain = mips(Image { width: w, height: h, pixels });
        let sizes: Vec<(u32, u32)> = chain.iter().map(|m| (m.width, m.height)).collect();
        assert_eq!(sizes, [(8, 4), (4, 2), (2, 1), (1, 1)]);
        for level in &chain[1..] {
            assert!(level.pixels.iter().all(|p| *p == [0.5, 0.5, 0.5, 1.0]), "{level:?}: {:?}", level.pixels);
        }
    }

    #[test]
    fn layers_share_the_largest_size_and_a_scene_without_textures_has_a_white_one() {
        let img = |w, h| Image { width: w, height: h, pixels: vec![[0.25; 4]; (w * h) as usize] };
        let layers = Layers::of(vec![img(4, 4), img(2, 8)]);
        let resampled: Vec<usize> = layers.resampled().collect();
        assert_eq!((layers.width, layers.height, resampled), (4, 8, vec![0, 1]));
        assert!(layers.layers.iter().all(|l| l[0].pixels.iter().all(|p| *p == [0.25; 4])), "a flat image stays flat");
        let empty = Layers::default();
        assert_eq!((empty.width, empty.height, empty.layers.len()), (1, 1, 1));
        assert_eq!(empty.layers[0][0].pixels, [[1.0; 4]]);
    }

    /// A texture path naming a FIFO is refused at once: opening it would
    /// wait for a writer that never comes, and the scene would never load.
    #[test]
    fn a_fifo_is_refused_not_waited_on() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("mask.png");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
        let source = TextureSource { path: fifo, space: ColorSpace::Linear, location: crate::diag::Location::file_start("a.mat") };
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || tx.send(read(&source).map(|_| ()).map_err(|d| d.message)));
        let answer = rx.recv_timeout(std::time::Duration::from_secs(10)).expect("an answer, not a wait for a writer");
        let message = answer.expect_err("a FIFO is not read");
        assert!(message.contains("not a regular file"), "{message}");
    }

    #[test]
    fn bad_files_say_why() {
        let at = |path: &str, bytes: &[u8]| decode(Path::new(path), bytes, ColorSpace::Srgb).unwrap_err();
        assert!(at("a.jpg", b"\xff\xd8").contains("PNG or EXR"));
        assert!(at("a.png", b"not a png").contains("not a PNG"));
        assert!(at("a.exr", b"not an exr").contains("not an EXR"));
        let huge = encode_png(MAX_FILE_SIZE + 1, 1, image::ExtendedColorType::L8, &vec![0; MAX_FILE_SIZE as usize + 1]);
        assert!(at("a.png", &huge).contains("larger than"));
    }
}
