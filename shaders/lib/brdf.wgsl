// The surface BRDF: Lambert diffuse plus GGX specular with the height-
// correlated Smith visibility term and Schlick's Fresnel. Metals tint the
// specular with the base colour and have no diffuse. The diffuse is the
// light Fresnel lets into the surface toward l and out of it toward v,
// (1 - F(n·l)) (1 - F(n·v)) / (1 - f0): reciprocal, and never more than
// the specular leaves, so the directional albedo of a white surface stays
// at or below 1 (the stability suite's furnace case). Weighted by
// 1 - F(v·h) instead, as it was, a white dielectric reflected 1.5× the
// light it received at n·v = 0.1: v·h of a diffuse direction is far
// from n·v, so the diffuse kept what the specular had already taken.
#define_import_path loupe::brdf

const PI: f32 = 3.14159265358979;

// GGX normal distribution of half vector `h` about `n` (both unit); `a` is
// roughness squared (alpha): a² / (π d²), d = (n·h)² (a² - 1) + 1.
// - d is summed as |n × h|² + (n·h)² a²: 1 - (n·h)² cancels near n·h = 1,
//   where f32's step in n·h (6e-8) is a few % of a² at the smallest
//   roughness (4e-6), enough to make the pdf of a mirror-like lobe
//   integrate to 1.008 (the stability suite's chi-square cases);
// - D is formed as k (k / π), k = a / d, never d²: near the peak d² is
//   ~1e-11, below half precision's range, and the form stays in range in
//   f16 up to f16's largest value (the suite's half-precision case).
// h below the surface counts as n·h = 0.
fn d_ggx(n: vec3<f32>, h: vec3<f32>, a: f32) -> f32 {
    let n_h = dot(n, h);
    let t = cross(n, h);
    let d = select(1.0, dot(t, t) + n_h * n_h * a * a, n_h > 0.0);
    let k = a / d;
    return k * (k / PI);
}

// Smith-GGX visibility, height-correlated: G / (4 n·l n·v).
fn v_smith(n_v: f32, n_l: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = n_l * sqrt(n_v * n_v * (1.0 - a2) + a2);
    let gl = n_v * sqrt(n_l * n_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-7);
}

// The base is clamped: v·h (or n·v) of unit vectors can round past 1, and
// pow of a negative base is NaN. With light coming back along the view
// (l = v to rounding: a light at the camera) one evaluation in five was
// NaN: NaN pixels in the raster, light the path tracer silently dropped.
fn f_schlick(f0: vec3<f32>, v_h: f32) -> vec3<f32> {
    return f_schlick_edge(f0, vec3(1.0), v_h);
}

// Schlick's Fresnel toward `f90` at grazing angles instead of white (a
// material's edge tint); with f90 = 1 it is `f_schlick` to the bit.
fn f_schlick_edge(f0: vec3<f32>, f90: vec3<f32>, v_h: f32) -> vec3<f32> {
    return f0 + (f90 - f0) * pow(clamp(1.0 - v_h, 0.0, 1.0), 5.0);
}

// (1 - F(x)) / (1 - f0): the share of Schlick's Fresnel that passes at
// cosine x, without dividing by 1 - f0 (0 for a white metal).
fn schlick_transmission(x: f32) -> f32 {
    return 1.0 - pow(clamp(1.0 - x, 0.0, 1.0), 5.0);
}

fn specular_f0(base_color: vec3<f32>, metallic: f32) -> vec3<f32> {
    return mix(vec3(0.04), base_color, metallic);
}

// Roughness is clamped so a perfect mirror lit by a point light stays finite.
fn alpha(roughness: f32) -> f32 {
    let r = max(roughness, 0.045);
    return r * r;
}

// BRDF × cosine for light from `l`, seen from `v`.
fn brdf_cos(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, roughness: f32) -> vec3<f32> {
    return slab_cos(n, v, l, base_color, metallic, specular_f0(base_color, metallic), vec3(1.0), roughness);
}

