enable wgpu_debug_printf;

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    for (var i = 0; i < 3; i++) {
        debugPrintf("i = %d, p = %.2v4f, even = %u", i, p, i % 2 == 0);
    }
    return p;
}
