enable wgpu_debug_printf;

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let x = debugPrintf("%f", p.x);
    debugPrintf("unterminated %f, p.x);
    return p;
}
