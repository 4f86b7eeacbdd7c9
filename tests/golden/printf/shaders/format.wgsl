enable wgpu_debug_printf;

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    // A comment may say debugPrintf("%q") without being read.
    debugPrintf("p = %v2f, depth = %q", p.xy, p.z);
    return p;
}
