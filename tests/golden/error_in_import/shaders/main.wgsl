#import demo::util::scale

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4(scale(0.5));
}
