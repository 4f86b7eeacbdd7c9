//! The BRDF's importance sampling (`shaders/lib/brdf.wgsl`) on the device,
//! for the path tracer: `brdf_pdf` is the density the sampler draws from
//! (over the hemisphere it integrates to the share of samples that stay
//! above the surface: 1 but for the specular lobe's grazing reflections,
//! which end the path), a sample carries the pdf `brdf_pdf` gives its
//! direction,
//! and the sampled estimate of the directional albedo equals a quadrature
//! of `brdf_cos` itself. Each case is a material seen from an angle.

use std::f64::consts::PI;

use crate::gpu::testing::Kernel;
use crate::testing::uniforms;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    /// View direction (local frame, n = +z); w: roughness.
    v: [f32; 4],
    /// Light direction; w: metallic.
    l: [f32; 4],
    base: [f32; 4],
    /// Three uniform numbers for `brdf_sample`.
    u: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Out {
    a: [f32; 4],
    b: [f32; 4],
}

const SHADER: &str = r#"
#import loupe::brdf::{brdf_cos, brdf_pdf, brdf_sample}

struct Query { v: vec4<f32>, l: vec4<f32>, base: vec4<f32>, u: vec4<f32> }
struct Out { a: vec4<f32>, b: vec4<f32> }

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<Out>;

const N = vec3(0.0, 0.0, 1.0);

// a: (pdf, brdf_cos) of direction l.
@compute @workgroup_size(64)
fn evaluate(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    let f = brdf_cos(N, q.v.xyz, q.l.xyz, q.base.rgb, q.l.w, q.v.w);
    output[id.x] = Out(vec4(brdf_pdf(N, q.v.xyz, q.l.xyz, q.base.rgb, q.l.w, q.v.w), f), vec4(0.0));
}

// a: (l, pdf) of a sample; b: (weight, brdf_pdf(l)).
@compute @workgroup_size(64)
fn sample(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    let s = brdf_sample(N, q.v.xyz, q.u.xyz, q.base.rgb, q.l.w, q.v.w);
    output[id.x] = Out(vec4(s.l, s.pdf), vec4(s.weight, brdf_pdf(N, q.v.xyz, s.l, q.base.rgb, q.l.w, q.v.w)));
}
"#;

/// (view angle from n, roughness, metallic, base colour).
const CASES: [(f64, f32, f32, [f32; 3]); 4] = [
    (0.3, 0.5, 0.0, [0.8, 0.8, 0.8]),
    (1.2, 0.3, 1.0, [0.9, 0.6, 0.3]),
    (0.8, 0.8, 0.5, [0.5, 0.2, 0.7]),
    (1.45, 0.6, 0.0, [0.1, 0.9, 0.2]),
];

fn view(theta: f64) -> [f32; 3] {
    [theta.sin() as f32, 0.0, theta.cos() as f32]
}

/// Histogram bins over the upper hemisphere, by θ and φ.
const BINS: (usize, usize) = (8, 16);

fn bin(l: [f32; 3]) -> usize {
    let theta = f64::from(l[2]).clamp(-1.0, 1.0).acos();
    let phi = f64::from(l[1]).atan2(f64::from(l[0])).rem_euclid(2.0 * PI);
    let i = ((theta / (PI / 2.0)) * BINS.0 as f64).min(BINS.0 as f64 - 1.0) as usize;
    let j = ((phi / (2.0 * PI)) * BINS.1 as f64).min(BINS.1 as f64 - 1.0) as usize;
    i * BINS.1 + j
}

/// Midpoint quadrature of the upper hemisphere: (direction, solid angle).
fn hemisphere(n_theta: usize, n_phi: usize) -> Vec<([f32; 3], f64)> {
    let (dt, dp) = (PI / 2.0 / n_theta as f64, 2.0 * PI / n_phi as f64);
    let mut out = Vec::with_capacity(n_theta * n_phi);
    for i in 0..n_theta {
        let t = (i as f64 + 0.5) * dt;
        for j in 0..n_phi {
            let p = (j as f64 + 0.5) * dp;
            out.push(([(t.sin() * p.cos()) as f32, (t.sin() * p.sin()) as f32, t.cos() as f32], t.sin() * dt * dp));
        }
    }
    out
}

