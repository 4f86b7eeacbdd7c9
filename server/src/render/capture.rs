//! Captured pass outputs: texels read back from the GPU, converted to RGBA
//! f32 so every format is inspected the same way, with the statistics the
//! NaN report and the inspector need.

use serde::Serialize;

use super::resource::{Element, TensorLayout};
pub use crate::color::{linear_to_srgb, srgb_to_linear};

/// One pass output of one frame, exactly as the pass wrote it.
#[derive(Debug, Clone)]
pub struct CapturedImage {
    pub pass: String,
    pub output: String,
    pub frame: u64,
    pub width: u32,
    pub height: u32,
    /// The texture format's name, e.g. `Rgba16Float`.
    pub format: String,
    /// RGBA, row-major, top row first: `width * height * 4` values. Formats
    /// with fewer channels fill the rest with 0 (alpha with 1).
    pub data: Vec<f32>,
    pub stats: ImageStats,
}

#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct ImageStats {
    pub nan: u64,
    pub inf: u64,
    pub negative: u64,
    /// Per channel, over finite values only.
    pub min: [f32; 4],
    pub max: [f32; 4],
    /// The first pixel (x, y) in row order holding a NaN or Inf.
    pub first_nan: Option<[u32; 2]>,
}

impl ImageStats {
    pub fn of(data: &[f32], width: u32) -> Self {
        let mut s = ImageStats { min: [f32::INFINITY; 4], max: [f32::NEG_INFINITY; 4], ..Default::default() };
        for (i, px) in data.chunks_exact(4).enumerate() {
            let mut bad = false;
            for (c, &v) in px.iter().enumerate() {
                if v.is_nan() {
                    s.nan += 1;
                    bad = true;
                } else if v.is_infinite() {
                    s.inf += 1;
                    bad = true;
                } else {
                    if v < 0.0 {
                        s.negative += 1;
                    }
                    s.min[c] = s.min[c].min(v);
                    s.max[c] = s.max[c].max(v);
                }
            }
            if bad && s.first_nan.is_none() {
                s.first_nan = Some([i as u32 % width, i as u32 / width]);
            }
        }
        for c in 0..4 {
            if s.min[c] > s.max[c] {
                (s.min[c], s.max[c]) = (0.0, 0.0); // no finite value at all
            }
        }
        s
    }

    /// Whether any value is NaN or infinite.
    pub fn has_non_finite(&self) -> bool {
        self.nan + self.inf > 0
    }
}

/// How a texture format's texels become RGBA f32.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    pub channels: usize,
    pub bytes_per_channel: usize,
    kind: Kind,
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    F16,
    F32,
    Unorm8,
    /// 8-bit sRGB-encoded colour: decoded to linear on readback, as a
    /// shader sampling the texture sees it (alpha stays linear).
    Srgb8,
    /// 8-bit BGRA, swizzled to RGBA; `srgb` decodes as `Srgb8` does.
    Bgra8 {
        srgb: bool,
    },
}

impl Layout {
    /// `None` for formats loupe cannot read back (compressed, packed).
    pub fn of(format: wgpu::TextureFormat) -> Option<Layout> {
        use wgpu::TextureFormat as F;
        let (channels, bytes_per_channel, kind) = match format {
            F::R16Float => (1, 2, Kind::F16),
            F::Rg16Float => (2, 2, Kind::F16),
            F::Rgba16Float => (4, 2, Kind::F16),
            F::R32Float | F::Depth32Float => (1, 4, Kind::F32),
            F::Rg32Float => (2, 4, Kind::F32),
            F::Rgba32Float => (4, 4, Kind::F32),
            F::R8Unorm => (1, 1, Kind::Unorm8),
            F::Rg8Unorm => (2, 1, Kind::Unorm8),
            F::Rgba8Unorm => (4, 1, Kind::Unorm8),
            F::Rgba8UnormSrgb => (4, 1, Kind::Srgb8),
            F::Bgra8Unorm => (4, 1, Kind::Bgra8 { srgb: false }),
            F::Bgra8UnormSrgb => (4, 1, Kind::Bgra8 { srgb: true }),
            _ => return None,
        };
        Some(Layout { channels, bytes_per_channel, kind })
    }

    pub fn bytes_per_texel(&self) -> usize {
        self.channels * self.bytes_per_channel
    }

