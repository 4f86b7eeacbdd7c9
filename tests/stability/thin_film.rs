//! The thin film's Fresnel (`shaders/lib/iridescence.wgsl`, Belcour &
//! Barla's analytic spectral integration) against a reference computed
//! here the long way: the exact Airy reflectance of the film at every
//! wavelength from 380 to 780 nm in 10 nm steps, summed against the
//! tabulated CIE 1931 colour matching functions (equal-energy light), then
//! the same XYZ → linear Rec. 709 and white balance.

use loupe::gpu::Gpu;
use loupe::gpu::testing::Kernel;

const SHADER: &str = r#"
#import loupe::iridescence::thin_film_fresnel

// x: cosine in air, y: thickness (µm), z: the film's IOR, w: unused; then
// the base's IOR per channel.
struct Query { film: vec4<f32>, base: vec4<f32> }

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    output[id.x] = vec4(thin_film_fresnel(q.film.x, q.film.y, q.film.z, q.base.xyz), 0.0);
}
"#;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Query {
    film: [f32; 4],
    base: [f32; 4],
}

/// One film seen at one angle.
#[derive(Debug, Clone, Copy)]
pub struct Film {
    pub cos: f64,
    /// Micrometres.
    pub thickness: f64,
    pub ior: f64,
    pub base: [f64; 3],
}

impl std::fmt::Display for Film {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "film {} µm, IOR {} over {:?} at cos {}", self.thickness, self.ior, self.base, self.cos)
    }
}

/// Films from none to 1 µm (where the colours have washed out to a few
/// per cent), soap-like and oxide-like, over air (a bubble), glass, and a
/// base whose index differs per channel (a metal through its F0), seen
/// head-on to grazing.
pub fn cases() -> Vec<Film> {
    let mut cases = Vec::new();
    for base in [[1.0; 3], [1.5; 3], [3.0, 2.2, 1.6]] {
        for ior in [1.33, 2.0] {
            for thickness in [0.0, 0.1, 0.2, 0.3, 0.45, 0.7, 1.0] {
                for cos in [1.0, 0.7, 0.4, 0.15] {
                    cases.push(Film { cos, thickness, ior, base });
                }
            }
        }
    }
    cases
}

/// The kernel's reflectance for each case.
pub fn device(gpu: &Gpu, cases: &[Film]) -> Vec<[f64; 3]> {
    let kernel = Kernel::new(gpu, SHADER, "main").unwrap_or_else(|e| panic!("{e}"));
    let queries: Vec<Query> = cases
        .iter()
        .map(|c| Query {
            film: [c.cos as f32, c.thickness as f32, c.ior as f32, 0.0],
            base: [c.base[0] as f32, c.base[1] as f32, c.base[2] as f32, 0.0],
        })
        .collect();
    let out: Vec<[f32; 4]> = kernel.run(gpu, &queries, queries.len(), &[]).unwrap();
    out.iter().map(|o| [0, 1, 2].map(|k| f64::from(o[k]))).collect()
}

/// The CIE 1931 2° observer, x̄ ȳ z̄, at 380, 390, …, 780 nm (CIE 15, as
/// tabulated by the CVRL at 1 nm, every tenth row).
const CMF: [[f64; 3]; 41] = [
    [0.001368, 0.000039, 0.006450],
    [0.004243, 0.000120, 0.020050],
    [0.014310, 0.000396, 0.067850],
    [0.043510, 0.001210, 0.207400],
    [0.134380, 0.004000, 0.645600],
    [0.283900, 0.011600, 1.385600],
    [0.348280, 0.023000, 1.747060],
    [0.336200, 0.038000, 1.772110],
    [0.290800, 0.060000, 1.669200],
    [0.195360, 0.090980, 1.287640],
    [0.095640, 0.139020, 0.812950],
    [0.032010, 0.208020, 0.465180],
    [0.004900, 0.323000, 0.272000],
    [0.009300, 0.503000, 0.158200],
    [0.063270, 0.710000, 0.078250],
    [0.165500, 0.862000, 0.042160],
    [0.290400, 0.954000, 0.020300],
    [0.433450, 0.994950, 0.008750],
    [0.594500, 0.995000, 0.003900],
    [0.762100, 0.952000, 0.002100],
    [0.916300, 0.870000, 0.001650],
    [1.026300, 0.757000, 0.001100],
    [1.062200, 0.631000, 0.000800],
    [1.002600, 0.503000, 0.000340],
    [0.854450, 0.381000, 0.000190],
    [0.642400, 0.265000, 0.000050],
    [0.447900, 0.175000, 0.000020],
    [0.283500, 0.107000, 0.0],
    [0.164900, 0.061000, 0.0],
    [0.087400, 0.032000, 0.0],
    [0.046770, 0.017000, 0.0],
    [0.022700, 0.008210, 0.0],
    [0.011359, 0.004102, 0.0],
    [0.005790, 0.002091, 0.0],
    [0.002899, 0.001047, 0.0],
    [0.001440, 0.000520, 0.0],
    [0.000690, 0.000249, 0.0],
    [0.000332, 0.000120, 0.0],
    [0.000166, 0.000060, 0.0],
    [0.000083, 0.000030, 0.0],
    [0.000042, 0.000015, 0.0],
];

