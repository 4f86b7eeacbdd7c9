// 2×2 max-pool of a channels-last tensor (vec4 blocks of channels, stored
// as `lib/tensor.wgsl` says). An odd edge pools the pixels it has.

#import loupe::tensor::{load, store}

#ifdef F16
alias Stored = vec2<u32>;
#else
alias Stored = vec4<f32>;
#endif

struct Pool {
    // Input size; the output is half of it, rounded up.
    width: u32,
    height: u32,
    blocks: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> pool: Pool;
@group(0) @binding(1) var<storage, read> input: array<Stored>;
@group(0) @binding(2) var<storage, read_write> out: array<Stored>;

@compute @workgroup_size(8, 8, 1)
fn max_pool(@builtin(global_invocation_id) id: vec3<u32>) {
    let ow = (pool.width + 1u) / 2u;
    let oh = (pool.height + 1u) / 2u;
    if id.x >= ow || id.y >= oh || id.z >= pool.blocks {
        return;
    }
    let x0 = id.x * 2u;
    let y0 = id.y * 2u;
    let x1 = min(x0 + 1u, pool.width - 1u);
    let y1 = min(y0 + 1u, pool.height - 1u);
    let at = vec4(y0 * pool.width + x0, y0 * pool.width + x1, y1 * pool.width + x0, y1 * pool.width + x1) * pool.blocks + id.z;
    let v = max(max(load(input[at.x]), load(input[at.y])), max(load(input[at.z]), load(input[at.w])));
    out[(id.y * ow + id.x) * pool.blocks + id.z] = store(v);
}
