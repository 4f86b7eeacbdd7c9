//! The environment's light, checked against integrals done here:
//! - the GGX table (`dfg`, `prefilter_k`) against quadrature of the same
//!   BRDF (`ltc::tests::ggx_albedo`) and of the lobe's mean direction;
//! - the WGSL of `loupe::ambient`, run on the device: the radiance against
//!   its formula, the closed-form irradiance against a quadrature of the
//!   gradient over the cosine-weighted hemisphere, the table lookup against
//!   the CPU figures between texels.

use super::*;
use crate::gpu::testing::{self, Kernel};
use crate::render::ltc::tests::ggx_albedo;

/// Texels `(i, j)` on the grid, and the (n·v, roughness) they hold.
fn texel(i: u32, j: u32) -> (f64, f64) {
    let s = f64::from(j) / 63.0;
    (1.0 - s * s, f64::from(i) / 63.0)
}

#[test]
fn the_table_is_the_integral_of_the_brdf() {
    let t = table();
    assert_eq!(t.len(), (SIZE * SIZE * 4) as usize);
    // Roughness from 0.19 up: the quadrature (96 × 96 × 16 points) cannot
    // resolve sharper lobes.
    let mut worst: f64 = 0.0;
    for (i, j) in [(12, 5), (20, 30), (32, 10), (40, 50), (50, 20), (63, 0), (63, 45), (25, 60)] {
        let (n_v, roughness) = texel(i, j);
        let [total, fresnel] = ggx_albedo(n_v, alpha(roughness));
        let at = ((j * SIZE + i) * 4) as usize;
        let (scale, bias) = (f64::from(t[at]), f64::from(t[at + 1]));
        let err = (scale - (total - fresnel)).abs().max((bias - fresnel).abs());
        worst = worst.max(err);
        assert!(err < 5e-3, "n·v {n_v:.3}, roughness {roughness:.3}: table ({scale}, {bias}), quadrature ({}, {fresnel})", total - fresnel);
    }
    eprintln!("worst DFG error {worst:.1e}");
    // A mirror reflects everything: scale 1, bias 0 at normal incidence.
    let [scale, bias] = dfg(1.0, 0.0);
    assert!((scale - 1.0).abs() < 1e-3 && bias.abs() < 1e-3, "{scale} {bias}");
}

/// k as a quadrature over the half vector's angle: with n = v, h at angle θ
/// has density D(θ) cos θ and reflects to l with n·l = cos 2θ.
fn k_quadrature(roughness: f64) -> f64 {
    let a2 = alpha(roughness).powi(2);
    let steps = 200_000;
    let (mut num, mut den) = (0.0, 0.0);
    for s in 0..steps {
        let theta = (f64::from(s) + 0.5) / f64::from(steps) * (PI / 4.0);
        let c = theta.cos();
        let d = a2 / (PI * (c * c * (a2 - 1.0) + 1.0).powi(2));
        let w = d * c * theta.sin();
        let n_l = (2.0 * theta).cos();
        num += w * n_l * n_l;
        den += w * n_l;
    }
    num / den
}

#[test]
fn the_prefilter_factor_is_the_lobes_mean_direction() {
    for roughness in [0.1, 0.3, 0.5, 0.75, 1.0] {
        let (k, q) = (prefilter_k(roughness), k_quadrature(roughness));
        assert!((k - q).abs() < 2e-3, "roughness {roughness}: {k} vs {q}");
    }
    assert!(prefilter_k(0.0) > 0.999, "a mirror does not blur");
    assert!(prefilter_k(1.0) < 0.7, "a rough lobe averages the gradient");
}

const KERNEL: &str = r"
#import loupe::ambient::{gradient_radiance, gradient_irradiance, dfg}