// The same lobes with the interface's reflectance given: F0 (from an IOR
// and a tint, or a metal's colour) and F90 (the edge tint). A material
// slab's core (`loupe::material`); `brdf_cos` is the slab whose F0 follows
// from metalness and F90 is white.
fn slab_cos(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, f90: vec3<f32>, roughness: f32) -> vec3<f32> {
    let n_l = dot(n, l);
    // Written so that a NaN (from a NaN normal or direction) takes this
    // branch too: the light is 0, not NaN.
    if !(n_l > 0.0) {
        return vec3(0.0);
    }
    let h = normalize(v + l);
    let n_v = max(dot(n, v), 1e-4);
    let a = alpha(roughness);
    let specular = d_ggx(n, h, a) * v_smith(n_v, n_l, a) * f_schlick_edge(f0, f90, max(dot(v, h), 0.0));
    return (slab_diffuse(n_l, n_v, base_color, metallic, f0) + specular) * n_l;
}

// The slab's diffuse BRDF (without the cosine): what Fresnel lets in
// toward l and out toward v.
fn slab_diffuse(n_l: f32, n_v: f32, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>) -> vec3<f32> {
    return (1.0 - metallic) * (1.0 - f0) * schlick_transmission(n_l) * schlick_transmission(n_v) * base_color / PI;
}

// ---- importance sampling (the path tracer) --------------------------------
//
// One direction from a mixture of the two lobes: cosine-weighted for the
// diffuse, GGX visible normals (Heitz 2018, "Sampling the GGX Distribution
// of Visible Normals") for the specular. The lobe is picked with a
// probability that depends on n·v and the material only, never on the
// sampled direction, so `brdf_pdf` gives any direction's mixture pdf:
// what multiple importance sampling needs to weigh a light sample against
// a BRDF sample.

struct BrdfSample {
    l: vec3<f32>,
    // The mixture pdf of `l` (solid angle); 0, with `l` the zero vector,
    // when no direction was made (the sample went below the surface): the
    // path ends.
    pdf: f32,
    // brdf_cos(l) / pdf.
    weight: vec3<f32>,
}

fn luminance_of(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// How often the specular lobe is sampled: its share of the reflected
// energy, estimated from Fresnel at n·v against the diffuse albedo.
fn specular_probability(n_v: f32, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>) -> f32 {
    let f = luminance_of(f_schlick(f0, n_v));
    let d = (1.0 - metallic) * luminance_of(base_color) * (1.0 - f);
    return clamp(f / max(f + d, 1e-6), 0.05, 1.0);
}

// An orthonormal basis around unit `n` (Duff et al. 2017, branchless).
fn basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return mat3x3(vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x), vec3(b, s + n.y * n.y * a, -n.y), n);
}

// Smith's masking of GGX for one direction.
fn g1_smith(n_x: f32, a: f32) -> f32 {
    let a2 = a * a;
    return 2.0 * n_x / (n_x + sqrt(a2 + (1.0 - a2) * n_x * n_x));
}

// A visible normal for view `ve` (local frame, z along n).
fn sample_vndf(ve: vec3<f32>, a: f32, u: vec2<f32>) -> vec3<f32> {
    return sample_vndf_aniso(ve, vec2(a), u);
}

// `sample_vndf` with alpha a.x along the frame's x and a.y along its y:
// Heitz's stretch makes the anisotropic lobe the isotropic one of alpha 1.
fn sample_vndf_aniso(ve: vec3<f32>, a: vec2<f32>, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3(a.x * ve.x, a.y * ve.y, ve.z));
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = select(vec3(1.0, 0.0, 0.0), vec3(-vh.y, vh.x, 0.0) * inverseSqrt(len2), len2 > 0.0);
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(a.x * nh.x, a.y * nh.y, max(nh.z, 0.0)));
}

// The mixture pdf (solid angle) of sampling `l` with `brdf_sample`.
fn brdf_pdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, roughness: f32) -> f32 {
    return slab_pdf(n, v, l, base_color, metallic, specular_f0(base_color, metallic), roughness);
}

