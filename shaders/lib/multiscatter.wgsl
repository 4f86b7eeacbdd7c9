// Energy compensation for the GGX specular's missing multiple scattering
// (Turquin 2019, "Practical multiple scattering compensation for
// microfacet models"). Single scattering keeps E(n·v, roughness) of the
// light a white (F = 1) GGX lobe receives: as little as 0.31 at
// roughness 1 seen head-on. The light that scatters more than once
// between the microfacets leaves in about the same lobe, so the lobe is
// scaled by 1 + f0 (1 / E - 1): a white metal (f0 = 1) then returns all
// its light, a dielectric's f0 = 0.04 a few % more.
//
// E is an analytic fit, not a texture, so the raster and the path tracer
// share this code without a binding: a uniform bicubic B-spline over
// x = roughness (from brdf.wgsl's clamp, 0.045, to 1) and
// y = sqrt(n·v) (from 0.02 to 1), its control points fitted by least
// squares to `render::dfg::albedo` (16,384 Hammersley points per value).
// `render/tests/multiscatter.rs` checks it on the device against that
// albedo within 3e-3 relative for n·v ≥ 0.05 and 6e-3 from 0.02, and
// `LOUPE_BLESS=1 cargo test -p loupe --lib render::tests::multiscatter`
// refits the points below. Below n·v = 0.02 the fit holds E(0.02).
#define_import_path loupe::multiscatter

// The spline's intervals per axis; it has INTERVALS + 3 control points
// along each.
const INTERVALS: u32 = 14u;
// brdf.wgsl's `alpha` clamp: E is constant below it.
const ROUGHNESS_MIN: f32 = 0.045;
const N_V_MIN: f32 = 0.02;

// The control points, row by row (rows: roughness), generated.
// fit: begin
const E_FIT = array<f32, 289>(
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
    1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
);
// fit: end

// The uniform cubic B-spline's four weights at t in [0, 1].
fn bspline_weights(t: f32) -> vec4<f32> {
    let s = 1.0 - t;
    let t2 = t * t;
    return vec4(s * s * s, 3.0 * t2 * t - 6.0 * t2 + 4.0, -3.0 * t2 * t + 3.0 * t2 + 3.0 * t + 1.0, t2 * t) / 6.0;
}

// The directional albedo of brdf.wgsl's GGX specular with F = 1.
fn ggx_albedo(n_v: f32, roughness: f32) -> f32 {
    let n = f32(INTERVALS);
    let x = clamp((max(roughness, ROUGHNESS_MIN) - ROUGHNESS_MIN) / (1.0 - ROUGHNESS_MIN), 0.0, 1.0) * n;
    let s0 = sqrt(N_V_MIN);
    let y = clamp((sqrt(max(n_v, N_V_MIN)) - s0) / (1.0 - s0), 0.0, 1.0) * n;
    let i = min(u32(x), INTERVALS - 1u);
    let j = min(u32(y), INTERVALS - 1u);
    let wx = bspline_weights(x - f32(i));
    let wy = bspline_weights(y - f32(j));
    var e = 0.0;
    for (var a = 0u; a < 4u; a++) {
        let k = (i + a) * (INTERVALS + 3u) + j;
        e += wx[a] * dot(wy, vec4(E_FIT[k], E_FIT[k + 1u], E_FIT[k + 2u], E_FIT[k + 3u]));
    }
    return e;
}

// Turquin's factor for a GGX lobe with Fresnel at normal incidence f0: the
// lobe times it returns what single and multiple scattering do together.
fn energy_compensation(f0: vec3<f32>, n_v: f32, roughness: f32) -> vec3<f32> {
    return 1.0 + f0 * (1.0 / ggx_albedo(n_v, roughness) - 1.0);
}
