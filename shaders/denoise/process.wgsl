// OIDN's processing around the network, for its `RT` filter, mirroring the
// CPU reference `denoise::process` function by function (its constants are
// OIDN's, `core/color.h`): `input` is `process::input` (the network's
// input tensor from the path tracer's colour, albedo and normal) and
// `output` is `process::output` (the denoised colour from the network's
// output). The transfer function is the mode's: HDR the PU curve, LDR_SRGB
// none (the colour is sRGB-encoded already), otherwise sRGB. The input
// scale is what `autoexposure.wgsl` measured (AUTOEXPOSURE) or the one
// the uniforms carry (given, or 1).

#import loupe::tensor::{load, store}
#import loupe::sanitize::{F32_MAX, sanitize, sanitize3}

#ifdef F16
alias Stored = vec2<u32>;
#else
alias Stored = vec4<f32>;
#endif

struct Input {
    // The image's size and the padded tensor's.
    width: u32,
    height: u32,
    padded_width: u32,
    padded_height: u32,
    // Channel blocks of the tensor: 1 (colour), 2 (+ albedo), 3 (+ normal).
    blocks: u32,
    // The input scale unless AUTOEXPOSURE.
    scale: f32,
    _pad1: u32,
    _pad2: u32,
}

struct Output {
    width: u32,
    height: u32,
    padded_width: u32,
    scale: f32,
}

@group(0) @binding(0) var<uniform> input_params: Input;
@group(0) @binding(1) var color: texture_2d<f32>;
@group(0) @binding(2) var albedo: texture_2d<f32>;
@group(0) @binding(3) var normal: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> tensor: array<Stored>;

@group(0) @binding(5) var<uniform> output_params: Output;
@group(0) @binding(6) var<storage, read> network_output: array<Stored>;
@group(0) @binding(7) var denoised: texture_storage_2d<rgba32float, write>;

#ifdef AUTOEXPOSURE
// The input scale (`autoexposure.wgsl`).
@group(1) @binding(0) var<storage, read> scale: array<f32>;
#endif

// `Transfer::Srgb` (`process::srgb`).
const SRGB_A: f32 = 12.92;
const SRGB_B: f32 = 1.055;
const SRGB_C: f32 = 1.0 / 2.4;
const SRGB_D: f32 = -0.055;
const SRGB_Y0: f32 = 0.0031308;
const SRGB_X0: f32 = 0.04045;

fn srgb_forward(y: f32) -> f32 {
    if y <= SRGB_Y0 {
        return SRGB_A * y;
    }
    return SRGB_B * pow(y, SRGB_C) + SRGB_D;
}

fn srgb_inverse(x: f32) -> f32 {
    if x <= SRGB_X0 {
        return x / SRGB_A;
    }
    return pow((x - SRGB_D) / SRGB_B, 1.0 / SRGB_C);
}

// `Transfer::Pu` (`process::pu`): the PU curve's fit, normalised so that
// 65504 (`Y_MAX`, the largest f16) maps to 1.
const PU_A: f32 = 1.41283765e+03;
const PU_B: f32 = 1.64593172e+00;
const PU_C: f32 = 4.31384981e-01;
const PU_D: f32 = -2.94139609e-03;
const PU_E: f32 = 1.92653254e-01;
const PU_F: f32 = 6.26026094e-03;
const PU_G: f32 = 9.98620152e-01;
const PU_Y0: f32 = 1.57945760e-06;
const PU_Y1: f32 = 3.22087631e-02;
const PU_X0: f32 = 2.23151711e-03;
const PU_X1: f32 = 3.70974749e-01;
const Y_MAX: f32 = 65504.0;

fn pu_forward(y: f32) -> f32 {
    if y <= PU_Y0 {
        return PU_A * y;
    }
    if y <= PU_Y1 {
        return PU_B * pow(y, PU_C) + PU_D;
    }
    return PU_E * log(y + PU_F) + PU_G;
}

