//! Linearly Transformed Cosine (LTC) tables for GGX, the building block of
//! rectangular area lights (`shaders/lib/ltc.wgsl`, `loupe::ltc`).
//!
//! # Provenance and license of the tables
//!
//! `server/assets/ltc_ggx_1.bin` and `ltc_ggx_2.bin` are the 64 x 64 GGX
//! fit published with "Real-Time Polygonal-Light Shading with Linearly
//! Transformed Cosines", Eric Heitz, Jonathan Dupuy, Stephen Hill and David
//! Neubelt, ACM TOG (SIGGRAPH 2016) 35(4); project page
//! <https://eheitzresearch.wordpress.com/415-2/>. The figures are those of
//! `fit/results/ltc.js` (arrays `g_ltc_1`, `g_ltc_2`) in
//! <https://github.com/selfshadow/ltc_code> at commit 31e5e96 (the fit as
//! renormalised by the matrix's middle element, 5c0770b, October 2017; the
//! same fit three.js ships in `RectAreaLightUniformsLib`). They were
//! converted, value for value, from that decimal text to little-endian f32;
//! they agree with the repository's half-float `ltc_1.dds` / `ltc_2.dds` to
//! half precision. Only the data is taken; the code here is our own.
//!
//! License of the data: BSD 3-clause style, reproduced in full in
//! `server/assets/LICENSE-ltc_code.txt`. "Copyright (c) 2017, Eric Heitz,
//! Jonathan Dupuy, Stephen Hill and David Neubelt. All rights reserved."
//! Redistribution in source and binary forms is permitted provided that
//! source redistributions retain the notice, and binary redistributions
//! (loupe's binary embeds the tables) reproduce the notice, conditions and
//! disclaimer in their documentation: ship that file with binaries. Users
//! of the code are asked to cite the paper above. Provided "as is", without
//! warranty.
//!
//! # Parameterisation
//!
//! Texel `(i, j)` (column `i`, row `j`) holds the fit for
//! `roughness = i / 63` (perceptual roughness; GGX `alpha = roughness²`) and
//! `sqrt(1 - cos θv) = j / 63`, with the view vector at
//! `(sin θv, 0, cos θv)` in the shading frame. Texel centres are the fitted
//! samples, so shaders read at texel coordinate `(roughness, sqrt(1 - n·v)) * 63`.
//! The BRDF fitted is GGX with the height-correlated Smith term
//! `G2 = 1 / (1 + Λ(v) + Λ(l))` and no Fresnel; the Fresnel channel is the
//! same integral weighted by Schlick's `(1 - v·h)^5`.

/// Width and height of both tables.
pub const SIZE: u32 = 64;

/// Both tables are stored and uploaded as f32: the smallest entries (the
/// inverse matrix at low roughness, ~2e-5) are below half precision's
/// normal range. The renderer reads them with `textureLoad`, so they need
/// not be filterable.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

const TEXELS: usize = (SIZE * SIZE) as usize;
const TABLE_BYTES: usize = TEXELS * 4 * 4;

static MATRIX_BYTES: &[u8] = include_bytes!("../../assets/ltc_ggx_1.bin");
static AMPLITUDE_BYTES: &[u8] = include_bytes!("../../assets/ltc_ggx_2.bin");

/// Decodes a table: RGBA texels, row by row, little-endian f32.
fn decode(bytes: &[u8]) -> Vec<f32> {
    assert_eq!(bytes.len(), TABLE_BYTES, "LTC table has the wrong size");
    bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

/// Table 0, the inverse LTC matrix, divided by its middle element so that
/// only four coefficients vary. Channels `(r, g, b, a) = (m00, m20, m02, m22)`
/// of
/// ```text
///         | r  0  b |
/// M^-1 =  | 0  1  0 |     (rows; x towards v, z along the normal)
///         | g  0  a |
/// ```
pub fn matrix_table() -> Vec<f32> {
    decode(MATRIX_BYTES)
}

/// Table 1: `r` = the lobe's magnitude, ∫ f·cos over the hemisphere with
/// F = 1 (the directional albedo of GGX); `g` = the same integral weighted by
/// `(1 - v·h)^5`, so Schlick's `F = f0 + (f90 - f0)(1 - v·h)^5` scales the
/// lobe by `f0·(r - g) + f90·g`; `b` = 0 (unused); `a` = the form factor of a
/// sphere clipped to the horizon, for the "vector form factor" horizon
/// approximation (indexed differently: column = `(cos elevation + 1) / 2 * 63`,
/// row = `|form factor vector| * 63`). `ltc.wgsl` clips exactly and does not
/// read `a`.
pub fn amplitude_table() -> Vec<f32> {
    decode(AMPLITUDE_BYTES)
}

/// Creates the two 64 x 64 `Rgba32Float` tables, uploaded and ready to bind
/// as unfilterable float textures: `[0]` is [`matrix_table`] (the inverse
/// LTC matrix, `m_tex` in `ltc.wgsl`), `[1]` is [`amplitude_table`]
/// (magnitude, Fresnel, 0, sphere form factor; `amp_tex`). See those two
/// functions for what each channel holds.
pub fn create_textures(device: &wgpu::Device, queue: &wgpu::Queue) -> [wgpu::Texture; 2] {
    textures_from(device, queue, &matrix_table(), &amplitude_table())
}

fn textures_from(device: &wgpu::Device, queue: &wgpu::Queue, matrix: &[f32], amplitude: &[f32]) -> [wgpu::Texture; 2] {
    [upload(device, queue, "ltc.matrix", matrix), upload(device, queue, "ltc.amplitude", amplitude)]
}

/// A `SIZE` x `SIZE` table of RGBA f32 texels as a texture the renderer
/// binds unfilterable (and copies from).
pub fn upload(device: &wgpu::Device, queue: &wgpu::Queue, label: &str, texels: &[f32]) -> wgpu::Texture {
    let size = wgpu::Extent3d { width: SIZE, height: SIZE, depth_or_array_layers: 1 };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    // Native-endian bytes from the decoded values: the file is
    // little-endian whatever the host is.
    queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(texels),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(SIZE * 16), rows_per_image: None },
        size,
    );
    texture
}

#[cfg(test)]
pub(crate) mod tests;
