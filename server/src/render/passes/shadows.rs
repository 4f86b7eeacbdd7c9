//! Shadow maps for every shadow-casting light, one layer per light (six
//! for point lights), drawn from the light.

use crate::gpu::pipeline::{DEPTH, Depth, Group, PipelineSpec, Stages, VERT, sizes, storage, uniform};
use crate::render::context::DepthTarget;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Handle, PipelineKey, TextureDesc};
use crate::render::scene_gpu::shadow_layout;
use crate::scene::Scene;

pub static SHADOW: PipelineSpec = PipelineSpec {
    name: "geometry.shadow",
    shader: "geometry/shadow.wgsl",
    stages: Stages::Mesh { vertex: "vs_main", fragment: None, targets: &[], depth: Depth::Biased },
    groups: &[Group::always(0, &[uniform("shadow_view", 0, VERT, sizes::MAT4), storage("objects", 1, VERT)])],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&SHADOW];

pub fn shadows(g: &mut GraphBuilder, scene: &Scene) -> Option<Handle> {
    let (_, layers) = shadow_layout(scene);
    if !scene.quality.shadows {
        g.cull("shadows", "quality.shadows is off");
        return None;
    }
    if layers == 0 {
        let why = if scene.objects.is_empty() { "no objects to cast shadows" } else { "no light casts shadows" };
        g.cull("shadows", why);
        return None;
    }
    let size = scene.quality.shadow_map_size;
    let mut p = g.pass("shadows", PassKind::Raster);
    let key = p.pipeline(PipelineKey::new(&SHADOW, &[]));
    let depth = p.create("depth", TextureDesc::array(DEPTH, size, size, layers), Access::DepthTarget);
    p.execute(move |ctx| {
        let s = ctx.scene;
        for (layer, m) in s.shadow_layers.iter().enumerate() {
            let view = ctx.uniform(bytemuck::cast_slice(&m.to_cols_array()));
            let target = DepthTarget { texture: depth, layer: layer as u32, clear: true };
            ctx.draw_objects(&key, &[("shadow_view", view.as_entire_binding()), ("objects", s.objects.as_entire_binding())], &[], Some(target));
        }
    });
    Some(depth)
}

#[cfg(test)]
#[path = "shadows/tests.rs"]
mod tests;
