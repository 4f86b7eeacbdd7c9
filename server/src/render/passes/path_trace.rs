//! The reference path tracer (`shaders/passes/path_trace.wgsl`): one
//! sample per pixel per frame, accumulated in a history buffer up to
//! `quality.path_spp`, over the raster's own triangles in a BVH
//! (`render::path_geometry`). Its outputs are the running means: `color`
//! (linear radiance), the first hit's `albedo` and `normal` (what a
//! denoiser takes), and `samples`. The session forgets the history, so
//! accumulation restarts, whenever the scene or its pipeline changes.

use super::{LIGHTS, MATERIAL_INSTANCES, MATERIAL_PARAMS, MATERIAL_SAMPLER, MATERIAL_TEXTURES, MEDIA, VIEW, material_bindings};
use crate::gpu::pipeline::{COMPUTE, Group, HDR, PipelineSpec, Stages, sizes, storage, storage_rw, storage_texture, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Element, Handle, PipelineKey, TensorLayout, TextureDesc};
use crate::scene::{Renderer, Scene};

/// The def that compiles the media code in: only scenes with media pay for it.
pub const MEDIA_DEF: &str = "MEDIA";
/// The shader's workgroup side.
const TILE: u32 = 8;
/// f32s of history per pixel: colour sum and count, albedo and normal sums.
const ACCUMULATED: u32 = 12;

pub const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const SAMPLES: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

pub static PATH_TRACE: PipelineSpec = PipelineSpec {
    name: "path_trace",
    shader: "passes/path_trace.wgsl",
    stages: Stages::Compute { entry: "path_trace" },
    groups: &[
        Group::always(
            0,
            &[
                VIEW,
                LIGHTS,
                storage("shading", 3, COMPUTE),
                uniform("params", 4, COMPUTE, sizes::VEC4),
                storage_rw("accumulated", 5),
                storage_texture("color", 6, COLOR),
                storage_texture("albedo", 7, HDR),
                storage_texture("normal", 8, HDR),
                storage_texture("samples", 9, SAMPLES),
                MATERIAL_PARAMS,
                MATERIAL_INSTANCES,
                MATERIAL_TEXTURES,
                MATERIAL_SAMPLER,
            ],
        ),
        Group::always(1, &[storage("nodes", 0, COMPUTE), storage("triangles", 1, COMPUTE)]),
        Group::when(3, MEDIA_DEF, MEDIA),
    ],
    defs: &[MEDIA_DEF],
};
pub const SPECS: &[&PipelineSpec] = &[&PATH_TRACE];

/// The path-traced outputs.
pub struct Traced {
    pub color: Handle,
    pub albedo: Handle,
    pub normal: Handle,
    pub samples: Handle,
}

/// The path tracer, or `None` (culled) when the renderer is the raster.
pub fn path_trace(g: &mut GraphBuilder, scene: &Scene) -> Option<Traced> {
    if scene.quality.renderer != Renderer::Path {
        g.cull("path_trace", "quality.renderer is raster");
        return None;
    }
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("path_trace", PassKind::Compute);
    p.one_invocation_per_pixel();
    let key = p.pipeline(PipelineKey::new(&PATH_TRACE, &[(MEDIA_DEF, !scene.media.is_empty())]));
    let accumulated = p.history("accumulated", Meaning::Data, TensorLayout::new(&[("pixel", w * h), ("channel", ACCUMULATED)], Element::F32), Access::StorageWrite);
    let color = p.create("color", Meaning::Color, TextureDesc::d2(COLOR, w, h), Access::StorageWrite);
    let albedo = p.create("albedo", Meaning::Color, TextureDesc::d2(HDR, w, h), Access::StorageWrite);
    let normal = p.create("normal", Meaning::Normal, TextureDesc::d2(HDR, w, h), Access::StorageWrite);
    let samples = p.create("samples", Meaning::Data, TextureDesc::d2(SAMPLES, w, h), Access::StorageWrite);
    let params = [scene.quality.path_spp, scene.quality.path_bounces, 0, 0];
    let media = !scene.media.is_empty();
    p.execute(move |ctx| {
        let s = ctx.scene;
        let geometry = s.path.as_ref().expect("a path-traced scene has path geometry");
        let u = ctx.uniform(bytemuck::cast_slice(&params));
        let mut b = vec![
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("shading", geometry.shading.as_entire_binding()),
            ("params", u.as_entire_binding()),
            ("accumulated", ctx.bind(accumulated)),
            ("color", ctx.bind(color)),
            ("albedo", ctx.bind(albedo)),
            ("normal", ctx.bind(normal)),
            ("samples", ctx.bind(samples)),
            ("nodes", geometry.nodes().as_entire_binding()),
            ("triangles", geometry.triangles().as_entire_binding()),
        ];
        b.extend(material_bindings(s));
        if media {
            b.push(("media", s.media.as_entire_binding()));
        }
        ctx.dispatch(&key, &b, [w.div_ceil(TILE), h.div_ceil(TILE), 1]);
    });
    Some(Traced { color, albedo, normal, samples })
}

#[cfg(test)]
mod glass_tests;
#[cfg(test)]
mod tests;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
