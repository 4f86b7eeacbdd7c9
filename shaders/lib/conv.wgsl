// What both of the denoiser's convolution kernels read and write
// (`denoise/conv.wgsl`, direct; `denoise/conv_tiled.wgsl`, workgroup-tiled):
// one 3×3 layer of the U-Net, "same" zero padding, bias, optional ReLU.
// Tensors are channels-last with channels padded to a multiple of 4, one
// vec4 per (pixel, block of 4 channels), stored as f32 or (F16) as halves
// (`lib/tensor.wgsl`); sums are f32. The input is `a`, optionally read 2×
// nearest-upsampled (UPSAMPLE), followed along channels by `b` when CONCAT:
// upsample + concat + conv fused in one pass, so the upsampled and
// concatenated tensors are never stored.
//
// Weights are laid out by the host as mat4x4 blocks,
// [tap (ky·3+kx)][input block][output block], column c holding input
// channel c's weights to the block's 4 outputs, so `w * x` adds a whole
// input block to an output block (`render::denoise_weights::pack_conv`).
// Their output blocks (and the bias's) are padded with zeros to a multiple
// of BLOCKS, so a kernel's loops over its output blocks have a constant
// count.
#define_import_path loupe::conv

#import loupe::tensor::{load, store}
#ifdef F16
#import loupe::tensor::overflows
#endif

struct Layer {
    // Output (and `b`) size in pixels.
    width: u32,
    height: u32,
    // `a`'s width: half the output's, rounded up, when UPSAMPLE.
    a_width: u32,
    a_height: u32,
    // Channel blocks (of 4) of a, b and the output.
    a_blocks: u32,
    b_blocks: u32,
    out_blocks: u32,
    relu: u32,
}

@group(0) @binding(0) var<uniform> layer: Layer;
// A tensor's element (`lib/tensor.wgsl`), wrapped: a composable module
// cannot declare the `Stored` alias entry points use.
struct Stored {
#ifdef F16
    v: vec2<u32>,
#else
    v: vec4<f32>,
#endif
}

@group(0) @binding(1) var<storage, read> a: array<Stored>;
#ifdef CONCAT
@group(1) @binding(0) var<storage, read> b: array<Stored>;
#endif
@group(0) @binding(3) var<storage, read> weights: array<mat4x4<f32>>;
@group(0) @binding(4) var<storage, read> bias: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> out: array<Stored>;
#ifdef F16
// Values of this layer too large for an f16, counted before the store.
@group(2) @binding(0) var<storage, read_write> overflow: atomic<u32>;
#endif

// Output blocks one invocation (direct) or workgroup (tiled) computes:
// `render::denoise_weights::CONV_BLOCKS`.
const BLOCKS: u32 = 4u;

// Output blocks as the weights are laid out: padded to a multiple of BLOCKS.
fn weight_stride() -> u32 {
    return (layer.out_blocks + BLOCKS - 1u) / BLOCKS * BLOCKS;
}

// Stores output block `block` of `pixel` from its sum; returns how many of
// its lanes overflow an f16 (always 0 without F16).
fn store_block(pixel: u32, block: u32, sum: vec4<f32>) -> u32 {
    var v = sum;
    if layer.relu != 0u {
        v = max(v, vec4(0.0));
    }
    out[pixel * layer.out_blocks + block] = Stored(store(v));
#ifdef F16
    return overflows(v);
#else
    return 0u;
#endif
}

// Adds an invocation's overflow count to the layer's: rare, so one atomic
// per invocation that overflowed and none otherwise.
fn count_overflows(over: u32) {
#ifdef F16
    if over > 0u {
        atomicAdd(&overflow, over);
    }
#endif
}
