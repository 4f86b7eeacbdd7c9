//! The passes of the frame, each a free function: it takes the graph
//! builder and its input handles and returns its output handles, or records
//! why the scene does not call for it.

use super::graph::{GraphBuilder, Handle, PipelineKey, Target};
use crate::gpu::pipeline::{self, DEPTH, HDR, LDR};
use crate::scene::{DebugView, Estimator, Scene, Tonemap};

fn spec(name: &str) -> &'static pipeline::PipelineSpec {
    pipeline::spec(name).expect("pass names a registered pipeline spec")
}

fn fullscreen_defs(scene: &Scene) -> Vec<&'static str> {
    if scene.post.two_triangles { vec!["TWO_TRIANGLES"] } else { vec![] }
}

fn vec4_bytes(v: [f32; 4]) -> Vec<u8> {
    bytemuck::cast_slice(&v).to_vec()
}

/// A pattern of known values, the frame of a scene with nothing in it.
pub fn test_pattern(g: &mut GraphBuilder, scene: &Scene, frame: u64) -> Handle {
    let key = PipelineKey::new(spec("debug.test_pattern"), fullscreen_defs(scene));
    let (w, h) = (scene.width, scene.height);
    let exec_key = key.clone();
    g.add_pass(
        "test_pattern",
        vec![key],
        &[],
        vec![Target::new("color", HDR, w, h)],
        Box::new(move |ctx| {
            let mut u = vec4_bytes([w as f32, h as f32, 0.0, 0.0]);
            u[12..16].copy_from_slice(&(frame as u32).to_le_bytes());
            let buf = ctx.uniform(&u);
            ctx.fullscreen(&exec_key, &[&[buf.as_entire_binding()]]);
        }),
    )[0]
}

/// Shadow maps for every shadow-casting light, one layer per light (six
/// for point lights), drawn from the light.
pub fn shadows(g: &mut GraphBuilder, scene: &Scene) -> Option<Handle> {
    let (_, layers) = super::scene_gpu::shadow_layout(scene);
    if !scene.quality.shadows {
        g.cull("shadows", "quality.shadows is off");
        return None;
    }
    if layers == 0 {
        let why = if scene.objects.is_empty() { "no objects to cast shadows" } else { "no light casts shadows" };
        g.cull("shadows", why);
        return None;
    }
    let key = PipelineKey::new(spec("geometry.shadow"), []);
    let exec_key = key.clone();
    let size = scene.quality.shadow_map_size;
    let out = g.add_pass(
        "shadows",
        vec![key],
        &[],
        vec![Target::new("depth", DEPTH, size, size).layers(layers)],
        Box::new(move |ctx| {
            let s = ctx.scene;
            for (layer, m) in s.shadow_layers.iter().enumerate() {
                let u = ctx.uniform(bytemuck::cast_slice(&m.to_cols_array()));
                let target = ctx.output_layer(0, layer as u32);
                ctx.draw_objects(&exec_key, &[&[u.as_entire_binding(), s.objects.as_entire_binding()]], &[], Some((&target, true)));
            }
        }),
    );
    Some(out[0])
}

/// Depth of the nearest surface per pixel, so the G-buffer pass shades
/// each pixel once.
pub fn depth_prepass(g: &mut GraphBuilder, scene: &Scene) -> Handle {
    let key = PipelineKey::new(spec("geometry.depth"), []);
    let exec_key = key.clone();
    g.add_pass(
        "depth_prepass",
        vec![key],
        &[],
        vec![Target::new("depth", DEPTH, scene.width, scene.height)],
        Box::new(move |ctx| {
            let (s, target) = (ctx.scene, ctx.outputs[0]);
            ctx.draw_objects(&exec_key, &[&[s.view.as_entire_binding(), s.objects.as_entire_binding()]], &[], Some((target, true)));
        }),
    )[0]
}

pub struct GBuffer {
    pub normal: Handle,
    pub albedo: Handle,
    pub material: Handle,
}

