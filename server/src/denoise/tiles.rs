//! Cutting an image too large for the device into tiles the network runs
//! on one at a time, as OIDN does (`core/unet_filter.cpp`): each tile's
//! window overlaps its neighbours by the network's receptive radius, so
//! every pixel kept from a tile saw all the input it would have seen in
//! one pass over the whole image. Windows start on the network's
//! alignment, so pooling cuts them on the same grid as the whole image,
//! and a window at the right or bottom edge ends where the whole image's
//! zero padding ends. The pixels kept from the tiles are then the ones
//! the untiled network makes, not a blend.

use super::network::{Network, Op};

/// A rectangle of the image, in pixels: `[x, x + width) × [y, y + height)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// One run of the network: the pixels it reads (`window`, clipped to the
/// image) and the ones kept from its output (`inner`, inside `window`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    pub window: Rect,
    pub inner: Rect,
}

/// How far, in input pixels, an output pixel of `net` sees. A pixel of a
/// tensor at level L (the image halved L times) covers 2^L input pixels
/// and depends on those and on `radius` more on either side: a 3×3
/// convolution adds its neighbours' 2^L; a 2×2 pool adds nothing (its
/// output pixel covers exactly its inputs); a nearest upsample to level L
/// adds 2^L, because an odd pixel reads the coarse pixel that starts one
/// fine pixel before it.
pub fn receptive_radius(net: &Network) -> u32 {
    let mut radius = vec![0u32; net.tensors.len()];
    for op in &net.ops {
        let src = op.srcs().iter().map(|s| radius[s.0]).max().unwrap_or(0);
        radius[op.dst().0] = match op {
            Op::Conv(c) => src + (1 << net.tensor(c.src).level),
            Op::Upsample { dst, .. } => src + (1 << net.tensor(*dst).level),
            Op::Pool { .. } | Op::Concat { .. } => src,
        };
    }
    radius[net.output.0]
}

/// The overlap between tiles: the receptive radius on the alignment.
pub fn overlap(net: &Network) -> u32 {
    receptive_radius(net).next_multiple_of(net.alignment() as u32)
}

/// Bytes of every tensor of a `side` × `side` window (`element` bytes a
/// value, channels padded to blocks of 4), and of the largest one.
pub fn window_bytes(net: &Network, side: u32, element: u64) -> (u64, u64) {
    let bytes = |t: &super::network::Tensor| {
        let s = u64::from(side >> t.level);
        s * s * (t.channels.next_multiple_of(4) as u64) * element
    };
    let all: Vec<u64> = net.tensors.iter().map(bytes).collect();
    (all.iter().sum(), all.iter().copied().max().unwrap_or(0))
}

/// The largest square window (a multiple of the alignment) whose largest
/// tensor fits in `max_binding` bytes and all of whose tensors fit in
/// `budget`; `None` when not even a window twice the overlap fits.
pub fn window_side(net: &Network, element: u64, max_binding: u64, budget: u64) -> Option<u32> {
    let align = net.alignment() as u32;
    let smallest = 2 * overlap(net) + align;
    let fits = |side: u32| {
        let (all, largest) = window_bytes(net, side, element);
        largest <= max_binding && all <= budget
    };
    if !fits(smallest) {
        return None;
    }
    // Tensor sizes grow with the side: the largest fitting side by bisection.
    let (mut lo, mut hi) = (smallest / align, 1 << 12);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if fits(mid * align) { lo = mid } else { hi = mid - 1 }
    }
    Some(lo * align)
}

/// The tiles covering a `width` × `height` image with windows of at most
/// `side` × `side` (a multiple of `align`, more than twice `overlap`,
/// itself a multiple of `align`). An image whose padded size fits one
/// window is one tile.
pub fn plan(width: u32, height: u32, side: u32, overlap: u32, align: u32) -> Vec<Tile> {
    let xs = spans(width, side, overlap, align);
    let ys = spans(height, side, overlap, align);
    ys.iter()
        .flat_map(|&(wy, iy)| {
            xs.iter().map(move |&(wx, ix)| Tile {
                window: Rect { x: wx.0, y: wy.0, width: wx.1, height: wy.1 },
                inner: Rect { x: ix.0, y: iy.0, width: ix.1, height: iy.1 },
            })
        })
        .collect()
}

