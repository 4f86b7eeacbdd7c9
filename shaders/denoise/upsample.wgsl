// 2× nearest-neighbour upsample of a channels-last tensor (vec4 blocks of
// channels, stored as `lib/tensor.wgsl` says): what the fused convolution
// reads on the fly, stored so that it can be inspected.

#ifdef F16
alias Stored = vec2<u32>;
#else
alias Stored = vec4<f32>;
#endif

struct Upsample {
    // Output size; the input is half of it.
    width: u32,
    height: u32,
    blocks: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> upsample: Upsample;
@group(0) @binding(1) var<storage, read> input: array<Stored>;
@group(0) @binding(2) var<storage, read_write> out: array<Stored>;

@compute @workgroup_size(8, 8, 1)
fn upsample_nearest(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= upsample.width || id.y >= upsample.height || id.z >= upsample.blocks {
        return;
    }
    let source = (id.y / 2u) * (upsample.width / 2u) + id.x / 2u;
    out[(id.y * upsample.width + id.x) * upsample.blocks + id.z] = input[source * upsample.blocks + id.z];
}
