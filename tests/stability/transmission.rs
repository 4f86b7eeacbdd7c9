//! `dielectric_direction` against `dielectric_pdf` and `dielectric_cos`
//! (shaders/lib/btdf.wgsl), on the device, over the whole sphere: the
//! reflection lobe above the surface and the refracted (or, for a thin
//! wall, straight-through) lobe below, each in a histogram of its own
//! warped toward its lobe's centre, joined into one chi-square test.

use std::f64::consts::PI;

use crate::chi2::{self, Axis, Fit};
use crate::sampling::{self, Density};
use loupe::gpu::Gpu;
use loupe::gpu::testing::Kernel;

/// `sampling::INPUT`'s rest here: `input[0].w` is the roughness,
/// `input[1]` eta and thin.
const PRELUDE: &str = r#"
#import loupe::btdf::{dielectric_cos, dielectric_pdf, dielectric_direction}

fn roughness() -> f32 { return input[0].w; }
fn eta() -> f32 { return input[1].x; }
fn thin() -> f32 { return input[1].y; }
fn f(l: vec3<f32>) -> vec3<f32> { return dielectric_cos(N, view(), l, eta(), roughness(), thin(), vec3(1.0)); }
fn pdf(l: vec3<f32>) -> f32 { return dielectric_pdf(N, view(), l, eta(), roughness(), thin()); }
"#;

/// Invocation i draws with `input[2 + i].xyz`: (direction, its pdf), (f / pdf).
const SAMPLE: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 2>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let l = dielectric_direction(N, view(), input[2u + id.x].xyz, eta(), roughness(), thin());
    let p = pdf(l);
    output[id.x] = array(vec4(l, p), vec4(select(vec3(0.0), f(l) / p, p > 0.0), 0.0));
}
"#;

/// Invocation i evaluates direction `input[2 + i].xyz`: (pdf, f).
const DENSITY: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let l = input[2u + id.x].xyz;
    output[id.x] = vec4(pdf(l), f(l));
}
"#;

/// Samples per case.
pub const SAMPLES: usize = 1 << 19;
/// Cells of each hemisphere's histogram: cos θ × φ.
const CELLS: (usize, usize) = (32, 64);

/// An interface seen from one angle.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// n·v.
    pub cos_v: f64,
    pub roughness: f32,
    /// The relative IOR from v's side (below 1: inside the denser medium).
    pub eta: f32,
    pub thin: bool,
}

impl std::fmt::Display for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = if self.thin { "thin wall" } else { "solid" };
        write!(f, "{kind}, n·v {}, roughness {}, eta {}", self.cos_v, self.roughness, self.eta)
    }
}

/// Solids from outside (eta 1.5) and inside (1/1.5: total internal
/// reflection beyond 41.8°), at the brdf grid's views and roughness; thin
/// walls at a middle and a grazing view.
pub fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for roughness in [0.001, 0.05, 0.5, 1.0] {
        for cos_v in [1.0, 0.5, 0.1, 0.001] {
            for eta in [1.5, 1.0 / 1.5] {
                out.push(Case { cos_v, roughness, eta, thin: false });
            }
        }
        for cos_v in [0.5, 0.001] {
            out.push(Case { cos_v, roughness, eta: 1.5, thin: true });
        }
    }
    out
}

/// A clear smooth interface: the furnace's cases.
pub fn smooth() -> Vec<Case> {
    let mut out = Vec::new();
    for cos_v in [1.0, 0.8, 0.5, 0.2, 0.1] {
        for (eta, thin) in [(1.5, false), (1.0 / 1.5, false), (1.5, true)] {
            out.push(Case { cos_v, roughness: 0.001, eta, thin });
        }
    }
    out
}

/// The roughness → alpha rule of brdf.wgsl, clamp included.
fn alpha(roughness: f32) -> f64 {
    f64::from(roughness).max(0.045).powi(2)
}

pub struct Kernels {
    sample: Kernel,
    density: Kernel,
}

impl Kernels {
    pub fn new(gpu: &Gpu) -> Kernels {
        let kernel =
            |body: &str| Kernel::new(gpu, &format!("{}{PRELUDE}{body}", sampling::INPUT), "main").unwrap_or_else(|e| panic!("{e}"));
        Kernels { sample: kernel(SAMPLE), density: kernel(DENSITY) }
    }
}

fn header(case: &Case) -> [[f32; 4]; 2] {
    let sin_v = (1.0 - case.cos_v * case.cos_v).sqrt();
    [[sin_v as f32, 0.0, case.cos_v as f32, case.roughness], [case.eta, if case.thin { 1.0 } else { 0.0 }, 0.0, 0.0]]
}

/// One hemisphere's histogram: its cos θ range and axes.
struct Half {
    below: bool,
    /// The cos θ the cells are finest at.
    center: f64,
    cos: Axis,
    phi: Axis,
}

