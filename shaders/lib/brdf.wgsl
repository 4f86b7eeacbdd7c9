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
    let diffuse = (1.0 - metallic) * (1.0 - f0) * schlick_transmission(n_l) * schlick_transmission(n_v) * base_color / PI;
    return (diffuse + specular) * n_l;
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
    let vh = normalize(vec3(a * ve.x, a * ve.y, ve.z));
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = select(vec3(1.0, 0.0, 0.0), vec3(-vh.y, vh.x, 0.0) * inverseSqrt(len2), len2 > 0.0);
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(a * nh.x, a * nh.y, max(nh.z, 0.0)));
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
    let frame = basis(n);
    let n_v = max(dot(n, v), 1e-4);
    var l: vec3<f32>;
    if u.x < specular_probability(n_v, base_color, metallic, f0) {
        let ve = normalize(transpose(frame) * v);
        let h = frame * sample_vndf(ve, alpha(roughness), u.yz);
        l = reflect(-v, h);
    } else {
        l = cosine_direction(frame, u.yz);
    }
    return l;
}
