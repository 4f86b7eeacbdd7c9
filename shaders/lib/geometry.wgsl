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
    // glTF's: origin at the image's top left, v down.
    @location(2) uv: vec2<f32>,
    // xyz: unit, along increasing u; w = ±1: the bitangent
    // cross(normal, tangent.xyz) * w points up the image (decreasing v).
    @location(3) tangent: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> objects: array<Object>;

fn world_position(v: Vertex, object: u32) -> vec4<f32> {
    return objects[object].model * vec4(v.position, 1.0);
}

fn world_normal(v: Vertex, object: u32) -> vec3<f32> {
    return normalize((objects[object].normal * vec4(v.normal, 0.0)).xyz);
}

// The tangent in world space: a direction on the surface, so it moves with
// the model matrix (normals take its inverse transpose). A mirroring model
// matrix flips the handedness, as the bitangent it implies must still be
// the model matrix times the object-space one.
fn world_tangent(v: Vertex, object: u32) -> vec4<f32> {
    let m = objects[object].model;
    let linear = mat3x3(m[0].xyz, m[1].xyz, m[2].xyz);
    let mirrored = determinant(linear) < 0.0;
    return vec4(normalize(linear * v.tangent.xyz), select(v.tangent.w, -v.tangent.w, mirrored));
}