/// CIE XYZ to linear Rec. 709 (IEC 61966-2-1), by rows.
const XYZ_TO_REC709: [[f64; 3]; 3] =
    [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]];

/// (s, p) amplitude reflection coefficients from index n1 to n2 at
/// cosines c1 (before) and c2 (after).
fn amplitudes(n1: f64, n2: f64, c1: f64, c2: f64) -> [f64; 2] {
    [(n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2), (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2)]
}

/// The exact unpolarised reflectance of the film at one wavelength (nm):
/// Airy's r = (r12 + r23 e^{iδ}) / (1 + r12 r23 e^{iδ}), δ the round
/// trip's phase, |r|² averaged over s and p.
pub fn airy(film: &Film, base: f64, lambda: f64) -> f64 {
    let (c1, n2) = (film.cos, film.ior);
    let sin2 = 1.0 - c1 * c1;
    let c2 = (1.0 - sin2 / (n2 * n2)).sqrt();
    let c3 = (1.0 - sin2 / (base * base)).max(0.0).sqrt();
    let (r12, r23) = (amplitudes(1.0, n2, c1, c2), amplitudes(n2, base, c2, c3));
    let delta = 4.0 * std::f64::consts::PI * n2 * film.thickness * 1000.0 * c2 / lambda;
    let (cos, sin) = (delta.cos(), delta.sin());
    let reflectance = |a: f64, b: f64| {
        // (a + b e^{iδ}) / (1 + a b e^{iδ}), squared magnitude.
        let (nr, ni) = (a + b * cos, b * sin);
        let (dr, di) = (1.0 + a * b * cos, a * b * sin);
        (nr * nr + ni * ni) / (dr * dr + di * di)
    };
    0.5 * (reflectance(r12[0], r23[0]) + reflectance(r12[1], r23[1]))
}

/// Linear Rec. 709 of a reflectance spectrum under equal-energy light,
/// divided by what a flat spectrum of 1 gives (so flat stays grey).
fn rgb(spectrum: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    let mut white = [0.0; 3];
    for (i, cmf) in CMF.iter().enumerate() {
        let r = spectrum(380.0 + 10.0 * i as f64);
        for k in 0..3 {
            xyz[k] += r * cmf[k];
            white[k] += cmf[k];
        }
    }
    let to_rgb = |v: [f64; 3]| XYZ_TO_REC709.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2]);
    let (c, w) = (to_rgb(xyz), to_rgb(white));
    [0, 1, 2].map(|k| (c[k] / w[k]).clamp(0.0, 1.0))
}

/// The reference: each channel from the spectrum over that channel's base.
pub fn reference(film: &Film) -> [f64; 3] {
    [0, 1, 2].map(|k| rgb(|lambda| airy(film, film.base[k], lambda))[k])
}

/// The exact unpolarised Fresnel reflectance from air into index n at
/// cosine c: what a film of thickness 0 must give back.
pub fn fresnel(c: f64, n: f64) -> f64 {
    let c2 = (1.0 - (1.0 - c * c) / (n * n)).sqrt();
    let r = amplitudes(1.0, n, c, c2);
    0.5 * (r[0] * r[0] + r[1] * r[1])
}