/// Surface attributes per pixel (layout in `geometry/gbuffer.wgsl`).
pub fn gbuffer(g: &mut GraphBuilder, scene: &Scene, depth: Handle) -> GBuffer {
    let key = PipelineKey::new(spec("geometry.gbuffer"), []);
    let exec_key = key.clone();
    let (w, h) = (scene.width, scene.height);
    let out = g.add_pass(
        "gbuffer",
        vec![key],
        &[depth],
        vec![Target::new("normal", HDR, w, h), Target::new("albedo", HDR, w, h), Target::new("material", HDR, w, h)],
        Box::new(move |ctx| {
            let (s, depth, colors) = (ctx.scene, ctx.inputs[0], ctx.outputs.clone());
            let bindings = [s.view.as_entire_binding(), s.objects.as_entire_binding(), s.materials.as_entire_binding()];
            ctx.draw_objects(&exec_key, &[&bindings], &colors, Some((depth, false)));
        }),
    );
    GBuffer { normal: out[0], albedo: out[1], material: out[2] }
}

/// The LTC tables as textures the lighting pass reads; only for scenes
/// with a rect light. Copied in each frame from tables uploaded once, so
/// the inspector can show them like any other output.
pub fn ltc_tables(g: &mut GraphBuilder, scene: &Scene) -> Option<[Handle; 2]> {
    if !scene.has_rect_lights() {
        g.cull("ltc_tables", "no rectangular area light");
        return None;
    }
    let n = super::ltc::SIZE;
    let out = g.add_pass(
        "ltc_tables",
        vec![],
        &[],
        vec![Target::new("matrix", super::ltc::FORMAT, n, n), Target::new("amplitude", super::ltc::FORMAT, n, n)],
        Box::new(|ctx| {
            let Some(tables) = &ctx.scene.ltc else { return };
            for (i, t) in tables.iter().enumerate() {
                ctx.encoder.copy_texture_to_texture(t.as_image_copy(), ctx.output_textures[i].as_image_copy(), t.size());
            }
        }),
    );
    Some([out[0], out[1]])
}

/// Direct light from every light on the G-buffer, with shadows.
pub fn lighting(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle, shadows: Option<Handle>, ltc: Option<[Handle; 2]>) -> Handle {
    let mut defs = fullscreen_defs(scene);
    let mut reads = vec![gb.normal, gb.albedo, gb.material, depth];
    if let Some(s) = shadows {
        defs.push("SHADOWS");
        reads.push(s);
    }
    if let Some(t) = ltc {
        defs.push("LIGHT_RECT");
        reads.extend(t);
    }
    let media = !scene.media.is_empty();
    if media {
        defs.push("MEDIA_SHADOWS");
    }
    let key = PipelineKey::new(spec("lighting.deferred"), defs);
    let exec_key = key.clone();
    let (has_shadows, has_ltc) = (shadows.is_some(), ltc.is_some());
    g.add_pass(
        "lighting",
        vec![key],
        &reads,
        vec![Target::new("color", HDR, scene.width, scene.height)],
        Box::new(move |ctx| {
            let (s, i) = (ctx.scene, ctx.inputs.clone());
            let core = [
                s.view.as_entire_binding(),
                s.lights.as_entire_binding(),
                wgpu::BindingResource::TextureView(i[0]),
                wgpu::BindingResource::TextureView(i[1]),
                wgpu::BindingResource::TextureView(i[2]),
                wgpu::BindingResource::TextureView(i[3]),
            ];
            let mut next = 4;
            let shadow_group: Vec<wgpu::BindingResource> = if has_shadows {
                next += 1;
                vec![wgpu::BindingResource::TextureView(i[4]), s.shadow_views.as_entire_binding()]
            } else {
                vec![]
            };
            let ltc_group: Vec<wgpu::BindingResource> = if has_ltc {
                vec![wgpu::BindingResource::TextureView(i[next]), wgpu::BindingResource::TextureView(i[next + 1])]
            } else {
                vec![]
            };
            let media_group: Vec<wgpu::BindingResource> = if media { vec![s.media.as_entire_binding()] } else { vec![] };
            ctx.fullscreen(&exec_key, &[&core, &shadow_group, &ltc_group, &media_group]);
        }),
    )[0]
}

