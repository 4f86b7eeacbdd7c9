//! The GPU side of material textures: the scene's `material::texture::Layers`
//! uploaded as one `Rgba16Float` `texture_2d_array` with every mip level,
//! and the filtering sampler the generated module reads it with
//! (`material::back::Bindings::textures` and `sampler`).

use crate::material::texture::Layers;

/// The uploaded array's view and its sampler.
pub struct MaterialTextures {
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
}

impl MaterialTextures {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, layers: &Layers) -> Self {
        let levels = layers.layers[0].len() as u32;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("material textures"),
            size: wgpu::Extent3d { width: layers.width, height: layers.height, depth_or_array_layers: layers.layers.len() as u32 },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            // Half floats: filterable everywhere, linear values of 8-bit
            // sRGB and of EXR alike (16-bit PNGs keep 11 bits of mantissa).
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (layer, chain) in layers.layers.iter().enumerate() {
            for (level, img) in chain.iter().enumerate() {
                let texels: Vec<u16> = img.pixels.iter().flatten().map(|&x| half::f16::from_f32(x).to_bits()).collect();
                queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: level as u32,
                        origin: wgpu::Origin3d { x: 0, y: 0, z: layer as u32 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    bytemuck::cast_slice(&texels),
                    wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(img.width * 8), rows_per_image: Some(img.height) },
                    wgpu::Extent3d { width: img.width, height: img.height, depth_or_array_layers: 1 },
                );
            }
        }
        let view = texture
            .create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material textures"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        MaterialTextures { view, sampler }
    }
}
