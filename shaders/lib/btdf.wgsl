// Light through a dielectric interface, for materials with a transmission
// weight (`loupe::material` imports it only then). `n` faces the viewer
// (n·v > 0) and `eta` is the relative index across the interface seen from
// v's side, η(beyond) / η(v's side): the material's IOR from outside, its
// inverse from inside a solid (the path tracer says which).
//
// - A solid: GGX microfacet reflection and refraction (Walter et al. 2007,
//   "Microfacet Models for Refraction through Rough Surfaces") with the
//   exact unpolarised dielectric Fresnel, total internal reflection
//   included. The refraction carries no 1/η² radiance scaling: it cancels
//   on a closed mesh's way in and out, and without it a sample's weight is
//   G2/G1 whichever way it goes, so a clear smooth interface returns all
//   the light (the stability suite's transmission furnace).
// - A thin wall: the same reflection lobe with the wall's reflectance
//   (both faces and the light bouncing between them: 2R / (1 + R)), and
//   its mirror image below the surface carrying the rest times `tint`: the
//   light goes straight through, blurred by the roughness.
//
// Roughness is clamped as brdf.wgsl clamps it (`alpha`), so there are no
// delta lobes and `dielectric_pdf` describes `dielectric_direction`'s
// directions exactly (the stability suite's chi-square cases).
#define_import_path loupe::btdf

#import loupe::brdf::{alpha, basis, d_ggx, g1_smith, sample_vndf, v_smith}

// Fresnel reflectance of a dielectric interface at cosine `cos_i` on v's
// side; 1 past the critical angle (total internal reflection).
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// What the interface reflects: one face of a solid, or a thin wall's two
// faces with the light between them (R + T²R / (1 − R²) = 2R / (1 + R)).
fn dielectric_reflectance(cos_i: f32, eta: f32, thin: f32) -> f32 {
    let r = fresnel_dielectric(cos_i, eta);
    return select(r, 2.0 * r / (1.0 + r), thin > 0.5);
}

// The microfacet normal that refracts v into l, on n's side.
fn refraction_half(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, eta: f32) -> vec3<f32> {
    let h = normalize(v + eta * l);
    return select(-h, h, dot(h, n) >= 0.0);
}

// A direction below the surface mirrored above it (a thin wall's
// straight-through lobe is the reflection lobe's mirror image).
fn mirrored(n: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    return l - 2.0 * dot(n, l) * n;
}

// The half vector of the reflection lobe at l: of l itself above the
// surface, of its mirror image above for a thin wall's light below.
fn reflection_half(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    return normalize(v + select(mirrored(n, l), l, dot(n, l) > 0.0));
}

// The share of the light at microfacet cosine v·h that goes to l's side:
// the reflectance above, the rest below.
fn reflection_share(n_l: f32, v_h: f32, eta: f32, thin: f32) -> f32 {
    let r = dielectric_reflectance(max(v_h, 0.0), eta, thin);
    return select(1.0 - r, r, n_l > 0.0);
}

// BSDF × |n·l| for light from l seen from v: the interface's reflection
// above the surface, what it lets through below.
fn dielectric_cos(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, eta: f32, roughness: f32, thin: f32, tint: vec3<f32>) -> vec3<f32> {
    let n_l = dot(n, l);
    // A NaN takes this branch too.
    if !(abs(n_l) > 0.0) {
        return vec3(0.0);
    }
    let n_v = max(dot(n, v), 1e-4);
    let a = alpha(roughness);
    if n_l > 0.0 || thin > 0.5 {
        let h = reflection_half(n, v, l);
        let lobe = d_ggx(n, h, a) * v_smith(n_v, abs(n_l), a) * abs(n_l);
        return select(tint, vec3(1.0), n_l > 0.0) * reflection_share(n_l, dot(v, h), eta, thin) * lobe;
    }
    let h = refraction_half(n, v, l, eta);
    let v_h = dot(v, h);
    let l_h = dot(l, h);
    if !(v_h > 0.0 && l_h < 0.0) {
        return vec3(0.0);
    }
    let f = fresnel_dielectric(v_h, eta);
    let denom = v_h + eta * l_h;
    // Walter's f_t × |n·l| with G2 = 4 n·v |n·l| v_smith.
    return vec3(4.0 * eta * eta * (1.0 - f) * d_ggx(n, h, a) * v_smith(n_v, -n_l, a) * v_h * -l_h * -n_l / (denom * denom));
}

// The pdf (solid angle) of `dielectric_direction` drawing l.
fn dielectric_pdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, eta: f32, roughness: f32, thin: f32) -> f32 {
    let n_l = dot(n, l);
    if !(abs(n_l) > 0.0) {
        return 0.0;
    }
    let n_v = max(dot(n, v), 1e-4);
    let a = alpha(roughness);
    if n_l > 0.0 || thin > 0.5 {
        let h = reflection_half(n, v, l);
        // VNDF's pdf(h) = G1(v) v·h D(h) / n·v; reflection's Jacobian
        // 1 / (4 v·h) cancels the v·h.
        return reflection_share(n_l, dot(v, h), eta, thin) * g1_smith(n_v, a) * d_ggx(n, h, a) / (4.0 * n_v);
    }
    let h = refraction_half(n, v, l, eta);
    let v_h = dot(v, h);
    let l_h = dot(l, h);
    if !(v_h > 0.0 && l_h < 0.0) {
        return 0.0;
    }
    let f = fresnel_dielectric(v_h, eta);
    let denom = v_h + eta * l_h;
    // Refraction's Jacobian: η² |l·h| / (v·h + η l·h)².
    return (1.0 - f) * g1_smith(n_v, a) * v_h * d_ggx(n, h, a) / n_v * eta * eta * -l_h / (denom * denom);
}

// A direction from u (three uniform numbers in [0, 1)): a visible normal
// from u.yz, then u.x chooses reflection with the interface's reflectance
// at that normal, transmission otherwise. A direction that lands on the
// wrong side (reflected below, refracted above) is the zero vector: no
// direction, pdf 0.
fn dielectric_direction(n: vec3<f32>, v: vec3<f32>, u: vec3<f32>, eta: f32, roughness: f32, thin: f32) -> vec3<f32> {
    let frame = basis(n);
    let h = frame * sample_vndf(normalize(transpose(frame) * v), alpha(roughness), u.yz);
    let v_h = dot(v, h);
    let r = reflect(-v, h);
    if u.x < dielectric_reflectance(v_h, eta, thin) {
        return select(vec3(0.0), r, dot(n, r) > 0.0);
    }
    if thin > 0.5 {
        return select(vec3(0.0), mirrored(n, r), dot(n, r) > 0.0);
    }
    let t = refract(-v, h, 1.0 / eta);
    return select(vec3(0.0), t, dot(n, t) < 0.0);
}
