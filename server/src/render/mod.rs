//! The renderer: scene → render graph → pipelines → frame → captures.

pub mod capture;
pub mod frame;
pub mod graph;
pub mod ltc;
pub mod passes;
pub mod pipelines;

use crate::scene::Scene;
use graph::{Graph, GraphBuilder};

/// Builds the frame's graph from the scene: only what the scene calls for.
pub fn build_graph(scene: &Scene, frame: u64) -> Graph {
    let mut g = GraphBuilder::new();
    let hdr = passes::test_pattern(&mut g, scene, frame);
    let ldr = passes::tonemap(&mut g, scene, hdr);
    g.output(ldr);
    g.build()
}
