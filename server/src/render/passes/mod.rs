//! The passes of the frame, one module each: its pipeline spec(s), the
//! defs and settings it reads, why it is culled, and its builder — a free
//! function taking the graph builder and input handles and returning
//! output handles. `render::build_graph` assembles them into a frame.

use crate::gpu::pipeline::{ALL, Binding, COMPUTE, FRAG, Group, PipelineSpec, Stages, sizes, storage, uniform};
use crate::material::back::Bindings;
use crate::scene::Scene;
use crate::scene::settings::FULLSCREEN;

use super::resource::PipelineKey;

pub use crate::gpu::pipeline::TWO_TRIANGLES;

/// Lists the pass modules; every spec they declare lands in `specs()`.
macro_rules! passes {
    ($($pass:ident),* $(,)?) => {
        $(pub mod $pass;)*

        /// Each pass module's name and its `SPECS`.
        const MODULES: &[(&str, &[&PipelineSpec])] = &[$((stringify!($pass), $pass::SPECS)),*];
    };
}

passes![
    test_pattern,
    shadows,
    depth_prepass,
    gbuffer,
    classify,
    ltc_tables,
    lighting,
    volume_shadows,
    volume_march,
    volumes,
    path_trace,
    images,
    denoise,
    auto_exposure,
    exposure,
    tonemap,
    debug_view,
    nan_watch,
];

/// Every pipeline any pass can build: what `loupe check` creates.
pub fn specs() -> impl Iterator<Item = &'static PipelineSpec> {
    MODULES.iter().flat_map(|(_, specs)| specs.iter().copied())
}

/// The passes drawn as a fullscreen triangle: the modules declaring a
/// `Stages::Fullscreen` spec, since a fullscreen pass is named after its
/// module (a test holds every frame to that).
pub fn fullscreen() -> impl Iterator<Item = &'static str> {
    MODULES.iter().filter(|(_, specs)| specs.iter().any(|s| matches!(s.stages, Stages::Fullscreen { .. }))).map(|(name, _)| *name)
}

/// A setting's `affects` as pass names: its groups (`settings::FULLSCREEN`)
/// expanded, and `lighting` as every tile class's lighting pass
/// (`lighting::PASSES`): what changes the lighting changes each.
pub fn affected(affects: &[&'static str]) -> Vec<&'static str> {
    affects
        .iter()
        .flat_map(|&a| match a {
            FULLSCREEN => fullscreen().collect(),
            "lighting" => lighting::PASSES.to_vec(),
            _ => vec![a],
        })
        .fold(Vec::new(), |mut out, p| {
            // A group and a pass of it may both be named: each once.
            if !out.contains(&p) {
                out.push(p);
            }
            out
        })
}

/// The spec named `name`.
pub fn spec(name: &str) -> Option<&'static PipelineSpec> {
    specs().find(|s| s.name == name)
}

/// The def that turns on shadow-map lookups (`lib/shadows.wgsl`).
pub const SHADOWS: &str = "SHADOWS";

/// The camera, as `lib/view.wgsl` declares it.
pub const VIEW: Binding = uniform("view", 0, ALL, sizes::VIEW);
/// The scene's lights, as `lib/lights.wgsl` declares them: read by raster
/// and compute passes (the path tracer).
pub const LIGHTS: Binding = storage("lights", 1, FRAG.union(COMPUTE));
/// Shadow maps and their views (`lib/shadows.wgsl`), with SHADOWS on.
pub const SHADOW_GROUP: Group =
    Group::when(1, SHADOWS, &[crate::gpu::pipeline::depth_array("shadow_maps", 0), storage("shadow_views", 1, FRAG.union(COMPUTE))]);
/// The participating media (`lib/media.wgsl`), for raster and compute passes.
/// `loupe::material`'s parameters and instance table (group 0, in every
/// pass that imports the module; `material::back`'s binding numbers).
pub const MATERIAL_PARAMS: Binding = storage("material_params", Bindings::RENDERER.params, FRAG.union(COMPUTE));
pub const MATERIAL_INSTANCES: Binding = storage("material_instances", Bindings::RENDERER.instances, FRAG.union(COMPUTE));
/// Its textures (one filterable array, every layout has it so a texture
/// added to a scene changes no layout) and their sampler.
pub const MATERIAL_TEXTURES: Binding = Binding {
    name: "material_textures",
    entry: wgpu::BindGroupLayoutEntry {
        binding: Bindings::RENDERER.textures,
        visibility: FRAG.union(COMPUTE),
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    },
};
pub const MATERIAL_SAMPLER: Binding = Binding {
    name: "material_sampler",
    entry: wgpu::BindGroupLayoutEntry {
        binding: Bindings::RENDERER.sampler,
        visibility: FRAG.union(COMPUTE),
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    },
};
/// Binds them.
pub fn material_bindings(s: &crate::render::scene_gpu::SceneGpu) -> [(&'static str, wgpu::BindingResource<'_>); 4] {
    [
        ("material_params", s.material_params.as_entire_binding()),
        ("material_instances", s.material_instances.as_entire_binding()),
        ("material_textures", wgpu::BindingResource::TextureView(&s.material_textures.view)),
        ("material_sampler", wgpu::BindingResource::Sampler(&s.material_textures.sampler)),
    ]
}
pub const MEDIA: &[Binding] = &[storage("media", 0, FRAG.union(COMPUTE))];

/// A fullscreen pass's key: TWO_TRIANGLES as the scene says, plus `defs`.
pub fn fullscreen_key(spec: &'static PipelineSpec, scene: &Scene, defs: &[(&'static str, bool)]) -> PipelineKey {
    let mut all = vec![(TWO_TRIANGLES, scene.post.two_triangles)];
    all.extend_from_slice(defs);
    PipelineKey::new(spec, &all)
}

