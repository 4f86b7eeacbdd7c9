//! The renderer: scene → render graph → pipelines → frame → captures,
//! driven through one `Session` by the daemon and the offline commands
//! alike. It knows nothing of the wire protocol.

pub mod capture;
pub mod context;
pub mod debug_print;
pub mod denoise_weights;
pub mod dfg;
pub mod frame;
pub mod graph;
pub mod ltc;
pub mod material_textures;
pub mod passes;
pub mod path_geometry;
pub mod pipelines;
pub mod pixel_history;
pub mod pool;
pub mod preview;
pub mod print_selection;
pub mod quads;
pub mod readback;
pub mod resource;
pub mod scene_gpu;
pub mod session;
pub mod vertex_capture;

use crate::denoise::network::Network;
use crate::scene::Scene;
use graph::{Graph, GraphBuilder};
use passes::*;

/// What a frame is built for beyond the scene.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameOptions {
    /// Count NaN/Inf texels of the HDR frame every frame (`nan_watch`): the
    /// daemon's cue to trace a frame.
    pub nan_watch: bool,
    /// The most bytes one buffer may bind on the device (the session's);
    /// `None`: unknown, nothing is culled for its size.
    pub max_buffer: Option<u64>,
    /// The most words a pixel of the scene's materials takes in the
    /// material buffer, simplified to the budget
    /// (`material::Program::raster_words`, the session's).
    pub material_words: u32,
    /// The tile classes the scene's materials can make
    /// (`classify::Classes::of`, the session's): the others' lighting
    /// passes are culled.
    pub tile_classes: classify::Classes,
}

/// Assembles the frame from the scene and the network its `[denoiser]`
/// names (`loaded::Loaded::denoiser`): only what the scene calls for.
pub fn build_graph(scene: &Scene, denoiser: Option<&Network>, options: FrameOptions) -> Graph {
    let mut g = GraphBuilder::new();
    // Every pass that makes the HDR image but the path tracer.
    let raster: Vec<&str> = crate::scene::settings::RENDERED.iter().copied().filter(|p| *p != "path_trace").collect();
    let (hdr, gbuffer) = if scene.is_empty() {
        let empty = "the scene is empty: it shows the test pattern";
        for pass in raster.iter().chain(&["path_trace"]) {
            g.cull(pass, empty);
        }
        denoise::cull(&mut g, scene, empty);
        (test_pattern::test_pattern(&mut g, scene), None)
    } else if let Some(traced) = path_trace::path_trace(&mut g, scene) {
        g.cull("test_pattern", "the scene has content to render");
        for pass in raster {
            g.cull(pass, "quality.renderer is path");
        }
        let noisy = denoise::Noisy { color: traced.color, albedo: traced.albedo, normal: traced.normal };
        (denoise::denoise(&mut g, scene, denoiser, &noisy, options.max_buffer), None)
    } else {
        denoise::cull(&mut g, scene, "quality.renderer is raster");
        g.cull("test_pattern", "the scene has content to render");
        let shadows = shadows::shadows(&mut g, scene);
        let depth = depth_prepass::depth_prepass(&mut g, scene);
        let gb = gbuffer::gbuffer(&mut g, scene, depth, options.material_words);
        let tiles = classify::classify(&mut g, scene, &gb, depth, options.tile_classes);
        let ltc = ltc_tables::ltc_tables(&mut g, scene);
        let lit = lighting::lighting(&mut g, scene, &gb, depth, tiles, options.tile_classes, shadows, ltc);
        let grid = volume_shadows::volume_shadows(&mut g, scene);
        let marched = volume_march::volume_march(&mut g, scene, depth, shadows, grid);
        (volumes::volumes(&mut g, scene, lit, depth, marched), Some((gb, depth, tiles)))
    };
    let adapted = auto_exposure::auto_exposure(&mut g, scene, hdr);
    let exposed = exposure::exposure(&mut g, scene, hdr, adapted);
    let ldr = tonemap::tonemap(&mut g, scene, exposed);
    let watch = options.nan_watch.then(|| nan_watch::nan_watch(&mut g, scene, exposed));
    let debug = match &gbuffer {
        Some((gb, depth, tiles)) => debug_view::debug_view(&mut g, scene, gb, *depth, *tiles),
        None => {
            g.cull("debug_view", "no G-buffer to show: the scene is empty or path traced");
            None
        }
    };
    // The debug view, when on, is what the frame shows; the tonemapped
    // frame stays an output so switching back costs nothing.
    if let Some(d) = debug {
        g.output(d);
    }
    g.output(ldr);
    if let Some(w) = watch {
        g.output(w);
    }
    g.build()
}

/// The frame `loupe denoise` renders for one tile: its images, then the
/// denoiser the scene's `[denoiser]` describes (an otherwise empty scene
/// of the tile's size).
pub fn denoise_graph(scene: &Scene, network: &Network, tile: std::sync::Arc<images::TileImages>) -> Graph {
    let mut g = GraphBuilder::new();
    let noisy = images::images(&mut g, tile);
    let color = denoise::denoise(&mut g, scene, Some(network), &noisy, None);
    g.output(color);
    g.build()
}

#[cfg(test)]
mod tests;
