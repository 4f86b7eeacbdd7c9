//! What the model counts: per draw and summed over a pass's draws, and the
//! two per-pass maps the inspector draws over the target.

use std::iter::Sum;
use std::ops::{Add, AddAssign};

use serde::ser::{Serialize, SerializeStruct, Serializer};

/// Set bits of a 4-bit lane mask: `count_ones` without POPCNT (not in the
/// x86-64 baseline) costs more than the rest of counting a quad.
const LANES: [u8; 16] = [0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4];

/// One figure of a draw (or of several, summed).
///
/// Serialized with the keys `triangles`, `culled_triangles`, `pixels`,
/// `quads`, `helper_lanes` and `quad_efficiency` (null without quads).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct QuadStats {
    /// Primitives the draw submitted (complete triangles).
    pub triangles: u64,
    /// Of those, the ones that reached no pixel test: a NaN or infinite
    /// coordinate, face culling, clipped away entirely by the near or far
    /// plane (or behind the eye), or zero area once snapped. A primitive
    /// that is drawn but covers no pixel centre (off screen, between
    /// centres, outside the scissor) is not culled.
    pub culled_triangles: u64,
    /// Covered pixels, a pixel counted once per primitive covering it.
    pub pixels: u64,
    /// 2×2 quads launched: one per primitive per target-aligned block where
    /// it covers at least one pixel.
    pub quads: u64,
}

impl QuadStats {
    /// Lanes of launched quads that cover no pixel of their primitive and
    /// run only to feed derivatives, lanes outside the target included.
    pub fn helper_lanes(&self) -> u64 {
        (4 * self.quads).saturating_sub(self.pixels)
    }

    /// Covered pixels per lane launched, 1 at best; `None` without quads.
    pub fn quad_efficiency(&self) -> Option<f64> {
        (self.quads > 0).then(|| self.pixels as f64 / (4 * self.quads) as f64)
    }

    /// Counts one quad whose covered lanes are the bits of `mask`, if any.
    pub(super) fn launch(&mut self, mask: u8) {
        if mask != 0 {
            self.quads += 1;
            self.pixels += u64::from(LANES[usize::from(mask & 0xf)]);
        }
    }
}

impl Serialize for QuadStats {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut out = s.serialize_struct("QuadStats", 6)?;
        out.serialize_field("triangles", &self.triangles)?;
        out.serialize_field("culled_triangles", &self.culled_triangles)?;
        out.serialize_field("pixels", &self.pixels)?;
        out.serialize_field("quads", &self.quads)?;
        out.serialize_field("helper_lanes", &self.helper_lanes())?;
        out.serialize_field("quad_efficiency", &self.quad_efficiency())?;
        out.end()
    }
}

impl Add for QuadStats {
    type Output = QuadStats;
    fn add(self, o: QuadStats) -> QuadStats {
        QuadStats {
            triangles: self.triangles + o.triangles,
            culled_triangles: self.culled_triangles + o.culled_triangles,
            pixels: self.pixels + o.pixels,
            quads: self.quads + o.quads,
        }
    }
}

/// A draw's figures: everything rasterized, and where the pipeline tests
/// depth, what passes the test and so runs the fragment shader (assuming
/// early depth testing, see docs/quads.md).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct DrawStats {
    pub rasterized: QuadStats,
    /// `None`: no depth test, everything rasterized is shaded. Triangle
    /// counts are the rasterized ones.
    pub shaded: Option<QuadStats>,
}

impl DrawStats {
    /// What runs the fragment shader: `shaded`, else `rasterized`.
    pub fn shaded_or_rasterized(&self) -> QuadStats {
        self.shaded.unwrap_or(self.rasterized)
    }
}

/// Summing draws with and without a depth test: a draw without one
/// contributes its rasterized figure to the shaded sum.
impl Add for DrawStats {
    type Output = DrawStats;
    fn add(self, o: DrawStats) -> DrawStats {
        let shaded = (self.shaded.is_some() || o.shaded.is_some()).then(|| self.shaded_or_rasterized() + o.shaded_or_rasterized());
        DrawStats { rasterized: self.rasterized + o.rasterized, shaded }
    }
}

