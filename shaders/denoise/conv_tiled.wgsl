// The workgroup-tiled convolution kernel, in the manner of an implicit
// GEMM (`lib/conv.wgsl` says what it computes and how the tensors and
// weights are laid out). A workgroup makes a TILE_W × TILE_H tile of
// output pixels for BLOCKS output blocks. Per chunk of CHUNK input blocks
// it copies the tile's input patch (with the 1-pixel halo, upsampled and
// concatenated when fused, zero outside the image) and the chunk's weights
// into workgroup memory, then each invocation adds PIXELS pixels × BLOCKS
// blocks from there: every input value and weight is read from the storage
// buffers once per workgroup, instead of once per invocation that uses it.
//
// Loop iterations per invocation, counted as if nothing were unrolled
// (llvmpipe ends an invocation's loops after 65,535 in all): per chunk 1 +
// 6 (patch) + 2 (weights) + 200 (sums: 2 blocks, 18 taps, 36 pixels, 144
// products) = 209; the widest layer (dec_conv1a with OIDN's weights, 19
// input blocks) has 10 chunks: about 2,110 with the bias and the stores.

#import loupe::tensor::load
#import loupe::conv::{layer, a, weights, bias, BLOCKS, weight_stride, store_block, count_overflows}
#ifdef CONCAT
#import loupe::conv::b
#endif

const GROUP_W: u32 = 8u;
const GROUP_H: u32 = 8u;
const INVOCATIONS: u32 = GROUP_W * GROUP_H;
// Output pixels per invocation, GROUP_W apart along x.
const PIXELS: u32 = 2u;
// The workgroup's output tile (`render::passes::denoise::kernels::TILED`).
const TILE_W: u32 = GROUP_W * PIXELS;
const TILE_H: u32 = GROUP_H;
// Its input patch: the tile and a 1-pixel halo on every side.
const PATCH_W: u32 = TILE_W + 2u;
const PATCH_H: u32 = TILE_H + 2u;
// Input blocks per chunk: the patch and the weights take 10 KiB of
// workgroup memory, within WebGPU's 16 KiB.
const CHUNK: u32 = 2u;

// [patch pixel][input block of the chunk].
var<workgroup> inputs: array<vec4<f32>, PATCH_W * PATCH_H * CHUNK>;
// [tap][input block of the chunk][output block].
var<workgroup> taps: array<mat4x4<f32>, 9u * CHUNK * BLOCKS>;

// Input block `block` at output pixel `(x, y)` of the (upsampled,
// concatenated) input; zero outside the image and past the last block.
fn input_at(x: i32, y: i32, block: u32) -> vec4<f32> {
    if x < 0 || y < 0 || x >= i32(layer.width) || y >= i32(layer.height) {
        return vec4(0.0);
    }
    if block < layer.a_blocks {
#ifdef UPSAMPLE
        let a_pixel = u32(y / 2) * layer.a_width + u32(x / 2);
#else
        let a_pixel = u32(y) * layer.a_width + u32(x);
#endif
        return load(a[a_pixel * layer.a_blocks + block].v);
    }
#ifdef CONCAT
    let bb = block - layer.a_blocks;
    if bb < layer.b_blocks {
        return load(b[(u32(y) * layer.width + u32(x)) * layer.b_blocks + bb].v);
    }
#endif
    return vec4(0.0);
}

@compute @workgroup_size(GROUP_W, GROUP_H, 1)
fn conv(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    let x0 = group.x * TILE_W;
    let y0 = group.y * TILE_H;
    let first = group.z * BLOCKS;
    let in_blocks = layer.a_blocks + layer.b_blocks;
    let stride = weight_stride();
    // acc[p * BLOCKS + k]: pixel p, output block first + k.
    var acc: array<vec4<f32>, PIXELS * BLOCKS>;
    for (var p = 0u; p < PIXELS; p++) {
        for (var k = 0u; k < BLOCKS; k++) {
            acc[p * BLOCKS + k] = bias[first + k];
        }
    }
    // Every invocation runs every chunk, those past the image's edge too:
    // they load part of the patch, and barriers need the whole workgroup.
    for (var c0 = 0u; c0 < in_blocks; c0 += CHUNK) {
        for (var i = index; i < PATCH_W * PATCH_H * CHUNK; i += INVOCATIONS) {
            let pixel = i / CHUNK;
            let px = i32(x0 + pixel % PATCH_W) - 1;
            let py = i32(y0 + pixel / PATCH_W) - 1;
            inputs[i] = input_at(px, py, c0 + i % CHUNK);
        }
        for (var i = index; i < 9u * CHUNK * BLOCKS; i += INVOCATIONS) {
            let k = i % BLOCKS;
            let block = c0 + i / BLOCKS % CHUNK;
            let tap = i / (BLOCKS * CHUNK);
            // Past the last input block these are the next tap's weights
            // (or, after the last tap, whatever WGSL reads past the end):
            // the patch there is zero, so they add nothing.
            taps[i] = weights[(tap * in_blocks + block) * stride + first + k];
        }
        workgroupBarrier();
        for (var ci = 0u; ci < CHUNK; ci++) {
            for (var tap = 0u; tap < 9u; tap++) {
                let row = (local.y + tap / 3u) * PATCH_W + local.x + tap % 3u;
                for (var p = 0u; p < PIXELS; p++) {
                    let v = inputs[(row + p * GROUP_W) * CHUNK + ci];
                    for (var k = 0u; k < BLOCKS; k++) {
                        acc[p * BLOCKS + k] += taps[(tap * CHUNK + ci) * BLOCKS + k] * v;
                    }
                }
            }
        }
        // The next chunk overwrites what this one read.
        workgroupBarrier();
    }
    let y = y0 + local.y;
    let count = min(BLOCKS, layer.out_blocks - first);
    var over = 0u;
    for (var p = 0u; p < PIXELS; p++) {
        let x = x0 + local.x + p * GROUP_W;
        if x < layer.width && y < layer.height {
            for (var k = 0u; k < count; k++) {
                over += store_block(y * layer.width + x, first + k, acc[p * BLOCKS + k]);
            }
        }
    }
    count_overflows(over);
}
