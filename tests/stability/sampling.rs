//! `brdf_sample` against `brdf_pdf` and `brdf_cos` (shaders/lib/brdf.wgsl),
//! on the device, over a grid of materials and views:
//! - the directions it draws follow the pdf (chi-square, `super::chi2`);
//! - the weight it returns is brdf_cos / pdf of its direction;
//! - the directional albedo (quadrature of brdf_cos) is at most 1, and the
//!   mean weight estimates it;
//! - brdf_cos / n·l is reciprocal.
//!
//! The base colour is white: the brightest material, the one a white
//! furnace test needs.

use std::f64::consts::PI;

use crate::chi2::{self, Axis, Fit, GAUSS};
use loupe::gpu::Gpu;
use loupe::gpu::testing::Kernel;

/// What every kernel of the suite reads (`sampling`'s, `transmission`'s,
/// `library`'s, `furnace`'s): `input[0].xyz` is the view in the local
/// frame, n = +z, and `input[2 + i]` invocation i's operand; what
/// `input[0].w` and `input[1]` hold is each kernel family's own. The
/// quadrature, the draw layout and the chi-square fit here rely on it.
pub const INPUT: &str = r#"
@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;

const N = vec3(0.0, 0.0, 1.0);

fn view() -> vec3<f32> { return input[0].xyz; }
"#;

/// `INPUT`'s rest for the kernels here: `input[0].w` is the roughness,
/// `input[1]` the base colour and metallic.
const PRELUDE: &str = r#"
#import loupe::brdf::{brdf_cos, brdf_pdf, brdf_sample}

fn roughness() -> f32 { return input[0].w; }
fn base() -> vec3<f32> { return input[1].rgb; }
fn metallic() -> f32 { return input[1].w; }
"#;

/// Invocation i draws a sample with the uniform numbers `input[2 + i].xyz`:
/// (direction, pdf), (weight, brdf_pdf of the direction), (brdf_cos of it).
const SAMPLE: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 3>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let v = view();
    let s = brdf_sample(N, v, input[2u + id.x].xyz, base(), metallic(), roughness());
    let pdf = brdf_pdf(N, v, s.l, base(), metallic(), roughness());
    let f = brdf_cos(N, v, s.l, base(), metallic(), roughness());
    output[id.x] = array(vec4(s.l, s.pdf), vec4(s.weight, pdf), vec4(f, 0.0));
}
"#;

/// Invocation i evaluates direction `input[2 + i].xyz`: (pdf, brdf_cos).
const DENSITY: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let l = input[2u + id.x].xyz;
    output[id.x] = vec4(brdf_pdf(N, view(), l, base(), metallic(), roughness()), brdf_cos(N, view(), l, base(), metallic(), roughness()));
}
"#;

/// brdf_cos / n·l both ways for pairs of directions `input[2 + i]` (v) and
/// `input[2 + i + pairs]` (l), where pairs = arrayLength(&output).
const RECIPROCAL: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 2>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pairs = arrayLength(&output);
    if id.x >= pairs { return; }
    let a = input[2u + id.x].xyz;
    let b = input[2u + id.x + pairs].xyz;
    let ab = brdf_cos(N, a, b, base(), metallic(), roughness()) / b.z;
    let ba = brdf_cos(N, b, a, base(), metallic(), roughness()) / a.z;
    output[id.x] = array(vec4(ab, 0.0), vec4(ba, 0.0));
}
"#;

/// Samples per chi-square case.
pub const SAMPLES: usize = 1 << 20;
/// Histogram cells: cos θ × φ.
const CELLS: (usize, usize) = (64, 128);

/// A material seen from one angle.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// n·v.
    pub cos_v: f64,
    pub roughness: f32,
    pub metallic: f32,
}

impl std::fmt::Display for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "n·v {}, roughness {}, metallic {}", self.cos_v, self.roughness, self.metallic)
    }
}

/// The grid: views down to n·v = 0.001 (the module clamps n·v at 1e-4),
/// roughness from below the module's clamp (0.045) to 1, dielectric and
/// metal.
pub fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for cos_v in [1.0, 0.5, 0.1, 0.001] {
        for roughness in [0.001, 0.05, 0.5, 1.0] {
            for metallic in [0.0, 1.0] {
                out.push(Case { cos_v, roughness, metallic });
            }
        }
    }
    out
}

/// The roughness → alpha rule of brdf.wgsl, clamp included.
fn alpha(roughness: f32) -> f64 {
    f64::from(roughness).max(0.045).powi(2)
}

/// The compiled kernels, built once for every case.
pub struct Kernels {
    sample: Kernel,
    density: Kernel,
    reciprocal: Kernel,
}

impl Kernels {
    pub fn new(gpu: &Gpu) -> Kernels {
        Kernels { sample: kernel(gpu, SAMPLE), density: kernel(gpu, DENSITY), reciprocal: kernel(gpu, RECIPROCAL) }
    }
}

/// A kernel of `body` after `INPUT` and the prelude (the view, material
/// and operands it reads), entry point `main`.
pub fn kernel(gpu: &Gpu, body: &str) -> Kernel {
    Kernel::new(gpu, &format!("{INPUT}{PRELUDE}{body}"), "main").unwrap_or_else(|e| panic!("{e}"))
}

