// OIDN's autoexposure (`process::autoexposure` in the CPU reference, OIDN's
// `cpu_autoexposure`): the input scale of HDR denoising, which maps the
// colour's geometric-mean luminance to 0.18. Two entry points, one
// workgroup per bin and then one for the whole image.

#import loupe::sanitize::{F32_MAX, sanitize, sanitize3}

@group(0) @binding(0) var color: texture_2d<f32>;
// Each bin's mean luminance, row by row.
@group(0) @binding(1) var<storage, read_write> bins: array<f32>;
// The scale: one value.
@group(0) @binding(2) var<storage, read_write> scale: array<f32>;

// `process::autoexposure`, first half: the colour cut into bins of at most
// 16×16 pixels (one workgroup each), a bin's mean luminance.
const MAX_BIN: u32 = 16u;
var<workgroup> partial: array<f32, 256>;

@compute @workgroup_size(16, 16, 1)
fn autoexposure_bins(@builtin(workgroup_id) bin: vec3<u32>, @builtin(local_invocation_index) lane: u32, @builtin(local_invocation_id) local: vec3<u32>) {
    let size = textureDimensions(color);
    let grid = (size + vec2(MAX_BIN - 1u)) / MAX_BIN;
    let lo = bin.xy * size / grid;
    let hi = (bin.xy + 1u) * size / grid;
    let p = lo + local.xy;
    var l = 0.0;
    if all(p < hi) {
        let c = sanitize3(textureLoad(color, p, 0).rgb, 0.0, F32_MAX);
        l = 0.212671 * c.r + 0.715160 * c.g + 0.072169 * c.b;
    }
    partial[lane] = l;
    for (var stride = 128u; stride > 0u; stride /= 2u) {
        workgroupBarrier();
        if lane < stride {
            partial[lane] += partial[lane + stride];
        }
    }
    if lane == 0u {
        let count = (hi - lo).x * (hi - lo).y;
        bins[bin.y * grid.x + bin.x] = partial[0] / f32(count);
    }
}

// `process::autoexposure`, second half, in one workgroup: 0.18 over the
// geometric mean of the bins' luminances above 1e-8 (1 when none is).
var<workgroup> partial_count: array<u32, 256>;

@compute @workgroup_size(256, 1, 1)
fn autoexposure_scale(@builtin(local_invocation_index) lane: u32) {
    let size = textureDimensions(color);
    let grid = (size + vec2(MAX_BIN - 1u)) / MAX_BIN;
    let n = grid.x * grid.y;
    var sum = 0.0;
    var count = 0u;
    for (var i = lane; i < n; i += 256u) {
        let l = bins[i];
        if l > 1e-8 {
            sum += log2(l);
            count += 1u;
        }
    }
    partial[lane] = sum;
    partial_count[lane] = count;
    for (var stride = 128u; stride > 0u; stride /= 2u) {
        workgroupBarrier();
        if lane < stride {
            partial[lane] += partial[lane + stride];
            partial_count[lane] += partial_count[lane + stride];
        }
    }
    if lane == 0u {
        let total = partial_count[0];
        scale[0] = select(1.0, 0.18 / exp2(partial[0] / f32(total)), total > 0u);
    }
}
