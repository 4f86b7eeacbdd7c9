// Fuzz (sheen): a layer of fibres over a slab, as a microfacet lobe with
// the "Charlie" distribution of Estevez and Kulla ("Production Friendly
// Microfacet Sheen BRDF", 2017), D(h) = (2 + 1/α) sin(θh)^(1/α) / 2π with
// α = roughness², and Ashikhmin's visibility 1 / (4 (n·l + n·v - n·l n·v)),
// which needs no table. That visibility gains energy at grazing views
// when the fibres are sharp: the lobe's directional albedo at n·v = 0.001
// is 11.5 at roughness 0.001, 1.40 at 0.3, 1.10 at 0.4 and 0.93 at 0.5
// (Monte Carlo, 4M directions; the stability suite's chi-square test
// found it at 5.5). Until an albedo table normalises the lobe, roughness
// below FUZZ_ROUGHNESS_MIN is taken as it. Only materials with fuzz
// import this module.
#define_import_path loupe::fuzz

const FUZZ_PI: f32 = 3.14159265358979;
const FUZZ_ROUGHNESS_MIN: f32 = 0.5;

// The fuzz lobe × cosine for light from `l`, seen from `v` (no colour).
fn fuzz_cos(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, roughness: f32) -> f32 {
    let n_l = dot(n, l);
    if !(n_l > 0.0) {
        return 0.0;
    }
    let n_v = max(dot(n, v), 1e-4);
    let h = normalize(v + l);
    let r = max(roughness, FUZZ_ROUGHNESS_MIN);
    let inv_a = 1.0 / (r * r);
    let cos_h = clamp(dot(n, h), 0.0, 1.0);
    let sin_h = sqrt(max(1.0 - cos_h * cos_h, 0.0));
    let d = (2.0 + inv_a) * pow(sin_h, inv_a) / (2.0 * FUZZ_PI);
    let vis = 1.0 / (4.0 * (n_l + n_v - n_l * n_v));
    return d * vis * n_l;
}