/// What `input[0]` and `input[1]` hold for a case (see `PRELUDE`).
pub fn header(case: &Case) -> [[f32; 4]; 2] {
    let sin_v = (1.0 - case.cos_v * case.cos_v).sqrt();
    [[sin_v as f32, 0.0, case.cos_v as f32, case.roughness], [1.0, 1.0, 1.0, case.metallic]]
}

/// The histogram's axes for a case: both centred on the mirror direction
/// (cos θ = n·v, φ = π), cells there about a fifth of the specular lobe's
/// width.
fn axes(case: &Case, cells: (usize, usize)) -> (Axis, Axis) {
    let a = alpha(case.roughness);
    let sin_v = (1.0 - case.cos_v * case.cos_v).sqrt();
    // A half vector tilted by δ from n turns the reflection by 2δ(v·h)
    // across the plane of incidence and by about 2δ in it, v·h ≈ n·v: the
    // lobe spans about alpha · sin θ in cos θ (alpha² at the pole, where
    // cos θ is flat) and alpha · (n·v + alpha) / sin θ in φ, a sliver at
    // grazing views.
    let cos = Axis::new(0.0, 1.0, case.cos_v, a * sin_v + a * a, cells.0);
    let phi = Axis::new(0.0, 2.0 * PI, PI, (a * (case.cos_v + a) / sin_v).min(10.0), cells.1);
    (cos, phi)
}

/// The offsets of direction `l` from the axes' centres, computed without
/// cancellation near the pole: 1 − cos θ from the tangential components.
fn offsets(case: &Case, l: [f32; 3]) -> (f64, f64) {
    let [x, y, z] = l.map(f64::from);
    let one_minus_cos = if z > 0.5 { (x * x + y * y) / (1.0 + z) } else { 1.0 - z };
    let phi = y.atan2(x).rem_euclid(2.0 * PI);
    ((1.0 - case.cos_v) - one_minus_cos, phi - PI)
}

/// What a case's pdf says: each cell's probability, and the directional
/// albedo (∫ brdf_cos over the hemisphere, per channel), by Gauss–Legendre
/// quadrature over the same cells.
pub struct Density {
    pub cells: Vec<f64>,
    pub albedo: [f64; 3],
}

pub fn density(gpu: &Gpu, k: &Kernels, case: &Case) -> Density {
    quadrature(gpu, &k.density, case)
}

/// `density` of a kernel written as `DENSITY` is: (pdf, reflected light ×
/// cosine) of direction `input[2 + i].xyz`.
pub fn quadrature(gpu: &Gpu, kernel: &Kernel, case: &Case) -> Density {
    quadrature_bound(gpu, kernel, case, CELLS, &[])
}

/// `quadrature` over `cells` (cos θ × φ; `fit` needs the default ones),
/// with `buffers` bound at group 1 (a material module's).
pub fn quadrature_bound(gpu: &Gpu, kernel: &Kernel, case: &Case, cells: (usize, usize), buffers: &[&wgpu::Buffer]) -> Density {
    integrate(gpu, kernel, &header(case), &[axes(case, cells)], case, buffers)
}

/// The quadrature of a kernel written as `DENSITY` is, after `header`,
/// over the cells of `grids` (each a (cos θ, φ) pair of axes; cells
/// numbered grid by grid, cos θ major): each cell's probability and the
/// integral of the light.
pub fn integrate(
    gpu: &Gpu,
    kernel: &Kernel,
    header: &[[f32; 4]],
    grids: &[(Axis, Axis)],
    what: &dyn std::fmt::Display,
    buffers: &[&wgpu::Buffer],
) -> Density {
    let mut points = Vec::new();
    let mut weights = Vec::new();
    let mut input = header.to_vec();
    let mut first = 0;
    for (cos, phi) in grids {
        for i in 0..cos.cells {
            for j in 0..phi.cells {
                for (ta, wa) in GAUSS {
                    let (c, dc) = cos.at((i as f64 + ta) / cos.cells as f64);
                    for (tb, wb) in GAUSS {
                        let (p, dp) = phi.at((j as f64 + tb) / phi.cells as f64);
                        let s = (1.0 - c * c).max(0.0).sqrt();
                        input.push([(s * p.cos()) as f32, (s * p.sin()) as f32, c as f32, 0.0]);
                        points.push(first + i * phi.cells + j);
                        weights.push(wa * wb * dc * dp / (cos.cells * phi.cells) as f64);
                    }
                }
            }
        }
        first += cos.cells * phi.cells;
    }
    let out: Vec<[f32; 4]> = kernel.run_bound(gpu, &input, points.len(), &[], buffers).unwrap();
    let mut cells = vec![0.0; first];
    let mut albedo = [0.0; 3];
    for ((o, cell), w) in out.iter().zip(&points).zip(&weights) {
        assert!(o.iter().all(|x| x.is_finite()), "{what}: pdf, light = {o:?}");
        cells[*cell] += f64::from(o[0]) * w;
        for c in 0..3 {
            albedo[c] += f64::from(o[1 + c]) * w;
        }
    }
    Density { cells, albedo }
}

