// The denoiser's input rule, as OIDN applies it (`process::sanitize` in the
// CPU reference): NaN becomes 0, everything is clamped to the range the
// input may hold (+Inf to the largest float).
#define_import_path loupe::sanitize

const F32_MAX: f32 = 3.40282347e+38;

// By the bits: a compiler may fold `v != v` away.
fn is_nan(v: f32) -> bool {
    return (bitcast<u32>(v) & 0x7fffffffu) > 0x7f800000u;
}

fn sanitize(v: f32, lo: f32, hi: f32) -> f32 {
    if is_nan(v) {
        return 0.0;
    }
    return clamp(v, lo, hi);
}

fn sanitize3(v: vec3<f32>, lo: f32, hi: f32) -> vec3<f32> {
    return vec3(sanitize(v.x, lo, hi), sanitize(v.y, lo, hi), sanitize(v.z, lo, hi));
}
