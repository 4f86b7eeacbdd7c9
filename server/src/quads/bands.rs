//! One draw spread over the threads by rows of the target. Each band of
//! block rows runs every primitive, in API order, over its own rows of the
//! depth buffer and maps, and blocks never straddle bands (they start at
//! even rows), so the result is the sequential one, bit for bit. Bands
//! outside the draw's rectangle (a scissor) are skipped, but for one that
//! counts the primitives.

use rayon::prelude::*;

use super::depth::DepthTest;
use super::input::{DepthState, Draw, Viewport};
use super::primitive::{Launch, Rasterizer, Tally, Vertex};
use super::probe::Watch;
use super::raster::Rect;
use super::stats::{QuadMaps, QuadStats};

/// A draw, checked and its vertices mapped, ready to rasterize.
pub(super) struct Job<'a> {
    pub draw: &'a Draw<'a>,
    pub vertices: &'a [Vertex],
    pub triangles: usize,
    /// Target, viewport and scissor, intersected.
    pub rect: Rect,
    pub viewport: Viewport,
    pub depth: Option<DepthState>,
}

/// What a draw launched: rasterized and shaded, counted once; the probed
/// pixel's fragments go to `watch`.
pub(super) fn rasterize(
    job: &Job,
    maps: &mut QuadMaps,
    depth: Option<&mut [f32]>,
    launches: &mut Vec<Vec<Launch>>,
    watch: Option<Watch<'_>>,
) -> (QuadStats, QuadStats) {
    let (width, height) = maps.size();
    // One band a thread: each band sets up every primitive again, so more
    // bands would cost more than their balance gains.
    let block_rows = height.div_ceil(2).div_ceil(rayon::current_num_threads() as u32).max(1);
    let maps = maps.bands(block_rows as usize);
    let depth: Vec<Option<&mut [f32]>> = match (depth, job.depth) {
        (Some(buffer), Some(_)) => buffer.chunks_mut(2 * block_rows as usize * width as usize).map(Some).collect(),
        _ => maps.iter().map(|_| None).collect(),
    };
    launches.resize_with(maps.len(), Vec::new);
    let rows = |band: usize| {
        let first_row = 2 * block_rows * band as u32;
        Rect { y0: job.rect.y0.max(first_row.into()), y1: job.rect.y1.min((first_row + 2 * block_rows).into()), ..job.rect }
    };
    // The band that counts every primitive: the first with rows to draw.
    let counting = (0..maps.len()).find(|&b| rows(b).y0 < rows(b).y1).unwrap_or(0);
    let mut watches: Vec<Option<Watch>> = maps.iter().map(|_| None).collect();
    if let Some(w) = watch {
        let band = (w.row() / (2 * block_rows)) as usize;
        watches[band] = Some(w);
    }
    let tallies: Vec<(QuadStats, QuadStats)> = (maps.into_par_iter().zip(depth).zip(launches.par_iter_mut()).zip(watches).enumerate())
        .map(|(band, (((maps, depth), launches), watch))| {
            let first_row = 2 * block_rows * band as u32;
            let rows = rows(band);
            if rows.y0 >= rows.y1 && band != counting {
                return Default::default();
            }
            let mut raster = Rasterizer {
                rect: rows,
                cull: job.draw.cull,
                front_face: job.draw.front_face,
                depth: depth.zip(job.depth).map(|(buffer, state)| DepthTest::new(buffer, first_row, width, state, &job.viewport)),
                tally: Tally { maps, rasterized: QuadStats::default(), shaded: QuadStats::default() },
                launches,
                watch,
            };
            let indices = job.draw.indices;
            let vertex = |t: usize, k: usize| &job.vertices[indices.map_or(3 * t + k, |i| i[3 * t + k] as usize)];
            for t in 0..job.triangles {
                raster.triangle(t as u32, [vertex(t, 0), vertex(t, 1), vertex(t, 2)]);
            }
            (raster.tally.rasterized, raster.tally.shaded)
        })
        .collect();
    // The counting band counted every primitive; pixels and quads are each
    // band's own.
    let first = tallies[counting].0;
    let sum = |pick: fn(&(QuadStats, QuadStats)) -> QuadStats| QuadStats {
        triangles: first.triangles,
        culled_triangles: first.culled_triangles,
        ..tallies.iter().map(pick).fold(QuadStats::default(), |a, b| a + b)
    };
    (sum(|t| t.0), sum(|t| t.1))
}
