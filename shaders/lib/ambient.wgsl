// Light from a gradient environment, L(d) = mix(bottom, top, d.y * 0.5 + 0.5)
// for a unit direction d, on a surface with the BRDF of `loupe::brdf`: the
// radiance itself, the diffuse irradiance in closed form and the split-sum
// specular (Karis 2013) with the pre-integrated table of `render/dfg.rs`.
// Pure functions of their arguments (no bindings), so tests run them alone;
// `loupe::environment` applies them to the scene's environment.
#define_import_path loupe::ambient

#import loupe::ltc::{ltc_fetch, ltc_table_coord}

const AMBIENT_PI: f32 = 3.14159265358979;

fn gradient_radiance(top: vec3<f32>, bottom: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    return mix(bottom, top, d.y * 0.5 + 0.5);
}

// Cosine-weighted irradiance at unit normal n. Write L(d) = a + b d.y with
// a = (top + bottom) / 2, b = (top - bottom) / 2. Over the hemisphere H(n),
//     E(n) = ∫_H L(l) (n·l) dl = a ∫_H (n·l) dl + b · (∫_H l (n·l) dl).y.
// ∫_H (n·l) dl = π. By symmetry about n, ∫_H l (n·l) dl points along n, with
// length ∫_H (n·l)² dl = 2π ∫_0^{π/2} cos²θ sinθ dθ = 2π/3. So
//     E(n) = π a + (2π/3) b n.y,
// and a Lambertian surface sends albedo/π · E = albedo (a + (2/3) b n.y).
fn gradient_irradiance(top: vec3<f32>, bottom: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let a = 0.5 * (top + bottom);
    let b = 0.5 * (top - bottom);
    return AMBIENT_PI * a + (2.0 * AMBIENT_PI / 3.0) * b * n.y;
}

// The split sum's pre-filtered radiance along the reflection vector r: the
// GGX lobe around n = v = r averages l to k·r (`render/dfg.rs`), so a linear
// gradient pre-filters exactly to a + b k r.y.
fn gradient_prefiltered(top: vec3<f32>, bottom: vec3<f32>, r: vec3<f32>, k: f32) -> vec3<f32> {
    return gradient_radiance(top, bottom, vec3(0.0, k * r.y, 0.0));
}

// The pre-integrated GGX table at (n·v, roughness): x = scale and y = bias
// of f0 (∫ f (n·l) dl = f0 x + y), z = the prefilter factor k. Laid out as
// the LTC tables, so it is read with their bilinear fetch.
fn dfg(table: texture_2d<f32>, n_v: f32, roughness: f32) -> vec3<f32> {
    return ltc_fetch(table, ltc_table_coord(roughness, n_v)).xyz;
}

// Outgoing radiance toward v from the environment's light: Lambert diffuse
// of the irradiance plus the split-sum specular. Surfaces are not shadowed
// from the environment.
fn ambient_light(top: vec3<f32>, bottom: vec3<f32>, n: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, metallic: f32, f0: vec3<f32>, roughness: f32, table: texture_2d<f32>) -> vec3<f32> {
    let n_v = max(dot(n, v), 1e-4);
    let t = dfg(table, n_v, roughness);
    let r = reflect(-v, n);
    let diffuse = (1.0 - metallic) * base_color / AMBIENT_PI * gradient_irradiance(top, bottom, n);
    let specular = (f0 * t.x + t.y) * gradient_prefiltered(top, bottom, r, t.z);
    return diffuse + specular;
}
