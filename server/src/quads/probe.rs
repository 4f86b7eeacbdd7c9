//! One chosen pixel's history: every primitive of every draw that reaches
//! it, in rasterization order, with what became of its fragment there. The
//! rasterizer hands each launch of the pixel's 2×2 block to a `Watch`, so
//! the verdicts are the ones the counts and maps are made of.

use super::raster::Rect;

/// One primitive's fragment at the probed pixel.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Fragment {
    /// The draw's index within the pass: 0 for the first `Pass::draw` call
    /// (refused calls count too, so it is the caller's index).
    pub draw: usize,
    /// The triangle's index within the draw (positions or indices
    /// `3·primitive..3·primitive + 3`).
    pub primitive: u32,
    /// The depth the test compared, as the buffer would store it (bias
    /// included, clamped to the viewport's range, rounded to f32); `None`
    /// when nothing was tested: no depth test, a helper lane, culled.
    pub depth: Option<f32>,
    pub verdict: Verdict,
    /// The lane ran as a helper lane here: its quad ran the fragment
    /// shader (another pixel of it passed) but this pixel did not, either
    /// because the primitive does not cover it (`NotTested`) or because it
    /// failed the depth test (`FailedDepth`).
    pub helper: bool,
}

/// What happened to a fragment at the probed pixel. A fragment survives
/// (runs the shader and may write) when it is `Passed`, or `NotTested`
/// without being a helper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Covered, and passed the depth test.
    Passed,
    /// Covered, and failed the depth test.
    FailedDepth,
    /// Covered by a draw without a depth test, or a helper lane.
    NotTested,
    /// Face culling removed the primitive, whose coverage (either winding)
    /// includes the pixel.
    Culled,
}

/// The probed pixel and the fragments recorded there so far.
#[derive(Debug, Clone)]
pub(super) struct Probe {
    x: u32,
    y: u32,
    fragments: Vec<Fragment>,
}

impl Probe {
    pub fn new(x: u32, y: u32) -> Probe {
        Probe { x, y, fragments: Vec::new() }
    }

    pub fn fragments(&self) -> &[Fragment] {
        &self.fragments
    }

    pub fn clear(&mut self) {
        self.fragments.clear();
    }

    /// The probe as draw number `draw` records into it.
    pub fn watch(&mut self, draw: usize) -> Watch<'_> {
        let (x, y) = (self.x, self.y);
        Watch { block: (x / 2, y / 2), lane: (x & 1 | (y & 1) << 1) as usize, x, y, draw, primitive: 0, fragments: &mut self.fragments }
    }
}

/// The probe during one draw, in the band of rows that holds the pixel.
pub(super) struct Watch<'a> {
    block: (u32, u32),
    /// The pixel's lane within its block: bit `lane` of a block's mask.
    lane: usize,
    x: u32,
    y: u32,
    draw: usize,
    /// The primitive being rasterized.
    pub primitive: u32,
    fragments: &'a mut Vec<Fragment>,
}

impl Watch<'_> {
    /// Whether block (bx, by) holds the pixel.
    pub fn at(&self, bx: u32, by: u32) -> bool {
        (bx, by) == self.block
    }

    /// The pixel's row, to find the band of the target that holds it.
    pub fn row(&self) -> u32 {
        self.y
    }

    pub fn lane(&self) -> usize {
        self.lane
    }

    /// The pixel alone, where it lies inside `rect`.
    pub fn pixel(&self, rect: Rect) -> Rect {
        let (x, y) = (i64::from(self.x), i64::from(self.y));
        Rect { x0: rect.x0.max(x), y0: rect.y0.max(y), x1: rect.x1.min(x + 1), y1: rect.y1.min(y + 1) }
    }

    /// The primitive launched the pixel's block: `covered` lanes, of which
    /// `shaded` run the shader, the pixel's fragment tested at `depth`
    /// (`None` without a depth test). An uncovered pixel of a quad that
    /// does not run leaves no fragment.
    pub fn launch(&mut self, covered: u8, shaded: u8, depth: Option<f32>) {
        let bit = 1 << self.lane;
        let ran = shaded != 0;
        let (verdict, depth) = match (covered & bit != 0, depth) {
            (false, _) if !ran => return,
            (false, _) | (true, None) => (Verdict::NotTested, None),
            (true, Some(d)) if shaded & bit != 0 => (Verdict::Passed, Some(d)),
            (true, Some(d)) => (Verdict::FailedDepth, Some(d)),
        };
        self.push(verdict, depth, ran && shaded & bit == 0);
    }

    /// Face culling removed the primitive, which covers the pixel.
    pub fn culled(&mut self) {
        self.push(Verdict::Culled, None, false);
    }

    fn push(&mut self, verdict: Verdict, depth: Option<f32>, helper: bool) {
        self.fragments.push(Fragment { draw: self.draw, primitive: self.primitive, depth, verdict, helper });
    }
}