/// The two histograms: above, centred on the mirror direction; below, on
/// the refracted one for the normal itself (the horizon past the critical
/// angle) or the mirror's image for a thin wall. A refracted lobe is
/// narrower than the reflected one (by about 1 − 1/eta head-on), so its
/// cells start ten times finer; and it ends where microfacets on the
/// horizon refract to, cos θ = −n·v / eta (below it from outside, above it
/// from inside), where its pdf piles up: the histogram ends there too, so
/// that no cell straddles the edge.
fn halves(case: &Case) -> [Half; 2] {
    let a = alpha(case.roughness);
    let sin_v = (1.0 - case.cos_v * case.cos_v).sqrt();
    let width = a * sin_v + a * a;
    let phi_width = (a * (case.cos_v + a) / sin_v.max(1e-9)).min(10.0);
    let eta = f64::from(case.eta);
    let sin2_t = sin_v * sin_v / (eta * eta);
    let edge = (-case.cos_v / eta).max(-1.0);
    let (lo, hi, center, fine) = if case.thin {
        (-1.0, 0.0, -case.cos_v, 1.0)
    } else if eta > 1.0 {
        (-1.0, edge, -(1.0 - sin2_t).sqrt(), 0.1)
    } else {
        let peak = if sin2_t < 1.0 { -(1.0 - sin2_t).sqrt() } else { 0.0 };
        (edge, 0.0, peak.max(edge), 0.1)
    };
    [
        Half {
            below: false,
            center: case.cos_v,
            cos: Axis::new(0.0, 1.0, case.cos_v, width, CELLS.0),
            phi: Axis::new(0.0, 2.0 * PI, PI, phi_width, CELLS.1),
        },
        Half {
            below: true,
            center,
            cos: Axis::new(lo, hi, center, width * fine, CELLS.0),
            phi: Axis::new(0.0, 2.0 * PI, PI, phi_width * fine, CELLS.1),
        },
    ]
}

/// The offsets of `l` from a half's centres, computed without cancellation
/// near the poles; `None` when `l` lies in the other half.
fn offsets(half: &Half, l: [f32; 3]) -> Option<(f64, f64)> {
    let center = half.center;
    let [x, y, z] = l.map(f64::from);
    if (z < 0.0) != half.below || z == 0.0 {
        return None;
    }
    let t = x * x + y * y;
    let cos = if z > 0.5 {
        (1.0 - center) - t / (1.0 + z)
    } else if z < -0.5 {
        (-1.0 - center) + t / (1.0 - z)
    } else {
        z - center
    };
    Some((cos, y.atan2(x).rem_euclid(2.0 * PI) - PI))
}

/// Each cell's probability (both halves, above first) and the directional
/// albedo (∫ f over the sphere), by `sampling::integrate`.
pub fn density(gpu: &Gpu, k: &Kernels, case: &Case) -> Density {
    sampling::integrate(gpu, &k.density, &header(case), &halves(case).map(|h| (h.cos, h.phi)), case, &[])
}

/// One drawn sample: (direction, pdf), (weight).
pub type Drawn = [[f32; 4]; 2];

pub fn draw(gpu: &Gpu, k: &Kernels, case: &Case, u: &[[f32; 3]]) -> Vec<Drawn> {
    let mut input = header(case).to_vec();
    input.extend(u.iter().map(|u| [u[0], u[1], u[2], 0.0]));
    k.sample.run(gpu, &input, u.len(), &[]).unwrap()
}

/// The chi-square test of the drawn directions (those with pdf > 0)
/// against the density's cells.
pub fn fit(case: &Case, drawn: &[Drawn], density: &Density) -> Fit {
    let halves = halves(case);
    let mut observed = vec![0.0; density.cells.len()];
    for d in drawn.iter().filter(|d| d[0][3] > 0.0) {
        let l = [d[0][0], d[0][1], d[0][2]];
        let mut base = 0;
        for half in &halves {
            if let Some((oc, op)) = offsets(half, l) {
                observed[base + half.cos.cell(oc) * half.phi.cells + half.phi.cell(op)] += 1.0;
            }
            base += half.cos.cells * half.phi.cells;
        }
    }
    let expected: Vec<f64> = density.cells.iter().map(|p| p * drawn.len() as f64).collect();
    chi2::pearson(&observed, &expected)
}

/// The mean weight (red channel: the cases are clear) and its standard
/// error: the Monte Carlo albedo.
pub fn mean_weight(drawn: &[Drawn]) -> (f64, f64) {
    let n = drawn.len() as f64;
    let (s, s2) = drawn.iter().fold((0.0, 0.0), |(s, s2), d| {
        let w = f64::from(d[1][0]);
        (s + w, s2 + w * w)
    });
    let mean = s / n;
    (mean, ((s2 / n - mean * mean).max(0.0) / n).sqrt())
}
