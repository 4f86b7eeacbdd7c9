// Base pass: writes the G-buffer. Layout (exact in the inspector):
//   normal:   Rgba16Float, xyz world-space unit normal, w = 1 where geometry
//             was drawn
//   albedo:   Rgba16Float, rgb base colour, a = metallic
//   material: Rgba16Float, x = roughness, y = metallic, z = material index,
//             w = shading model (1 = standard lit; the material header later
//             layers grow)
//   uv:       Rg32Float, xy = the vertex UV (glTF's, v down), interpolated
// 32 bytes per pixel in all.
#import loupe::geometry::{Vertex, Material, objects, world_position, world_normal}
#import loupe::view::view

@group(0) @binding(2) var<storage, read> materials: array<Material>;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) @interpolate(flat) object: u32,
    @location(2) uv: vec2<f32>,
}

struct GBuffer {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) material: vec4<f32>,
    @location(3) uv: vec2<f32>,
}

@vertex
fn vs_main(v: Vertex, @builtin(instance_index) object: u32) -> Varyings {
    return Varyings(view.view_proj * world_position(v, object), world_normal(v, object), object, v.uv);
}

@fragment
fn fs_main(in: Varyings, @builtin(front_facing) front: bool) -> GBuffer {
    let id = objects[in.object].ids.x;
    let m = materials[id];
    // Planes and open meshes are seen from both sides: face the viewer.
    let n = normalize(in.normal) * select(-1.0, 1.0, front);
    return GBuffer(
        vec4(n, 1.0),
        m.base_color,
        vec4(m.params.x, m.base_color.a, f32(id), 1.0),
        in.uv,
    );
}