fn pu_inverse(x: f32) -> f32 {
    if x <= PU_X0 {
        return x / PU_A;
    }
    if x <= PU_X1 {
        return pow((x - PU_D) / PU_B, 1.0 / PU_C);
    }
    return exp((x - PU_G) / PU_E) - PU_F;
}

// `Transfer::forward` and `Transfer::inverse` of the mode's transfer.
fn forward(y: f32) -> f32 {
#ifdef HDR
    return pu_forward(y) * (1.0 / pu_forward(Y_MAX));
#else ifdef LDR_SRGB
    return y;
#else
    return srgb_forward(y);
#endif
}

fn inverse(x: f32) -> f32 {
#ifdef HDR
    return pu_inverse(x * pu_forward(Y_MAX));
#else ifdef LDR_SRGB
    return x;
#else
    return srgb_inverse(x);
#endif
}

// What multiplies the colour before the network (`process::input_scale`).
fn input_scale(given: f32) -> f32 {
#ifdef AUTOEXPOSURE
    return scale[0];
#else
    return given;
#endif
}

// `process::input`: colour (scaled, sanitised, through the transfer
// function), then albedo (clamped to [0, 1]) and normal (clamped to
// [-1, 1], mapped to [0, 1]) as the network takes them, zero beyond the
// image (the padding at the right and bottom). One invocation per padded
// pixel.
@compute @workgroup_size(8, 8, 1)
fn input(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = input_params;
    if id.x >= p.padded_width || id.y >= p.padded_height {
        return;
    }
    var v = array<vec4<f32>, 3>(vec4(0.0), vec4(0.0), vec4(0.0));
    if id.x < p.width && id.y < p.height {
#ifdef HDR
        let hi = F32_MAX;
#else
        let hi = 1.0;
#endif
        let s = input_scale(p.scale);
        let c0 = sanitize3(textureLoad(color, id.xy, 0).rgb * s, 0.0, hi);
        let c = vec3(forward(c0.r), forward(c0.g), forward(c0.b));
        let a = sanitize3(textureLoad(albedo, id.xy, 0).rgb, 0.0, 1.0);
        let n = sanitize3(textureLoad(normal, id.xy, 0).rgb, -1.0, 1.0) * 0.5 + 0.5;
        v[0] = vec4(c, a.r);
        v[1] = vec4(a.gb, n.xy);
        v[2] = vec4(n.z, 0.0, 0.0, 0.0);
        // Colour alone: the fourth channel is padding.
        if p.blocks == 1u {
            v[0].w = 0.0;
        }
        // Colour and albedo: the normal's lanes are padding.
        if p.blocks == 2u {
            v[1] = vec4(a.gb, 0.0, 0.0);
        }
    }
    let pixel = id.y * p.padded_width + id.x;
    for (var k = 0u; k < p.blocks; k++) {
        tensor[pixel * p.blocks + k] = store(v[k]);
    }
}

// `process::output`: the top-left width × height of the network's output
// (3 channels: one block), NaN and negatives to 0, through the inverse
// transfer, clamped to 1 unless HDR, divided by the input scale (0 for a
// scale of 0).
@compute @workgroup_size(8, 8, 1)
fn output(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = output_params;
    if id.x >= p.width || id.y >= p.height {
        return;
    }
    let o = load(network_output[id.y * p.padded_width + id.x]).rgb;
    var v = vec3(inverse(sanitize(o.r, 0.0, F32_MAX)), inverse(sanitize(o.g, 0.0, F32_MAX)), inverse(sanitize(o.b, 0.0, F32_MAX)));
#ifndef HDR
    v = min(v, vec3(1.0));
#endif
    let s = input_scale(p.scale);
    let out_scale = select(0.0, 1.0 / s, s != 0.0);
    textureStore(denoised, id.xy, vec4(v * out_scale, 1.0));
}