    /// Appends tightly packed texels (no row padding) as RGBA f32. One
    /// loop per kind, so the per-texel work has no branches on the format.
    pub fn extend_rgba_f32(&self, bytes: &[u8], out: &mut Vec<f32>) {
        let (n, size) = (self.channels, self.bytes_per_channel);
        match self.kind {
            Kind::F16 => push_texels(bytes, n, size, out, |b, _| half::f16::from_le_bytes([b[0], b[1]]).to_f32()),
            Kind::F32 => push_texels(bytes, n, size, out, |b, _| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Kind::Unorm8 | Kind::Bgra8 { srgb: false } => push_texels(bytes, n, size, out, |b, _| UNORM8[usize::from(b[0])]),
            Kind::Srgb8 | Kind::Bgra8 { srgb: true } => {
                let lut = srgb8_to_linear();
                push_texels(bytes, n, size, out, |b, c| if c < 3 { lut[usize::from(b[0])] } else { UNORM8[usize::from(b[0])] });
            }
        }
        if matches!(self.kind, Kind::Bgra8 { .. }) {
            let texels = bytes.len() / self.bytes_per_texel();
            let start = out.len() - texels * 4;
            for px in out[start..].chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
    }
}

/// Appends each texel of `channels` channels of `size` bytes as RGBA,
/// missing channels 0 and missing alpha 1.
#[inline(always)]
fn push_texels(bytes: &[u8], channels: usize, size: usize, out: &mut Vec<f32>, channel: impl Fn(&[u8], usize) -> f32) {
    out.reserve(bytes.len() / (channels * size) * 4);
    for t in bytes.chunks_exact(channels * size) {
        let mut px = [0.0, 0.0, 0.0, 1.0];
        for (c, v) in px.iter_mut().enumerate().take(channels) {
            *v = channel(&t[c * size..], c);
        }
        out.extend_from_slice(&px);
    }
}

/// Byte / 255 for every byte.
static UNORM8: [f32; 256] = {
    let mut t = [0.0; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = i as f32 / 255.0;
        i += 1;
    }
    t
};

/// The linear value of every sRGB-encoded byte.
fn srgb8_to_linear() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| srgb_to_linear(UNORM8[i])))
}

impl CapturedImage {
    pub fn new(pass: &str, output: &str, frame: u64, width: u32, height: u32, format: wgpu::TextureFormat, data: Vec<f32>) -> Self {
        let stats = ImageStats::of(&data, width);
        CapturedImage { pass: pass.to_owned(), output: output.to_owned(), frame, width, height, format: format!("{format:?}"), data, stats }
    }

    /// `pass/output`, the key captures are listed and fetched by.
    pub fn key(&self) -> String {
        format!("{}/{}", self.pass, self.output)
    }

    /// An 8-bit sRGB PNG for display: linear values are clamped to [0, 1]
    /// and encoded (for an sRGB texture, that gives back its stored bytes);
    /// NaN shows as magenta so it is never mistaken for black.
    pub fn to_png(&self) -> Vec<u8> {
        let mut rgba = Vec::with_capacity(self.data.len());
        for px in self.data.chunks_exact(4) {
            if px.iter().any(|v| !v.is_finite()) {
                rgba.extend_from_slice(&[255, 0, 255, 255]);
                continue;
            }
            for (c, &v) in px.iter().enumerate() {
                let v = v.clamp(0.0, 1.0);
                let v = if c == 3 { v } else { linear_to_srgb(v) };
                rgba.push((v * 255.0 + 0.5) as u8);
            }
        }
        let mut out = Vec::new();
        let encoder = image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Fast,
            image::codecs::png::FilterType::Sub,
        );
        image::ImageEncoder::write_image(encoder, &rgba, self.width, self.height, image::ExtendedColorType::Rgba8)
            .expect("an in-memory PNG of matching size cannot fail");
        out
    }

    /// OpenEXR, 32-bit float RGBA: the exact values.
    pub fn to_exr(&self) -> Result<Vec<u8>, String> {
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        let data = &self.data;
        let image = Image::from_channels(
            (w, h),
            SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
                let i = (y * w + x) * 4;
                (data[i], data[i + 1], data[i + 2], data[i + 3])
            }),
        );
        let mut out = std::io::Cursor::new(Vec::new());
        image.write().to_buffered(&mut out).map_err(|e| e.to_string())?;
        Ok(out.into_inner())
    }

    /// Raw little-endian RGBA f32, top row first.
    pub fn raw_f32(&self) -> Vec<u8> {
        self.data.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// Raw little-endian RGBA f16, top row first.
    pub fn raw_f16(&self) -> Vec<u8> {
        self.data.iter().flat_map(|v| half::f16::from_f32(*v).to_le_bytes()).collect()
    }

    /// RGBA at pixel (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [self.data[i], self.data[i + 1], self.data[i + 2], self.data[i + 3]]
    }
}

