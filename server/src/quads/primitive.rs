//! One primitive, from its vertices to the quads it launches: face culling,
//! clipping when a vertex needs it, the depth test, and the count.
//!
//! A primitive the near or far plane cuts becomes a convex polygon, fanned
//! into triangles for coverage. Real GPUs rasterize the clipped polygon as
//! one primitive, so its fan pieces' blocks are merged: a quad touched by
//! two pieces is launched once, not twice.

use super::clip::{self, DEPTH_PLANES, Framebuffer, Homogeneous, MAX_VERTICES, NON_FINITE, Polygon};
use super::depth::DepthTest;
use super::input::{Face, FrontFace};
use super::raster::{self, Rect};
use super::stats::{MapRows, QuadStats};

/// A draw's vertex, mapped once for every triangle that shares it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Vertex {
    h: Homogeneous,
    code: u8,
    /// Snapped framebuffer position and NDC depth, when `code` is 0 (the
    /// vertex needs no clipping).
    fixed: [i64; 2],
    ndc: f64,
}

impl Vertex {
    pub fn new(frame: &Framebuffer, position: [f32; 4]) -> Vertex {
        let h = frame.map(position);
        let code = clip::outcode(&h);
        let (fixed, ndc) = if code == 0 { project(&h) } else { ([0, 0], 0.0) };
        Vertex { h, code, fixed, ndc }
    }
}

/// The divide by w and the snap, the same for a vertex however it was reached.
fn project(h: &Homogeneous) -> ([i64; 2], f64) {
    ([raster::snap(h[0] / h[3]), raster::snap(h[1] / h[3])], h[2] / h[3])
}

/// The lanes one primitive covers in one block, and which of them shade.
#[derive(Debug, Clone, Copy)]
pub(super) struct Launch {
    block: u64,
    covered: u8,
    shaded: u8,
}

/// What a draw's launched quads add up to.
pub(super) struct Tally<'a> {
    pub maps: MapRows<'a>,
    pub rasterized: QuadStats,
    pub shaded: QuadStats,
}

impl Tally<'_> {
    fn launch(&mut self, bx: u32, by: u32, covered: u8, shaded: u8) {
        self.rasterized.launch(covered);
        self.shaded.launch(shaded);
        if shaded != 0 {
            self.maps.launch(bx, by, shaded);
        }
    }
}

/// The fixed-function state of one draw, applied to its primitives in order.
pub(super) struct Rasterizer<'a> {
    pub rect: Rect,
    pub cull: Option<Face>,
    pub front_face: FrontFace,
    pub depth: Option<DepthTest<'a>>,
    pub tally: Tally<'a>,
    /// The blocks of a clipped primitive's fan pieces, merged before they
    /// are counted; kept between primitives and draws for its allocation.
    pub launches: &'a mut Vec<Launch>,
}

