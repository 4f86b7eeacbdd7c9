// Single scattering through the participating media, ray-marched per pixel
// from the camera to the first opaque surface and composited over it.
// Each step scatters light from every light toward the camera, attenuated
// by the media between the step and the light (self-shadowing) and by the
// opaque occluders' shadow maps. Outputs the composited colour and the
// camera-to-surface transmittance.
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::view::{view, world_position, camera_ray}
#import loupe::lights::{lights, incident}
#import loupe::media::{coefficients, media_span, transmittance}
#ifdef SHADOWS
#import loupe::shadows::shadow_hard
#endif

@group(0) @binding(2) var opaque: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;

struct Out {
    @location(0) color: vec4<f32>,
    @location(1) transmittance: vec4<f32>,
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

// Isotropic phase function.
const PHASE: f32 = 0.07957747; // 1 / (4π)

// Light scattered toward the camera at `p`, per unit σs.
fn in_scattered(p: vec3<f32>) -> vec3<f32> {
    var sum = vec3(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let inc = incident(lights[i], p);
        var seen = transmittance(p, inc.l, min(inc.distance, view.params.z), max(view.counts.w, 1u));
#ifdef SHADOWS
        seen *= shadow_hard(lights[i], p);
#endif
        sum += inc.radiance * seen;
    }
    return sum * PHASE;
}

// Interleaved gradient noise: a per-pixel offset of the first step trades
// banding for fine noise, the same every frame so captures are stable.
fn jitter(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

@fragment
fn fs_main(in: FullscreenOut) -> Out {
    let pixel = vec2<i32>(in.position.xy);
    let background = textureLoad(opaque, pixel, 0);
    let z = textureLoad(depth, pixel, 0);
    let origin = view.position.xyz;
    let dir = camera_ray(in.position.xy);
    var t_max = view.params.z;
    if z < 1.0 {
        t_max = length(world_position(in.position.xy, z) - origin);
    }
    let span = media_span(origin, dir, t_max);
    if span.x >= span.y {
        return Out(background, vec4(1.0));
    }
    let steps = max(view.counts.z, 1u);
    let dt = (span.y - span.x) / f32(steps);
    var t = span.x + dt * jitter(in.position.xy);
    var throughput = vec3(1.0);
    var radiance = vec3(0.0);
    for (var i = 0u; i < steps; i++) {
        if t >= span.y {
            break;
        }
        let step = min(dt, span.y - t);
        let p = origin + dir * (t + 0.5 * step);
        let c = coefficients(p);
        if any(c.extinction > vec3(0.0)) || any(c.emission > vec3(0.0)) {
            let source = c.scattering * in_scattered(p) + c.emission;
            let step_t = exp(-c.extinction * step);
#ifdef VOLUME_ANALYTIC
            // ∫0^dt S e^{-σt s} ds = S (1 - e^{-σt dt}) / σt, exact for
            // constant coefficients over the step; S·dt where σt → 0.
            let integral = select(source * step, source * (1.0 - step_t) / c.extinction, c.extinction > vec3(1e-6));
#else
            // Left Riemann sum: over-counts in dense media at few steps.
            let integral = source * step;
#endif
            radiance += throughput * integral;
            throughput *= step_t;
        }
        t += step;
    }
    return Out(vec4(background.rgb * throughput + radiance, background.a), vec4(throughput, 1.0));
}
