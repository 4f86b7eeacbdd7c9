// The NaN watch: counts the texels of the HDR frame holding a NaN or an
// Inf in any channel, so `loupe serve` notices a bad value the 8-bit final
// image would hide (a unorm target stores NaN as 0). Two counters:
// [0] texels with a NaN, [1] texels with an Inf and no NaN.

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>, 2>;

var<workgroup> local_counts: array<atomic<u32>, 2>;

// Checked on the bits: WGSL lets implementations assume floats are finite.
fn is_nan(x: f32) -> bool {
    let b = bitcast<u32>(x);
    return (b & 0x7f800000u) == 0x7f800000u && (b & 0x007fffffu) != 0u;
}

fn is_inf(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) == 0x7f800000u;
}

@compute @workgroup_size(16, 16, 1)
fn count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    if index < 2u {
        atomicStore(&local_counts[index], 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(hdr);
    if id.x < size.x && id.y < size.y {
        let v = textureLoad(hdr, vec2<i32>(id.xy), 0);
        if is_nan(v.r) || is_nan(v.g) || is_nan(v.b) || is_nan(v.a) {
            atomicAdd(&local_counts[0], 1u);
        } else if is_inf(v.r) || is_inf(v.g) || is_inf(v.b) || is_inf(v.a) {
            atomicAdd(&local_counts[1], 1u);
        }
    }
    workgroupBarrier();
    if index < 2u {
        let n = atomicLoad(&local_counts[index]);
        if n > 0u {
            atomicAdd(&counts[index], n);
        }
    }
}
