enable wgpu_debug_printf;

struct Light { color: vec3<f32>, power: f32 }

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let light = Light(vec3(1.0), 2.0);
    debugPrintf("power %f, color %f", light.power, light.color);
    debugPrintf("the light %f", light);
    return p;
}
