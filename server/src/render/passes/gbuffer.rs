//! Surface attributes per pixel (layout in `geometry/gbuffer.wgsl`).

use super::{MATERIAL_INSTANCES, MATERIAL_PARAMS, MATERIAL_SAMPLER, MATERIAL_TEXTURES, VIEW, material_bindings};
use crate::gpu::pipeline::{ALL, Depth, Group, HDR, PipelineSpec, Stages, depth_texture, storage, storage_rw_fragment};
use crate::render::context::DepthTarget;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Element, Handle, Meaning, PipelineKey, TensorLayout, TextureDesc};
use crate::scene::Scene;

/// The `uv` target's format: f32, so a texture's texel is exact at any UV
/// range or tiling (f16 has 11 bits: a 4096² texture's texel at UV 1 would
/// be lost).
pub const UV: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// What the inspection targets spend per pixel, on every material alike:
/// normal, albedo and material at `HDR` (8 bytes each) and `uv` at `UV`
/// (8), for the inspector and the debug views; the lighting reads the
/// material buffer instead (`material::pack::words` per material). A test
/// checks it against the formats.
pub const BYTES_PER_PIXEL: u32 = 32;

/// Where the material buffer is bound in the G-buffer's group 0 (and the
/// lighting's, read-only): after the material module's bindings.
pub const WORDS_BINDING: u32 = 14;

pub static GBUFFER: PipelineSpec = PipelineSpec {
    name: "geometry.gbuffer",
    shader: "geometry/gbuffer.wgsl",
    stages: Stages::Mesh { vertex: "vs_main", fragment: Some("fs_main"), targets: &[HDR, HDR, HDR, UV], depth: Depth::Equal },
    groups: &[Group::always(
        0,
        &[VIEW, storage("objects", 1, ALL), MATERIAL_PARAMS, MATERIAL_INSTANCES, MATERIAL_TEXTURES, MATERIAL_SAMPLER, storage_rw_fragment("material_words", WORDS_BINDING), depth_texture("depth", WORDS_BINDING + 1)],
    )],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&GBUFFER];

pub struct GBuffer {
    pub normal: Handle,
    pub albedo: Handle,
    pub material: Handle,
    pub uv: Handle,
    /// The material buffer: per pixel its material after `init`, packed
    /// (`material::pack`), word k of pixel i at `k * width * height + i`.
    pub words: Handle,
}

pub fn gbuffer(g: &mut GraphBuilder, scene: &Scene, depth: Handle, material_words: u32) -> GBuffer {
    let d = TextureDesc::d2(HDR, scene.width, scene.height);
    let mut p = g.pass("gbuffer", PassKind::Raster);
    let key = p.pipeline(PipelineKey::new(&GBUFFER, &[]));
    p.access(depth, Access::DepthTest);
    p.sample(depth);
    let gb = GBuffer {
        normal: p.create("normal", Meaning::Normal, d.clone(), Access::ColorTarget),
        albedo: p.create("albedo", Meaning::Color, d.clone(), Access::ColorTarget),
        material: p.create("material", Meaning::Data, d, Access::ColorTarget),
        uv: p.create("uv", Meaning::Data, TextureDesc::d2(UV, scene.width, scene.height), Access::ColorTarget),
        words: p.create(
            "material_words",
            Meaning::Data,
            TensorLayout::new(&[("word", material_words), ("y", scene.height), ("x", scene.width)], Element::U32),
            Access::StorageWrite,
        ),
    };
    let words = gb.words;
    let targets = [gb.normal, gb.albedo, gb.material, gb.uv];
    p.execute(move |ctx| {
        let s = ctx.scene;
        let [params, instances, textures, sampler] = material_bindings(s);
        let bindings = [
            ("view", s.view.as_entire_binding()),
            ("objects", s.objects.as_entire_binding()),
            params,
            instances,
            textures,
            sampler,
            ("material_words", ctx.bind(words)),
            ("depth", ctx.bind(depth)),
        ];
        ctx.draw_objects(&key, &bindings, &targets, Some(DepthTarget { texture: depth, layer: 0, clear: false }));
    });
    gb
}

#[cfg(test)]
mod tests {
    #[test]
    fn bytes_per_pixel_are_the_targets_formats() {
        let targets = [super::HDR, super::HDR, super::HDR, super::UV];
        let sum: u32 = targets.iter().map(|f| f.block_copy_size(None).expect("a colour format")).sum();
        assert_eq!(super::BYTES_PER_PIXEL, sum);
    }
}
