// Deferred lighting: every light on every G-buffer pixel, with shadows,
// the media's shadows on surfaces, and rect lights integrated with LTC
// (LIGHT_RECT) or by sampling their area (RECT_SAMPLED, the reference).
// The environment lights every surface; pixels without geometry show it.
// One workgroup lights one 8×8 tile of one class's list (the classify
// pass's). SIMPLE_CLASS compiles against `loupe::material_simple`
// (one closure, no optional feature): the simple tiles' specialisation;
// SINGLE_CLASS against `loupe::material_single` (one closure, the
// one-closure materials' features): the single tiles'.
#import loupe::view::{view, world_position}
#import loupe::lights::{Light, lights, incident, light_type, rect_area, rect_cosine, LIGHT_RECT}
#import loupe::environment::environment_radiance
#import loupe::tiles::{STATS_TILES, tile_count, tile_origin}
#ifdef SIMPLE_CLASS
#import loupe::material_simple::{Surface, MATERIAL_WORDS, material_word_count, material_unpack, material_eval, material_ambient, material_emission}
#else ifdef SINGLE_CLASS
#import loupe::material_single::{Surface, MATERIAL_WORDS, material_word_count, material_unpack, material_eval, material_ambient, material_emission}
#else
#import loupe::material::{Surface, MATERIAL_WORDS, material_word_count, material_unpack, material_eval, material_ambient, material_emission}
#endif
#ifdef SHADOWS
#import loupe::shadows::shadow
#endif
#ifdef MEDIA_SHADOWS
#import loupe::media::transmittance
#endif
#ifdef LIGHT_RECT
#ifdef SIMPLE_CLASS
#import loupe::material_simple::material_rect
#else ifdef SINGLE_CLASS
#import loupe::material_single::material_rect
#else
#import loupe::material::material_rect
#endif
@group(2) @binding(0) var ltc_matrix: texture_2d<f32>;
@group(2) @binding(1) var ltc_amplitude: texture_2d<f32>;
#endif

#ifdef RECT_SAMPLED
// Points per side of the grid over a rect light.
const RECT_GRID: u32 = 16u;

// A rect light's reflected radiance by a stratified grid of points over
// its area, each through the material itself: Σ L f cos_light A / (N² d²).
fn rect_sampled(light: Light, n: vec3<f32>, v: vec3<f32>, p: vec3<f32>, s: Surface) -> vec3<f32> {
    let half = light.extra.xy;
    var sum = vec3(0.0);
    for (var j = 0u; j < RECT_GRID; j++) {
        for (var i = 0u; i < RECT_GRID; i++) {
            let uv = (vec2(f32(i), f32(j)) + 0.5) / f32(RECT_GRID) * 2.0 - 1.0;
            let q = light.position.xyz + light.right.xyz * (uv.x * half.x) + light.up.xyz * (uv.y * half.y);
            let to_light = q - p;
            let d2 = max(dot(to_light, to_light), 1e-8);
            let l = to_light * inverseSqrt(d2);
            sum += material_eval(s, n, v, l) * (rect_cosine(light, l) / d2);
        }
    }
    return light.color.rgb * sum * (rect_area(light) / f32(RECT_GRID * RECT_GRID));
}
#endif

@group(0) @binding(5) var depth: texture_depth_2d;
@group(0) @binding(6) var dfg: texture_2d<f32>;
// The G-buffer's material buffer (`geometry/gbuffer.wgsl`): with depth,
// all the lighting reads of the surface.
@group(0) @binding(14) var<storage, read> material_words: array<u32>;
@group(0) @binding(15) var lit: texture_storage_2d<rgba16float, write>;
// The classify pass's tile lists and statistics (tiles per class), and
// which class this pass lights (x).
@group(4) @binding(0) var<storage, read> tile_lists: array<u32>;
@group(4) @binding(1) var<storage, read> tile_stats: array<u32>;
@group(4) @binding(2) var<uniform> tile_class: vec4<u32>;

// How much of a light reaches `p`: occluders' shadow maps times the media's
// transmittance toward the light.
fn visibility(light: Light, p: vec3<f32>, n: vec3<f32>, l: vec3<f32>, distance: f32) -> vec3<f32> {
    var v = vec3(1.0);
#ifdef SHADOWS
    v *= shadow(light, p, n);
#endif
#ifdef MEDIA_SHADOWS
    v *= transmittance(p, l, min(distance, view.params.z), max(view.counts.w, 1u));
#endif
    return v;
}

// The words of the pixel: its header, then only as many more as the
// header says it has.
fn load_words(pixel: vec2<i32>) -> array<u32, MATERIAL_WORDS> {
    let width = u32(view.params.x);
    let plane = width * u32(view.params.y);
    let i = u32(pixel.y) * width + u32(pixel.x);
    var words: array<u32, MATERIAL_WORDS>;
    words[0] = material_words[i];
    let count = min(material_word_count(words[0]), MATERIAL_WORDS);
    for (var k = 1u; k < count; k++) {
        words[k] = material_words[k * plane + i];
    }
    return words;
}

@compute @workgroup_size(8, 8)
fn light(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let size = textureDimensions(depth);
    let kind = tile_class.x;
    let count = tile_stats[STATS_TILES + kind];
    // More tiles than one dispatch's workgroups: each takes every
    // groups.x-th.
    for (var t = group.x; t < count; t += groups.x) {
        let tile = tile_lists[kind * tile_count(size) + t];
        shade_at(tile_origin(tile, size) + local.xy, size);
    }
}

fn shade_at(pixel: vec2<u32>, size: vec2<u32>) {
    if any(pixel >= size) {
        return;
    }
    textureStore(lit, pixel, vec4(shade(pixel), 1.0));
}

// The lit colour of one pixel.
fn shade(texel: vec2<u32>) -> vec3<f32> {
    let pixel = vec2<i32>(texel);
    let centre = vec2<f32>(texel) + 0.5;
    let z = textureLoad(depth, pixel, 0);
    if z >= 1.0 {
        let p = world_position(centre, 1.0);
        return environment_radiance(normalize(p - view.position.xyz));
    }
    let p = world_position(centre, z);
    let v = normalize(view.position.xyz - p);
    let unpacked = material_unpack(load_words(pixel), v);
    let s = unpacked.surface;
    let n = unpacked.normal;

    var color = material_ambient(s, n, v, view.environment_top.rgb, view.environment_bottom.rgb, dfg) + material_emission(s);
    for (var i = 0u; i < view.counts.x; i++) {
        let light = lights[i];
#ifdef LIGHT_RECT
        if light_type(light) == LIGHT_RECT {
            let c = light.position.xyz;
            let rx = light.right.xyz * light.extra.x;
            let ry = light.up.xyz * light.extra.y;
            let corners = array<vec3<f32>, 4>(c - rx - ry, c + rx - ry, c + rx + ry, c - rx + ry);
            let lit = material_rect(s, n, v, p, corners, light.extra.z > 0.5, ltc_matrix, ltc_amplitude);
            let to_light = c - p;
            let seen = visibility(light, p, n, normalize(to_light), length(to_light));
            color += light.color.rgb * lit * seen;
            continue;
        }
#endif
#ifdef RECT_SAMPLED
        if light_type(light) == LIGHT_RECT {
            let to_light = light.position.xyz - p;
            color += rect_sampled(light, n, v, p, s) * visibility(light, p, n, normalize(to_light), length(to_light));
            continue;
        }
#endif
        let inc = incident(light, p);
        let seen = visibility(light, p, n, inc.l, inc.distance);
        color += inc.radiance * material_eval(s, n, v, inc.l) * seen;
    }
    return color;
}
