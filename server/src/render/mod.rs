//! The renderer: scene → render graph → pipelines → frame → captures.

pub mod capture;
pub mod frame;
pub mod graph;
pub mod ltc;
pub mod passes;
pub mod pipelines;
pub mod scene_gpu;

use crate::scene::Scene;
use graph::{Graph, GraphBuilder};

/// Builds the frame's graph from the scene: only what the scene calls for.
pub fn build_graph(scene: &Scene, frame: u64) -> Graph {
    let mut g = GraphBuilder::new();
    let (hdr, gbuffer) = if scene.is_empty() {
        for pass in ["shadows", "depth_prepass", "gbuffer", "ltc_tables", "lighting", "volumes"] {
            g.cull(pass, "the scene is empty: it shows the test pattern");
        }
        (passes::test_pattern(&mut g, scene, frame), None)
    } else {
        g.cull("test_pattern", "the scene has content to render");
        let shadows = passes::shadows(&mut g, scene);
        let depth = passes::depth_prepass(&mut g, scene);
        let gb = passes::gbuffer(&mut g, scene, depth);
        let ltc = passes::ltc_tables(&mut g, scene);
        let lit = passes::lighting(&mut g, scene, &gb, depth, shadows, ltc);
        (passes::volumes(&mut g, scene, lit, depth, shadows), Some((gb, depth)))
    };
    let exposed = passes::exposure(&mut g, scene, hdr);
    let ldr = passes::tonemap(&mut g, scene, exposed);
    let debug = match &gbuffer {
        Some((gb, depth)) => passes::debug_view(&mut g, scene, gb, *depth),
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
