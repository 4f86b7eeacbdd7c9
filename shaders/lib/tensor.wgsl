// How the denoiser's tensors are stored: channels-last, one element per
// (pixel, block of 4 channels). Without F16 an element is a vec4<f32>; with
// F16 it is four halves in a vec2<u32>, the bytes of a vec4<f16>, packed
// with pack2x16float. That builtin is core WGSL, so f16 storage needs no
// shader-f16 feature (and `loupe check` passes on adapters without one);
// arithmetic stays f32. An entry point declares its tensors as
// `array<Stored>` with the alias for its permutation:
//
//     #ifdef F16
//     alias Stored = vec2<u32>;
//     #else
//     alias Stored = vec4<f32>;
//     #endif
#define_import_path loupe::tensor

#ifdef F16
// The largest finite f16: a value beyond it overflows when stored.
const F16_MAX: f32 = 65504.0;

fn load(s: vec2<u32>) -> vec4<f32> {
    return vec4(unpack2x16float(s.x), unpack2x16float(s.y));
}

// One f32 as the bits of the f16 a rounding conversion gives (what
// `half::f16::from_f32`, and so the CPU reference, stores): NaN stays NaN,
// and from 65520 on (half-way past the largest f16) the value is ±inf.
// pack2x16float alone is indeterminate outside f16's finite range.
fn half_bits(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    let magnitude = bits & 0x7fffffffu;
    let sign = (bits >> 16u) & 0x8000u;
    if magnitude > 0x7f800000u {
        return sign | 0x7e00u;
    }
    if magnitude >= 0x477ff000u {
        return sign | 0x7c00u;
    }
    return pack2x16float(vec2(x, 0.0)) & 0xffffu;
}

fn store(v: vec4<f32>) -> vec2<u32> {
    return vec2(half_bits(v.x) | (half_bits(v.y) << 16u), half_bits(v.z) | (half_bits(v.w) << 16u));
}

// Lanes of `v` that do not fit in an f16 (|x| > 65504 before the store).
fn overflows(v: vec4<f32>) -> u32 {
    let over = select(vec4(0u), vec4(1u), abs(v) > vec4(F16_MAX));
    return over.x + over.y + over.z + over.w;
}
#else
fn load(s: vec4<f32>) -> vec4<f32> {
    return s;
}

fn store(v: vec4<f32>) -> vec4<f32> {
    return v;
}
#endif
