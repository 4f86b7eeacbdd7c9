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
    1.8606305, 0.74787223, 0.891743, 1.0245878, 1.0112224, 1.0081338, 0.9967392, 0.9966494, 0.99884754, 0.9991909, 1.0003341, 1.0012172, 0.9994154, 0.9998448, 1.0007166, 0.99952865, 1.0002582,
    0.7865886, 1.0983721, 1.0365508, 0.9933159, 0.99668425, 0.99769604, 1.0010769, 1.0010437, 1.0003601, 1.0003517, 0.9998563, 0.9996499, 1.0001552, 1.0000615, 0.9997438, 1.0001596, 0.99984443,
    0.8684567, 0.8372119, 0.95426327, 1.0003544, 1.0009323, 1.0006555, 0.99885374, 0.998875, 0.99953663, 0.9994524, 1.0002229, 1.0002351, 0.9999538, 0.9999188, 1.0003041, 0.99987125, 1.0002155,
    1.0039034, 0.899473, 0.8596543, 0.90520185, 0.9542223, 0.9774509, 0.98925674, 0.99438405, 0.99607265, 0.99795324, 0.9974405, 0.99841654, 0.9984939, 0.9989468, 0.99893546, 0.99908847, 1.0000498,
    0.9621989, 0.9433642, 0.9018306, 0.87531793, 0.8894442, 0.9244585, 0.95084023, 0.96820396, 0.9789873, 0.9849537, 0.9899914, 0.9923652, 0.9940366, 0.995336, 0.99594736, 0.9963729, 0.99734086,
    0.99520147, 0.9584706, 0.9241557, 0.8956252, 0.88071895, 0.87905604, 0.8985177, 0.9223801, 0.9437051, 0.9595416, 0.96977603, 0.97691613, 0.9819845, 0.98530805, 0.98796564, 0.98923266, 0.99139947,
    0.9794263, 0.9700427, 0.94059503, 0.91020155, 0.8781927, 0.8685607, 0.8697297, 0.882196, 0.8992624, 0.9174307, 0.93395525, 0.94740564, 0.9572849, 0.9649651, 0.97028893, 0.974884, 0.9767476,
    1.0015385, 0.9683324, 0.9474705, 0.9118214, 0.8869342, 0.8663893, 0.85482574, 0.852387, 0.8592126, 0.87220776, 0.88757914, 0.9031874, 0.91748, 0.92953646, 0.93936753, 0.9472143, 0.9531884,
    0.9783422, 0.9742182, 0.94329864, 0.9120564, 0.88687384, 0.8624686, 0.84273034, 0.83067083, 0.82640797, 0.8291511, 0.83775496, 0.85002685, 0.8638623, 0.87780887, 0.8909682, 0.9023161, 0.9128639,
    0.98098445, 0.9713893, 0.93524027, 0.9085663, 0.8803561, 0.8522274, 0.82795924, 0.8087388, 0.795308, 0.788794, 0.78788686, 0.7925462, 0.8011113, 0.81229407, 0.8249439, 0.8378357, 0.85023135,
    0.98505175, 0.96474546, 0.9277278, 0.8997549, 0.8671929, 0.83607686, 0.8077213, 0.7827215, 0.76259494, 0.74715656, 0.7375901, 0.7329832, 0.7333201, 0.7375861, 0.74513, 0.75491935, 0.76635575,
    1.0139523, 0.94908196, 0.9207459, 0.8861101, 0.8497393, 0.81479234, 0.78164, 0.7516238, 0.7250612, 0.70295405, 0.68499887, 0.671721, 0.6628008, 0.65814763, 0.65731597, 0.65984744, 0.6651151,
    0.99242496, 0.94543713, 0.90928626, 0.8698781, 0.828633, 0.7888023, 0.75074637, 0.71553916, 0.6834755, 0.6547554, 0.6299082, 0.60876375, 0.5913758, 0.5777041, 0.56753546, 0.56071424, 0.55691373,
    0.98018956, 0.93653536, 0.8972321, 0.8512862, 0.80477893, 0.7595843, 0.7162315, 0.67557645, 0.6380137, 0.60375077, 0.57274574, 0.5451025, 0.52060246, 0.49924543, 0.4808469, 0.46523905, 0.45233637,
    0.9698988, 0.9294861, 0.88316154, 0.8308049, 0.77905566, 0.72774214, 0.6790996, 0.63318723, 0.59045625, 0.55104506, 0.51496476, 0.48205486, 0.45222235, 0.4252075, 0.40083587, 0.37890866, 0.35920274,
    0.972383, 0.92026716, 0.8687713, 0.8094047, 0.7517164, 0.6947625, 0.6405111, 0.5894478, 0.5422045, 0.4983637, 0.45816913, 0.42152023, 0.38795885, 0.35752156, 0.32966933, 0.30446127, 0.28119078,
    0.9376152, 0.9164163, 0.8487408, 0.7891382, 0.7216405, 0.6604606, 0.60113794, 0.5459784, 0.49361846, 0.44711235, 0.40393785, 0.36452186, 0.3293156, 0.29701075, 0.2685015, 0.24225675, 0.2197719,
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