// `brdf_pdf` of a slab with its F0 given (`slab_cos`).
fn slab_pdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, roughness: f32) -> f32 {
    let n_l = dot(n, l);
    // NaN takes this branch too (see brdf_cos).
    if !(n_l > 0.0) {
        return 0.0;
    }
    let n_v = max(dot(n, v), 1e-4);
    let h = normalize(v + l);
    let a = alpha(roughness);
    // VNDF: pdf(h) = G1(v) max(v·h, 0) D(h) / n·v; the reflection's
    // Jacobian 1 / (4 v·h) cancels the v·h.
    let specular = g1_smith(n_v, a) * d_ggx(n, h, a) / (4.0 * n_v);
    let diffuse = n_l / PI;
    let p = specular_probability(n_v, base_color, metallic, f0);
    return p * specular + (1.0 - p) * diffuse;
}

// A cosine-distributed direction about `frame`'s z (pdf n·l / π): the
// diffuse lobe's sample, and the path tracer's environment sample.
fn cosine_direction(frame: mat3x3<f32>, u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return frame * vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u.x, 0.0)));
}

// A direction from `u` (three uniform numbers in [0, 1)): u.x picks the
// lobe, u.yz place the direction.
fn brdf_sample(n: vec3<f32>, v: vec3<f32>, u: vec3<f32>, base_color: vec3<f32>, metallic: f32, roughness: f32) -> BrdfSample {
    let l = slab_direction(n, v, u, base_color, metallic, specular_f0(base_color, metallic), roughness);
    let pdf = brdf_pdf(n, v, l, base_color, metallic, roughness);
    // No direction (below the surface, or NaN from a NaN normal): the
    // path ends. The zero vector says so, and stays finite.
    if !(pdf > 0.0) {
        return BrdfSample(vec3(0.0), 0.0, vec3(0.0));
    }
    return BrdfSample(l, pdf, brdf_cos(n, v, l, base_color, metallic, roughness) / pdf);
}

// The direction `brdf_sample` draws, for a slab with its F0 given: a
// material mixing slabs weighs it by its own pdf and evaluation.
fn slab_direction(n: vec3<f32>, v: vec3<f32>, u: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, roughness: f32) -> vec3<f32> {
    let n_v = max(dot(n, v), 1e-4);
    return lobes_direction(basis(n), v, u, specular_probability(n_v, base_color, metallic, f0), vec2(alpha(roughness)));
}

// The specular lobe (alphas along the frame's x and y) with probability
// `p`, else the diffuse; `frame`'s z is the normal.
fn lobes_direction(frame: mat3x3<f32>, v: vec3<f32>, u: vec3<f32>, p: f32, a: vec2<f32>) -> vec3<f32> {
    var l: vec3<f32>;
    if u.x < p {
        let ve = normalize(transpose(frame) * v);
        let h = frame * sample_vndf_aniso(ve, a, u.yz);
        l = reflect(-v, h);
    } else {
        l = cosine_direction(frame, u.yz);
    }
    return l;
}

// ---- anisotropic GGX (a material's `specular_roughness_anisotropy`) -------
//
// The slab's lobes with the specular stretched along `t`, a direction on
// the surface (made perpendicular to n here, so a closure's own normal
// can tilt away from the tangent it was given). Only modules with an
// anisotropic material call these, for every closure (at anisotropy 0 the
// isotropic lobe); a module without one keeps the functions above.

// OpenPBR's mapping (specification 1.0, "Specular reflection"): alpha
// along t, α_t = r² √(2 / (1 + (1 − a)²)), and across it, α_b = (1 − a) α_t,
// so α_t² + α_b² = 2 r⁴: the lobe keeps its isotropic roughness's mean
// square alpha, which is why the albedo table, the split sum and the LTC
// fit read `roughness` unchanged. Both keep `alpha`'s floor.
fn alpha_aniso(roughness: f32, anisotropy: f32) -> vec2<f32> {
    let b = 1.0 - anisotropy;
    let t = alpha(roughness) * sqrt(2.0 / (1.0 + b * b));
    return vec2(t, max(b * t, alpha(0.0)));
}

