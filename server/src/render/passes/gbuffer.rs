//! Surface attributes per pixel (layout in `geometry/gbuffer.wgsl`).

use super::{MATERIAL_INSTANCES, MATERIAL_PARAMS, MATERIAL_SAMPLER, MATERIAL_TEXTURES, VIEW, material_bindings};
use crate::gpu::pipeline::{ALL, Depth, Group, HDR, PipelineSpec, Stages, storage};
use crate::render::context::DepthTarget;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Handle, PipelineKey, TextureDesc};
use crate::scene::Scene;

/// The `uv` target's format: f32, so a texture's texel is exact at any UV
/// range or tiling (f16 has 11 bits: a 4096² texture's texel at UV 1 would
/// be lost).
pub const UV: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// What the G-buffer spends per pixel, on every material alike: normal,
/// albedo and material at `HDR` (8 bytes each) and `uv` at `UV` (8); the
/// compile report's `gbuffer_bytes_per_pixel`. A test checks it against
/// the formats.
pub const BYTES_PER_PIXEL: u32 = 32;

pub static GBUFFER: PipelineSpec = PipelineSpec {
    name: "geometry.gbuffer",
    shader: "geometry/gbuffer.wgsl",
    stages: Stages::Mesh { vertex: "vs_main", fragment: Some("fs_main"), targets: &[HDR, HDR, HDR, UV], depth: Depth::Equal },
    groups: &[Group::always(0, &[VIEW, storage("objects", 1, ALL), MATERIAL_PARAMS, MATERIAL_INSTANCES, MATERIAL_TEXTURES, MATERIAL_SAMPLER])],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&GBUFFER];

pub struct GBuffer {
    pub normal: Handle,
    pub albedo: Handle,
    pub material: Handle,
    pub uv: Handle,
}

pub fn gbuffer(g: &mut GraphBuilder, scene: &Scene, depth: Handle) -> GBuffer {
    let d = TextureDesc::d2(HDR, scene.width, scene.height);
    let mut p = g.pass("gbuffer", PassKind::Raster);
    let key = p.pipeline(PipelineKey::new(&GBUFFER, &[]));
    p.access(depth, Access::DepthTest);
    let gb = GBuffer {
        normal: p.create("normal", Meaning::Normal, d.clone(), Access::ColorTarget),
        albedo: p.create("albedo", Meaning::Color, d.clone(), Access::ColorTarget),
        material: p.create("material", Meaning::Data, d, Access::ColorTarget),
        uv: p.create("uv", Meaning::Data, TextureDesc::d2(UV, scene.width, scene.height), Access::ColorTarget),
    };
    let targets = [gb.normal, gb.albedo, gb.material, gb.uv];
    p.execute(move |ctx| {
        let s = ctx.scene;
        let [params, instances, textures, sampler] = material_bindings(s);
        let bindings =
            [("view", s.view.as_entire_binding()), ("objects", s.objects.as_entire_binding()), params, instances, textures, sampler];
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
