// One 3×3 convolution layer of the denoiser's U-Net, "same" zero padding,
// bias, optional ReLU. Tensors are channels-last with channels padded to a
// multiple of 4, one vec4 per (pixel, block of 4 channels), stored as f32
// or (F16) as halves (`lib/tensor.wgsl`); sums are f32. The input is
// `a`, optionally read 2× nearest-upsampled (UPSAMPLE), followed along
// channels by `b` when CONCAT: upsample + concat + conv fused in one pass,
// so the upsampled and concatenated tensors are never stored.
//
// Weights are laid out by the host as mat4x4 blocks,
// [tap (ky·3+kx)][input block][output block], column c holding input
// channel c's weights to the block's 4 outputs, so `w * x` adds a whole
// input block to an output block (`render::denoise_weights::pack_conv`).

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

#import loupe::tensor::{load, store}
#ifdef F16
#import loupe::tensor::overflows
#endif

#ifdef F16
alias Stored = vec2<u32>;
#else
alias Stored = vec4<f32>;
#endif

@group(0) @binding(0) var<uniform> layer: Layer;
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

// Output blocks per invocation: each input vec4 read serves this many.
const BLOCKS: u32 = 4u;

@compute @workgroup_size(8, 8, 1)
fn conv(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = i32(id.x);
    let y = i32(id.y);
    let first = id.z * BLOCKS;
    if id.x >= layer.width || id.y >= layer.height || first >= layer.out_blocks {
        return;
    }
    let count = min(BLOCKS, layer.out_blocks - first);
    let in_blocks = layer.a_blocks + layer.b_blocks;
    // The weights' and bias's output blocks are padded to a multiple of
    // BLOCKS (with zeros), so the loops over k have a constant count: the
    // compiler unrolls them and keeps `acc` in registers (on llvmpipe twice
    // as fast as looping to `count`).
    let stride = (layer.out_blocks + BLOCKS - 1u) / BLOCKS * BLOCKS;
    var acc: array<vec4<f32>, BLOCKS>;
    for (var k = 0u; k < BLOCKS; k++) {
        acc[k] = bias[first + k];
    }
    for (var tap = 0u; tap < 9u; tap++) {
        let sx = x + i32(tap % 3u) - 1;
        let sy = y + i32(tap / 3u) - 1;
        if sx < 0 || sy < 0 || sx >= i32(layer.width) || sy >= i32(layer.height) {
            continue;
        }
#ifdef UPSAMPLE
        let a_pixel = u32(sy / 2) * layer.a_width + u32(sx / 2);
#else
        let a_pixel = u32(sy) * layer.a_width + u32(sx);
#endif
        for (var ci = 0u; ci < layer.a_blocks; ci++) {
            let v = load(a[a_pixel * layer.a_blocks + ci]);
            let row = (tap * in_blocks + ci) * stride + first;
            for (var k = 0u; k < BLOCKS; k++) {
                acc[k] += weights[row + k] * v;
            }
        }
#ifdef CONCAT
        let b_pixel = u32(sy) * layer.width + u32(sx);
        for (var ci = 0u; ci < layer.b_blocks; ci++) {
            let v = load(b[b_pixel * layer.b_blocks + ci]);
            let row = (tap * in_blocks + layer.a_blocks + ci) * stride + first;
            for (var k = 0u; k < BLOCKS; k++) {
                acc[k] += weights[row + k] * v;
            }
        }
#endif
    }
    let pixel = id.y * layer.width + id.x;
#ifdef F16
    var over = 0u;
#endif
    for (var k = 0u; k < count; k++) {
        var v = acc[k];
        if layer.relu != 0u {
            v = max(v, vec4(0.0));
        }
#ifdef F16
        over += overflows(v);
#endif
        out[pixel * layer.out_blocks + first + k] = store(v);
    }
#ifdef F16
    // Rare: one atomic per invocation that overflowed, none otherwise.
    if over > 0u {
        atomicAdd(&overflow, over);
    }
#endif
}
