@fragment
fn fs_main() -> @location(0) vec4<f32> {
    let a = 1.0;
    let b = 2u;
    return vec4(a + b);
}
