//! A bounding-volume hierarchy over world-space triangles, for the path
//! tracer: it traces the very triangles the raster draws. Built on the CPU
//! with a binned surface-area heuristic, laid out flat for upload (the
//! WGSL traversal mirrors the layout below), and traversed here too, as the
//! reference the GPU traversal is tested against.
//!
//! Layout (all little-endian, std430-compatible):
//! - `nodes`: 32 bytes each, depth first, the root at 0. A leaf holds
//!   `count` triangles from `first` on; an interior node has `count ==
//!   INTERIOR` and its two children at `first` and `first + 1`.
//!   `[min.xyz: f32×3, first: u32, max.xyz: f32×3, count: u32]`.
//! - `triangles`: 48 bytes each, in leaf order: three vertices as
//!   `vec4<f32>` (w unused).
//! - `ids`: per triangle, `[object, primitive]` (`u32×2`): which scene
//!   object it belongs to and its index in that object's mesh, for
//!   materials and shading normals.
//!
//! An empty hierarchy is one leaf with no triangles and an empty box.

use std::cell::Cell;

use glam::Vec3;

/// `Node::count` of an interior node.
pub const INTERIOR: u32 = u32::MAX;
/// Bins per axis for the surface-area heuristic.
const BINS: usize = 16;
/// Leaves are made at this depth whatever the heuristic says: traversal
/// stacks (here and in WGSL) are sized for it.
pub const MAX_DEPTH: usize = 48;
/// A node with this many triangles or fewer is a leaf.
const MIN_SPLIT: usize = 2;
/// Relative cost of visiting a node against testing a triangle.
const TRAVERSAL_COST: f32 = 1.0;

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Triangle {
    pub v: [[f32; 4]; 3],
}

impl Triangle {
    fn vertex(&self, i: usize) -> Vec3 {
        Vec3::from_slice(&self.v[i][..3])
    }
}

/// What a build made, for reports and benchmarks.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct BuildStats {
    pub triangles: usize,
    /// Triangles left out: a vertex that is NaN or infinite.
    pub skipped: usize,
    pub nodes: usize,
    pub leaves: usize,
    pub max_depth: usize,
    pub max_leaf: usize,
    /// The hierarchy's expected cost of a ray (surface-area heuristic,
    /// in triangle tests), relative to the root's area.
    pub sah_cost: f32,
}

/// A ray's closest hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Index into `Bvh::triangles` (and `ids`).
    pub triangle: u32,
    /// Barycentrics of vertices 1 and 2.
    pub u: f32,
    pub v: f32,
}

#[derive(Debug, Clone, Default)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    pub triangles: Vec<Triangle>,
    pub ids: Vec<[u32; 2]>,
    pub stats: BuildStats,
}

#[derive(Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    fn grow(self, o: Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    fn of(t: &[Vec3; 3]) -> Aabb {
        Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }
    }

    /// Half the surface area (the heuristic only compares areas).
    fn area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

impl Bvh {
    /// Builds over `triangles` (world space) with their `[object,
    /// primitive]` ids. Triangles with a non-finite vertex are left out
    /// and counted in `stats.skipped`.
    pub fn build(triangles: &[([Vec3; 3], [u32; 2])]) -> Bvh {
        let kept: Vec<&([Vec3; 3], [u32; 2])> = triangles.iter().filter(|(t, _)| t.iter().all(|v| v.is_finite())).collect();
        let bounds: Vec<Aabb> = kept.iter().map(|(t, _)| Aabb::of(t)).collect();
        let centroids: Vec<Vec3> = bounds.iter().map(|b| (b.min + b.max) * 0.5).collect();
        let mut order: Vec<u32> = (0..kept.len() as u32).collect();
        let mut nodes = vec![Node { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 }];
        let mut stats = BuildStats { triangles: kept.len(), skipped: triangles.len() - kept.len(), ..Default::default() };
        let mut root_area = 0.0;
        // (node, first, end, depth): ranges of `order`.
        let mut stack = vec![(0usize, 0usize, kept.len(), 0usize)];
        while let Some((node, first, end, depth)) = stack.pop() {
            let range = &mut order[first..end];
            let bound = range.iter().fold(Aabb::EMPTY, |b, &i| b.grow(bounds[i as usize]));
            if node == 0 {
                root_area = bound.area();
            }
            nodes[node].min = bound.min.to_array();
            nodes[node].max = bound.max.to_array();
            let split = if range.len() > MIN_SPLIT && depth < MAX_DEPTH { best_split(range, &bounds, &centroids, bound) } else { None };
            let Some(mid) = split else {
                nodes[node].first = first as u32;
                nodes[node].count = range.len() as u32;
                stats.leaves += 1;
                stats.max_leaf = stats.max_leaf.max(range.len());
                stats.max_depth = stats.max_depth.max(depth);
                if root_area > 0.0 {
                    stats.sah_cost += bound.area() / root_area * range.len() as f32;
                }
                continue;
            };
            let left = nodes.len();
            nodes.push(nodes[node]);
            nodes.push(nodes[node]);
            nodes[node].first = left as u32;
            nodes[node].count = INTERIOR;
            if root_area > 0.0 {
                stats.sah_cost += bound.area() / root_area * TRAVERSAL_COST;
            }
            stack.push((left + 1, first + mid, end, depth + 1));
            stack.push((left, first, first + mid, depth + 1));
        }
        stats.nodes = nodes.len();
        let triangles = order
            .iter()
            .map(|&i| {
                let t = &kept[i as usize].0;
                Triangle { v: [0, 1, 2].map(|k| [t[k].x, t[k].y, t[k].z, 0.0]) }
            })
            .collect();
        let ids = order.iter().map(|&i| kept[i as usize].1).collect();
        Bvh { nodes, triangles, ids, stats }
    }

