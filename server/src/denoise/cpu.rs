//! The CPU reference: the network's ops in plain f32 Rust, rows in
//! parallel. Written to be read and trusted, not to be fast: the GPU
//! backend is tested against it.
//!
//! Tensors are channels-last (`data[(y * width + x) * channels + c]`), the
//! layout the GPU uses, so a dumped tensor compares element for element.

use rayon::prelude::*;

use super::Precision;
use super::network::{Conv, Network, Op};

/// An image of `channels` values per pixel, channels-last, rows top first.
#[derive(Debug, Clone, PartialEq)]
pub struct Tensor {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub data: Vec<f32>,
}

impl Tensor {
    pub fn zeros(width: usize, height: usize, channels: usize) -> Tensor {
        Tensor { width, height, channels, data: vec![0.0; width * height * channels] }
    }

    /// The values of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> &[f32] {
        let at = (y * self.width + x) * self.channels;
        &self.data[at..at + self.channels]
    }

    /// Rounds every value to the nearest f16, as a store to f16 memory does
    /// (beyond ±65504 that is ±inf).
    fn store(mut self, precision: Precision) -> Tensor {
        if precision == Precision::F16 {
            self.data.par_iter_mut().for_each(|v| *v = half::f16::from_f32(*v).to_f32());
        }
        self
    }
}

/// Runs the network on `input` (already pre-processed and padded: its sides
/// a multiple of `net.alignment()`, `net`'s input channels) and returns
/// its output tensor.
pub fn run(net: &Network, input: Tensor, precision: Precision) -> Tensor {
    let mut tensors = walk(net, input, precision, false);
    tensors[net.output.0].take().expect("the output is kept")
}

/// Runs the network and returns every tensor, indexed as `net.tensors`.
pub fn run_all(net: &Network, input: Tensor, precision: Precision) -> Vec<Tensor> {
    walk(net, input, precision, true).into_iter().map(|t| t.expect("every tensor is kept")).collect()
}

fn walk(net: &Network, input: Tensor, precision: Precision, keep: bool) -> Vec<Option<Tensor>> {
    let align = net.alignment();
    assert!(
        input.width.is_multiple_of(align) && input.height.is_multiple_of(align) && input.channels == net.tensor(net.input).channels,
        "the input must be padded to a multiple of {align} and have the network's channels"
    );
    let mut tensors: Vec<Option<Tensor>> = vec![None; net.tensors.len()];
    tensors[net.input.0] = Some(input.store(precision));
    for (i, op) in net.ops.iter().enumerate() {
        let get = |id: super::network::TensorId| tensors[id.0].as_ref().expect("ops read tensors made before them");
        let out = match op {
            Op::Conv(c) => conv(c, get(c.src)),
            Op::Pool { src, .. } => pool(get(*src)),
            Op::Upsample { src, .. } => upsample(get(*src)),
            Op::Concat { first, second, .. } => concat(get(*first), get(*second)),
        };
        tensors[op.dst().0] = Some(out.store(precision));
        if !keep {
            for src in op.srcs() {
                if net.tensor(src).last_use == i {
                    tensors[src.0] = None;
                }
            }
        }
    }
    tensors
}

/// 3×3 convolution, zero padding 1, plus bias, then ReLU when the layer has one.
fn conv(c: &Conv, src: &Tensor) -> Tensor {
    let (w, h, ci, co) = (src.width, src.height, c.in_channels, c.out_channels);
    // OIHW → [tap][in][out], so that one input value meets its row of
    // output weights contiguously (the inner loop vectorises).
    let mut taps = vec![0.0f32; 9 * ci * co];
    for o in 0..co {
        for i in 0..ci {
            for k in 0..9 {
                taps[(k * ci + i) * co + o] = c.weight[(o * ci + i) * 9 + k];
            }
        }
    }
    let mut out = Tensor::zeros(w, h, co);
    out.data.par_chunks_mut(w * co).enumerate().for_each(|(y, row)| {
        for (x, acc) in row.chunks_exact_mut(co).enumerate() {
            acc.copy_from_slice(&c.bias);
            for ky in 0..3 {
                let Some(sy) = (y + ky).checked_sub(1).filter(|&sy| sy < h) else { continue };
                for kx in 0..3 {
                    let Some(sx) = (x + kx).checked_sub(1).filter(|&sx| sx < w) else { continue };
                    let tap = &taps[(ky * 3 + kx) * ci * co..][..ci * co];
                    for (&v, weights) in src.pixel(sx, sy).iter().zip(tap.chunks_exact(co)) {
                        for (a, &wt) in acc.iter_mut().zip(weights) {
                            *a += v * wt;
                        }
                    }
                }
            }
            if c.relu {
                acc.iter_mut().for_each(|a| *a = a.max(0.0));
            }
        }
    });
    out
}

/// 2×2 max-pool, stride 2.
fn pool(src: &Tensor) -> Tensor {
    let (w, h, c) = (src.width / 2, src.height / 2, src.channels);
    let mut out = Tensor::zeros(w, h, c);
    out.data.par_chunks_mut(w * c).enumerate().for_each(|(y, row)| {
        for (x, px) in row.chunks_exact_mut(c).enumerate() {
            let quad = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| src.pixel(2 * x + dx, 2 * y + dy));
            for (k, v) in px.iter_mut().enumerate() {
                *v = quad.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max);
            }
        }
    });
    out
}

/// 2× nearest-neighbour upsample.
fn upsample(src: &Tensor) -> Tensor {
    let (w, h, c) = (src.width * 2, src.height * 2, src.channels);
    let mut out = Tensor::zeros(w, h, c);
    out.data.par_chunks_mut(w * c).enumerate().for_each(|(y, row)| {
        for (x, px) in row.chunks_exact_mut(c).enumerate() {
            px.copy_from_slice(src.pixel(x / 2, y / 2));
        }
    });
    out
}

/// The channels of `a`, then of `b`, per pixel.
fn concat(a: &Tensor, b: &Tensor) -> Tensor {
    let (w, h, c) = (a.width, a.height, a.channels + b.channels);
    let mut out = Tensor::zeros(w, h, c);
    out.data.par_chunks_mut(w * c).enumerate().for_each(|(y, row)| {
        for (x, px) in row.chunks_exact_mut(c).enumerate() {
            px[..a.channels].copy_from_slice(a.pixel(x, y));
            px[a.channels..].copy_from_slice(b.pixel(x, y));
        }
    });
    out
}

#[cfg(test)]
mod tests;
