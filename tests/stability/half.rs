//! The GGX term near n·h = 1 at the smallest roughness (alpha = 0.045²,
//! alpha² = 4.1e-6), in half precision. The adapter's SHADER_F16 is not
//! relied on: f16 is emulated by rounding through `pack2x16float` /
//! `unpack2x16float` after every operation (what f16 storage does to a
//! value, and, operation by operation, what f16 arithmetic does). Values
//! are clamped to ±65504 before each rounding, since WGSL leaves the
//! packing of values beyond f16's range undefined.
//!
//! Per half vector, the kernel gives D four ways:
//! 0. `d_ggx` as the module evaluates it, in f32;
//! 1. `d_ggx` of the normal as the G-buffer stores it (Rgba16Float) and
//!    the lighting pass normalizes it;
//! 2. the module's form, d = |n × h|² + (n·h)² alpha², D = k (k / π) with
//!    k = alpha / d, in f16 arithmetic, saturated at 65504;
//! 3. the textbook form, d = (n·h)² (alpha² − 1) + 1, D = alpha² / (π d²),
//!    in f16 arithmetic.

use loupe::gpu::testing::Kernel;

const SHADER: &str = r#"
#import loupe::brdf::{d_ggx, PI}

// n, h (unit), w of n: alpha.
struct Query { n: vec4<f32>, h: vec4<f32> }

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

const F16_MAX: f32 = 65504.0;

// One f16 rounding.
fn q(x: f32) -> f32 {
    return unpack2x16float(pack2x16float(vec2(clamp(x, -F16_MAX, F16_MAX), 0.0))).x;
}

fn q3(v: vec3<f32>) -> vec3<f32> {
    return vec3(q(v.x), q(v.y), q(v.z));
}

fn dot_half(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return q(q(q(a.x * b.x) + q(a.y * b.y)) + q(a.z * b.z));
}

// D from its denominator d: the module's k (k / π), k = a / d.
fn module_d(d: f32, a: f32) -> f32 {
    let k = q(a / d);
    return q(k * q(k / PI));
}

// D from d as textbooks write it: a² / (π d²).
fn textbook_d(d: f32, a2: f32) -> f32 {
    return q(a2 / q(q(PI * d) * d));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let n = input[id.x].n.xyz;
    let h = input[id.x].h.xyz;
    let a = input[id.x].n.w;
    let stored = normalize(q3(n));
    // f16 operands: the normal and half vector rounded, alpha and alpha².
    let nh = q3(n);
    let hh = q3(h);
    let a2 = q(q(a) * q(a));
    let n_h = dot_half(nh, hh);
    let t = q3(cross(nh, hh));
    let cross_form = q(dot_half(t, t) + q(q(n_h * n_h) * a2));
    let textbook = q(q(q(n_h * n_h) * q(a2 - 1.0)) + 1.0);
    output[id.x] = vec4(d_ggx(n, h, a), d_ggx(stored, h, a), module_d(cross_form, q(a)), textbook_d(textbook, a2));
}
"#;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    n: [f32; 4],
    h: [f32; 4],
}

type V3 = [f64; 3];

/// GGX's D in f64 for the directions of n and h.
fn exact(n: V3, h: V3, a: f64) -> f64 {
    let unit = |v: V3| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / l)
    };
    let (n, h) = (unit(n), unit(h));
    let c = n[0] * h[0] + n[1] * h[1] + n[2] * h[2];
    let t = [n[1] * h[2] - n[2] * h[1], n[2] * h[0] - n[0] * h[2], n[0] * h[1] - n[1] * h[0]];
    let d = t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + c * c * a * a;
    a * a / (std::f64::consts::PI * d * d)
}

/// A value rounded to f16 and back.
fn f16(x: f32) -> f64 {
    f64::from(half::f16::from_f32(x).to_f32())
}

/// The worst relative error of each way, over half vectors from n·h = 1
/// out to 8 alpha (where D has fallen to 0.02 % of its peak), in every
/// azimuth, about a normal in general position; and how many were not
/// finite. Ways 0 and 1 are measured against D of the exact directions
/// (way 1's error is then the G-buffer's f16 normal); ways 2 and 3
/// against D of their f16 operands, saturated at 65504 (their error is
/// then the f16 arithmetic's).
pub struct Errors {
    pub worst: [f64; 4],
    pub non_finite: [usize; 4],
    /// The largest D in f32 and f16 (saturated).
    pub peak: [f64; 2],
}

pub fn run(gpu: &loupe::gpu::Gpu) -> Errors {
    let kernel = Kernel::new(gpu, SHADER, "main").unwrap_or_else(|e| panic!("{e}"));
    let a = 0.045f64 * 0.045;
    let n = [0.3f64, 0.5, 0.8];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let n = n.map(|x| x / len);
    // A tangent frame about n.
    let t = {
        let c = [n[1], -n[0], 0.0];
        let l = (c[0] * c[0] + c[1] * c[1]).sqrt();
        c.map(|x| x / l)
    };
    let b = [n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]];
    let mut queries = Vec::new();
    for i in 0..=400 {
        let theta = 8.0 * a * f64::from(i) / 400.0;
        for j in 0..16 {
            let phi = std::f64::consts::TAU * f64::from(j) / 16.0;
            let h = [0, 1, 2].map(|k| theta.cos() * n[k] + theta.sin() * (phi.cos() * t[k] + phi.sin() * b[k]));
            queries.push(Query { n: [n[0] as f32, n[1] as f32, n[2] as f32, a as f32], h: [h[0] as f32, h[1] as f32, h[2] as f32, 0.0] });
        }
    }
    let out: Vec<[f32; 4]> = kernel.run(gpu, &queries, queries.len(), &[]).unwrap();
    let mut errors = Errors { worst: [0.0; 4], non_finite: [0; 4], peak: [0.0; 2] };
    for (o, q) in out.iter().zip(&queries) {
        let f64s = |v: [f32; 4]| [v[0], v[1], v[2]].map(f64::from);
        let (n, h) = (f64s(q.n), f64s(q.h));
        let operands = exact(q.n.map(f16)[..3].try_into().unwrap(), q.h.map(f16)[..3].try_into().unwrap(), f16(q.n[3]));
        let want = [exact(n, h, f64::from(q.n[3])); 2].into_iter().chain([operands.min(65504.0); 2]);
        for (k, want) in want.enumerate() {
            let got = f64::from(o[k]);
            if !got.is_finite() {
                errors.non_finite[k] += 1;
                continue;
            }
            errors.worst[k] = errors.worst[k].max((got - want).abs() / want);
        }
        errors.peak[0] = errors.peak[0].max(f64::from(o[0]));
        errors.peak[1] = errors.peak[1].max(f64::from(o[2]));
    }
    errors
}
