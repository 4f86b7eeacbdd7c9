// The surface BRDF: Lambert diffuse plus GGX specular with the height-
// correlated Smith visibility term and Schlick's Fresnel. Metals tint the
// specular with the base colour and have no diffuse.
#define_import_path loupe::brdf

const PI: f32 = 3.14159265358979;

// GGX normal distribution; `a` is roughness squared (alpha).
fn d_ggx(n_h: f32, a: f32) -> f32 {
    let a2 = a * a;
    let d = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Smith-GGX visibility, height-correlated: G / (4 n·l n·v).
fn v_smith(n_v: f32, n_l: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = n_l * sqrt(n_v * n_v * (1.0 - a2) + a2);
    let gl = n_v * sqrt(n_l * n_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-7);
}

fn f_schlick(f0: vec3<f32>, v_h: f32) -> vec3<f32> {
    return f0 + (1.0 - f0) * pow(1.0 - v_h, 5.0);
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
    let n_l = dot(n, l);
    if n_l <= 0.0 {
        return vec3(0.0);
    }
    let h = normalize(v + l);
    let n_v = max(dot(n, v), 1e-4);
    let n_h = max(dot(n, h), 0.0);
    let a = alpha(roughness);
    let f = f_schlick(specular_f0(base_color, metallic), max(dot(v, h), 0.0));
    let specular = d_ggx(n_h, a) * v_smith(n_v, n_l, a) * f;
    let diffuse = (1.0 - metallic) * (1.0 - f) * base_color / PI;
    return (diffuse + specular) * n_l;
}
