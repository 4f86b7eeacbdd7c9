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
use super::probe::Watch;
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
    /// The probed pixel, when the pass has one and it lies in these rows.
    pub watch: Option<Watch<'a>>,
}

impl Rasterizer<'_> {
    /// Rasterizes and counts triangle `index` of the draw.
    pub fn triangle(&mut self, index: u32, v: [&Vertex; 3]) {
        self.tally.rasterized.triangles += 1;
        if let Some(watch) = &mut self.watch {
            watch.primitive = index;
        }
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
        if area == 0 {
            return false;
        }
        let v = if area > 0 { v } else { [v[0], v[2], v[1]] };
        let fixed = v.map(|v| v.fixed);
        if self.culls(area > 0) {
            self.watch_culled([fixed]);
            return false;
        }
        let ndc = v.map(|v| v.ndc);
        let rect = self.rect;
        if !raster::reaches(&fixed, rect) {
            return true;
        }
        let Rasterizer { depth, tally, watch, .. } = self;
        match depth {
            None => raster::cover(&fixed, rect, |bx, by, m| {
                tally.launch(bx, by, m, m);
                if let Some(w) = watch.as_mut().filter(|w| w.at(bx, by)) {
                    w.launch(m, m, None);
                }
            }),
            Some(test) => {
                let z = ndc.map(|n| test.depth(n));
                let surface = test.surface(&fixed, z, z[0].max(z[1]).max(z[2]));
                raster::cover(&fixed, rect, |bx, by, m| {
                    let shaded = test.shade(&surface, bx, by, m);
                    tally.launch(bx, by, m, shaded);
                    if let Some(w) = watch.as_mut().filter(|w| w.at(bx, by)) {
                        w.launch(m, shaded, Some(test.fragment(&surface, bx, by, w.lane())));
                    }
                });
            }
        }
        true
    }

    /// Records a culled primitive, as the clockwise triangles `pieces`, at
    /// the probed pixel if they cover it.
    fn watch_culled(&mut self, pieces: impl IntoIterator<Item = [[i64; 2]; 3]>) {
        let Some(watch) = &mut self.watch else { return };
        let pixel = watch.pixel(self.rect);
        if pixel.x0 < pixel.x1 && pixel.y0 < pixel.y1 && pieces.into_iter().any(|p| raster::covers_any(&p, pixel)) {
            watch.culled();
        }
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
        let culled = self.culls(orientation > 0.0);
        // Clipping a culled primitive only serves the probe.
        if orientation == 0.0 || culled && self.watch.is_none() {
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
            return !culled;
        }
        let mut corners = [([0, 0], 0.0); MAX_VERTICES];
        for (corner, h) in corners.iter_mut().zip(&polygon.v[..polygon.n]) {
            *corner = project(h);
        }
        let corners = &corners[..polygon.n];
        if culled {
            self.watch_culled(pieces(corners, orientation > 0.0).map(|(fixed, _)| fixed));
            return false;
        }
        self.fan(corners, orientation > 0.0)
    }

    /// Rasterizes a clipped polygon as triangles (0, i, i + 1) and counts
    /// each block it covers once. False when no piece has area left once
    /// snapped.
    fn fan(&mut self, corners: &[([i64; 2], f64)], clockwise: bool) -> bool {
        let rect = self.rect;
        let max_depth = self.depth.as_ref().map(|d| corners.iter().map(|c| d.depth(c.1)).fold(f64::MIN, f64::max));
        self.launches.clear();
        let mut drawn = false;
        // The depth the piece covering the probed pixel tested it at.
        let mut probed = None;
        for (fixed, ndc) in pieces(corners, clockwise) {
            drawn = true;
            let Rasterizer { depth, launches, watch, .. } = self;
            let surface = depth.as_ref().zip(max_depth).map(|(d, max)| d.surface(&fixed, ndc.map(|n| d.depth(n)), max));
            raster::cover(&fixed, rect, |bx, by, covered| {
                let shaded = match (depth.as_mut(), &surface) {
                    (Some(test), Some(s)) => {
                        if let Some(w) = watch.as_ref().filter(|w| w.at(bx, by) && covered & 1 << w.lane() != 0) {
                            probed = Some(test.fragment(s, bx, by, w.lane()));
                        }
                        test.shade(s, bx, by, covered)
                    }
                    _ => covered,
                };
                launches.push(Launch { block: u64::from(by) << 32 | u64::from(bx), covered, shaded });
            });
        }
        // Pieces never share a pixel (the fill rule), only blocks.
        self.launches.sort_unstable_by_key(|l| l.block);
        for run in self.launches.chunk_by(|a, b| a.block == b.block) {
            let (covered, shaded) = run.iter().fold((0, 0), |(c, s), l| (c | l.covered, s | l.shaded));
            let (bx, by) = (run[0].block as u32, (run[0].block >> 32) as u32);
            self.tally.launch(bx, by, covered, shaded);
            if let Some(w) = self.watch.as_mut().filter(|w| w.at(bx, by)) {
                w.launch(covered, shaded, probed);
            }
        }
        drawn
    }
}

/// The pieces (0, i, i + 1) of a clipped polygon's fan, wound clockwise
/// with their corners' NDC depths, leaving out those that snapping
/// flattens or flips (slivers: they cover nothing).
fn pieces(corners: &[([i64; 2], f64)], clockwise: bool) -> impl Iterator<Item = ([[i64; 2]; 3], [f64; 3])> + '_ {
    (1..corners.len() - 1).filter_map(move |i| {
        let (a, mut b, mut c) = (corners[0], corners[i], corners[i + 1]);
        let area = raster::area2(a.0, b.0, c.0);
        if area == 0 || (area > 0) != clockwise {
            return None;
        }
        if area < 0 {
            (b, c) = (c, b);
        }
        Some(([a.0, b.0, c.0], [a.1, b.1, c.1]))
    })
}