/// Along one axis of `len` pixels: per tile, (window start, window length)
/// and (inner start, inner length).
fn spans(len: u32, side: u32, overlap: u32, align: u32) -> Vec<((u32, u32), (u32, u32))> {
    let padded = len.next_multiple_of(align);
    if padded <= side {
        return vec![((0, len), (0, len))];
    }
    let stride = side - 2 * overlap;
    (0..len.div_ceil(stride))
        .map(|i| {
            let inner = i * stride;
            let inner_end = (inner + stride).min(len);
            // Back by the overlap, but no window past the padded edge.
            let start = inner.saturating_sub(overlap).min(padded - side);
            ((start, (start + side).min(len) - start), (inner, inner_end - inner))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::denoise::testing::{network, small_unet};

    #[test]
    fn the_receptive_radius_of_oidns_base_unet_is_94_pixels() {
        // Convolutions: enc_conv0, 1 +2, enc_conv2 +2, enc_conv3 +4,
        // enc_conv4 +8, enc_conv5a, b +32, dec_conv4a, b +16, dec_conv3a, b
        // +8, dec_conv2a, b +4, dec_conv1a, b, dec_conv0 +3; upsamples
        // +8 +4 +2 +1.
        let net = network(&small_unet(9), 1);
        assert_eq!(receptive_radius(&net), 94);
        assert_eq!(overlap(&net), 96);
    }

    /// Every pixel is kept from exactly one tile; each window is aligned,
    /// at most `side` wide, inside the padded image, and holds its inner
    /// pixels' neighbourhood of `overlap` wherever the image has one.
    #[test]
    fn tiles_cover_the_image_once_with_their_overlap_inside_the_window() {
        let (align, overlap) = (16, 96);
        for (w, h, side) in [(4096, 4096, 1024), (1000, 37, 256), (17, 33, 224), (1, 1, 224), (500, 700, 224), (1280, 720, 448)] {
            let tiles = plan(w, h, side, overlap, align);
            let mut kept = vec![0u8; (w * h) as usize];
            for t in &tiles {
                let (win, inn) = (t.window, t.inner);
                assert!(win.x % align == 0 && win.y % align == 0, "{w}×{h}: window {win:?} is aligned");
                assert!(win.width <= side && win.height <= side && win.x + win.width <= w && win.y + win.height <= h, "{win:?}");
                for (ws, wl, is, il, len) in [(win.x, win.width, inn.x, inn.width, w), (win.y, win.height, inn.y, inn.height, h)] {
                    assert!(ws == 0 || ws + overlap <= is, "{w}×{h}: {t:?} lacks the overlap before its inner pixels");
                    let end = ws + wl;
                    assert!(end == len || is + il + overlap <= end, "{w}×{h}: {t:?} lacks the overlap after");
                }
                for y in inn.y..inn.y + inn.height {
                    for x in inn.x..inn.x + inn.width {
                        kept[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(kept.iter().all(|&k| k == 1), "{w}×{h}: every pixel kept once");
            if w.next_multiple_of(align) <= side && h.next_multiple_of(align) <= side {
                assert_eq!(tiles.len(), 1);
            }
        }
        assert_eq!(plan(4096, 4096, 1024, overlap, align).len(), 25, "(1024 - 192)-pixel strides");
    }

    #[test]
    fn the_window_is_the_largest_whose_tensors_fit_the_limits() {
        let net = network(&small_unet(9), 1);
        let side = window_side(&net, 4, 128 << 20, 1 << 30).expect("a window fits");
        assert_eq!(side % 16, 0);
        let fits = |s| {
            let (all, largest) = window_bytes(&net, s, 4);
            largest <= 128 << 20 && all <= 1 << 30
        };
        assert!(fits(side) && !fits(side + 16), "{side} fits and {} does not", side + 16);
        assert_eq!(window_side(&net, 4, 1 << 10, 1 << 30), None, "nothing fits a kilobyte");
    }
}