fn query(theta: f64, roughness: f32, metallic: f32, base: [f32; 3], l: [f32; 3], u: [f32; 3]) -> Query {
    let v = view(theta);
    Query {
        v: [v[0], v[1], v[2], roughness],
        l: [l[0], l[1], l[2], metallic],
        base: [base[0], base[1], base[2], 1.0],
        u: [u[0], u[1], u[2], 0.0],
    }
}

#[test]
fn the_brdf_pdf_is_a_density_and_sampling_estimates_the_albedo_it_integrates() {
    let gpu = crate::gpu::testing::device();
    let evaluate = Kernel::new(&gpu, SHADER, "evaluate").unwrap_or_else(|e| panic!("{e}"));
    let sample = Kernel::new(&gpu, SHADER, "sample").unwrap_or_else(|e| panic!("{e}"));
    let grid = hemisphere(512, 512);
    let u = uniforms(1 << 18);
    for (theta, roughness, metallic, base) in CASES {
        let case = format!("view {theta} rad, roughness {roughness}, metallic {metallic}, base {base:?}");
        let queries: Vec<Query> = grid.iter().map(|(l, _)| query(theta, roughness, metallic, base, *l, [0.0; 3])).collect();
        let out: Vec<Out> = evaluate.run(&gpu, &queries, queries.len(), &[]).unwrap();
        let integral: f64 = out.iter().zip(&grid).map(|(o, (_, dw))| f64::from(o.a[0]) * dw).sum();
        // The probability of each bin, from the pdf; the grid's cells nest
        // in the bins.
        let mut expected = vec![0.0f64; BINS.0 * BINS.1];
        for (o, (l, dw)) in out.iter().zip(&grid) {
            expected[bin(*l)] += f64::from(o.a[0]) * dw;
        }
        let albedo: Vec<f64> = (1..4).map(|c| out.iter().zip(&grid).map(|(o, (_, dw))| f64::from(o.a[c]) * dw).sum()).collect();

        let queries: Vec<Query> = u.iter().map(|u| query(theta, roughness, metallic, base, [0.0; 3], *u)).collect();
        let out: Vec<Out> = sample.run(&gpu, &queries, queries.len(), &[]).unwrap();
        let valid = out.iter().filter(|o| o.a[3] > 0.0).count() as f64 / out.len() as f64;
        assert!(
            integral <= 1.0 + 0.005 && (integral - valid).abs() < 0.01,
            "{case}: the pdf integrates to {integral}; {valid} of the samples are valid"
        );
        // Where the samples land: the pdf's bins, within a total variation
        // distance that 2^18 samples over 128 bins comfortably meet (their
        // noise is about 0.01).
        let mut observed = vec![0.0f64; BINS.0 * BINS.1];
        for o in out.iter().filter(|o| o.a[3] > 0.0) {
            let len = (o.a[0] * o.a[0] + o.a[1] * o.a[1] + o.a[2] * o.a[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-4, "{case}: a sampled direction of length {len}");
            observed[bin([o.a[0], o.a[1], o.a[2]])] += 1.0 / out.len() as f64;
        }
        let distance: f64 = observed.iter().zip(&expected).map(|(o, e)| (o - e).abs()).sum::<f64>() / 2.0;
        assert!(distance < 0.02, "{case}: samples and pdf differ by {distance} (total variation)");
        let mut estimate = [0.0f64; 3];
        for o in &out {
            let (pdf, again) = (o.a[3], o.b[3]);
            assert!(o.a.iter().chain(&o.b).all(|x| x.is_finite()), "{case}: {o:?}");
            assert!((pdf - again).abs() <= 1e-4 * pdf.max(1.0), "{case}: a sample's pdf {pdf} vs brdf_pdf {again}");
            for (e, b) in estimate.iter_mut().zip(&o.b) {
                *e += f64::from(*b) / out.len() as f64;
            }
        }
        for c in 0..3 {
            let (e, a) = (estimate[c], albedo[c]);
            assert!((e - a).abs() <= 0.02 * a + 1e-3, "{case}, channel {c}: sampled albedo {e} vs quadrature {a}");
        }
    }
}