    /// The closest hit with `t_min < t < t_max` of the ray `origin + t·dir`.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let far = Cell::new(t_max);
        self.traverse(origin, dir, t_min, &far, |this, i| {
            if let Some((t, u, v)) = intersect_triangle(&this.triangles[i as usize], origin, dir, t_min, far.get()) {
                far.set(t);
                best = Some(Hit { t, triangle: i, u, v });
            }
            false
        });
        best
    }

    /// Whether anything lies on the ray with `t_min < t < t_max` (shadow
    /// rays: the first hit ends the search).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let mut hit = false;
        self.traverse(origin, dir, t_min, &Cell::new(t_max), |this, i| {
            hit = intersect_triangle(&this.triangles[i as usize], origin, dir, t_min, t_max).is_some();
            hit
        });
        hit
    }

    /// Visits the leaves' triangles a ray may hit, nearer child first;
    /// `visit` returns true to stop, `far` is the current search bound.
    fn traverse(&self, origin: Vec3, dir: Vec3, t_min: f32, far: &Cell<f32>, mut visit: impl FnMut(&Self, u32) -> bool) {
        let inv = dir.recip();
        let mut stack = [0u32; MAX_DEPTH + 1];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.count != INTERIOR {
                for i in node.first..node.first + node.count {
                    if visit(self, i) {
                        return;
                    }
                }
                continue;
            }
            let (a, b) = (node.first, node.first + 1);
            let ta = slab(&self.nodes[a as usize], origin, inv, t_min, far.get());
            let tb = slab(&self.nodes[b as usize], origin, inv, t_min, far.get());
            // Push the farther first, so the nearer is visited first.
            let mut push = |n: u32| {
                stack[top] = n;
                top += 1;
            };
            match (ta, tb) {
                (Some(x), Some(y)) if x <= y => {
                    push(b);
                    push(a);
                }
                (Some(_), Some(_)) => {
                    push(a);
                    push(b);
                }
                (Some(_), None) => push(a),
                (None, Some(_)) => push(b),
                (None, None) => {}
            }
        }
    }
}

/// Where the ray enters `node`'s box within (t_min, t_max), if it does.
fn slab(node: &Node, origin: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    let t0 = (Vec3::from(node.min) - origin) * inv;
    let t1 = (Vec3::from(node.max) - origin) * inv;
    // NaN (0 · ∞ on a box face) compares false and is skipped by min/max.
    let near = t0.min(t1).max_element().max(t_min);
    let far = t0.max(t1).min_element().min(t_max);
    (near <= far).then_some(near)
}

/// Möller–Trumbore: (t, u, v) of a hit with t_min < t < t_max. Not
/// watertight: a ray through an edge shared by two triangles can miss both
/// by rounding, rarely; the WGSL traversal uses the same test, so the two
/// agree.
fn intersect_triangle(tri: &Triangle, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
    let (v0, v1, v2) = (tri.vertex(0), tri.vertex(1), tri.vertex(2));
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None; // parallel to the plane, or a degenerate triangle
    }
    let inv = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > t_min && t < t_max).then_some((t, u, v))
}

/// The best split of `range` by the binned surface-area heuristic: the
/// range is partitioned and the left part's length returned; `None` when
/// a leaf is cheaper. Centroids all in one point: split in the middle,
/// so identical triangles still end in small leaves.
fn best_split(range: &mut [u32], bounds: &[Aabb], centroids: &[Vec3], bound: Aabb) -> Option<usize> {
    let cb = range.iter().fold(Aabb::EMPTY, |b, &i| b.grow(Aabb { min: centroids[i as usize], max: centroids[i as usize] }));
    let extent = cb.max - cb.min;
    if extent.max_element() <= 0.0 {
        return Some(range.len() / 2);
    }
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, first bin on the right)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bin_of = |c: Vec3| bin(c, axis, &cb, extent);
        let mut boxes = [Aabb::EMPTY; BINS];
        let mut counts = [0usize; BINS];
        for &i in range.iter() {
            let b = bin_of(centroids[i as usize]);
            boxes[b] = boxes[b].grow(bounds[i as usize]);
            counts[b] += 1;
        }
        // Sweep from the right, then evaluate each boundary from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.grow(boxes[b]);
            n += counts[b];
            right_area[b] = acc.area();
            right_count[b] = n;
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for b in 1..BINS {
            acc = acc.grow(boxes[b - 1]);
            n += counts[b - 1];
            if n == 0 || right_count[b] == 0 {
                continue;
            }
            let cost = acc.area() * n as f32 + right_area[b] * right_count[b] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let (cost, axis, edge) = best?;
    let leaf = range.len() as f32;
    if TRAVERSAL_COST + cost / bound.area().max(f32::MIN_POSITIVE) >= leaf {
        return None;
    }
    // Partition by the same bin arithmetic the costs used.
    let mut mid = 0;
    for i in 0..range.len() {
        if bin(centroids[range[i] as usize], axis, &cb, extent) < edge {
            range.swap(i, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < range.len()).then_some(mid)
}

/// The bin of centroid `c` along `axis` of the centroid bounds `cb`.
fn bin(c: Vec3, axis: usize, cb: &Aabb, extent: Vec3) -> usize {
    (((c[axis] - cb.min[axis]) / extent[axis] * BINS as f32) as usize).min(BINS - 1)
}

#[cfg(test)]
mod tests;
