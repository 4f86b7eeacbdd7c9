//! The hierarchy against brute force over every triangle, its structure,
//! and the inputs that break naive builders.

use glam::Vec3;

use super::*;
use crate::testing::Rng;

/// `n` triangles of size about `size` scattered in a cube of side `spread`.
fn soup(rng: &mut Rng, n: usize, spread: f32, size: f32) -> Vec<([Vec3; 3], [u32; 2])> {
    (0..n as u32)
        .map(|i| {
            let c = rng.centered(spread);
            ([c + rng.centered(size), c + rng.centered(size), c + rng.centered(size)], [i % 7, i])
        })
        .collect()
}

/// The closest hit over every triangle, the slow way.
fn brute(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(f32, [u32; 2])> {
    let mut best: Option<(f32, [u32; 2])> = None;
    for (i, t) in bvh.triangles.iter().enumerate() {
        if let Some((t, _, _)) = intersect_triangle(t, origin, dir, 1e-4, best.map_or(t_max, |b| b.0)) {
            best = Some((t, bvh.ids[i]));
        }
    }
    best
}

#[test]
fn closest_hits_and_occlusion_equal_brute_force() {
    let mut rng = Rng(7);
    for (n, spread, size) in [(1, 1.0, 1.0), (50, 4.0, 0.8), (2000, 10.0, 0.6), (5000, 3.0, 0.05)] {
        let tris = soup(&mut rng, n, spread, size);
        let bvh = Bvh::build(&tris);
        let mut hits = 0;
        for _ in 0..2000 {
            // Half the rays aimed at a triangle, so there are hits to find.
            let origin = rng.centered(spread * 1.5);
            let dir = if rng.f() < 0.5 {
                let [a, b, c] = tris[(rng.f() * n as f32) as usize % n].0;
                ((a + b + c) / 3.0 - origin).normalize()
            } else {
                rng.dir()
            };
            let t_max = if rng.f() < 0.3 { rng.f() * spread } else { f32::INFINITY };
            let got = bvh.intersect(origin, dir, 1e-4, t_max).map(|h| (h.t, bvh.ids[h.triangle as usize]));
            let want = brute(&bvh, origin, dir, t_max);
            assert_eq!(got, want, "{n} triangles: ray {origin} → {dir}");
            assert_eq!(bvh.occluded(origin, dir, 1e-4, t_max), want.is_some(), "{n} triangles: shadow ray {origin} → {dir}");
            hits += usize::from(want.is_some());
        }
        assert!(hits > 500, "{n} triangles: the rays should hit something ({hits} of 2000 did)");
    }
}

/// Every triangle once, in leaves; every box holds what is below it; the
/// depth stays within what traversal stacks are sized for.
#[test]
fn the_structure_holds_every_triangle_once_inside_every_box() {
    let mut rng = Rng(11);
    let tris = soup(&mut rng, 3000, 20.0, 1.0);
    let bvh = Bvh::build(&tris);
    assert_eq!(bvh.triangles.len(), 3000);
    let mut seen = vec![0u32; 3000];
    for id in &bvh.ids {
        seen[id[1] as usize] += 1;
    }
    assert!(seen.iter().all(|&n| n == 1), "each triangle exactly once");
    let inside = |inner: ([f32; 3], [f32; 3]), outer: &Node| (0..3).all(|k| inner.0[k] >= outer.min[k] && inner.1[k] <= outer.max[k]);
    let (mut leaves, mut covered) = (0, 0);
    let mut stack = vec![(0usize, 0usize)];
    while let Some((n, depth)) = stack.pop() {
        let node = &bvh.nodes[n];
        assert!(depth <= MAX_DEPTH);
        if node.count == INTERIOR {
            for c in [node.first, node.first + 1] {
                let child = &bvh.nodes[c as usize];
                assert!(inside((child.min, child.max), node), "node {c} pokes out of its parent {n}");
                stack.push((c as usize, depth + 1));
            }
        } else {
            leaves += 1;
            covered += node.count;
            for t in &bvh.triangles[node.first as usize..(node.first + node.count) as usize] {
                for v in &t.v {
                    assert!(inside(([v[0], v[1], v[2]], [v[0], v[1], v[2]]), node), "leaf {n} misses a vertex");
                }
            }
        }
    }
    assert_eq!((leaves, covered), (bvh.stats.leaves, 3000));
    assert_eq!(bvh.stats.nodes, bvh.nodes.len());
    assert!(bvh.stats.max_leaf <= 8, "the heuristic keeps leaves small here: {:?}", bvh.stats);
}

/// Separated clusters: the heuristic splits between them, so a ray costs
/// far fewer triangle tests than the triangles there are.
#[test]
fn the_surface_area_heuristic_finds_the_clusters() {
    let mut rng = Rng(3);
    let mut tris = Vec::new();
    for c in 0..8 {
        let centre = Vec3::new((c % 2) as f32, ((c / 2) % 2) as f32, (c / 4) as f32) * 100.0;
        tris.extend(soup(&mut rng, 200, 2.0, 0.2).into_iter().map(|(t, id)| (t.map(|v| v + centre), id)));
    }
    let bvh = Bvh::build(&tris);
    assert!(bvh.stats.sah_cost < 40.0, "{:?}", bvh.stats);
}

#[test]
fn degenerate_inputs_build_and_trace() {
    // Nothing at all: every ray misses.
    let empty = Bvh::build(&[]);
    assert_eq!(empty.nodes.len(), 1);
    assert_eq!(empty.intersect(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY), None);
    assert!(!empty.occluded(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY));

    // A thousand copies of one triangle (one centroid): small leaves, and
    // the nearest copy is hit.
    let one = [Vec3::new(-1.0, -1.0, 5.0), Vec3::new(1.0, -1.0, 5.0), Vec3::new(0.0, 1.0, 5.0)];
    let same: Vec<_> = (0..1000).map(|i| (one, [0, i])).collect();
    let bvh = Bvh::build(&same);
    assert!(bvh.stats.max_leaf <= 2 && bvh.stats.max_depth <= MAX_DEPTH, "{:?}", bvh.stats);
    let hit = bvh.intersect(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY).expect("a hit");
    assert!((hit.t - 5.0).abs() < 1e-5);

    // NaN and infinite vertices are left out and counted; the rest stay.
    let mut bad =
        vec![([Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y], [0, 0]), ([Vec3::splat(f32::INFINITY), Vec3::X, Vec3::Y], [0, 1])];
    bad.push((one, [0, 2]));
    let bvh = Bvh::build(&bad);
    assert_eq!((bvh.stats.triangles, bvh.stats.skipped), (1, 2));
    assert_eq!(bvh.ids, [[0, 2]]);

    // Zero-area triangles and rays in a triangle's plane hit nothing.
    let flat = Bvh::build(&[([Vec3::ZERO, Vec3::X, Vec3::X * 2.0], [0, 0]), (one, [0, 1])]);
    assert_eq!(flat.intersect(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 0.0, f32::INFINITY), None);
    assert_eq!(flat.intersect(Vec3::new(-5.0, 0.0, 5.0), Vec3::X, 0.0, f32::INFINITY), None, "in the plane of `one`");

    // A ray leaving a surface does not hit it again past t_min.
    let hit = flat.intersect(Vec3::new(0.0, 0.0, 5.0), Vec3::Z, 1e-4, f32::INFINITY);
    assert_eq!(hit, None);
}
