// Objects as the renderer uploads them. Each draw is one
// object: its index arrives as the instance index, so no per-draw binding
// changes are needed.
#define_import_path loupe::geometry

struct Object {
    model: mat4x4<f32>,
    // Inverse transpose of the model matrix, for normals.
    normal: mat4x4<f32>,
    // x: material index (the instance `loupe::material` reads).
    ids: vec4<u32>,
}

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

@group(0) @binding(1) var<storage, read> objects: array<Object>;

fn world_position(v: Vertex, object: u32) -> vec4<f32> {
    return objects[object].model * vec4(v.position, 1.0);
}

fn world_normal(v: Vertex, object: u32) -> vec3<f32> {
    return normalize((objects[object].normal * vec4(v.normal, 0.0)).xyz);
}