impl AddAssign for DrawStats {
    fn add_assign(&mut self, o: DrawStats) {
        *self = *self + o;
    }
}

impl Sum for DrawStats {
    fn sum<I: Iterator<Item = DrawStats>>(draws: I) -> DrawStats {
        draws.fold(DrawStats::default(), Add::add)
    }
}

/// Per-pass maps of shaded quads (see `DrawStats`), accumulated over the
/// pass's draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct QuadMaps {
    width: u32,
    height: u32,
    quads: Vec<u32>,
    helper_lanes: Vec<u32>,
}

impl QuadMaps {
    pub(super) fn new(width: u32, height: u32) -> QuadMaps {
        let blocks = width.div_ceil(2) as usize * height.div_ceil(2) as usize;
        QuadMaps { width, height, quads: vec![0; blocks], helper_lanes: vec![0; width as usize * height as usize] }
    }

    pub(super) fn clear(&mut self) {
        self.quads.fill(0);
        self.helper_lanes.fill(0);
    }

    /// The target's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The quad map's size: one entry per 2×2 block, ceil(width / 2) ×
    /// ceil(height / 2).
    pub fn blocks(&self) -> (u32, u32) {
        (self.width.div_ceil(2), self.height.div_ceil(2))
    }

    /// Quads launched at each 2×2 block (quad overdraw), rows top first.
    pub fn quads(&self) -> &[u32] {
        &self.quads
    }

    /// Times each pixel of the target ran as a helper lane, rows top first.
    pub fn helper_lanes(&self) -> &[u32] {
        &self.helper_lanes
    }

    /// The maps cut into bands of `block_rows` rows of blocks (twice as many
    /// pixel rows), top first, for bands of the target drawn in parallel.
    pub(super) fn bands(&mut self, block_rows: usize) -> Vec<MapRows<'_>> {
        let (width, height) = (self.width, self.height);
        let quads = self.quads.chunks_mut(block_rows * width.div_ceil(2) as usize);
        let helpers = self.helper_lanes.chunks_mut(2 * block_rows * width as usize);
        (quads.zip(helpers).enumerate())
            .map(|(i, (quads, helper_lanes))| MapRows { quads, helper_lanes, width, height, first_block_row: (i * block_rows) as u32 })
            .collect()
    }
}

/// One band's rows of the maps.
pub(super) struct MapRows<'a> {
    quads: &'a mut [u32],
    helper_lanes: &'a mut [u32],
    width: u32,
    height: u32,
    first_block_row: u32,
}

impl MapRows<'_> {
    /// Counts a shaded quad at block (bx, by), inside this band, whose
    /// shading lanes are `mask`.
    pub(super) fn launch(&mut self, bx: u32, by: u32, mask: u8) {
        let row = (by - self.first_block_row) as usize;
        let block = row * self.width.div_ceil(2) as usize + bx as usize;
        self.quads[block] = self.quads[block].saturating_add(1);
        if mask == 0xf {
            return;
        }
        let width = self.width as usize;
        let top = 2 * row * width + 2 * bx as usize;
        let lanes = [top, top + 1, top + width, top + width + 1];
        if 2 * bx + 1 < self.width && 2 * by + 1 < self.height {
            // All four lanes inside the target: add without branching on
            // which ones help, which a partial block makes unpredictable.
            for (lane, at) in lanes.into_iter().enumerate() {
                let helps = u32::from(mask >> lane & 1 == 0);
                self.helper_lanes[at] = self.helper_lanes[at].saturating_add(helps);
            }
        } else {
            for (lane, at) in lanes.into_iter().enumerate() {
                let (x, y) = (2 * bx + (lane as u32 & 1), 2 * by + (lane as u32 >> 1));
                if mask & 1 << lane == 0 && x < self.width && y < self.height {
                    self.helper_lanes[at] = self.helper_lanes[at].saturating_add(1);
                }
            }
        }
    }
}
