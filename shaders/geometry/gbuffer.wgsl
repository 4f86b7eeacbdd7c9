// Base pass: writes the G-buffer.
//
// The material buffer `material_words` is what the lighting reads (with
// depth, and nothing else): per pixel, the material after `init` (its
// textures sampled here, with this pass's derivatives and the vertex
// tangent; the view-dependent parts at this pixel's view direction),
// quantised by `material_pack` into the smallest storage class that holds
// it: simple 16 B, single 8 B + 16 B and its features' words, complex the
// same per closure (docs/materials.md "Storage classes"). Word k of pixel i
// sits at k * width * height + i, so a pixel with few words touches few
// cache lines. Pixels without geometry write nothing.
//
// The inspection targets, for the inspector and the debug views (exact in
// the inspector), 32 bytes per pixel:
//   normal:   Rgba16Float, xyz world-space unit normal, w = 1 where geometry
//             was drawn
//   albedo:   Rgba16Float, rgb base colour, a = metallic (the material's
//             closures' values by weight, `material_base_color`: what the
//             debug views show)
//   material: Rgba16Float, x = roughness, y = metallic, z = material index
//             (the instance), w = shading model (1 = standard lit)
//   uv:       Rg32Float, xy = the vertex UV (glTF's, v down), interpolated
#import loupe::geometry::{Vertex, objects, world_position, world_normal, world_tangent}
#import loupe::view::view
#import loupe::material::{MaterialPoint, material_surface_at, material_pack_at, material_base_color, material_metallic, material_roughness}

@group(0) @binding(14) var<storage, read_write> material_words: array<u32>;
// The depth pre-pass's, attached read-only: a shader that writes storage
// runs for fragments the depth test then discards (no early test is
// guaranteed), so the words are written only where this fragment is the
// one the test keeps.
@group(0) @binding(15) var depth: texture_depth_2d;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) @interpolate(flat) object: u32,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @location(4) world: vec3<f32>,
}

struct GBuffer {
    @location(0) normal: vec4<f32>,
    @location(1) albedo: vec4<f32>,
    @location(2) material: vec4<f32>,
    @location(3) uv: vec2<f32>,
}

@vertex
fn vs_main(v: Vertex, @builtin(instance_index) object: u32) -> Varyings {
    let world = world_position(v, object);
    return Varyings(view.view_proj * world, world_normal(v, object), object, v.uv, world_tangent(v, object), world.xyz);
}

@fragment
fn fs_main(in: Varyings, @builtin(front_facing) front: bool) -> GBuffer {
    let id = objects[in.object].ids.x;
    // Planes and open meshes are seen from both sides: face the viewer.
    let n = normalize(in.normal) * select(-1.0, 1.0, front);
    let v = normalize(view.position.xyz - in.world);
    // Derivatives before any branch (the material's switch is one).
    let point = MaterialPoint(in.uv, dpdx(in.uv), dpdy(in.uv), in.tangent);
    // Before the energy compensation: the lighting redoes it when it
    // unpacks (the words keep F90 grey where the material has no tint).
    let s = material_surface_at(id, n, v, point);
    let pixel = vec2<u32>(in.position.xy);
    let width = u32(view.params.x);
    let plane = width * u32(view.params.y);
    let packed = material_pack_at(id, s, n, pixel);
    let visible = in.position.z <= textureLoad(depth, pixel, 0);
    for (var k = 0u; k < select(0u, packed.count, visible); k++) {
        material_words[k * plane + pixel.y * width + pixel.x] = packed.words[k];
    }
    let metallic = material_metallic(s);
    return GBuffer(
        vec4(n, 1.0),
        vec4(material_base_color(s), metallic),
        vec4(material_roughness(s), metallic, f32(id), 1.0),
        in.uv,
    );
}
