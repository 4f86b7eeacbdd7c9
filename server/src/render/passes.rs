//! The passes of the frame, each a free function: it takes the graph
//! builder and its input handles and returns its output handles.

use super::graph::{GraphBuilder, Handle, PipelineKey};
use crate::gpu::pipeline::{self, HDR, LDR};
use crate::scene::{Scene, Tonemap};

fn spec(name: &str) -> &'static pipeline::PipelineSpec {
    pipeline::spec(name).expect("pass names a registered pipeline spec")
}

fn fullscreen_defs(scene: &Scene) -> Vec<&'static str> {
    if scene.post.two_triangles { vec!["TWO_TRIANGLES"] } else { vec![] }
}

/// A pattern of known values, the frame of a scene with nothing else in it.
pub fn test_pattern(g: &mut GraphBuilder, scene: &Scene, frame: u64) -> Handle {
    let key = PipelineKey::new(spec("debug.test_pattern"), fullscreen_defs(scene));
    let (w, h) = (scene.width, scene.height);
    let exec_key = key.clone();
    let out = g.add_pass(
        "test_pattern",
        vec![key],
        &[],
        vec![("color", HDR, w, h)],
        Box::new(move |ctx| {
            let mut u = [0u8; 16];
            u[0..4].copy_from_slice(&(w as f32).to_le_bytes());
            u[4..8].copy_from_slice(&(h as f32).to_le_bytes());
            u[12..16].copy_from_slice(&(frame as u32).to_le_bytes());
            let buf = ctx.uniform(&u);
            ctx.fullscreen(&exec_key, &[buf.as_entire_binding()]);
        }),
    );
    out[0]
}

/// Exposure and tonemapping to the displayable final image.
pub fn tonemap(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Handle {
    let mut defs = fullscreen_defs(scene);
    if scene.post.tonemap == Tonemap::Reinhard {
        defs.push("TONEMAP_REINHARD");
    }
    let key = PipelineKey::new(spec("post.tonemap"), defs);
    let exec_key = key.clone();
    let exposure = 2f32.powf(scene.post.exposure_ev);
    let out = g.add_pass(
        "tonemap",
        vec![key],
        &[hdr],
        vec![("color", LDR, scene.width, scene.height)],
        Box::new(move |ctx| {
            let mut u = [0u8; 16];
            u[0..4].copy_from_slice(&exposure.to_le_bytes());
            let buf = ctx.uniform(&u);
            let input = ctx.inputs[0].clone();
            ctx.fullscreen(&exec_key, &[buf.as_entire_binding(), wgpu::BindingResource::TextureView(&input)]);
        }),
    );
    out[0]
}
