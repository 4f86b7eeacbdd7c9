enable wgpu_debug_printf;

@compute @workgroup_size(8, 8)
fn cs(@builtin(global_invocation_id) id: vec3<u32>) {
    debugPrintf("id = %v3u, lane = %u",
                id);
}
