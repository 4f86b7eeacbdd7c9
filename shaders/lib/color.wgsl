// Colour-space and tonemapping helpers shared by every pass.
#define_import_path loupe::color

// Rec. 709 / sRGB primaries luminance weights.
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3(2.4));
    return select(hi, lo, c <= vec3(0.04045));
}

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3(0.0031308));
}

// Reinhard on luminance, so hue is kept.
fn tonemap_reinhard(c: vec3<f32>) -> vec3<f32> {
    let l = luminance(c);
    return c / (1.0 + l);
}

// Narkowicz's fit of the ACES filmic curve (2015).
fn tonemap_aces(c: vec3<f32>) -> vec3<f32> {
    let a = 2.51;
    let b = 0.03;
    let d = 2.43;
    let e = 0.59;
    let f = 0.14;
    return clamp((c * (a * c + b)) / (c * (d * c + e) + f), vec3(0.0), vec3(1.0));
}
