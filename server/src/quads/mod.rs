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
//! A pass can also probe one pixel: record every fragment its draws make
//! there, with the depth test's verdict (`Pass::probe`).

mod bands;
mod clip;
mod depth;
mod input;
mod primitive;
mod probe;
mod raster;
mod stats;
#[cfg(test)]
mod tests;

pub use input::{Compare, DEPTH_TOLERANCE, DepthBias, DepthState, Draw, Face, FrontFace, MAX_TARGET_SIZE, QuadError, Scissor, Viewport};
pub use probe::{Fragment, Verdict};
pub use raster::SUBPIXEL_BITS;
pub use stats::{DrawStats, QuadMaps, QuadStats};

use bands::Job;
use primitive::{Launch, Vertex};
use probe::Probe;
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
    /// `Pass::draw` calls so far: the next draw's index.
    draws: usize,
    probe: Option<Probe>,
    /// Kept between draws for their allocations.
    vertices: Vec<Vertex>,
    launches: Vec<Vec<Launch>>,
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
            draws: 0,
            probe: None,
            vertices: Vec::new(),
            launches: Vec::new(),
        })
    }

    /// The pass with a depth buffer holding `initial`, one depth a pixel,
    /// rows top first: all 1.0 for one cleared to 1, or the depth an
    /// earlier pass left (captured from the GPU).
    pub fn with_depth(mut self, initial: Vec<f32>) -> Result<Pass, QuadError> {
        self.check_depth(&initial)?;
        self.depth = Some(initial);
        Ok(self)
    }

    /// Starts the pass over (no draws, maps zeroed, no fragments, the
    /// probe kept) with `depth` as its depth buffer (as `with_depth`) or
    /// none, reusing its memory: a pass kept from frame to frame costs no
    /// fresh pages each frame.
    pub fn reset(&mut self, depth: Option<&[f32]>) -> Result<(), QuadError> {
        if let Some(values) = depth {
            self.check_depth(values)?;
        }
        match (depth, &mut self.depth) {
            (Some(values), Some(buffer)) => buffer.copy_from_slice(values),
            (values, buffer) => *buffer = values.map(<[f32]>::to_vec),
        }
        self.start_over();
        Ok(())
    }

    /// `reset` with the depth buffer cleared to `value`, as a render pass
    /// that clears its depth attachment starts: no buffer to copy from.
    pub fn reset_cleared(&mut self, value: f32) -> Result<(), QuadError> {
        if !value.is_finite() {
            return Err(QuadError::DepthValue { x: 0, y: 0, value });
        }
        let pixels = self.width as usize * self.height as usize;
        match &mut self.depth {
            Some(buffer) => buffer.fill(value),
            None => self.depth = Some(vec![value; pixels]),
        }
        self.start_over();
        Ok(())
    }

    fn start_over(&mut self) {
        self.maps.clear();
        self.totals = DrawStats::default();
        self.draws = 0;
        if let Some(probe) = &mut self.probe {
            probe.clear();
        }
    }

    /// Records the fragments at (x, y) of every draw from now on (those
    /// recorded at another pixel are dropped): see `fragments`.
    pub fn probe(&mut self, x: u32, y: u32) -> Result<(), QuadError> {
        let (width, height) = (self.width, self.height);
        if x >= width || y >= height {
            return Err(QuadError::Pixel { x, y, width, height });
        }
        self.probe = Some(Probe::new(x, y));
        Ok(())
    }

    /// The probed pixel's fragments, in rasterization order: draw by draw,
    /// primitive by primitive. Each primitive that reaches the pixel
    /// leaves one: covered (tested or not), a helper lane of a quad that
    /// ran, or culled by its facing. Primitives of zero area, clipped away
    /// or outside the scissor leave none. Empty without a probe.
    pub fn fragments(&self) -> &[Fragment] {
        self.probe.as_ref().map_or(&[], Probe::fragments)
    }

    fn check_depth(&self, values: &[f32]) -> Result<(), QuadError> {
        let (width, height) = (self.width, self.height);
        if values.len() != width as usize * height as usize {
            return Err(QuadError::DepthSize { got: values.len(), width, height });
        }
        match values.iter().position(|d| !d.is_finite()) {
            Some(at) => {
                let (x, y) = ((at % width as usize) as u32, (at / width as usize) as u32);
                Err(QuadError::DepthValue { x, y, value: values[at] })
            }
            None => Ok(()),
        }
    }

    /// Rasterizes one draw after those before it: its figures, which are
    /// also added to the pass's totals and maps (and its depth written,
    /// when its pipeline writes depth). A draw with bad state or indices is
    /// refused whole, leaving the pass as it was.
    pub fn draw(&mut self, draw: &Draw<'_>) -> Result<DrawStats, QuadError> {
        let index = self.draws;
        self.draws += 1;
        let (width, height) = (self.width, self.height);
        let viewport = draw.viewport.unwrap_or(Viewport::whole(width, height));
        viewport.check(width, height)?;
        let rect = covered_rect(&viewport, draw.scissor, width, height)?;
        let triangles = draw.triangles()?;
        let depth = match (draw.depth, &self.depth) {
            (None, _) => None,
            (Some(state), Some(_)) => {
                state.check()?;
                Some(state)
            }
            (Some(_), None) => return Err(QuadError::NoDepthBuffer),
        };

        let frame = clip::Framebuffer::new(&viewport);
        self.vertices.clear();
        self.vertices.extend(draw.positions.iter().map(|&p| Vertex::new(&frame, p)));
        let job = Job { draw, vertices: &self.vertices, triangles, rect, viewport, depth };
        let watch = self.probe.as_mut().map(|p| p.watch(index));
        let (rasterized, shaded) = bands::rasterize(&job, &mut self.maps, self.depth.as_deref_mut(), &mut self.launches, watch);
        let stats = DrawStats { rasterized, shaded: depth.map(|_| shaded) };
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

/// The pixels a draw may cover: those whose centres are inside the viewport
/// (its left and top edges included, as the fill rule treats clipped
/// edges) and inside the scissor rectangle. The viewport lies inside the
/// target (checked).
fn covered_rect(viewport: &Viewport, scissor: Option<Scissor>, width: u32, height: u32) -> Result<Rect, QuadError> {
    let centres = |from: f32, size: f32| {
        let edge = |at: f64| (at - 0.5).ceil() as i64;
        (edge(from.into()), edge(f64::from(from) + f64::from(size)))
    };
    let ((x0, x1), (y0, y1)) = (centres(viewport.x, viewport.width), centres(viewport.y, viewport.height));
    let rect = Rect { x0, y0, x1, y1 };
    let Some(s) = scissor else {
        return Ok(rect);
    };
    s.check(width, height)?;
    let (x, y) = (i64::from(s.x), i64::from(s.y));
    Ok(Rect { x0: rect.x0.max(x), y0: rect.y0.max(y), x1: rect.x1.min(x + i64::from(s.width)), y1: rect.y1.min(y + i64::from(s.height)) })
}
