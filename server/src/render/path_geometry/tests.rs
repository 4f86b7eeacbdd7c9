//! The path tracer's geometry on the device: the WGSL traversal
//! (`shaders/lib/bvh.wgsl`'s `trace` and `occluded`), run over the
//! hierarchy as `PathGeometry` uploads it, against the CPU traversal
//! (`crate::bvh`) over the same build: random rays through the bundled
//! torus knot hit the same triangle at the same distance; and the
//! hierarchy kept across scene edits that leave the triangles alone.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::Vec3;

use super::PathGeometry;
use crate::bvh::Bvh;
use crate::gpu::testing::Kernel;
use crate::render::scene_gpu::SceneGpu;
use crate::testing::Rng;

const KERNEL: &str = r"
#import loupe::bvh::{trace, occluded}

struct Ray {
    // w: t_min
    origin: vec4<f32>,
    // w: t_max
    dir: vec4<f32>,
}

struct Out {
    // t, u, v of the closest hit (t = t_max when none)
    hit: vec4<f32>,
    // the triangle (NO_HIT when none), and whether `occluded` said so
    ids: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> input: array<Ray>;
@group(0) @binding(1) var<storage, read_write> output: array<Out>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) {
        return;
    }
    let r = input[id.x];
    let h = trace(r.origin.xyz, r.dir.xyz, r.origin.w, r.dir.w);
    let o = occluded(r.origin.xyz, r.dir.xyz, r.origin.w, r.dir.w);
    output[id.x] = Out(vec4(h.t, h.u, h.v, 0.0), vec4(h.triangle, select(0u, 1u, o), 0u, 0u));
}
";

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Ray {
    origin: [f32; 4],
    dir: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Out {
    hit: [f32; 4],
    ids: [u32; 4],
}

/// The torus knot, placed as `scenes/minimal.toml` places it, but rotated
/// and scaled off the axes.
fn knot() -> Vec<([Vec3; 3], [u32; 2])> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mesh = crate::mesh::load_gltf(&root.join("meshes/torus_knot.gltf"), "torus_knot.gltf").unwrap_or_else(|d| panic!("{d}"));
    let text = "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"meshes/torus_knot.gltf\"\nmaterial = \"m\"\nposition = [0.3, 1.1, -0.2]\nrotation_deg = [10.0, 30.0, 5.0]\nscale = 0.8\n";
    let scene = crate::scene::parse("knot.toml", text).unwrap_or_else(|d| panic!("{d}"));
    crate::render::scene_gpu::world_triangles(&scene, &BTreeMap::from([("meshes/torus_knot.gltf".to_owned(), Arc::new(mesh))]))
}

