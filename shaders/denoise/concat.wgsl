// The channels of `a`, then of `b`, per pixel (channels-last tensors of the
// same size, stored as `lib/tensor.wgsl` says): what the fused convolution
// reads on the fly, stored so that it can be inspected. Channels are
// contiguous — channel i of the result is the network's channel i — so the
// convolution after it takes `a + b` channels as one input.

#import loupe::tensor::{load, store}

#ifdef F16
alias Stored = vec2<u32>;
#else
alias Stored = vec4<f32>;
#endif

struct Concat {
    width: u32,
    height: u32,
    // Channels (not blocks) of a and b.
    a_channels: u32,
    b_channels: u32,
}

@group(0) @binding(0) var<uniform> concat: Concat;
@group(0) @binding(1) var<storage, read> a: array<Stored>;
@group(0) @binding(2) var<storage, read> b: array<Stored>;
@group(0) @binding(3) var<storage, read_write> out: array<Stored>;

// Channel `c` of `a` (of `b`) at `pixel`.
fn channel_a(pixel: u32, c: u32) -> f32 {
    let blocks = (concat.a_channels + 3u) / 4u;
    return load(a[pixel * blocks + c / 4u])[c % 4u];
}

fn channel_b(pixel: u32, c: u32) -> f32 {
    let blocks = (concat.b_channels + 3u) / 4u;
    return load(b[pixel * blocks + c / 4u])[c % 4u];
}

@compute @workgroup_size(8, 8, 1)
fn concat_channels(@builtin(global_invocation_id) id: vec3<u32>) {
    let total = concat.a_channels + concat.b_channels;
    let blocks = (total + 3u) / 4u;
    if id.x >= concat.width || id.y >= concat.height || id.z >= blocks {
        return;
    }
    let pixel = id.y * concat.width + id.x;
    var v = vec4(0.0);
    for (var lane = 0u; lane < 4u; lane++) {
        let c = id.z * 4u + lane;
        if c < concat.a_channels {
            v[lane] = channel_a(pixel, c);
        } else if c < total {
            v[lane] = channel_b(pixel, c - concat.a_channels);
        }
    }
    out[pixel * blocks + id.z] = store(v);
}