impl Rasterizer<'_> {
    /// Rasterizes and counts one triangle of the draw.
    pub fn triangle(&mut self, v: [&Vertex; 3]) {
        self.tally.rasterized.triangles += 1;
        let drawn = if v.iter().all(|v| v.code == 0) { self.unclipped(v) } else { self.clipped(v) };
        if !drawn {
            self.tally.rasterized.culled_triangles += 1;
        }
    }

    /// Whether a primitive wound clockwise on screen (or not) is culled.
    fn culls(&self, clockwise: bool) -> bool {
        let front = match self.front_face {
            FrontFace::Ccw => !clockwise,
            FrontFace::Cw => clockwise,
        };
        match self.cull {
            None => false,
            Some(Face::Front) => front,
            Some(Face::Back) => !front,
        }
    }

    /// The common case: every vertex inside the clip volume and guard band.
    /// Facing is the sign of the snapped area, as the GPU sees it.
    fn unclipped(&mut self, v: [&Vertex; 3]) -> bool {
        let area = raster::area2(v[0].fixed, v[1].fixed, v[2].fixed);
        if area == 0 || self.culls(area > 0) {
            return false;
        }
        let v = if area > 0 { v } else { [v[0], v[2], v[1]] };
        let fixed = v.map(|v| v.fixed);
        let ndc = v.map(|v| v.ndc);
        let rect = self.rect;
        if !raster::reaches(&fixed, rect) {
            return true;
        }
        let Rasterizer { depth, tally, .. } = self;
        match depth {
            None => raster::cover(&fixed, rect, |bx, by, m| tally.launch(bx, by, m, m)),
            Some(test) => {
                let z = ndc.map(|n| test.depth(n));
                let surface = test.surface(&fixed, z, z[0].max(z[1]).max(z[2]));
                raster::cover(&fixed, rect, |bx, by, m| {
                    let shaded = test.shade(&surface, bx, by, m);
                    tally.launch(bx, by, m, shaded);
                });
            }
        }
        true
    }

    /// A primitive with a vertex outside the near or far plane, behind the
    /// eye, beyond the guard band or not finite.
    fn clipped(&mut self, v: [&Vertex; 3]) -> bool {
        let any = v[0].code | v[1].code | v[2].code;
        if any & NON_FINITE != 0 || v[0].code & v[1].code & v[2].code & DEPTH_PLANES != 0 {
            return false;
        }
        let h = v.map(|v| v.h);
        // The facing of the part in front of the eye, before clipping moves
        // any vertex.
        let orientation = clip::orientation(&h);
        if orientation == 0.0 || self.culls(orientation > 0.0) {
            return false;
        }
        let mut polygon = Polygon::triangle(h);
        polygon.clip(any & DEPTH_PLANES);
        if polygon.n < 3 {
            return false;
        }
        // What the guard band removes lies outside every target: drawn,
        // with nothing covered.
        polygon.clip(any & !DEPTH_PLANES);
        if polygon.n < 3 {
            return true;
        }
        let mut corners = [([0, 0], 0.0); MAX_VERTICES];
        for (corner, h) in corners.iter_mut().zip(&polygon.v[..polygon.n]) {
            *corner = project(h);
        }
        self.fan(&corners[..polygon.n], orientation > 0.0)
    }

    /// Rasterizes a clipped polygon as triangles (0, i, i + 1) and counts
    /// each block it covers once. False when no piece has area left once
    /// snapped.
    fn fan(&mut self, corners: &[([i64; 2], f64)], clockwise: bool) -> bool {
        let rect = self.rect;
        let max_depth = self.depth.as_ref().map(|d| corners.iter().map(|c| d.depth(c.1)).fold(f64::MIN, f64::max));
        self.launches.clear();
        let mut drawn = false;
        for i in 1..corners.len() - 1 {
            let (a, mut b, mut c) = (corners[0], corners[i], corners[i + 1]);
            let area = raster::area2(a.0, b.0, c.0);
            // Snapping can flatten or flip a sliver piece; it covers nothing.
            if area == 0 || (area > 0) != clockwise {
                continue;
            }
            drawn = true;
            if area < 0 {
                (b, c) = (c, b);
            }
            let fixed = [a.0, b.0, c.0];
            let Rasterizer { depth, launches, .. } = self;
            let surface = depth.as_ref().zip(max_depth).map(|(d, max)| d.surface(&fixed, [a.1, b.1, c.1].map(|n| d.depth(n)), max));
            raster::cover(&fixed, rect, |bx, by, covered| {
                let shaded = match (depth.as_mut(), &surface) {
                    (Some(test), Some(s)) => test.shade(s, bx, by, covered),
                    _ => covered,
                };
                launches.push(Launch { block: u64::from(by) << 32 | u64::from(bx), covered, shaded });
            });
        }
        // Pieces never share a pixel (the fill rule), only blocks.
        self.launches.sort_unstable_by_key(|l| l.block);
        for run in self.launches.chunk_by(|a, b| a.block == b.block) {
            let (covered, shaded) = run.iter().fold((0, 0), |(c, s), l| (c | l.covered, s | l.shaded));
            self.tally.launch(run[0].block as u32, (run[0].block >> 32) as u32, covered, shaded);
        }
        drawn
    }
}
