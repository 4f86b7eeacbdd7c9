//! The white furnace of the energy compensation
//! (`shaders/lib/multiscatter.wgsl`): brdf.wgsl's material with its GGX
//! lobe scaled by `energy_compensation`, its directional albedo by the
//! quadrature of `sampling::quadrature`, over views and roughness.

use crate::sampling::{self, Case, Density};
use loupe::gpu::Gpu;
use loupe::gpu::testing::Kernel;

/// (pdf, brdf_cos with the specular lobe compensated) of direction
/// `input[2 + i].xyz`: the lobe is brdf_cos's specular term, rebuilt from
/// brdf.wgsl's parts, times the factor less one added to brdf_cos.
const COMPENSATED: &str = r#"
#import loupe::brdf::{alpha, d_ggx, f_schlick, specular_f0, v_smith}
#import loupe::multiscatter::energy_compensation

@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let v = view();
    let l = input[2u + id.x].xyz;
    let f = brdf_cos(N, v, l, base(), metallic(), roughness());
    let n_l = dot(N, l);
    let n_v = max(v.z, 1e-4);
    let a = alpha(roughness());
    let f0 = specular_f0(base(), metallic());
    let h = normalize(v + l);
    let lobe = select(vec3(0.0), d_ggx(N, h, a) * v_smith(n_v, n_l, a) * f_schlick(f0, max(dot(v, h), 0.0)) * n_l, n_l > 0.0);
    let extra = lobe * (energy_compensation(f0, n_v, roughness()) - 1.0);
    output[id.x] = vec4(brdf_pdf(N, v, l, base(), metallic(), roughness()), f + extra);
}
"#;

/// The views and roughness the furnace runs at (white base colour).
pub fn cases(metallic: f32) -> Vec<Case> {
    let mut out = Vec::new();
    for cos_v in [0.05, 0.1, 0.2, 0.5, 0.8, 1.0] {
        for roughness in [0.001, 0.1, 0.25, 0.5, 0.75, 1.0] {
            out.push(Case { cos_v, roughness, metallic });
        }
    }
    out
}

/// The compensated material's kernel, compiled once for every case.
pub fn kernel(gpu: &Gpu) -> Kernel {
    sampling::kernel(gpu, COMPENSATED)
}

/// The directional albedo with the lobe compensated.
pub fn compensated(gpu: &Gpu, kernel: &Kernel, case: &Case) -> Density {
    sampling::quadrature(gpu, kernel, case)
}
