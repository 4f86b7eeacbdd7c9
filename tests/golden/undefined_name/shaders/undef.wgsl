struct Light {
    color: vec3<f32>,
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    let l = Light(vec3(1.0));
    return vec4(l.colour, 1.0);
}