/// Single scattering through the scene's media, over the lit frame.
pub fn volumes(g: &mut GraphBuilder, scene: &Scene, color: Handle, depth: Handle, shadows: Option<Handle>) -> Handle {
    if scene.media.is_empty() {
        g.cull("volumes", "the scene has no participating media");
        return color;
    }
    let mut defs = fullscreen_defs(scene);
    let mut reads = vec![color, depth];
    if let Some(s) = shadows {
        defs.push("SHADOWS");
        reads.push(s);
    }
    if scene.quality.volume_estimator == Estimator::Analytic {
        defs.push("VOLUME_ANALYTIC");
    }
    let key = PipelineKey::new(spec("volumes.raymarch"), defs);
    let exec_key = key.clone();
    let has_shadows = shadows.is_some();
    let (w, h) = (scene.width, scene.height);
    g.add_pass(
        "volumes",
        vec![key],
        &reads,
        vec![Target::new("color", HDR, w, h), Target::new("transmittance", HDR, w, h)],
        Box::new(move |ctx| {
            let (s, i) = (ctx.scene, ctx.inputs.clone());
            let core = [s.view.as_entire_binding(), s.lights.as_entire_binding(), wgpu::BindingResource::TextureView(i[0]), wgpu::BindingResource::TextureView(i[1])];
            let shadow_group: Vec<wgpu::BindingResource> =
                if has_shadows { vec![wgpu::BindingResource::TextureView(i[2]), s.shadow_views.as_entire_binding()] } else { vec![] };
            ctx.fullscreen(&exec_key, &[&core, &shadow_group, &[], &[s.media.as_entire_binding()]]);
        }),
    )[0]
}

/// Multiplies the HDR frame by 2^EV; culled at 0 EV, where it would copy.
pub fn exposure(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Handle {
    if scene.post.exposure_ev == 0.0 {
        g.cull("exposure", "post.exposure_ev is 0: the frame passes through unchanged");
        return hdr;
    }
    let key = PipelineKey::new(spec("post.exposure"), fullscreen_defs(scene));
    let exec_key = key.clone();
    let scale = 2f32.powf(scene.post.exposure_ev);
    g.add_pass(
        "exposure",
        vec![key],
        &[hdr],
        vec![Target::new("color", HDR, scene.width, scene.height)],
        Box::new(move |ctx| {
            let buf = ctx.uniform(&vec4_bytes([scale, 0.0, 0.0, 0.0]));
            let input = ctx.inputs[0];
            ctx.fullscreen(&exec_key, &[&[buf.as_entire_binding(), wgpu::BindingResource::TextureView(input)]]);
        }),
    )[0]
}

/// Tonemapping to the displayable final image.
pub fn tonemap(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Handle {
    let mut defs = fullscreen_defs(scene);
    if scene.post.tonemap == Tonemap::Reinhard {
        defs.push("TONEMAP_REINHARD");
    }
    let key = PipelineKey::new(spec("post.tonemap"), defs);
    let exec_key = key.clone();
    g.add_pass(
        "tonemap",
        vec![key],
        &[hdr],
        vec![Target::new("color", LDR, scene.width, scene.height)],
        Box::new(move |ctx| {
            let input = ctx.inputs[0];
            ctx.fullscreen(&exec_key, &[&[wgpu::BindingResource::TextureView(input)]]);
        }),
    )[0]
}

/// One G-buffer channel or the depth as the displayed image.
pub fn debug_view(g: &mut GraphBuilder, scene: &Scene, gb: &GBuffer, depth: Handle) -> Option<Handle> {
    let (source, mode) = match scene.post.debug_view {
        DebugView::None => {
            g.cull("debug_view", "post.debug_view is none");
            return None;
        }
        DebugView::Normal => (gb.normal, 0u32),
        DebugView::Albedo => (gb.albedo, 1),
        DebugView::Roughness => (gb.material, 2),
        DebugView::Metallic => (gb.material, 3),
        DebugView::Depth => (depth, 0),
    };
    let mut defs = fullscreen_defs(scene);
    if scene.post.debug_view == DebugView::Depth {
        defs.push("DEBUG_DEPTH");
    }
    let key = PipelineKey::new(spec("post.debug_view"), defs);
    let exec_key = key.clone();
    let (near, far) = (scene.camera.near, scene.camera.far);
    let out = g.add_pass(
        "debug_view",
        vec![key],
        &[source],
        vec![Target::new("color", LDR, scene.width, scene.height)],
        Box::new(move |ctx| {
            let mut u = vec4_bytes([0.0, near, far, 0.0]);
            u[0..4].copy_from_slice(&mode.to_le_bytes());
            let buf = ctx.uniform(&u);
            let input = ctx.inputs[0];
            ctx.fullscreen(&exec_key, &[&[buf.as_entire_binding()], &[wgpu::BindingResource::TextureView(input)]]);
        }),
    );
    Some(out[0])
}
