// Single scattering through the participating media, ray-marched from the
// camera to the first opaque surface at `volume_resolution` (one pixel of
// this pass's target per scale × scale pixels of the frame; `volumes`
// upsamples and composites). Each step scatters light from every light
// toward the camera, attenuated by the media between the step and the
// light (self-shadowing, read from the volume grid `volume_shadows`
// filled) and by the opaque occluders' shadow maps. Outputs the
// in-scattered light (a: the distance marched to, for the upsample's depth
// weights) and the camera-to-surface transmittance (a: the fraction of
// the march's steps that ran, 1 unless the driver cut the loop short).
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::view::{view, world_position, camera_ray}
#import loupe::lights::{lights, incident}
#import loupe::media::{coefficients, media_span}
#import loupe::volume_grid::{VolumeGrid, grid_index}
#ifdef SHADOWS
#import loupe::shadows::shadow_hard
#endif

// x: the scale, 1, 2 or 4.
@group(0) @binding(2) var<uniform> params: vec4<u32>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var<uniform> grid: VolumeGrid;
@group(0) @binding(5) var<storage, read> cells: array<vec4<f32>>;

struct Out {
    @location(0) scattered: vec4<f32>,
    @location(1) transmittance: vec4<f32>,
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

// Isotropic phase function.
const PHASE: f32 = 0.07957747; // 1 / (4π)

// The grid's transmittance toward `light` at `p`, trilinear between the
// eight points around it. Written out rather than looped: a loop here
// would run per light and per step.
fn grid_transmittance(light: u32, p: vec3<f32>) -> vec3<f32> {
    let last = grid.dims.xyz - 1u;
    let g = clamp((p - grid.lo.xyz) / grid.spacing.xyz, vec3(0.0), vec3<f32>(last));
    let c = min(vec3<u32>(g), last - 1u);
    let f = g - vec3<f32>(c);
    let i = grid_index(grid, light, c);
    let y = grid.dims.x;
    let z = grid.dims.x * grid.dims.y;
    let x00 = mix(cells[i].rgb, cells[i + 1u].rgb, f.x);
    let x10 = mix(cells[i + y].rgb, cells[i + y + 1u].rgb, f.x);
    let x01 = mix(cells[i + z].rgb, cells[i + z + 1u].rgb, f.x);
    let x11 = mix(cells[i + z + y].rgb, cells[i + z + y + 1u].rgb, f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

// Light scattered toward the camera at `p`, per unit σs.
fn in_scattered(p: vec3<f32>) -> vec3<f32> {
    var sum = vec3(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let inc = incident(lights[i], p);
        var seen = grid_transmittance(i, p);
#ifdef SHADOWS
        seen *= shadow_hard(lights[i], p);
#endif
        sum += inc.radiance * seen;
    }
    return sum * PHASE;
}

// Interleaved gradient noise: a per-pixel offset of the samples within
// their steps trades banding for fine noise, the same every frame so
// captures are stable.
fn jitter(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

@fragment
fn fs_main(in: FullscreenOut) -> Out {
    // The frame's pixel at the middle of this one's scale × scale block:
    // its ray and its depth (the same pixel at full resolution).
    let scale = params.x;
    let pixel = min(vec2<u32>(in.position.xy) * scale + scale / 2u, textureDimensions(depth) - 1u);
    let centre = vec2<f32>(pixel) + 0.5;
    let z = textureLoad(depth, pixel, 0);
    let origin = view.position.xyz;
    let dir = camera_ray(centre);
    var t_max = view.params.z;
    if z < 1.0 {
        t_max = length(world_position(centre, z) - origin);
    }
    let span = media_span(origin, dir, t_max);
    if span.x >= span.y {
        return Out(vec4(0.0, 0.0, 0.0, t_max), vec4(1.0));
    }
    // The span in `steps` equal steps, each sampled once at the same
    // jittered offset, so the steps tile the span exactly.
    let steps = max(view.counts.z, 1u);
    let dt = (span.y - span.x) / f32(steps);
    let offset = jitter(centre);
    var throughput = vec3(1.0);
    var radiance = vec3(0.0);
    var completed = 0u;
    for (var i = 0u; i < steps; i++) {
        let p = origin + dir * (span.x + (f32(i) + offset) * dt);
        let c = coefficients(p);
        if any(c.extinction > vec3(0.0)) || any(c.emission > vec3(0.0)) {
            let source = c.scattering * in_scattered(p) + c.emission;
            let step_t = exp(-c.extinction * dt);
#ifdef VOLUME_ANALYTIC
            // ∫0^dt S e^{-σt s} ds = S (1 - e^{-σt dt}) / σt, exact for
            // constant coefficients over the step; S·dt where σt → 0.
            let integral = select(source * dt, source * (1.0 - step_t) / c.extinction, c.extinction > vec3(1e-6));
#else
            // Left Riemann sum: over-counts in dense media at few steps.
            let integral = source * dt;
#endif
            radiance += throughput * integral;
            throughput *= step_t;
        }
        completed += 1u;
    }
    let ran = f32(completed) / f32(steps);
    return Out(vec4(radiance, t_max), vec4(throughput, ran));
}
