// Lights as the renderer uploads them, and the incident light they give at
// a point. Every light type shares one layout so one loop handles them all.
#define_import_path loupe::lights

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;
const LIGHT_RECT: u32 = 3u;

struct Light {
    // rgb: colour × intensity; w: type (LIGHT_*).
    color: vec4<f32>,
    // xyz: position (unused for directional); w: first shadow-map layer, or -1.
    position: vec4<f32>,
    // xyz: unit direction the light points; w: cos(outer cone) for spots.
    direction: vec4<f32>,
    // spot: x = cos(inner cone). rect: x, y = half width, half height; z = two-sided.
    extra: vec4<f32>,
    // rect: unit axes spanning the emitter (width along right, height along up).
    right: vec4<f32>,
    up: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> lights: array<Light>;

fn light_type(light: Light) -> u32 {
    return u32(light.color.w);
}

struct Incident {
    // Unit direction from the point toward the light.
    l: vec3<f32>,
    distance: f32,
    radiance: vec3<f32>,
}

// Distances are clamped so a point on (or in) a light never divides by zero.
const MIN_DISTANCE: f32 = 0.01;

// A rect light's area.
fn rect_area(light: Light) -> f32 {
    return 4.0 * light.extra.x * light.extra.y;
}

// The cosine a rect light sees `dir` (from the shading point) at, or 0 when
// its back faces that way and it is one-sided.
fn rect_cosine(light: Light, dir: vec3<f32>) -> f32 {
    let facing = dot(-dir, light.direction.xyz);
    return select(max(facing, 0.0), abs(facing), light.extra.z > 0.5);
}

// Light arriving at `p` from a light treated as a point (or direction). Rect
// lights are approximated by their centre here; the lighting pass integrates
// them exactly with LTC.
fn incident(light: Light, p: vec3<f32>) -> Incident {
    let kind = light_type(light);
    if kind == LIGHT_DIRECTIONAL {
        return Incident(-light.direction.xyz, 1e30, light.color.rgb);
    }
    let to_light = light.position.xyz - p;
    let d = max(length(to_light), MIN_DISTANCE);
    let l = to_light / d;
    var radiance = light.color.rgb / (d * d);
    if kind == LIGHT_SPOT {
        let cos_angle = dot(-l, light.direction.xyz);
        radiance *= smoothstep(light.direction.w, light.extra.x, cos_angle);
    } else if kind == LIGHT_RECT {
        radiance *= rect_area(light) * rect_cosine(light, l);
    }
    return Incident(l, d, radiance);
}
