//! Coverage of one triangle, exactly: vertices snapped to 8 sub-pixel bits,
//! integer edge functions evaluated at pixel centres, the top-left fill
//! rule, and the result handed out per 2×2 block of the target.
//!
//! Each pixel row's covered span is solved from the edge functions with
//! exact integer division rather than tested pixel by pixel, so large
//! triangles cost per row and per block, not per pixel.

/// Vertex positions snap to 1/256 pixel: Vulkan's `subPixelPrecisionBits`,
/// 8 on lavapipe (llvmpipe) and the D3D11 requirement most GPUs meet.
pub const SUBPIXEL_BITS: u32 = 8;
const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;

/// A framebuffer coordinate in pixels, snapped to the nearest sub-pixel
/// step (ties away from zero). The guard band bounds it (see `clip`).
pub(super) fn snap(pixels: f64) -> i64 {
    (pixels * ONE as f64).round() as i64
}

/// Back from sub-pixel units to pixels.
pub(super) fn pixels(fixed: i64) -> f64 {
    fixed as f64 / ONE as f64
}

/// Twice the signed area of a snapped triangle, in sub-pixel units squared:
/// positive when it is clockwise on screen (y down).
pub(super) fn area2(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// A half-open rectangle of pixels [x0, x1) × [y0, y1), inside the target.
#[derive(Debug, Clone, Copy)]
pub(super) struct Rect {
    pub x0: i64,
    pub y0: i64,
    pub x1: i64,
    pub y1: i64,
}

/// E(p) = a·px + b·py + c, >= 0 where the pixel centre p (sub-pixel units)
/// is covered with respect to this edge.
struct Edge {
    a: i64,
    b: i64,
    c: i64,
}

impl Edge {
    /// The edge from `p` to `q` of a triangle wound clockwise on screen, so
    /// that its inside is to the right of the direction of travel.
    fn new(p: [i64; 2], q: [i64; 2]) -> Edge {
        let a = p[1] - q[1];
        let b = q[0] - p[0];
        // The top-left rule: a centre exactly on the edge is covered only on
        // a top edge (horizontal, inside below: b > 0) or a left edge (going
        // up the screen: a > 0), so triangles sharing an edge never both
        // cover a pixel and never both miss it. Elsewhere E must exceed 0,
        // i.e. E - 1 >= 0.
        let top_left = a > 0 || (a == 0 && b > 0);
        Edge { a, b, c: -(a * p[0] + b * p[1]) - i64::from(!top_left) }
    }
}

/// The pixels [l, r) of row `y` whose centres all three edges cover, within [l, r).
fn span(edges: &[Edge; 3], y: i64, mut l: i64, mut r: i64) -> (i64, i64) {
    let centre_y = y * ONE + HALF;
    for e in edges {
        // E at pixel x is step·x + k.
        let step = e.a * ONE;
        let k = e.b * centre_y + e.c + e.a * HALF;
        if step > 0 {
            l = l.max(ceil_div(-k, step));
        } else if step < 0 {
            r = r.min(k.div_euclid(-step) + 1);
        } else if k < 0 {
            return (l, l);
        }
    }
    (l, r)
}

fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

/// Bits 0 and 1: pixels x and x + 1 of a row's span [l, r).
fn lanes((l, r): (i64, i64), x: i64) -> u8 {
    u8::from(l <= x && x < r) | u8::from(l <= x + 1 && x + 1 < r) << 1
}

const EMPTY: (i64, i64) = (0, 0);

/// The pixels of `rect` whose centres lie within the bounding box of the
/// triangle `v`; `None` when there are none.
fn centres(v: &[[i64; 2]; 3], rect: Rect) -> Option<Rect> {
    let lo = |k: usize| v[0][k].min(v[1][k]).min(v[2][k]);
    let hi = |k: usize| v[0][k].max(v[1][k]).max(v[2][k]);
    let x0 = rect.x0.max(ceil_div(lo(0) - HALF, ONE));
    let x1 = rect.x1.min((hi(0) - HALF).div_euclid(ONE) + 1);
    let y0 = rect.y0.max(ceil_div(lo(1) - HALF, ONE));
    let y1 = rect.y1.min((hi(1) - HALF).div_euclid(ONE) + 1);
    (x0 < x1 && y0 < y1).then_some(Rect { x0, y0, x1, y1 })
}

/// Whether the triangle `v` can cover a pixel of `rect`: a cheap test
/// before setting up anything else for it.
pub(super) fn reaches(v: &[[i64; 2]; 3], rect: Rect) -> bool {
    centres(v, rect).is_some()
}

/// Whether the triangle `v`, wound clockwise on screen, covers a pixel
/// centre inside `rect`.
pub(super) fn covers_any(v: &[[i64; 2]; 3], rect: Rect) -> bool {
    let mut any = false;
    cover(v, rect, |_, _, _| any = true);
    any
}

/// Calls `launch(bx, by, mask)` for every 2×2 block (pixels 2bx, 2bx + 1 ×
/// 2by, 2by + 1) where the triangle `v`, wound clockwise on screen, covers
/// a pixel centre inside `rect`. Mask bit 0 is the block's top-left pixel,
/// 1 top-right, 2 bottom-left, 3 bottom-right. Blocks come row by row.
pub(super) fn cover(v: &[[i64; 2]; 3], rect: Rect, mut launch: impl FnMut(u32, u32, u8)) {
    let Some(Rect { x0, y0, x1, y1 }) = centres(v, rect) else {
        return;
    };
    let [p, q, s] = *v;
    let edges = [Edge::new(p, q), Edge::new(q, s), Edge::new(s, p)];
    // Blocks align to the target's origin: start at the even row at or above y0.
    let mut y = y0 & !1;
    while y < y1 {
        let top = if y >= y0 { span(&edges, y, x0, x1) } else { EMPTY };
        let bottom = if y + 1 < y1 { span(&edges, y + 1, x0, x1) } else { EMPTY };
        let (l, r) = match (top.0 < top.1, bottom.0 < bottom.1) {
            (true, true) => (top.0.min(bottom.0), top.1.max(bottom.1)),
            (true, false) => top,
            (false, true) => bottom,
            (false, false) => EMPTY,
        };
        let mut x = l & !1;
        while x < r {
            // Two rows' spans can leave a gap of empty blocks between them
            // (a thin, nearly horizontal sliver).
            let mask = lanes(top, x) | lanes(bottom, x) << 2;
            if mask != 0 {
                launch((x / 2) as u32, (y / 2) as u32, mask);
            }
            x += 2;
        }
        y += 2;
    }
}
