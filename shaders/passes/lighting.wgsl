// Deferred lighting: every light on every G-buffer pixel, with shadows,
// the media's shadows on surfaces, and rect lights integrated with LTC
// (LIGHT_RECT) or by sampling their area (RECT_SAMPLED, the reference).
// The environment lights every surface; pixels without geometry show it.
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::view::{view, world_position}
#import loupe::lights::{Light, lights, incident, light_type, rect_area, rect_cosine, LIGHT_RECT}
#import loupe::environment::environment_radiance
#import loupe::material::{Surface, MaterialPoint, material_point, material_init_at, material_eval, material_ambient, material_emission}
#ifdef SHADOWS
#import loupe::shadows::shadow
#endif
#ifdef MEDIA_SHADOWS
#import loupe::media::transmittance
#endif
#ifdef LIGHT_RECT
#import loupe::material::material_rect
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

@group(0) @binding(2) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(3) var gbuffer_uv: texture_2d<f32>;
@group(0) @binding(4) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(5) var depth: texture_depth_2d;
@group(0) @binding(6) var dfg: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

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

#ifdef MATERIAL_POINT
// Where the material is evaluated: the G-buffer's UV with its derivatives
// across the 2×2 quad (for the textures' mip level) and a tangent from the
// derivatives of position and UV (the G-buffer stores none). Derivatives
// must be taken in uniform control flow: this runs before any branch. They
// are zero (the finest level, a flat normal map) where a neighbour in the
// quad is another instance, the background, or across a depth jump.
fn material_point_at(pixel: vec2<i32>, position: vec2<f32>, z: f32, n: vec3<f32>, instance: f32) -> MaterialPoint {
    let uv = textureLoad(gbuffer_uv, pixel, 0).xy;
    let p = world_position(position, z);
    let distance = length(p - view.position.xyz);
    let duv = mat2x2(dpdx(uv), dpdy(uv));
    let dp = mat2x3(dpdx(p), dpdy(p));
    let other = abs(dpdx(instance)) + abs(dpdy(instance)) + abs(dpdx(f32(z >= 1.0))) + abs(dpdy(f32(z >= 1.0)));
    let jump = max(abs(dpdx(distance)), abs(dpdy(distance))) > 0.05 * distance;
    if other > 0.0 || jump {
        return MaterialPoint(uv, vec2(0.0), vec2(0.0), vec4(0.0));
    }
    // The cotangent frame: the direction of growing u in the surface.
    let dp_y = cross(dp[1], n);
    let dp_x = cross(n, dp[0]);
    // Its scale is 1/det of the quad's UV Jacobian, whose sign flips where
    // the screen's axes (y down) wind against the normal: the gradients of
    // u and v, not their negations.
    let facing = select(-1.0, 1.0, dot(cross(dp[0], dp[1]), n) >= 0.0);
    let t = (dp_y * duv[0].x + dp_x * duv[1].x) * facing;
    let b = (dp_y * duv[0].y + dp_x * duv[1].y) * facing;
    // Handedness as the vertices carry it (mesh/mod.rs): the bitangent
    // cross(n, t) · w points up the image, against growing v.
    let sign = select(1.0, -1.0, dot(cross(n, t), b) > 0.0);
    let tangent = select(vec4(0.0), vec4(normalize(t), sign), dot(t, t) > 0.0);
    return MaterialPoint(uv, duv[0], duv[1], tangent);
}
#endif

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
    let z = textureLoad(depth, pixel, 0);
#ifdef MATERIAL_POINT
    let point = material_point_at(pixel, in.position.xy, z, normalize(textureLoad(gbuffer_normal, pixel, 0).xyz), textureLoad(gbuffer_material, pixel, 0).z);
#else
    // No material reads it (the generated module implies MATERIAL_POINT
    // when one does).
    let point = material_point(vec2(0.0), vec4(0.0));
#endif
    if z >= 1.0 {
        let p = world_position(in.position.xy, 1.0);
        return vec4(environment_radiance(normalize(p - view.position.xyz)), 1.0);
    }
    let n = normalize(textureLoad(gbuffer_normal, pixel, 0).xyz);
    let instance = u32(textureLoad(gbuffer_material, pixel, 0).z);
    let p = world_position(in.position.xy, z);
    let v = normalize(view.position.xyz - p);
    let s = material_init_at(instance, n, v, point);

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
    return vec4(color, 1.0);
}
