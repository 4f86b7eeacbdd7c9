// Quantisers for the material buffer (the adaptive G-buffer's words,
// `server/src/material/pack.rs` and docs/materials.md "Storage classes"):
// unsigned normalised fields of any width, octahedral unit vectors, the
// shared-exponent rgb9e5 for values above 1 (weights under `add`,
// emission), sqrt-encoded colours, and the per-pixel dither for 8-bit
// colours. Every encoder clamps to its range, so no input turns into a
// NaN or Inf on the way back; the bounds each round trip keeps are tested
// in `material::pack::tests`.
#define_import_path loupe::pack

// The largest value rgb9e5 holds: 511 × 2^(31 − 15 − 9).
const RGB9E5_MAX: f32 = 65408.0;

// x in [0, 1] to `bits` bits, rounded to nearest; `dither` in [-0.5, 0.5)
// moves the rounding point (0: none).
fn unorm_encode(x: f32, bits: u32, dither: f32) -> u32 {
    let top = f32((1u << bits) - 1u);
    // max(…, 0) first: it also turns a NaN into 0.
    return u32(clamp(floor(max(x, 0.0) * top + 0.5 + dither), 0.0, top));
}

fn unorm_decode(word: u32, shift: u32, bits: u32) -> f32 {
    let top = (1u << bits) - 1u;
    return f32((word >> shift) & top) / f32(top);
}

// A colour in [0, 1]³ as three `bits`-bit fields from bit 0.
fn pack_unorm3(c: vec3<f32>, bits: u32, dither: f32) -> u32 {
    return unorm_encode(c.r, bits, dither) | (unorm_encode(c.g, bits, dither) << bits) | (unorm_encode(c.b, bits, dither) << (2u * bits));
}

fn unpack_unorm3(word: u32, bits: u32) -> vec3<f32> {
    return vec3(unorm_decode(word, 0u, bits), unorm_decode(word, bits, bits), unorm_decode(word, 2u * bits, bits));
}

// A colour stored as its square root: twice the steps in the darks, where
// eyes see banding first.
fn pack_sqrt3(c: vec3<f32>, bits: u32, dither: f32) -> u32 {
    return pack_unorm3(sqrt(max(c, vec3(0.0))), bits, dither);
}

fn unpack_sqrt3(word: u32, bits: u32) -> vec3<f32> {
    let r = unpack_unorm3(word, bits);
    return r * r;
}

// A unit vector on the octahedron folded into [-1, 1]², each axis in
// `bits` bits (x low, y above it).
fn pack_octahedral(n: vec3<f32>, bits: u32) -> u32 {
    let a = abs(n);
    var p = n.xy / max(a.x + a.y + a.z, 1e-30);
    if n.z < 0.0 {
        p = (1.0 - abs(p.yx)) * select(vec2(-1.0), vec2(1.0), p >= vec2(0.0));
    }
    let q = p * 0.5 + 0.5;
    return unorm_encode(q.x, bits, 0.0) | (unorm_encode(q.y, bits, 0.0) << bits);
}

fn unpack_octahedral(word: u32, bits: u32) -> vec3<f32> {
    let p = vec2(unorm_decode(word, 0u, bits), unorm_decode(word, bits, bits)) * 2.0 - 1.0;
    var n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

// Three non-negative values with one 5-bit exponent and 9-bit mantissas
// (the shared-exponent format of GL's EXT_texture_shared_exponent):
// each channel within 2^-9 of the largest, up to RGB9E5_MAX.
fn pack_rgb9e5(c: vec3<f32>) -> u32 {
    let x = clamp(c, vec3(0.0), vec3(RGB9E5_MAX));
    let m = max(x.r, max(x.g, x.b));
    // The exponent, biased by 15, with the mantissa's 9 bits below it.
    var e = max(i32(floor(log2(max(m, 1e-30)))), -16) + 16;
    if f32(u32(floor(m / exp2(f32(e - 24)) + 0.5))) >= 512.0 {
        e += 1;
    }
    e = min(e, 31);
    let q = vec3<u32>(min(floor(x / exp2(f32(e - 24)) + 0.5), vec3(511.0)));
    return q.r | (q.g << 9u) | (q.b << 18u) | (u32(e) << 27u);
}

fn unpack_rgb9e5(word: u32) -> vec3<f32> {
    let q = vec3(word & 511u, (word >> 9u) & 511u, (word >> 18u) & 511u);
    return vec3<f32>(q) * exp2(f32(word >> 27u) - 24.0);
}

// Interleaved gradient noise (Jimenez 2014) at a pixel, in [-0.5, 0.5):
// the 8-bit colours' dither, so a smooth gradient quantises to noise
// finer than a step instead of bands.
fn pack_dither(pixel: vec2<u32>) -> f32 {
    let p = vec2<f32>(pixel);
    return fract(52.9829189 * fract(0.06711056 * p.x + 0.00583715 * p.y)) - 0.5;
}
