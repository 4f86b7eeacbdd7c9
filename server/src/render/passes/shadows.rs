//! Shadow maps for every shadow-casting light, one layer per light (six
//! for point lights), drawn from the light.

use crate::gpu::pipeline::{DEPTH, Depth, Group, PipelineSpec, Stages, VERT, sizes, storage, uniform};
use crate::render::context::DepthTarget;
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Handle, Meaning, PipelineKey, Projection, TextureDesc};
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
    let depth = p.create("depth", Meaning::Depth(Projection::Light), TextureDesc::array(DEPTH, size, size, layers), Access::DepthTarget);
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
mod tests {
    use std::collections::BTreeSet;

    use crate::render::passes::path_trace::testing::session;
    use crate::scene::overrides::Overrides;
    use crate::scene::settings::Value;

    /// `quality.shadow_filter`: radius 0 is one tap per lookup, and each larger
    /// radius moves the shadow's edge further from the hard one (the image's
    /// total difference from radius 0 grows with the radius); radius 1 is the
    /// 3×3 PCF the raster had before the setting.
    #[test]
    fn a_larger_filter_radius_softens_the_shadow_edge_more() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/minimal.toml");
        let scene = |r: i64| {
            let o = Overrides::from([("quality.shadow_filter".to_owned(), Value::Int(r)), ("output.width".to_owned(), Value::Int(96)), ("output.height".to_owned(), Value::Int(54))]);
            crate::loaded::load_with(&path, &o).unwrap_or_else(|d| panic!("{d}"))
        };
        let mut s = session(&scene(0));
        let wanted: BTreeSet<String> = ["lighting/color".to_owned()].into();
        let mut images = Vec::new();
        for r in 0..=3 {
            assert_eq!(s.set_scene_now(&scene(r)), vec![]);
            let pending = s.submit(Some(&wanted), 1.0 / 30.0);
            let frame = s.wait(pending);
            let lit = frame.captures.iter().find(|c| c.key() == "lighting/color").expect("captured");
            assert!(!lit.stats.has_non_finite());
            images.push(lit.data.clone());
        }
        let from_hard: Vec<f64> = images.iter().map(|img| img.iter().zip(&images[0]).map(|(a, b)| f64::from((a - b).abs())).sum()).collect();
        eprintln!("total difference from radius 0, radius 0 to 3: {from_hard:?}");
        assert!(from_hard[1] > 0.0 && from_hard[1] < from_hard[2] && from_hard[2] < from_hard[3], "{from_hard:?}");
    }
}
