// The camera and frame constants every scene pass binds at group 0,
// binding 0, and the conversions between pixels, depth and world space.
#define_import_path loupe::view

struct View {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // xyz: camera position; w: near plane distance.
    position: vec4<f32>,
    // xy: target size in pixels; z: far plane distance; w: the shadow
    // filter's radius in texels (`loupe::shadows`).
    params: vec4<f32>,
    // x: lights, y: media, z: volume steps, w: volume shadow steps.
    counts: vec4<u32>,
    // rgb: the environment's radiance straight up and straight down, times
    // its intensity (`loupe::environment`); w: unused.
    environment_top: vec4<f32>,
    environment_bottom: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

// World position of a pixel centre at a depth-buffer value (0 near, 1 far).
fn world_position(pixel: vec2<f32>, depth: f32) -> vec3<f32> {
    let ndc = vec2(pixel.x / view.params.x * 2.0 - 1.0, 1.0 - pixel.y / view.params.y * 2.0);
    let p = view.inv_view_proj * vec4(ndc, depth, 1.0);
    return p.xyz / p.w;
}

// Unit direction from the camera through a pixel centre.
fn camera_ray(pixel: vec2<f32>) -> vec3<f32> {
    return normalize(world_position(pixel, 1.0) - view.position.xyz);
}