/// One drawn sample: (direction, pdf), (weight, brdf_pdf(l)), (brdf_cos(l)).
pub type Drawn = [[f32; 4]; 3];

pub fn draw(gpu: &Gpu, k: &Kernels, case: &Case, u: &[[f32; 3]]) -> Vec<Drawn> {
    let mut input = header(case).to_vec();
    input.extend(u.iter().map(|u| [u[0], u[1], u[2], 0.0]));
    k.sample.run(gpu, &input, u.len(), &[]).unwrap()
}

/// The chi-square test of `drawn` against `density` (expected counts: the
/// cell probabilities times the number drawn; samples that left the
/// hemisphere, pdf 0, are in neither).
pub fn fit(case: &Case, drawn: &[Drawn], density: &Density) -> Fit {
    fit_in(case, CELLS, drawn, density)
}

/// `fit` over `cells` (those `density` was integrated over).
pub fn fit_in(case: &Case, cells: (usize, usize), drawn: &[Drawn], density: &Density) -> Fit {
    let (cos, phi) = axes(case, cells);
    let mut observed = vec![0.0; cos.cells * phi.cells];
    for d in drawn.iter().filter(|d| d[0][3] > 0.0) {
        let (oc, op) = offsets(case, [d[0][0], d[0][1], d[0][2]]);
        observed[cos.cell(oc) * phi.cells + phi.cell(op)] += 1.0;
    }
    let expected: Vec<f64> = density.cells.iter().map(|p| p * drawn.len() as f64).collect();
    chi2::pearson(&observed, &expected)
}

/// The worst relative difference, over the samples with a direction and
/// every channel where brdf_cos is not negligible, between the weight a
/// sample carries and brdf_cos / brdf_pdf of its direction; and the
/// largest weight.
pub fn weight_error(drawn: &[Drawn]) -> (f64, f64) {
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for d in drawn.iter().filter(|d| d[0][3] > 0.0) {
        let pdf = f64::from(d[1][3]);
        for (w, f) in d[1][..3].iter().zip(&d[2][..3]) {
            let (w, f) = (f64::from(*w), f64::from(*f));
            largest = largest.max(w);
            if f > 1e-6 {
                worst = worst.max((w - f / pdf).abs() / (f / pdf));
            }
        }
    }
    (worst, largest)
}

/// The mean weight per channel (the Monte Carlo albedo) and its standard
/// error.
pub fn mean_weight(drawn: &[Drawn]) -> [(f64, f64); 3] {
    let n = drawn.len() as f64;
    [0, 1, 2].map(|c| {
        let (s, s2) = drawn.iter().fold((0.0, 0.0), |(s, s2), d| {
            let w = f64::from(d[1][c]);
            (s + w, s2 + w * w)
        });
        let mean = s / n;
        (mean, ((s2 / n - mean * mean).max(0.0) / n).sqrt())
    })
}

/// The worst relative difference between f(a, b) and f(b, a) over pairs of
/// directions with n·a, n·b ≥ 1e-4 (where the module is reciprocal), and
/// how many pairs were compared.
pub fn reciprocity(gpu: &Gpu, k: &Kernels, case: &Case, pairs: usize) -> (f64, usize) {
    // Directions uniform in cos θ from 1e-4 and in φ; half the pairs made
    // mirror images of each other (b = a reflected about n), where the
    // specular lobe is at its peak.
    let u = loupe::testing::uniforms(2 * pairs);
    let dir = |u: &[f32; 3]| {
        let c = 1e-4 + (1.0 - 1e-4) * f64::from(u[0]);
        let s = (1.0 - c * c).sqrt();
        let p = 2.0 * PI * f64::from(u[1]);
        [s * p.cos(), s * p.sin(), c]
    };
    let a: Vec<[f64; 3]> = u[..pairs].iter().map(dir).collect();
    let b: Vec<[f64; 3]> =
        u[pairs..].iter().zip(&a).enumerate().map(|(i, (u, a))| if i % 2 == 0 { dir(u) } else { [-a[0], -a[1], a[2]] }).collect();
    let mut input = header(case).to_vec();
    input.extend(a.iter().chain(&b).map(|d| [d[0] as f32, d[1] as f32, d[2] as f32, 0.0]));
    let out: Vec<[[f32; 4]; 2]> = k.reciprocal.run(gpu, &input, pairs, &[]).unwrap();
    let mut worst = 0.0f64;
    for ((o, a), b) in out.iter().zip(&a).zip(&b) {
        for (ab, ba) in o[0][..3].iter().zip(&o[1][..3]) {
            let (ab, ba) = (f64::from(*ab), f64::from(*ba));
            assert!(ab.is_finite() && ba.is_finite(), "{case}: f(a, b) = {ab}, f(b, a) = {ba} for a = {a:?}, b = {b:?}");
            worst = worst.max((ab - ba).abs() / ab.abs().max(ba.abs()).max(1e-30));
        }
    }
    (worst, pairs)
}
