#import demo::nowhere::thing

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4(1.0);
}