#[test]
fn the_gpu_traversal_hits_what_the_cpu_traversal_hits() {
    let gpu = crate::gpu::testing::device();
    let source = knot();
    let cpu = Bvh::build(&source);
    let geometry = PathGeometry::new(&gpu.device, source.clone(), None, |ids| vec![[[0.0; 4]; 8]; ids.len()]);
    assert_eq!(geometry.stats(), &cpu.stats, "the uploaded hierarchy is this build");
    let (lo, hi) = (Vec3::from(cpu.nodes[0].min), Vec3::from(cpu.nodes[0].max));
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length();
    let mut rng = Rng(11);
    let mut rays = Vec::new();
    // From outside, aimed into the bounds: mostly hits.
    for _ in 0..4096 {
        let origin = centre + rng.dir() * radius;
        let dir = (rng.in_box(lo, hi) - origin).normalize();
        rays.push((origin, dir, 0.0, 1e30));
    }
    // From inside the bounds, every way; with a bound on t, so shadow rays
    // both reach and stop short of the nearest hit.
    for i in 0..2048 {
        let t_max = if i % 2 == 0 { 1e30 } else { rng.f() * radius };
        rays.push((rng.in_box(lo, hi), rng.dir(), 0.0, t_max));
    }
    // Along the axes and their planes: infinite reciprocals in the slab test.
    for i in 0..1024 {
        let mut d = rng.dir();
        d[i % 3] = 0.0;
        if i % 2 == 0 {
            d[(i + 1) % 3] = 0.0;
        }
        let d = if d.length_squared() > 0.0 { d.normalize() } else { Vec3::X };
        rays.push((rng.in_box(lo, hi) - d * radius * 0.5, d, 0.0, 1e30));
    }
    // Starting on a hit, as bounces do, with a t_min.
    for _ in 0..1024 {
        let origin = centre + rng.dir() * radius;
        let dir = (rng.in_box(lo, hi) - origin).normalize();
        if let Some(h) = cpu.intersect(origin, dir, 0.0, 1e30) {
            rays.push((origin + dir * h.t, rng.dir(), 1e-4, 1e30));
        }
    }
    let input: Vec<Ray> = rays.iter().map(|(o, d, t0, t1)| Ray { origin: [o.x, o.y, o.z, *t0], dir: [d.x, d.y, d.z, *t1] }).collect();
    let kernel = Kernel::new(&gpu, KERNEL, "main").unwrap_or_else(|e| panic!("{e}"));
    let out: Vec<Out> =
        kernel.run_bound(&gpu, &input, input.len(), &[], &[geometry.nodes(), geometry.triangles()]).unwrap_or_else(|e| panic!("{e}"));
    // Allowance: a ray through (within rounding of) an edge or a vertex
    // may find either triangle there or slip between them (Möller–Trumbore
    // is not watertight), and a GPU that fuses multiply-adds rounds the
    // test differently from the CPU; such rays, at most one in a thousand,
    // may disagree. Everything else must agree: the same triangle, t and
    // barycentrics within 1e-5 relative (lavapipe computes the CPU's bits:
    // 0 disagreements, t equal).
    // Within 1e-4 of an edge, in barycentrics, on either side of it.
    let edge = |u: f32, v: f32| u.min(v).min(1.0 - u - v).abs() < 1e-4;
    let (mut hits, mut ambiguous, mut worst_t, mut shadowed) = (0, Vec::new(), 0.0f32, [0; 2]);
    for (i, ((origin, dir, t_min, t_max), o)) in rays.iter().zip(&out).enumerate() {
        let want = cpu.intersect(*origin, *dir, *t_min, *t_max);
        let got = (o.ids[0] != u32::MAX).then_some((o.ids[0], o.hit[0], o.hit[1], o.hit[2]));
        let case = format!("ray {i} from {origin} along {dir}, t in ({t_min}, {t_max}): cpu {want:?}, gpu (triangle, t, u, v) {got:?}");
        let by_an_edge = want.is_some_and(|w| edge(w.u, w.v)) || got.is_some_and(|(_, _, u, v)| edge(u, v));
        match (want, got) {
            (Some(w), Some((triangle, t, u, v))) if w.triangle == triangle => {
                hits += 1;
                let dt = (t - w.t).abs() / w.t.max(1.0);
                worst_t = worst_t.max(dt);
                assert!(dt <= 1e-5 && (u - w.u).abs() <= 1e-5 && (v - w.v).abs() <= 1e-5, "{case}");
            }
            (None, None) => assert_eq!(o.hit[0], *t_max, "{case}: a miss reports t_max"),
            _ => {
                assert!(by_an_edge, "{case}: a different triangle, away from any edge");
                ambiguous.push(case.clone());
            }
        }
        let occluded = cpu.occluded(*origin, *dir, *t_min, *t_max);
        shadowed[usize::from(occluded)] += 1;
        if occluded != (o.ids[1] == 1) {
            assert!(by_an_edge, "{case}: occluded on the cpu {occluded}, on the gpu {}", o.ids[1] == 1);
            ambiguous.push(format!("{case}: occlusion"));
        }
    }
    eprintln!(
        "{} rays: {hits} hit the same triangle (t within {worst_t:e} relative), {} by an edge disagree; {} occluded, {} not",
        rays.len(),
        ambiguous.len(),
        shadowed[1],
        shadowed[0]
    );
    assert!(ambiguous.len() * 1000 <= rays.len(), "{} rays by an edge disagree:\n{}", ambiguous.len(), ambiguous.join("\n"));
    assert!(hits * 2 > rays.len() && shadowed[0] * 5 > rays.len(), "the rays both hit and miss: {hits} hits of {}", rays.len());
}

// ---- the hierarchy across scene edits ----------------------------------

const SCENE: &str = "[quality]\nrenderer = \"path\"\n[[materials]]\nname = \"m\"\n\
    [[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\nposition = [0, 0, 0]\n\
    [[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\n";

fn gpu_of(text: &str, previous: Option<&SceneGpu>, gpu: &crate::gpu::Gpu) -> SceneGpu {
    let scene = crate::scene::parse("s.toml", text).unwrap_or_else(|d| panic!("{d}"));
    SceneGpu::new(&gpu.device, &gpu.queue, &scene, &Default::default(), &Default::default(), None, previous)
}

/// Moving a light or changing a material keeps the hierarchy; moving
/// an object rebuilds it; the raster builds none.
#[test]
fn the_hierarchy_is_rebuilt_only_when_the_triangles_change() {
    let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("these tests need a GPU device (lavapipe will do): {e}"));
    let first = gpu_of(SCENE, None, &gpu);
    let path = first.path.as_ref().expect("a path-traced scene has path geometry");
    assert!(path.stats().triangles > 0);
    let light_moved = gpu_of(&SCENE.replace("[0, 2, 0]", "[1, 2, 0]"), Some(&first), &gpu);
    assert!(light_moved.path.as_ref().unwrap().same_hierarchy(path), "a light moved: the triangles are the same");
    let object_moved = gpu_of(&SCENE.replace("position = [0, 0, 0]", "position = [0, 0.5, 0]"), Some(&first), &gpu);
    assert!(!object_moved.path.as_ref().unwrap().same_hierarchy(path), "an object moved: rebuilt");
    let raster = gpu_of(&SCENE.replace("\"path\"", "\"raster\""), Some(&first), &gpu);
    assert!(raster.path.is_none(), "the raster traces nothing, so nothing is built");
}
