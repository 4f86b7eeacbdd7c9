// The direct convolution kernel (`lib/conv.wgsl` says what it computes and
// how the tensors and weights are laid out): one invocation per output
// pixel and BLOCKS output blocks, each reading its inputs and weights from
// the storage buffers itself.

#import loupe::tensor::load
#import loupe::conv::{layer, a, weights, bias, BLOCKS, weight_stride, store_block, count_overflows}
#ifdef CONCAT
#import loupe::conv::b
#endif

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
    // The loops over k have a constant count (the weights' output blocks
    // are padded): the compiler unrolls them and keeps `acc` in registers
    // (on llvmpipe twice as fast as looping to `count`).
    let stride = weight_stride();
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
            let v = load(a[a_pixel * layer.a_blocks + ci].v);
            let row = (tap * in_blocks + ci) * stride + first;
            for (var k = 0u; k < BLOCKS; k++) {
                acc[k] += weights[row + k] * v;
            }
        }
#ifdef CONCAT
        let b_pixel = u32(sy) * layer.width + u32(sx);
        for (var ci = 0u; ci < layer.b_blocks; ci++) {
            let v = load(b[b_pixel * layer.b_blocks + ci].v);
            let row = (tap * in_blocks + layer.a_blocks + ci) * stride + first;
            for (var k = 0u; k < BLOCKS; k++) {
                acc[k] += weights[row + k] * v;
            }
        }
#endif
    }
    let pixel = id.y * layer.width + id.x;
    var over = 0u;
    for (var k = 0u; k < count; k++) {
        over += store_block(pixel, first + k, acc[k]);
    }
    count_overflows(over);
}
