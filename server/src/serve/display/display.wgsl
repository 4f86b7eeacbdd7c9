// loupe view's display pass: one output of the frame graph drawn for the
// Inspector (`show`), and the finite range of its values (`measure`).
// Not a project shader: it belongs to the viewer, like egui's own, so it
// is compiled into the binary; `pick` reads one texel of a depth output.
// `SOURCE`, `LOAD` and `VIRIDIS` are filled
// in by display/pass.rs (the source's texture type, how a texel of it
// reads as RGBA, and the false-colour map of client/presets.json).

struct Params {
    // 0 RGB, 1 R, 2 G, 3 B, 4 A, 5 luminance.
    channel: u32,
    flags: u32,
    // 2^exposure.
    scale: f32,
    lo: f32,
    hi: f32,
    near: f32,
    far: f32,
    // A depth target's clear value, left out of `measure` with SKIP_CLEAR.
    clear: f32,
    // The texel `pick` reads.
    texel: vec2<u32>,
}

const SRGB: u32 = 1u;
const FALSE_COLOUR: u32 = 2u;
const OVERLAY: u32 = 4u;
const LINEARIZE: u32 = 8u;
const REVERSED: u32 = 16u;
const SKIP_CLEAR: u32 = 32u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var source: SOURCE;
// measure: per channel (R, G, B, A, luminance), the least and the
// greatest finite value, as order-preserving bits.
@group(0) @binding(2) var<storage, read_write> range: array<atomic<u32>, 10>;

// pick: the texel at `params.texel`, as a shader reads it.
@group(0) @binding(3) var<storage, read_write> picked: vec4<f32>;

const VIRIDIS = VIRIDIS_TABLE;

fn load(p: vec2<i32>) -> vec4<f32> {
    return LOAD;
}

// NaN and the infinities by their bits: comparisons with NaN may be
// folded away by shader compilers.
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// 0 finite, 1 NaN, 2 +Inf, 3 -Inf.
fn class_of(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    if (b & 0x7f800000u) != 0x7f800000u {
        return 0u;
    }
    if (b & 0x007fffffu) != 0u {
        return 1u;
    }
    return select(2u, 3u, (b >> 31u) != 0u);
}

// The more alarming of two classes: NaN before the infinities.
fn worse(a: u32, b: u32) -> u32 {
    if a == 0u {
        return b;
    }
    if b == 0u {
        return a;
    }
    return min(a, b);
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Depth as view distance when asked for; other channels as they are.
fn linearized(v: vec4<f32>) -> vec4<f32> {
    if (params.flags & LINEARIZE) == 0u {
        return v;
    }
    let n = params.near;
    let f = params.far;
    var d = n * f / (f - v.x * (f - n));
    if (params.flags & REVERSED) != 0u {
        d = n * f / (n + v.x * (f - n));
    }
    return vec4<f32>(d, v.yzw);
}

fn srgb_encode(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn viridis(t: f32) -> vec3<f32> {
    var c = vec3<f32>(0.0);
    for (var p = 6i; p >= 0i; p--) {
        c = c * t + VIRIDIS[p];
    }
    return clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
}

// (x · scale − lo) / (hi − lo) in [0, 1]; NaN shows as 0.
fn unit(x: f32) -> f32 {
    if class_of(x) == 1u {
        return 0.0;
    }
    var span = params.hi - params.lo;
    if span == 0.0 {
        span = 1e-30;
    }
    return clamp((x * params.scale - params.lo) / span, 0.0, 1.0);
}

@vertex
fn fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn show(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let v = linearized(load(vec2<i32>(at.xy)));
    var shown = vec3<f32>(0.0);
    var kind = 0u;
    switch params.channel {
        case 0u: {
            shown = v.xyz;
            // Alpha is not shown, but a NaN in it is still a bug to see.
            kind = worse(worse(class_of(v.x), class_of(v.y)), worse(class_of(v.z), class_of(v.w)));
        }
        case 5u: {
            shown = vec3<f32>(luminance(v.xyz));
            kind = worse(worse(class_of(v.x), class_of(v.y)), class_of(v.z));
        }
        default: {
            let x = v[params.channel - 1u];
            shown = vec3<f32>(x);
            kind = class_of(x);
        }
    }
    if (params.flags & OVERLAY) != 0u && kind != 0u {
        let overlay = array<vec3<f32>, 3>(vec3<f32>(1.0, 0.0, 1.0), vec3<f32>(1.0, 1.0, 0.0), vec3<f32>(0.0, 1.0, 1.0));
        return vec4<f32>(overlay[kind - 1u], 1.0);
    }
    if (params.flags & FALSE_COLOUR) != 0u {
        let x = select(shown.x, luminance(shown), params.channel == 0u);
        return vec4<f32>(viridis(unit(x)), 1.0);
    }
    var t = vec3<f32>(unit(shown.x), unit(shown.y), unit(shown.z));
    if (params.flags & SRGB) != 0u {
        t = vec3<f32>(srgb_encode(t.x), srgb_encode(t.y), srgb_encode(t.z));
    }
    return vec4<f32>(t, 1.0);
}

// Bits that order as the floats they hold.
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

var<workgroup> least: array<atomic<u32>, 5>;
var<workgroup> greatest: array<atomic<u32>, 5>;

@compute @workgroup_size(8, 8)
fn measure(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane < 5u {
        atomicStore(&least[lane], 0xffffffffu);
        atomicStore(&greatest[lane], 0u);
    }
    workgroupBarrier();
    if all(id.xy < textureDimensions(source)) {
        let raw = load(vec2<i32>(id.xy));
        if (params.flags & SKIP_CLEAR) == 0u || raw.x != params.clear {
            let v = linearized(raw);
            var values = array<f32, 5>(v.x, v.y, v.z, v.w, luminance(v.xyz));
            for (var c = 0u; c < 5u; c++) {
                if is_finite(values[c]) {
                    atomicMin(&least[c], ordered(values[c]));
                    atomicMax(&greatest[c], ordered(values[c]));
                }
            }
        }
    }
    workgroupBarrier();
    if lane < 5u {
        atomicMin(&range[lane], atomicLoad(&least[lane]));
        atomicMax(&range[5u + lane], atomicLoad(&greatest[lane]));
    }
}

// One texel, for formats a copy cannot read one texel of (depth: a copy
// of it must take the whole texture).
@compute @workgroup_size(1)
fn pick() {
    picked = load(vec2<i32>(params.texel));
}
