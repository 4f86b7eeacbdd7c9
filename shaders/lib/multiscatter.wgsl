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
// albedo within 2e-3 relative for n·v ≥ 0.05 and 4e-3 from 0.02
// (measured on lavapipe: 1.4e-3 and 2.5e-3, off the fit's grid), and
// `LOUPE_BLESS=1 cargo test -p loupe --lib render::tests::multiscatter`
// refits the points below. Below n·v = 0.02 the fit holds E(0.02).
#define_import_path loupe::multiscatter

// The spline's intervals per axis; it has INTERVALS + 3 control points
// along each.
const INTERVALS: u32 = 14u;
// brdf.wgsl's `alpha` clamp: E is constant below it.
const ROUGHNESS_MIN: f32 = 0.045;
const N_V_MIN: f32 = 0.02;

// The control points, row by row (rows: roughness), generated. A private
// variable, not a `const`: a `const` array read at a computed index is
// copied into a local array at every call (naga's SPIR-V): lavapipe ran
// the stability suite's energy furnace 5 times slower that way (11.3 s
// against 2.2 s, on a 16 × 32 grid).
// fit: begin
var<private> E_FIT: array<f32, 289> = array<f32, 289>(
    1.8316572, 0.7581281, 0.89202666, 1.0251864, 1.0116347, 1.007188, 0.9969613, 0.9972337, 0.9968885, 0.99992263, 0.9997286, 1.0007993, 0.99959177, 0.9996006, 0.9995577, 0.99957836, 1.0014635,
    0.81152916, 1.0939288, 1.0344005, 0.99373925, 0.99673647, 0.9981416, 1.0009456, 1.0008203, 1.0008743, 1.0000979, 1.0000682, 0.99978036, 1.0000931, 1.0001012, 1.000108, 1.000114, 0.9996024,
    0.859609, 0.837989, 0.95548904, 1.0001292, 1.0009472, 1.0004691, 0.9987838, 0.99898016, 0.99921954, 0.99971503, 0.9999578, 1.0001158, 0.9999969, 0.99995184, 0.99996233, 0.99995184, 1.0001848,
    1.0082201, 0.8993981, 0.8588866, 0.9053072, 0.95423275, 0.9774982, 0.9893966, 0.99422866, 0.99649847, 0.9974234, 0.9979117, 0.99819875, 0.9986252, 0.99890083, 0.9991024, 0.9991605, 0.9996023,
    0.959334, 0.94349647, 0.902213, 0.87530196, 0.88936377, 0.924454, 0.95073515, 0.9683116, 0.97874045, 0.9853546, 0.98965603, 0.9923782, 0.994056, 0.9952441, 0.9958709, 0.9966154, 0.9964891,
    0.9969822, 0.95835096, 0.92398995, 0.8955929, 0.8807719, 0.87910265, 0.89850193, 0.9223409, 0.9437775, 0.9593997, 0.96990675, 0.97702885, 0.98196286, 0.98527956, 0.9878221, 0.9893157, 0.9912219,
    0.97855204, 0.97000945, 0.940705, 0.910214, 0.8782913, 0.86851317, 0.8697818, 0.8821721, 0.899255, 0.91744584, 0.93397295, 0.94725895, 0.9573676, 0.9649674, 0.9703911, 0.9747936, 0.97700435,
    1.0020663, 0.9684837, 0.94743365, 0.91175276, 0.88696605, 0.8663913, 0.85480475, 0.8523969, 0.85920614, 0.8722102, 0.88756317, 0.90323, 0.917456, 0.9295099, 0.93938774, 0.9471536, 0.95343196,
    0.9788009, 0.9738625, 0.9433504, 0.91203207, 0.88688815, 0.86241424, 0.8428397, 0.8305884, 0.82649136, 0.82909626, 0.83779687, 0.84994555, 0.8638583, 0.8778468, 0.8908932, 0.9024565, 0.91236776,
    0.9780383, 0.9719798, 0.9351687, 0.908556, 0.880376, 0.85222346, 0.82788545, 0.8087873, 0.7953142, 0.78873473, 0.78793186, 0.79255635, 0.80108273, 0.81233484, 0.824928, 0.8378213, 0.8503188,
    0.9920277, 0.9631555, 0.9280271, 0.8997137, 0.8671752, 0.83609116, 0.807782, 0.78270036, 0.7625443, 0.74724454, 0.73756295, 0.73300016, 0.7332904, 0.7375803, 0.7451417, 0.754939, 0.76625973,
    1.0027109, 0.95242304, 0.9198105, 0.8864204, 0.8496031, 0.814834, 0.78155434, 0.7516515, 0.72512144, 0.7029294, 0.6850151, 0.671714, 0.6628038, 0.658154, 0.65730107, 0.65983975, 0.66516674,
    1.0001153, 0.94300276, 0.9099946, 0.86968684, 0.8286767, 0.7888068, 0.7507935, 0.71550626, 0.68343157, 0.6547924, 0.6299097, 0.60874563, 0.5913917, 0.5777041, 0.56754535, 0.5607086, 0.556914,
    0.97745234, 0.9373279, 0.8970559, 0.8512154, 0.8048476, 0.75953263, 0.7162059, 0.67560893, 0.6380132, 0.6037507, 0.5727369, 0.54507047, 0.52060485, 0.49922484, 0.4808546, 0.46522117, 0.4524159,
    0.97136825, 0.92912257, 0.8833188, 0.83089244, 0.77898866, 0.7278234, 0.67911613, 0.63315165, 0.5904785, 0.5510372, 0.5149773, 0.48206478, 0.45221576, 0.42522216, 0.40082178, 0.378929, 0.35911575,
    0.96880937, 0.9211834, 0.86801624, 0.80958956, 0.751578, 0.6946411, 0.6404984, 0.58952475, 0.5420924, 0.498366, 0.4581911, 0.42148933, 0.38799438, 0.35747024, 0.32972503, 0.3043975, 0.2814218,
    0.9513804, 0.9119324, 0.85239965, 0.78745097, 0.72312915, 0.66065854, 0.60127115, 0.5456176, 0.49436453, 0.4469831, 0.4039071, 0.3645794, 0.32921764, 0.297174, 0.26832002, 0.24245754, 0.21906503,
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