/// One buffer of one frame, read as the tensor its layout describes: any
/// number of channels, converted to f32, with the statistics images get.
#[derive(Debug, Clone)]
pub struct CapturedTensor {
    pub pass: String,
    pub output: String,
    pub frame: u64,
    pub layout: TensorLayout,
    /// Every element in layout order, as f32 (u32 and f16 converted).
    pub data: Vec<f32>,
    pub stats: TensorStats,
}

#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct TensorStats {
    pub nan: u64,
    pub inf: u64,
    pub negative: u64,
    /// Per channel (the innermost dimension), over finite values only.
    pub min: Vec<f32>,
    pub max: Vec<f32>,
    pub mean: Vec<f32>,
    /// The flat index of the first NaN or Inf.
    pub first_nan: Option<u64>,
}

impl TensorStats {
    pub fn of(data: &[f32], channels: usize) -> Self {
        let channels = channels.max(1);
        let mut s = TensorStats { min: vec![f32::INFINITY; channels], max: vec![f32::NEG_INFINITY; channels], ..Default::default() };
        let mut sum = vec![0f64; channels];
        let mut count = vec![0u64; channels];
        for (i, &v) in data.iter().enumerate() {
            let c = i % channels;
            if !v.is_finite() {
                if v.is_nan() {
                    s.nan += 1
                } else {
                    s.inf += 1
                }
                s.first_nan.get_or_insert(i as u64);
                continue;
            }
            s.negative += u64::from(v < 0.0);
            s.min[c] = s.min[c].min(v);
            s.max[c] = s.max[c].max(v);
            sum[c] += f64::from(v);
            count[c] += 1;
        }
        s.mean = sum.iter().zip(&count).map(|(s, n)| if *n == 0 { 0.0 } else { (s / *n as f64) as f32 }).collect();
        for ((min, max), n) in s.min.iter_mut().zip(s.max.iter_mut()).zip(&count) {
            if *n == 0 {
                (*min, *max) = (0.0, 0.0);
            }
        }
        s
    }

    pub fn has_non_finite(&self) -> bool {
        self.nan + self.inf > 0
    }
}

/// Tightly packed little-endian elements as f32 (u32 and f16 converted).
pub fn decode_elements(element: Element, bytes: &[u8]) -> Vec<f32> {
    match element {
        Element::F32 => bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        Element::U32 => bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32).collect(),
        Element::F16 => bytes.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect(),
    }
}

impl CapturedTensor {
    /// Reads `bytes` (tightly packed, little-endian) as `layout` says.
    pub fn new(pass: &str, output: &str, frame: u64, layout: TensorLayout, bytes: &[u8]) -> Self {
        let n = layout.len() as usize;
        let bytes = &bytes[..(n * layout.element.bytes() as usize).min(bytes.len())];
        let data = decode_elements(layout.element, bytes);
        let stats = TensorStats::of(&data, layout.channels());
        CapturedTensor { pass: pass.to_owned(), output: output.to_owned(), frame, layout, data, stats }
    }

    pub fn key(&self) -> String {
        format!("{}/{}", self.pass, self.output)
    }

