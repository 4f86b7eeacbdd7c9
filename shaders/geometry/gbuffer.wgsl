// Base pass: writes the G-buffer. Layout (exact in the inspector):
//   normal:   Rgba16Float, xyz world-space unit normal, w = 1 where geometry
//             was drawn
//   albedo:   Rgba16Float, rgb base colour, a = metallic (the material's
//             closures' values by weight, `material_base_color`: what the
//             debug views show)
//   material: Rgba16Float, x = roughness, y = metallic, z = material index
//             (the instance the lighting pass evaluates), w = shading model
//             (1 = standard lit; the material header later layers grow)
//   uv:       Rg32Float, xy = the vertex UV (glTF's, v down), interpolated
// 32 bytes per pixel in all.
#import loupe::geometry::{Vertex, objects, world_position, world_normal, world_tangent}
#import loupe::view::view
#import loupe::material::{MaterialPoint, material_init_at, material_base_color, material_metallic, material_roughness}

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) @interpolate(flat) object: u32,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
}

struct GBuffer {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) material: vec4<f32>,
    @location(3) uv: vec2<f32>,
}

@vertex
fn vs_main(v: Vertex, @builtin(instance_index) object: u32) -> Varyings {
    return Varyings(view.view_proj * world_position(v, object), world_normal(v, object), object, v.uv, world_tangent(v, object));
}

@fragment
fn fs_main(in: Varyings, @builtin(front_facing) front: bool) -> GBuffer {
    let id = objects[in.object].ids.x;
    // Planes and open meshes are seen from both sides: face the viewer.
    let n = normalize(in.normal) * select(-1.0, 1.0, front);
    // Seen along the normal: the summaries do not depend on the view.
    // Derivatives before any branch (the material's switch is one).
    let point = MaterialPoint(in.uv, dpdx(in.uv), dpdy(in.uv), in.tangent);
    let s = material_init_at(id, n, n, point);
    let metallic = material_metallic(s);
    return GBuffer(
        vec4(n, 1.0),
        vec4(material_base_color(s), metallic),
        vec4(material_roughness(s), metallic, f32(id), 1.0),
        in.uv,
    );
}