pub fn vec4_bytes(v: [f32; 4]) -> Vec<u8> {
    bytemuck::cast_slice(&v).to_vec()
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::render::graph::Graph;
    use crate::scene::overrides::{self, Overrides};
    use crate::scene::settings::Value;
    use crate::scene::settings::{self, Kind, SETTINGS};

    /// The values a setting is tried at: a toggle's two, a choice's every
    /// option, a number's extremes.
    fn switch_values(kind: Kind) -> Vec<Value> {
        match kind {
            Kind::Toggle => vec![Value::Bool(false), Value::Bool(true)],
            Kind::Choice(options) => options.iter().map(|o| Value::Text((*o).to_owned())).collect(),
            Kind::Int { min, max, .. } => vec![Value::Int(min), Value::Int(max)],
            Kind::Float { min, max, .. } => vec![Value::Float(min), Value::Float(max)],
        }
    }

    /// Every override of one setting of the table, so a new setting is
    /// tried without a line here.
    fn switches() -> impl Iterator<Item = (&'static str, Value)> {
        SETTINGS.iter().flat_map(|s| switch_values(s.kind).into_iter().map(move |v| (s.path, v)))
    }

    /// An override refused by the scene is one of an ordered pair's: the
    /// extreme crosses the other setting's value.
    fn refused_for_order(key: &str, why: impl std::fmt::Display) {
        assert!(settings::ORDERED.iter().any(|(a, b)| *a == key || *b == key), "{key}: {why}");
    }

    /// What the frames of the test use.
    #[derive(Default)]
    struct Seen {
        specs: BTreeSet<&'static str>,
        /// The passes that draw with a fullscreen spec.
        fullscreen: BTreeSet<String>,
    }

    /// Holds `graph` to `specs()` and notes what it uses.
    fn check(graph: &Graph, seen: &mut Seen) {
        for k in graph.pipelines() {
            assert!(specs().any(|s| std::ptr::eq(s, k.spec)), "{} is built by a frame but not listed for loupe check", k.label());
            seen.specs.insert(k.spec.name);
        }
        for p in &graph.passes {
            if p.pipelines.iter().any(|k| matches!(k.spec.stages, Stages::Fullscreen { .. })) {
                seen.fullscreen.insert(p.name.clone());
            }
        }
    }

    /// Every pipeline a frame can use is one `loupe check` creates: the
    /// graphs of every bundled scene under every value of every setting
    /// (each alone) only name specs in `specs()`, and every spec there is
    /// used by some frame. The passes drawn fullscreen are the ones
    /// `fullscreen()` names after their modules.
    #[test]
    fn every_pipeline_a_frame_uses_is_enumerated_for_loupe_check() {
        let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut seen = Seen::default();
        let mut scenes_seen = 0;
        for entry in std::fs::read_dir(&scenes).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            scenes_seen += 1;
            for (key, v) in switches() {
                let overrides = Overrides::from([(key.to_owned(), v)]);
                let loaded = match crate::loaded::load_with(&path, &overrides) {
                    Ok(loaded) => loaded,
                    Err(d) => {
                        refused_for_order(key, d);
                        continue;
                    }
                };
                for nan_watch in [false, true] {
                    let options = crate::render::FrameOptions { nan_watch, ..Default::default() };
                    check(&crate::render::build_graph(&loaded.scene, loaded.denoiser.as_deref(), options), &mut seen);
                }
            }
        }
        assert!(scenes_seen >= 4, "the bundled scenes are found");
        // No bundled scene names weights (they are not in the repository):
        // a denoised frame on a small random network, in each of its modes,
        // the first under every setting too.
        let network = crate::denoise::testing::network(&crate::denoise::testing::small_unet(9), 1);
        let modes = [
            ("f32", "hdr", true, "direct", ""),
            ("f16", "ldr", false, "tiled", ""),
            ("f16", "hdr", true, "tiled", ""),
            ("f32", "ldr", false, "direct", ""),
            ("f32", "ldr_srgb", true, "direct", ""),
            ("f32", "hdr", true, "tiled", "input_scale = 0.5"),
        ];
        for (i, (precision, mode, fused, kernel, scale)) in modes.into_iter().enumerate() {
            let text = format!(
                "[quality]\nrenderer = \"path\"\ndenoiser_fused = {fused}\ndenoiser_kernel = \"{kernel}\"\n[denoiser]\nweights = \"w.tza\"\nprecision = \"{precision}\"\nmode = \"{mode}\"\n{scale}\n\
                 [[materials]]\nname = \"m\"\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n"
            );
            let switched = if i == 0 { switches().map(|(k, v)| Overrides::from([(k.to_owned(), v)])).collect() } else { vec![] };
            for o in std::iter::once(Overrides::new()).chain(switched) {
                let scene = overrides::apply(&text, &o).and_then(|t| crate::scene::parse("denoised.toml", &t).map_err(|d| d.to_string()));
                match scene {
                    Ok(scene) => check(&crate::render::build_graph(&scene, Some(&network), Default::default()), &mut seen),
                    Err(why) => refused_for_order(o.keys().next().expect("only overrides are refused"), why),
                }
            }
        }
        let listed: BTreeSet<&str> = specs().map(|s| s.name).collect();
        assert_eq!(listed, seen.specs, "every listed spec is used by some frame");
        let named: BTreeSet<String> = fullscreen().map(str::to_owned).collect();
        assert_eq!(named, seen.fullscreen, "fullscreen() names the passes that draw fullscreen: each is named after its module");
    }
}
