@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    debugPrintf("x = %f", p.x);
    return p;
}