    /// Raw little-endian f32, in layout order.
    pub fn raw_f32(&self) -> Vec<u8> {
        self.data.iter().flat_map(|v| v.to_le_bytes()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_count_nan_inf_negative_and_find_the_first_bad_pixel() {
        let data = vec![
            0.5,
            0.0,
            -1.0,
            1.0, // (0,0): one negative
            f32::NAN,
            0.0,
            0.0,
            1.0, // (1,0): NaN
            f32::INFINITY,
            2.0,
            0.0,
            1.0, // (0,1): Inf
            0.25,
            0.0,
            0.0,
            1.0,
        ];
        let s = ImageStats::of(&data, 2);
        assert_eq!((s.nan, s.inf, s.negative), (1, 1, 1));
        assert_eq!(s.first_nan, Some([1, 0]));
        assert_eq!(s.min[0], 0.25);
        assert_eq!(s.max[1], 2.0);
    }

    #[test]
    fn tensors_read_every_element_type_with_per_channel_stats() {
        let layout = TensorLayout::new(&[("x", 3), ("c", 2)], Element::F32);
        let values = [1.0f32, -2.0, f32::NAN, 4.0, 3.0, f32::INFINITY];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = CapturedTensor::new("p", "t", 1, layout, &bytes);
        assert_eq!((t.stats.nan, t.stats.inf, t.stats.negative), (1, 1, 1));
        assert_eq!(t.stats.first_nan, Some(2));
        assert_eq!((t.stats.min.clone(), t.stats.max.clone()), (vec![1.0, -2.0], vec![3.0, 4.0]));
        assert_eq!(t.stats.mean, vec![2.0, 1.0]);

        let u: Vec<u8> = [7u32, 0, 3_000_000].iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = CapturedTensor::new("p", "h", 1, TensorLayout::new(&[("bin", 3)], Element::U32), &u);
        assert_eq!(t.data, [7.0, 0.0, 3_000_000.0]);
        let h: Vec<u8> = [0.5f32, 65504.0].iter().flat_map(|v| half::f16::from_f32(*v).to_le_bytes()).collect();
        let t = CapturedTensor::new("p", "f", 1, TensorLayout::new(&[("x", 2)], Element::F16), &h);
        assert_eq!(t.data, [0.5, 65504.0]);
    }

    #[test]
    fn srgb_texels_read_back_linear_and_their_png_is_the_stored_bytes() {
        let bytes: Vec<u8> = (0..=255u8).flat_map(|b| [b, b, 255 - b, b]).collect();
        for format in [wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::TextureFormat::Bgra8UnormSrgb] {
            let mut data = Vec::new();
            Layout::of(format).unwrap().extend_rgba_f32(&bytes, &mut data);
            for (b, px) in (0..=255u8).zip(data.chunks_exact(4)) {
                let lin = |b: u8| srgb_to_linear(f32::from(b) / 255.0);
                let (r, bl) = if format == wgpu::TextureFormat::Rgba8UnormSrgb { (b, 255 - b) } else { (255 - b, b) };
                assert_eq!(px, [lin(r), lin(b), lin(bl), f32::from(b) / 255.0], "{format:?} byte {b}");
            }
            let img = CapturedImage::new("p", "o", 1, 256, 1, format, data);
            let png = image::load_from_memory(&img.to_png()).unwrap().to_rgba8();
            let swizzled: Vec<u8> = if format == wgpu::TextureFormat::Bgra8UnormSrgb {
                bytes.chunks_exact(4).flat_map(|p| [p[2], p[1], p[0], p[3]]).collect()
            } else {
                bytes.clone()
            };
            assert_eq!(png.into_raw(), swizzled, "{format:?}: the PNG shows what the texture stores");
        }
        // The decode is the sRGB curve, not a plain /255: mid-grey 188 is
        // linear 0.5 (to 3 digits).
        assert!((srgb_to_linear(188.0 / 255.0) - 0.5029).abs() < 1e-3);
    }

    #[test]
    fn half_floats_convert_exactly() {
        let l = Layout::of(wgpu::TextureFormat::Rgba16Float).unwrap();
        let bytes: Vec<u8> = [1.5f32, -2.0, 65504.0, 0.0].iter().flat_map(|v| half::f16::from_f32(*v).to_le_bytes()).collect();
        let mut out = Vec::new();
        l.extend_rgba_f32(&bytes, &mut out);
        assert_eq!(out, [1.5, -2.0, 65504.0, 0.0]);
    }

    #[test]
    fn every_format_fills_rgba_in_order() {
        use wgpu::TextureFormat as F;
        let convert = |format, bytes: &[u8]| {
            let mut out = vec![9.0]; // appended to, not overwritten
            Layout::of(format).unwrap().extend_rgba_f32(bytes, &mut out);
            out
        };
        assert_eq!(convert(F::Rg8Unorm, &[0, 255, 51, 102]), [9.0, 0.0, 1.0, 0.0, 1.0, 0.2, 0.4, 0.0, 1.0]);
        assert_eq!(convert(F::Bgra8Unorm, &[0, 51, 255, 102]), [9.0, 1.0, 0.2, 0.0, 0.4]);
        let r32: Vec<u8> = [-3.5f32, f32::NAN].iter().flat_map(|v| v.to_le_bytes()).collect();
        let out = convert(F::R32Float, &r32);
        assert_eq!(out[..5], [9.0, -3.5, 0.0, 0.0, 1.0]);
        assert!(out[5].is_nan() && out[6..] == [0.0, 0.0, 1.0]);
    }

    #[test]
    fn encodings_round_trip() {
        let img =
            CapturedImage::new("p", "o", 1, 2, 1, wgpu::TextureFormat::Rgba16Float, vec![0.5, 1.0, 2.0, 1.0, f32::NAN, 0.0, 0.0, 1.0]);
        let png = image::load_from_memory(&img.to_png()).unwrap().to_rgba8();
        assert_eq!(png.get_pixel(1, 0).0, [255, 0, 255, 255], "NaN shows magenta");
        let raw = img.raw_f32();
        assert_eq!(f32::from_le_bytes(raw[8..12].try_into().unwrap()), 2.0);
        let exr = img.to_exr().unwrap();
        assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "EXR magic");
    }
}
