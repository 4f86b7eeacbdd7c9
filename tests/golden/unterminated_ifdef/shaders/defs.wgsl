@fragment
fn fs_main() -> @location(0) vec4<f32> {
#ifdef FANCY
    return vec4(2.0);
#else
    return vec4(1.0);
}
