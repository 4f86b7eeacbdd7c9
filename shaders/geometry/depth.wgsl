// Depth prepass: fills the depth buffer so the G-buffer pass shades each
// pixel once (it tests for equality and writes no depth).
#import loupe::geometry::{Vertex, world_position}
#import loupe::view::view

@vertex
fn vs_main(v: Vertex, @builtin(instance_index) object: u32) -> @builtin(position) vec4<f32> {
    return view.view_proj * world_position(v, object);
}
