// Shadow maps: one depth layer per directional, spot or rect light, six
// (a cube, face by dominant axis) per point light, all in one array at
// group 1. Filtered with a (2r + 1)² PCF of exact loads, r the view's
// `quality.shadow_filter`: no comparison sampler.
#define_import_path loupe::shadows

#import loupe::lights::{Light, LIGHT_POINT, light_type}
#import loupe::view::view

@group(1) @binding(0) var shadow_maps: texture_depth_2d_array;
@group(1) @binding(1) var<storage, read> shadow_views: array<mat4x4<f32>>;

fn cube_face(d: vec3<f32>) -> i32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1, 0, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3, 2, d.y > 0.0);
    }
    return select(5, 4, d.z > 0.0);
}

// Where `p` falls in its light's shadow map: (texel, depth, layer), or a
// negative layer when outside every map (lit).
fn shadow_lookup(light: Light, p: vec3<f32>) -> vec4<f32> {
    var layer = i32(light.position.w);
    if layer < 0 {
        return vec4(0.0, 0.0, 0.0, -1.0);
    }
    if light_type(light) == LIGHT_POINT {
        layer += cube_face(p - light.position.xyz);
    }
    let clip = shadow_views[layer] * vec4(p, 1.0);
    let ndc = clip.xyz / clip.w;
    if clip.w <= 0.0 || any(abs(ndc.xy) > vec2(1.0)) || ndc.z > 1.0 {
        return vec4(0.0, 0.0, 0.0, -1.0);
    }
    let size = vec2<f32>(textureDimensions(shadow_maps));
    return vec4((ndc.xy * vec2(0.5, -0.5) + 0.5) * size, ndc.z - 0.0005, f32(layer));
}

// One unfiltered tap: for ray-march samples, where the march itself
// averages many lookups and PCF would cost nine times as much.
fn shadow_hard(light: Light, p: vec3<f32>) -> f32 {
    let at = shadow_lookup(light, p);
    if at.w < 0.0 {
        return 1.0;
    }
    let size = vec2<i32>(textureDimensions(shadow_maps));
    let c = clamp(vec2<i32>(at.xy), vec2(0), size - 1);
    return select(0.0, 1.0, at.z <= textureLoad(shadow_maps, c, i32(at.w), 0));
}

// Fraction of the light reaching `p` (1 = lit). `n` offsets the lookup
// along the normal, which hides acne on surfaces at grazing angles.
fn shadow(light: Light, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(shadow_maps));
    let offset = n * (2.0 / f32(size.x)) * max(1.0, length(p - light.position.xyz) * 0.5);
    let at = shadow_lookup(light, p + offset);
    if at.w < 0.0 {
        return 1.0;
    }
    let r = i32(view.params.w);
    var lit = 0.0;
    for (var y = -r; y <= r; y++) {
        for (var x = -r; x <= r; x++) {
            let c = clamp(vec2<i32>(at.xy) + vec2(x, y), vec2(0), size - 1);
            lit += select(0.0, 1.0, at.z <= textureLoad(shadow_maps, c, i32(at.w), 0));
        }
    }
    let taps = f32((2 * r + 1) * (2 * r + 1));
    return lit / taps;
}
