// Thin-film interference (iridescence) after Belcour & Barla 2017, "A
// Practical Extension to Microfacet Theory for the Modeling of Varying
// Iridescence". A film of index `film_ior` and thickness d (micrometres)
// lies between the air and a base of index `base` (per channel): light
// reflected at its top and at its bottom interferes, and the reflectance
// of the pair is the Airy summation over the light's round trips in the
// film. Integrating it against the eye's response at every wavelength is
// done analytically: the round trips are a Fourier series in the optical
// path difference, and the CIE 1931 XYZ sensitivities, fitted with
// Gaussians over wavenumber, have Gaussians for Fourier transforms.
//
// - The air above (index 1) and a base of index ≥ 1 mean no total
//   internal reflection inside the film, so each interface's amplitude
//   coefficients are real and their phase is 0 or π.
// - A metal base's complex index is not in the material: its index is
//   taken from its F0 as a dielectric's, n = (1 + √F0) / (1 − √F0), with
//   k = 0 (the phase at the base is then π, never a conductor's).
// - The series is cut after three round trips (the fourth's weight is
//   (R12 R23)², under 2e-3 for films on dielectrics).
// - XYZ goes to linear Rec. 709 and is divided by the white that a
//   spectrally flat reflectance gives (the equal-energy white point), so a
//   film of thickness 0, or a flat spectrum, stays grey: a thickness of 0
//   gives back the base's own (exact, unpolarised) Fresnel.
#define_import_path loupe::iridescence

#import loupe::brdf::PI

// Amplitude reflection coefficients (s, p) at an interface from index n1
// to n2, with cosines c1 before and c2 after. A negative one reflects with
// a phase shift of π.
fn film_amplitudes(n1: f32, n2: f32, c1: f32, c2: f32) -> vec2<f32> {
    return vec2((n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2), (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2));
}

// The XYZ response to the m-th round trip, cos(2π ν opd + shift) over
// wavenumber ν, in the Fourier domain: each Gaussian lobe of the
// sensitivities (Belcour & Barla's fit: weight, mean ν in 1/m, variance)
// gives a cosine at its mean, damped by its width. `opd` in micrometres;
// normalised so that opd 0, shift 0 is Y = 1.
fn film_sensitivity(opd: f32, shift: f32) -> vec3<f32> {
    let phase = 2.0 * PI * opd * 1e-6;
    let val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = vec3(1.6810e6, 1.7953e6, 2.2084e6);
    let spread = vec3(4.3278e9, 9.3046e9, 6.6121e9);
    var xyz = val * sqrt(2.0 * PI * spread) * cos(pos * phase + shift) * exp(-spread * phase * phase);
    // x̄'s second, blue lobe.
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e9) * cos(2.2399e6 * phase + shift) * exp(-4.5282e9 * phase * phase);
    return xyz / 1.0685e-7;
}

// CIE XYZ to linear Rec. 709 (IEC 61966-2-1), by columns.
const XYZ_TO_REC709 = mat3x3<f32>(
    vec3(3.2404542, -0.9692660, 0.0556434),
    vec3(-1.5371385, 1.8760108, -0.2040259),
    vec3(-0.4985314, 0.0415560, 1.0572252),
);

// The unpolarised reflectance (XYZ) of the film over a base of index n3,
// light in air at cosine c1.
fn film_xyz(c1: f32, eta: f32, c2: f32, d: f32, n3: f32) -> vec3<f32> {
    let sin2 = 1.0 - c1 * c1;
    let c3 = sqrt(max(1.0 - sin2 / (n3 * n3), 0.0));
    let r12 = film_amplitudes(1.0, eta, c1, c2);
    let r23 = film_amplitudes(eta, n3, c2, c3);
    let big_r12 = r12 * r12;
    let big_r23 = r23 * r23;
    let t121 = vec2(1.0) - big_r12;
    // From inside the film its top reflects with the opposite sign.
    let phi21 = select(vec2(PI), vec2(0.0), r12 < vec2(0.0));
    let phi2 = phi21 + select(vec2(0.0), vec2(PI), r23 < vec2(0.0));
    let r123 = sqrt(big_r12 * big_r23);
    let rs = t121 * t121 * big_r23 / max(vec2(1.0) - big_r12 * big_r23, vec2(1e-6));
    // The mean over the phase, then the round trips' harmonics.
    let c0 = big_r12 + rs;
    var xyz = 0.5 * (c0.x + c0.y) * film_sensitivity(0.0, 0.0);
    var cm = rs - t121;
    let opd = 2.0 * eta * d * c2;
    for (var m = 1; m <= 3; m++) {
        cm *= r123;
        let k = f32(m);
        // 2 C_m per polarisation, averaged over the two.
        xyz += cm.x * film_sensitivity(k * opd, k * phi2.x) + cm.y * film_sensitivity(k * opd, k * phi2.y);
    }
    return xyz;
}

// The film's reflectance, linear Rec. 709, at cosine `cos_i` in air over a
// base of index `base` per channel; thickness in micrometres.
fn thin_film_fresnel(cos_i: f32, thickness: f32, film_ior: f32, base: vec3<f32>) -> vec3<f32> {
    let c1 = clamp(cos_i, 0.0, 1.0);
    let d = max(thickness, 0.0);
    // The film fades into the air as it thins (Belcour & Barla's blend
    // over the first 0.03 µm of optical path): at 0 only the base reflects.
    let eta = mix(1.0, max(film_ior, 1.0), smoothstep(0.0, 0.03, 2.0 * film_ior * d));
    let c2 = sqrt(max(1.0 - (1.0 - c1 * c1) / (eta * eta), 0.0));
    let white = XYZ_TO_REC709 * film_sensitivity(0.0, 0.0);
    if all(base == vec3(base.x)) {
        return clamp(XYZ_TO_REC709 * film_xyz(c1, eta, c2, d, base.x) / white, vec3(0.0), vec3(1.0));
    }
    let r = XYZ_TO_REC709 * film_xyz(c1, eta, c2, d, base.x) / white;
    let g = XYZ_TO_REC709 * film_xyz(c1, eta, c2, d, base.y) / white;
    let b = XYZ_TO_REC709 * film_xyz(c1, eta, c2, d, base.z) / white;
    return clamp(vec3(r.x, g.y, b.z), vec3(0.0), vec3(1.0));
}

// The index a dielectric of reflectance f0 at normal incidence has: how a
// metal's base under a film is approximated (k = 0).
fn f0_to_ior(f0: vec3<f32>) -> vec3<f32> {
    let s = sqrt(clamp(f0, vec3(0.0), vec3(0.99)));
    return (vec3(1.0) + s) / (vec3(1.0) - s);
}

// The F0 whose Schlick Fresnel at n·v is `f`: how the sampling's lobe
// choice and the raster's split-sum environment term, both written for
// Schlick's F0, see a film.
fn schlick_f0_of(f: vec3<f32>, n_v: f32) -> vec3<f32> {
    let s = pow(clamp(1.0 - n_v, 0.0, 1.0), 5.0);
    return clamp((f - vec3(s)) / max(1.0 - s, 1e-6), vec3(0.0), vec3(1.0));
}
