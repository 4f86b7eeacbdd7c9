//! The 2×2-quad model: how many quads a render pass's draws launch, how
//! many of their lanes cover a pixel and how many run as helper lanes,
//! computed exactly on the CPU from each draw's post-vertex-stage
//! clip-space positions, the way a Vulkan or D3D rasterizer decides it
//! (8-bit sub-pixel snapping, top-left rule, near/far clipping, primitive
//! order for the depth test). No GPU and no wgpu: docs/quads.md has the
//! model, its assumptions and what real hardware does differently.
//!
//! A `Pass` is one render pass's target: draws go through `Pass::draw` in
//! submission order, each returning its `DrawStats`, while the pass keeps
//! their sum, the quad-overdraw and helper-lane maps, and its depth buffer.

mod clip;
mod depth;
mod input;
mod primitive;
mod raster;
mod stats;
#[cfg(test)]
mod tests;

pub use input::{
    Compare, DEPTH_TOLERANCE, DepthBias, DepthState, Draw, Face, FrontFace, MAX_TARGET_SIZE,
    QuadError, Scissor, Viewport,
};
pub use raster::SUBPIXEL_BITS;
pub use stats::{DrawStats, QuadMaps, QuadStats};

use depth::DepthTest;
use primitive::{Launch, Rasterizer, Tally, Vertex};
use raster::Rect;

/// One render pass: its target size, its depth buffer if it has one, and
/// what its draws have launched so far.
#[derive(Debug, Clone)]
pub struct Pass {
    width: u32,
    height: u32,
    depth: Option<Vec<f32>>,
    maps: QuadMaps,
    totals: DrawStats,
    /// Kept between draws for their allocations.
    vertices: Vec<Vertex>,
    launches: Vec<Launch>,
}

impl Pass {
    /// A pass over a `width` × `height` target without a depth buffer.
    pub fn new(width: u32, height: u32) -> Result<Pass, QuadError> {
        if !(1..=MAX_TARGET_SIZE).contains(&width) || !(1..=MAX_TARGET_SIZE).contains(&height) {
            return Err(QuadError::TargetSize { width, height });
        }
        Ok(Pass {
            width,
            height,
            depth: None,
            maps: QuadMaps::new(width, height),
            totals: DrawStats::default(),
            vertices: Vec::new(),
            launches: Vec::new(),
        })
    }

    /// The pass with a depth buffer holding `initial`, one depth a pixel,
    /// rows top first: all 1.0 for one cleared to 1, or the depth an
    /// earlier pass left (captured from the GPU).
    pub fn with_depth(mut self, initial: Vec<f32>) -> Result<Pass, QuadError> {
        let (width, height) = (self.width, self.height);
        if initial.len() != width as usize * height as usize {
            return Err(QuadError::DepthSize {
                got: initial.len(),
                width,
                height,
            });
        }
        if let Some(at) = initial.iter().position(|d| !d.is_finite()) {
            let (x, y) = ((at % width as usize) as u32, (at / width as usize) as u32);
            return Err(QuadError::DepthValue {
                x,
                y,
                value: initial[at],
            });
        }
        self.depth = Some(initial);
        Ok(self)
    }

    /// Rasterizes one draw after those before it: its figures, which are
    /// also added to the pass's totals and maps (and its depth written,
    /// when its pipeline writes depth). A draw with bad state or indices is
    /// refused whole, leaving the pass as it was.
    pub fn draw(&mut self, draw: &Draw<'_>) -> Result<DrawStats, QuadError> {
        let (width, height) = (self.width, self.height);
        let viewport = draw.viewport.unwrap_or(Viewport::whole(width, height));
        viewport.check(width, height)?;
        // A pixel is inside the viewport when its centre is, edges included
        // on the left and top only, as the fill rule treats clipped edges.
        // The viewport lies inside the target (checked above).
        let centres = |from: f32, size: f32| {
            let edge = |at: f64| (at - 0.5).ceil() as i64;
            (edge(from.into()), edge(f64::from(from) + f64::from(size)))
        };
        let ((x0, x1), (y0, y1)) = (
            centres(viewport.x, viewport.width),
            centres(viewport.y, viewport.height),
        );
        let mut rect = Rect { x0, y0, x1, y1 };
        if let Some(s) = draw.scissor {
            s.check(width, height)?;
            let (x, y) = (i64::from(s.x), i64::from(s.y));
            rect = Rect {
                x0: rect.x0.max(x),
                y0: rect.y0.max(y),
                x1: rect.x1.min(x + i64::from(s.width)),
                y1: rect.y1.min(y + i64::from(s.height)),
            };
        }
        let triangles = draw.indices.map_or(draw.positions.len(), <[u32]>::len) / 3;
        if let Some(indices) = draw.indices {
            let vertices = draw.positions.len();
            if let Some(at) = indices[..3 * triangles]
                .iter()
                .position(|&i| i as usize >= vertices)
            {
                return Err(QuadError::Index {
                    at,
                    value: indices[at],
                    vertices,
                });
            }
        }
        let depth = match (draw.depth, self.depth.as_mut()) {
            (None, _) => None,
            (Some(state), Some(buffer)) => {
                state.check()?;
                Some(DepthTest::new(buffer, width, state, &viewport))
            }
            (Some(_), None) => return Err(QuadError::NoDepthBuffer),
        };

        let frame = clip::Framebuffer::new(&viewport);
        self.vertices.clear();
        self.vertices
            .extend(draw.positions.iter().map(|&p| Vertex::new(&frame, p)));
        let mut raster = Rasterizer {
            rect,
            cull: draw.cull,
            front_face: draw.front_face,
            depth,
            tally: Tally {
                maps: &mut self.maps,
                rasterized: QuadStats::default(),
                shaded: QuadStats::default(),
            },
            launches: &mut self.launches,
        };
        let vertex = |t: usize, k: usize| {
            &self.vertices[draw.indices.map_or(3 * t + k, |i| i[3 * t + k] as usize)]
        };
        for t in 0..triangles {
            raster.triangle([vertex(t, 0), vertex(t, 1), vertex(t, 2)]);
        }

        let rasterized = raster.tally.rasterized;
        let shaded = QuadStats {
            triangles: rasterized.triangles,
            culled_triangles: rasterized.culled_triangles,
            ..raster.tally.shaded
        };
        let stats = DrawStats {
            rasterized,
            shaded: draw.depth.map(|_| shaded),
        };
        self.totals += stats;
        Ok(stats)
    }

    /// The target's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The sum of every draw so far.
    pub fn totals(&self) -> DrawStats {
        self.totals
    }

    /// Quad overdraw and helper lanes of every draw so far, shaded quads only.
    pub fn maps(&self) -> &QuadMaps {
        &self.maps
    }

    /// The depth buffer as the draws so far left it.
    pub fn depth(&self) -> Option<&[f32]> {
        self.depth.as_deref()
    }

    /// The pass's totals and maps, when it is done.
    pub fn finish(self) -> (DrawStats, QuadMaps) {
        (self.totals, self.maps)
    }
}