struct Case {
    top: vec4<f32>,
    bottom: vec4<f32>,
    // xyz: a unit direction; w: roughness
    d: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> results: array<mat3x4<f32>>;
@group(0) @binding(2) var table: texture_2d<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&cases) {
        return;
    }
    let c = cases[id.x];
    let radiance = gradient_radiance(c.top.rgb, c.bottom.rgb, c.d.xyz);
    let irradiance = gradient_irradiance(c.top.rgb, c.bottom.rgb, c.d.xyz);
    // The direction's z as n·v.
    let t = dfg(table, c.d.z, c.d.w);
    results[id.x] = mat3x4(vec4(radiance, 0.0), vec4(irradiance, 0.0), vec4(t, 0.0));
}
";

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Case {
    top: [f32; 4],
    bottom: [f32; 4],
    d: [f32; 4],
}

fn radiance(top: [f64; 3], bottom: [f64; 3], d: [f64; 3]) -> [f64; 3] {
    let t = d[1] * 0.5 + 0.5;
    [0, 1, 2].map(|c| bottom[c] + (top[c] - bottom[c]) * t)
}

/// ∫ L(l) max(n·l, 0) dl over the sphere, by the midpoint rule in (θ, φ)
/// about +y (so the gradient's variation is resolved in θ).
fn irradiance_quadrature(top: [f64; 3], bottom: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let (nt, np) = (400, 400);
    let mut sum = [0.0; 3];
    for it in 0..nt {
        let theta = (f64::from(it) + 0.5) / f64::from(nt) * PI;
        for ip in 0..np {
            let phi = (f64::from(ip) + 0.5) / f64::from(np) * 2.0 * PI;
            let l = [theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()];
            let cos = (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0);
            let w = cos * theta.sin() * (PI / f64::from(nt)) * (2.0 * PI / f64::from(np));
            let lr = radiance(top, bottom, l);
            for c in 0..3 {
                sum[c] += lr[c] * w;
            }
        }
    }
    sum
}

#[test]
fn the_shader_matches_the_gradient_its_irradiance_and_the_table() {
    let gpu = testing::device();
    let top = [0.10, 0.16, 0.28];
    let bottom = [0.9, 0.4, 0.02];
    let dirs: [[f64; 3]; 6] = [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.0, -0.6, 0.8], [0.48, 0.6, 0.64]];
    // Between texels: roughness and n·v off the grid.
    let roughness = [0.05, 0.33, 0.5, 0.71, 0.9, 1.0];
    let f4 = |v: [f64; 3], w: f64| [v[0] as f32, v[1] as f32, v[2] as f32, w as f32];
    let cases: Vec<Case> =
        dirs.iter().zip(roughness).map(|(d, r)| Case { top: f4(top, 0.0), bottom: f4(bottom, 0.0), d: f4(*d, r) }).collect();
    let view = create_texture(&gpu.device, &gpu.queue).create_view(&Default::default());
    let out: Vec<[[f32; 4]; 3]> = Kernel::new(&gpu, KERNEL, "main").unwrap().run(&gpu, &cases, cases.len(), &[&view]).unwrap();
    for ((d, r), [rad, irr, t]) in dirs.iter().zip(roughness).zip(out) {
        let want = radiance(top, bottom, *d);
        // Irradiance: the quadrature's error is below 1e-4 of π·a here; the
        // tolerance is 1e-3 relative to the largest channel (~π·0.5).
        let e = irradiance_quadrature(top, bottom, *d);
        for c in 0..3 {
            assert!((f64::from(rad[c]) - want[c]).abs() < 1e-6, "radiance along {d:?}: {rad:?} vs {want:?}");
            assert!((f64::from(irr[c]) - e[c]).abs() < 1.6e-3, "irradiance at {d:?}: {irr:?} vs {e:?}");
        }
        // The table between texels: bilinear error only (5e-3).
        let n_v = d[2].max(0.0);
        let [scale, bias] = dfg(n_v.max(1e-3), r);
        let k = prefilter_k(r);
        let got = t.map(f64::from);
        assert!(
            (got[0] - scale).abs() < 5e-3 && (got[1] - bias).abs() < 5e-3 && (got[2] - k).abs() < 5e-3,
            "dfg at n·v {n_v}, roughness {r}: {got:?} vs ({scale}, {bias}, {k})"
        );
    }
}
