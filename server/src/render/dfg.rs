//! The pre-integrated GGX table of the split-sum approximation (Karis,
//! "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course notes), computed
//! here on the CPU once per process, for the environment's specular light
//! (`shaders/lib/ambient.wgsl`). The code is our own; the BRDF is the one of
//! `shaders/lib/brdf.wgsl`: GGX `D`, height-correlated Smith visibility,
//! Schlick's Fresnel, `alpha = max(roughness, 0.045)²`.
//!
//! Texel `(i, j)` is laid out like the LTC tables (`render/ltc.rs`), so the
//! shaders read it with the same bilinear fetch: `roughness = i / 63`,
//! `sqrt(1 - n·v) = j / 63`. Channels:
//! - `r`, `g`: the DFG scale and bias. With `f(v, l)` the specular BRDF and
//!   `F = f0 + (1 - f0)(1 - v·h)⁵`, `∫ f·(n·l) dl = f0·r + g`, where
//!   `r = ∫ f₁·(1 - (1 - v·h)⁵)(n·l) dl`, `g = ∫ f₁·(1 - v·h)⁵(n·l) dl` and
//!   `f₁` is the BRDF with `F = 1`;
//! - `b`: the prefilter factor `k(roughness)` for a linear gradient (same in
//!   every row). The split sum's prefiltered radiance along the reflection
//!   vector `r` is the GGX lobe's average of `L(l)` weighted by `n·l`, with
//!   `n = v = r` (Karis). The lobe is then symmetric about `r`, so the
//!   average of `l` is `k·r` with `k = Σ(n·l)² / Σ(n·l)`, and for
//!   `L(d) = a + b·d.y` the prefiltered radiance is exactly `a + b·k·r.y`;
//! - `a`: 0.
//!
//! Both integrals are estimated by importance-sampling the GGX normal
//! distribution with a Hammersley set of `SAMPLES` points (the same set in
//! every texel, so the table is smooth); `dfg/tests` compares with
//! quadrature.

use std::f64::consts::PI;
use std::sync::OnceLock;

/// Width and height, as the LTC tables (the shaders share their lookup).
pub const SIZE: u32 = super::ltc::SIZE;
pub const FORMAT: wgpu::TextureFormat = super::ltc::FORMAT;
const SAMPLES: u32 = 1024;
/// Samples of `albedo`: the energy compensation's fit is held to it at a
/// few parts in 10⁴, below the table's 1024 points' noise at grazing views.
const ALBEDO_SAMPLES: u32 = 16384;

/// GGX alpha for a perceptual roughness, as `alpha` in brdf.wgsl.
pub fn alpha(roughness: f64) -> f64 {
    let r = roughness.max(0.045);
    r * r
}

/// Height-correlated Smith visibility `G / (4 n·l n·v)`, as `v_smith`.
fn v_smith(n_v: f64, n_l: f64, a: f64) -> f64 {
    let a2 = a * a;
    let gv = n_l * (n_v * n_v * (1.0 - a2) + a2).sqrt();
    let gl = n_v * (n_l * n_l * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-12)
}

/// The `k`-th of `n` Hammersley points.
fn hammersley(k: u32, n: u32) -> (f64, f64) {
    (f64::from(k) / f64::from(n), f64::from(k.reverse_bits()) / 2f64.powi(32))
}

/// A half vector drawn with density `D(h)·(n·h)` (normal +z).
fn sample_h(u: (f64, f64), a: f64) -> [f64; 3] {
    let cos_t = ((1.0 - u.0) / (1.0 + (a * a - 1.0) * u.0)).sqrt();
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.1;
    [sin_t * phi.cos(), sin_t * phi.sin(), cos_t]
}

/// `(scale, bias)` of f0 for one view angle and roughness.
pub fn dfg(n_v: f64, roughness: f64) -> [f64; 2] {
    integrate(n_v, roughness, SAMPLES)
}

/// The directional albedo `E(n·v, roughness)` of the specular with `F = 1`
/// (`scale + bias`): what single scattering keeps of the light, the
/// energy compensation's `E` (`shaders/lib/multiscatter.wgsl` fits it).
pub fn albedo(n_v: f64, roughness: f64) -> f64 {
    integrate(n_v, roughness, ALBEDO_SAMPLES).iter().sum()
}

/// `dfg` over `samples` Hammersley points.
fn integrate(n_v: f64, roughness: f64, samples: u32) -> [f64; 2] {
    let a = alpha(roughness);
    let v = [(1.0 - n_v * n_v).max(0.0).sqrt(), 0.0, n_v];
    let mut sum = [0.0; 2];
    for k in 0..samples {
        let h = sample_h(hammersley(k, samples), a);
        let v_h = v[0] * h[0] + v[2] * h[2];
        let n_l = 2.0 * v_h * h[2] - v[2];
        if n_l <= 0.0 || v_h <= 0.0 {
            continue;
        }
        // f·(n·l) / pdf(l), pdf(l) = D(h)(n·h) / (4 v·h): D cancels.
        let w = 4.0 * v_smith(n_v, n_l, a) * n_l * v_h / h[2];
        let fc = (1.0 - v_h).powi(5);
        sum[0] += w * (1.0 - fc);
        sum[1] += w * fc;
    }
    sum.map(|s| s / f64::from(samples))
}

/// `k(roughness)`: the `n·l`-weighted mean of `l·r` over the GGX lobe
/// reflected about `n = v = r`.
pub fn prefilter_k(roughness: f64) -> f64 {
    let a = alpha(roughness);
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..SAMPLES {
        let h = sample_h(hammersley(k, SAMPLES), a);
        let n_l = 2.0 * h[2] * h[2] - 1.0;
        if n_l > 0.0 {
            num += n_l * n_l;
            den += n_l;
        }
    }
    if den > 0.0 { num / den } else { 1.0 }
}

/// The table's texels, RGBA row by row (rows: `sqrt(1 - n·v)`).
pub fn table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let last = f64::from(SIZE - 1);
        let ks: Vec<f64> = (0..SIZE).map(|i| prefilter_k(f64::from(i) / last)).collect();
        let mut out = Vec::with_capacity((SIZE * SIZE * 4) as usize);
        for j in 0..SIZE {
            let s = f64::from(j) / last;
            // The last row is n·v = 0, which no visible surface has: its
            // neighbour's figures are used, a little inside the horizon.
            let n_v = (1.0 - s * s).max(1e-3);
            for (i, k) in ks.iter().enumerate() {
                let [scale, bias] = dfg(n_v, i as f64 / last);
                out.extend([scale as f32, bias as f32, *k as f32, 0.0]);
            }
        }
        out
    })
}

/// The table uploaded as an unfilterable `Rgba32Float` texture.
pub fn create_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::Texture {
    super::ltc::upload(device, queue, "dfg", table())
}

#[cfg(test)]
mod tests;
