// Participating media: signed-distance shapes (spheres, boxes, half-spaces)
// joined by a smooth union, optionally eroded by fBm noise, with a soft
// edge. Density times the coefficients gives absorption, scattering and
// emission per unit length. Bound at group 3 by every pass that uses them.
#define_import_path loupe::media

#import loupe::view::view

const SHAPE_SPHERE: u32 = 0u;
const SHAPE_BOX: u32 = 1u;
const SHAPE_PLANE: u32 = 2u;
const MAX_SHAPES: u32 = 16u;

struct Medium {
    // rgb: σa; w: smooth-union radius.
    absorption: vec4<f32>,
    // rgb: σs; w: soft-edge width.
    scattering: vec4<f32>,
    // rgb: emitted radiance per unit length; w: shape count.
    emission: vec4<f32>,
    // x: octaves (0 = no noise), y: frequency, z: amplitude.
    noise: vec4<f32>,
    // The box the march is clipped to.
    bounds_min: vec4<f32>,
    bounds_max: vec4<f32>,
    // Per shape, two vectors: (type, a.xyz) and (b.xyz, c):
    // sphere: a = centre, c = radius; box: a = centre, b = half extents;
    // plane: a = unit normal, c = offset (inside where dot(p, a) < c).
    shapes: array<vec4<f32>, 32>,
}

@group(3) @binding(0) var<storage, read> media: array<Medium>;

fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    if k <= 0.0 {
        return min(a, b);
    }
    let h = clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
    return mix(b, a, h) - k * h * (1.0 - h);
}

fn shape_distance(m: u32, i: u32, p: vec3<f32>) -> f32 {
    let s0 = media[m].shapes[2u * i];
    let s1 = media[m].shapes[2u * i + 1u];
    let kind = u32(s0.x);
    if kind == SHAPE_SPHERE {
        return length(p - s0.yzw) - s1.w;
    }
    if kind == SHAPE_BOX {
        let q = abs(p - s0.yzw) - s1.xyz;
        return length(max(q, vec3(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0);
    }
    return dot(p, s0.yzw) - s1.w;
}

fn medium_distance(m: u32, p: vec3<f32>) -> f32 {
    let count = min(u32(media[m].emission.w), MAX_SHAPES);
    var d = 1e30;
    for (var i = 0u; i < count; i++) {
        d = smooth_min(d, shape_distance(m, i, p), media[m].absorption.w);
    }
    return d;
}

fn hash3(p: vec3<f32>) -> f32 {
    let q = fract(p * vec3(0.1031, 0.1030, 0.0973));
    let r = q + dot(q, q.yxz + 33.33);
    return fract((r.x + r.y) * r.z);
}

// Trilinear value noise in [0, 1].
fn value_noise(p: vec3<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let x00 = mix(hash3(i), hash3(i + vec3(1.0, 0.0, 0.0)), u.x);
    let x10 = mix(hash3(i + vec3(0.0, 1.0, 0.0)), hash3(i + vec3(1.0, 1.0, 0.0)), u.x);
    let x01 = mix(hash3(i + vec3(0.0, 0.0, 1.0)), hash3(i + vec3(1.0, 0.0, 1.0)), u.x);
    let x11 = mix(hash3(i + vec3(0.0, 1.0, 1.0)), hash3(i + vec3(1.0, 1.0, 1.0)), u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

// Fractal sum of octaves, normalised back to [0, 1].
fn fbm(p: vec3<f32>, octaves: u32) -> f32 {
    var sum = 0.0;
    var weight = 0.5;
    var total = 0.0;
    var q = p;
    for (var o = 0u; o < octaves; o++) {
        sum += weight * value_noise(q);
        total += weight;
        weight *= 0.5;
        q = q * 2.03 + vec3(17.1, 5.7, 11.3);
    }
    return sum / max(total, 1e-6);
}

// Density in [0, 1] of medium `m` at `p`: 0 outside, ramping to 1 over the
// soft edge inside, eroded by noise.
fn density(m: u32, p: vec3<f32>) -> f32 {
    let d = medium_distance(m, p);
    var rho = clamp(-d / media[m].scattering.w, 0.0, 1.0);
    let octaves = u32(media[m].noise.x);
    if octaves > 0u && rho > 0.0 {
        rho *= 1.0 - media[m].noise.z * (1.0 - fbm(p * media[m].noise.y, octaves));
    }
    return rho;
}

struct Coefficients {
    scattering: vec3<f32>,
    extinction: vec3<f32>,
    emission: vec3<f32>,
}

// Sum over every medium at `p`.
fn coefficients(p: vec3<f32>) -> Coefficients {
    var c = Coefficients(vec3(0.0), vec3(0.0), vec3(0.0));
    for (var m = 0u; m < view.counts.y; m++) {
        if any(p < media[m].bounds_min.xyz) || any(p > media[m].bounds_max.xyz) {
            continue;
        }
        let rho = density(m, p);
        c.scattering += rho * media[m].scattering.rgb;
        c.extinction += rho * (media[m].scattering.rgb + media[m].absorption.rgb);
        c.emission += rho * media[m].emission.rgb;
    }
    return c;
}

// Entry and exit distances of a ray through a box; empty when x > y.
fn ray_box(origin: vec3<f32>, dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    let inv = 1.0 / dir;
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    return vec2(max(max(near.x, near.y), near.z), min(min(far.x, far.y), far.z));
}

// The part of [0, t_max] along the ray inside any medium's bounds.
fn media_span(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> vec2<f32> {
    var span = vec2(1e30, -1e30);
    for (var m = 0u; m < view.counts.y; m++) {
        let t = ray_box(origin, dir, media[m].bounds_min.xyz, media[m].bounds_max.xyz);
        if t.x <= t.y {
            span = vec2(min(span.x, t.x), max(span.y, t.y));
        }
    }
    return vec2(max(span.x, 0.0), min(span.y, t_max));
}

struct OpticalDepth {
    optical: vec3<f32>,
    // Steps the loop ran: fewer than asked only where a driver cut the loop
    // short (llvmpipe caps the loop iterations of one invocation).
    completed: u32,
}

// Optical depth from `p` along `dir` for `dist`, marched in `steps`
// midpoint steps through the media.
fn optical_depth(p: vec3<f32>, dir: vec3<f32>, dist: f32, steps: u32) -> OpticalDepth {
    let span = media_span(p, dir, dist);
    if span.x >= span.y {
        return OpticalDepth(vec3(0.0), steps);
    }
    let dt = (span.y - span.x) / f32(steps);
    var out = OpticalDepth(vec3(0.0), 0u);
    for (var i = 0u; i < steps; i++) {
        out.optical += coefficients(p + dir * (span.x + (f32(i) + 0.5) * dt)).extinction * dt;
        out.completed += 1u;
    }
    return out;
}

// Beer–Lambert transmittance from `p` along `dir` for `dist`.
fn transmittance(p: vec3<f32>, dir: vec3<f32>, dist: f32, steps: u32) -> vec3<f32> {
    return exp(-optical_depth(p, dir, dist, steps).optical);
}
