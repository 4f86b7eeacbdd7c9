//! Images as the frame's input instead of a renderer's output: `loupe
//! denoise` feeds the denoiser's passes the files it was given, one tile
//! of them per frame (`render::denoise_graph`). The pass uploads them into
//! `Rgba32Float` textures, so the values reach the network as written.

use std::sync::Arc;

use super::denoise::Noisy;
use super::path_trace::COLOR;
use crate::denoise::image::Image;
use crate::gpu::pipeline::PipelineSpec;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, TextureDesc};

pub const SPECS: &[&PipelineSpec] = &[];

/// The colour, albedo and normal of one tile, all of one size (RGB); an
/// absent albedo or normal is never read by a network that does not take
/// it, and is uploaded as zeros.
pub struct TileImages {
    pub color: Image,
    pub albedo: Option<Image>,
    pub normal: Option<Image>,
}

/// The `images` pass: the tile's images as textures.
pub fn images(g: &mut GraphBuilder, tile: Arc<TileImages>) -> Noisy {
    let (w, h) = (tile.color.width as u32, tile.color.height as u32);
    let mut p = g.pass("images", PassKind::Copy);
    let desc = TextureDesc::d2(COLOR, w, h);
    let color = p.create("color", Meaning::Color, desc.clone(), Access::CopyDst);
    let albedo = p.create("albedo", Meaning::Color, desc.clone(), Access::CopyDst);
    let normal = p.create("normal", Meaning::Normal, desc, Access::CopyDst);
    p.execute(move |ctx| {
        for (image, target) in [(Some(&tile.color), color), (tile.albedo.as_ref(), albedo), (tile.normal.as_ref(), normal)] {
            let rows = rgba_rows(image, w as usize, h as usize);
            let staging = wgpu::util::DeviceExt::create_buffer_init(
                ctx.device,
                &wgpu::util::BufferInitDescriptor { label: Some("images"), contents: &rows.bytes, usage: wgpu::BufferUsages::COPY_SRC },
            );
            let layout = wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(rows.stride), rows_per_image: Some(h) };
            let texture = ctx.texture(target);
            ctx.encoder.copy_buffer_to_texture(wgpu::TexelCopyBufferInfo { buffer: &staging, layout }, texture.as_image_copy(), texture.size());
        }
    });
    Noisy { color, albedo, normal }
}

/// An image's pixels as RGBA f32 rows, each padded to wgpu's copy
/// alignment (zeros when there is no image).
struct Rows {
    bytes: Vec<u8>,
    stride: u32,
}

fn rgba_rows(image: Option<&Image>, w: usize, h: usize) -> Rows {
    let stride = crate::render::readback::padded_row(w as u32 * 16) as usize;
    let mut bytes = vec![0u8; stride * h];
    if let Some(image) = image {
        for (y, row) in bytes.chunks_mut(stride).enumerate() {
            for x in 0..w {
                let rgb = &image.data[(y * w + x) * 3..][..3];
                let texel: [f32; 4] = [rgb[0], rgb[1], rgb[2], 1.0];
                row[x * 16..][..16].copy_from_slice(bytemuck::cast_slice(&texel));
            }
        }
    }
    Rows { bytes, stride: stride as u32 }
}
