//! The renderer: scene → render graph → pipelines → frame → captures,
//! driven through one `Session` by the daemon and the offline commands
//! alike. It knows nothing of the wire protocol.

pub mod capture;
pub mod context;
pub mod frame;
pub mod graph;
pub mod ltc;
pub mod passes;
pub mod pipelines;
pub mod pool;
pub mod resource;
pub mod scene_gpu;
pub mod session;

use crate::scene::Scene;
use graph::{Graph, GraphBuilder};
use passes::*;

/// Assembles the frame from the scene: only what the scene calls for.
pub fn build_graph(scene: &Scene) -> Graph {
    let mut g = GraphBuilder::new();
    let (hdr, gbuffer) = if scene.is_empty() {
        for pass in ["shadows", "depth_prepass", "gbuffer", "ltc_tables", "lighting", "volumes"] {
            g.cull(pass, "the scene is empty: it shows the test pattern");
        }
        (test_pattern::test_pattern(&mut g, scene), None)
    } else {
        g.cull("test_pattern", "the scene has content to render");
        let shadows = shadows::shadows(&mut g, scene);
        let depth = depth_prepass::depth_prepass(&mut g, scene);
        let gb = gbuffer::gbuffer(&mut g, scene, depth);
        let ltc = ltc_tables::ltc_tables(&mut g, scene);
        let lit = lighting::lighting(&mut g, scene, &gb, depth, shadows, ltc);
        (volumes::volumes(&mut g, scene, lit, depth, shadows), Some((gb, depth)))
    };
    let adapted = auto_exposure::auto_exposure(&mut g, scene, hdr);
    let exposed = exposure::exposure(&mut g, scene, hdr, adapted);
    let ldr = tonemap::tonemap(&mut g, scene, exposed);
    let debug = match &gbuffer {
        Some((gb, depth)) => debug_view::debug_view(&mut g, scene, gb, *depth),
        None => {
            g.cull("debug_view", "the scene is empty: no G-buffer to show");
            None
        }
    };
    // The debug view, when on, is what the frame shows; the tonemapped
    // frame stays an output so switching back costs nothing.
    if let Some(d) = debug {
        g.output(d);
    }
    g.output(ldr);
    g.build()
}
