enable wgpu_debug_printf;

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    debugPrintf("x = %f, y = %f", p.x, p.y);
    return p + 1u;
}
