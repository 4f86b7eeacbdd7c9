// Depth only, from a light: one draw per object per shadow-map layer.
#import loupe::geometry::{Vertex, world_position}

struct ShadowView {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> shadow_view: ShadowView;

@vertex
fn vs_main(v: Vertex, @builtin(instance_index) object: u32) -> @builtin(position) vec4<f32> {
    return shadow_view.view_proj * world_position(v, object);
}