// (t, b, n): `t` made perpendicular to unit `n`; `basis(n)` where t lies
// along n.
fn tangent_frame(n: vec3<f32>, t: vec3<f32>) -> mat3x3<f32> {
    let p = t - n * dot(n, t);
    if dot(p, p) < 1e-12 {
        return basis(n);
    }
    let x = normalize(p);
    return mat3x3(x, cross(n, x), n);
}

// GGX's distribution of local half vector `h` (z along n), alphas a:
// 1 / (π a.x a.y d²), d = (h.x / a.x)² + (h.y / a.y)² + h.z². Every term
// is a square, nothing cancels near the peak.
fn d_ggx_aniso(h: vec3<f32>, a: vec2<f32>) -> f32 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    let s = vec3(h.x / a.x, h.y / a.y, h.z);
    let d = dot(s, s);
    return 1.0 / (PI * a.x * a.y * d * d);
}

// |(a.x w.x, a.y w.y, w.z)| with w.z = `n_w`: Smith's Λ(w) is
// (this / n_w − 1) / 2.
fn smith_length(w: vec3<f32>, n_w: f32, a: vec2<f32>) -> f32 {
    return length(vec3(a.x * w.x, a.y * w.y, n_w));
}

// Slab lobes × cosine, specular anisotropic: `slab_cos` with alphas
// `alpha_aniso(roughness, anisotropy)` along t and across it.
fn slab_cos_aniso(n: vec3<f32>, t: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, f90: vec3<f32>, roughness: f32, anisotropy: f32) -> vec3<f32> {
    let n_l = dot(n, l);
    if !(n_l > 0.0) {
        return vec3(0.0);
    }
    let local = transpose(tangent_frame(n, t));
    let h = normalize(v + l);
    let n_v = max(dot(n, v), 1e-4);
    let a = alpha_aniso(roughness, anisotropy);
    // Height-correlated Smith: G2 / (4 n·l n·v) = 0.5 / (n·l |v'| + n·v |l'|).
    let vis = 0.5 / max(n_l * smith_length(local * v, n_v, a) + n_v * smith_length(local * l, n_l, a), 1e-7);
    let specular = d_ggx_aniso(local * h, a) * vis * f_schlick_edge(f0, f90, max(dot(v, h), 0.0));
    return (slab_diffuse(n_l, n_v, base_color, metallic, f0) + specular) * n_l;
}

// The pdf (solid angle) of `slab_direction_aniso`'s directions: the
// visible normals' G1(v) D(h) / (4 n·v) against the cosine lobe.
fn slab_pdf_aniso(n: vec3<f32>, t: vec3<f32>, v: vec3<f32>, l: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, roughness: f32, anisotropy: f32) -> f32 {
    let n_l = dot(n, l);
    if !(n_l > 0.0) {
        return 0.0;
    }
    let local = transpose(tangent_frame(n, t));
    let n_v = max(dot(n, v), 1e-4);
    let a = alpha_aniso(roughness, anisotropy);
    let g1 = 2.0 * n_v / (n_v + smith_length(local * v, n_v, a));
    let specular = g1 * d_ggx_aniso(local * normalize(v + l), a) / (4.0 * n_v);
    let p = specular_probability(n_v, base_color, metallic, f0);
    return p * specular + (1.0 - p) * (n_l / PI);
}

// A direction from the anisotropic slab: visible normals of the stretched
// lobe in the tangent frame, or the cosine lobe.
fn slab_direction_aniso(n: vec3<f32>, t: vec3<f32>, v: vec3<f32>, u: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, roughness: f32, anisotropy: f32) -> vec3<f32> {
    let n_v = max(dot(n, v), 1e-4);
    return lobes_direction(tangent_frame(n, t), v, u, specular_probability(n_v, base_color, metallic, f0), alpha_aniso(roughness, anisotropy));
}
