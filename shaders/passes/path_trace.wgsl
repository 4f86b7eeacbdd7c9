// The reference: a progressive unidirectional path tracer over the very
// triangles, materials, lights and environment the raster renders, with
// the same BRDF module. One sample per pixel per frame is added to an f32
// history; the outputs are the running means (colour, and the first hit's
// albedo and normal for a denoiser) and the sample count. The albedo's
// alpha is the fraction of samples whose camera ray saw a rect light
// directly: the emitter mask of the page's path − raster difference (the
// raster draws no rect light).
//
// Light transport: at every surface or medium vertex, next-event
// estimation to every light (delta lights directly; rect lights by area
// and the environment by cosine, each weighed against BRDF sampling with
// the power heuristic), then a BRDF (or phase) sample continues the path;
// Russian roulette after three bounces. Media use the volume pass's
// density function: free flights by delta tracking against a majorant,
// shadow rays by ratio tracking.
//
// With a pixel selected (docs/printf.md), its sample of the frame prints
// a `path vertex` line at every vertex and a `path end` line where the
// path ends: the same path the frame accumulates, from the same random
// numbers. The sample's radiance is the sum over its lines of `emitted`,
// plus `throughput × nee` over the vertex lines.
enable wgpu_debug_printf;

#import loupe::view::{view, world_position}
#import loupe::lights::{Light, lights, incident, light_type, rect_area, rect_cosine, LIGHT_RECT}
#import loupe::brdf::{basis, cosine_direction, PI}
#import loupe::material_path::{Surface, material_init_at, material_point, material_eval, material_pdf, material_sample, material_emission, material_base_color}
#import loupe::environment::environment_radiance
#import loupe::random::{random_key, random_f32}
#import loupe::bvh::{trace, occluded, triangles, NO_HIT}
#ifdef MEDIA
#import loupe::media::{media, media_span, coefficients}
#endif
#ifdef MATERIAL_TRANSMISSION
#import loupe::material_path::{material_inside, material_medium}
#endif

struct Shading {
    // xyz: vertex normals (world); na.w: material index.
    na: vec4<f32>,
    nb: vec4<f32>,
    nc: vec4<f32>,
    // Vertex tangents (world): xyz unit, w = ±1 handedness, as
    // geometry.wgsl's `world_tangent`.
    ta: vec4<f32>,
    tb: vec4<f32>,
    tc: vec4<f32>,
    // Vertex UVs: a in xy, b in zw; c in uv_c.xy (zw unused).
    uv_ab: vec4<f32>,
    uv_c: vec4<f32>,
}

struct Accumulated {
    // rgb: radiance sum; w: samples.
    color: vec4<f32>,
    // rgb: first-hit albedo sum; w: samples that saw a rect light directly.
    albedo: vec4<f32>,
    normal: vec4<f32>,
}

@group(0) @binding(3) var<storage, read> shading: array<Shading>;
// x: samples per pixel to accumulate to; y: indirect bounces.
@group(0) @binding(4) var<uniform> params: vec4<u32>;
@group(0) @binding(5) var<storage, read_write> accumulated: array<Accumulated>;
@group(0) @binding(6) var out_color: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var out_albedo: texture_storage_2d<rgba16float, write>;
@group(0) @binding(8) var out_normal: texture_storage_2d<rgba16float, write>;
@group(0) @binding(9) var out_samples: texture_storage_2d<r32float, write>;

// Russian roulette starts after this many bounces.
const ROULETTE_AFTER: u32 = 3u;
// Steps a free flight or a shadow ray may take through a medium.
const MAX_MEDIUM_STEPS: u32 = 1024u;
const ISOTROPIC: f32 = 0.07957747; // 1 / (4π)

// Why a path ended: `path end`'s reason.
// It left the scene (its `emitted` holds the environment's light).
const END_ESCAPED: u32 = 0u;
// A medium absorbed it.
const END_ABSORBED: u32 = 1u;
// It reached a vertex past the last bounce.
const END_MAX_DEPTH: u32 = 2u;
// The BSDF drew no direction (pdf 0), or one between the geometric and
// the shading normal.
const END_NO_SAMPLE: u32 = 3u;
// Russian roulette.
const END_ROULETTE: u32 = 4u;
// Its throughput went to zero or stopped being finite.
const END_THROUGHPUT: u32 = 5u;
// `path vertex`'s material at a vertex in a medium.
const MEDIUM_MATERIAL: u32 = 0xffffffffu;

// The random numbers of this sample, drawn in order: deterministic per
// (pixel, sample) whatever the path does.
var<private> rng_key: u32;
var<private> rng_dim: u32;

fn rand() -> f32 {
    rng_dim += 1u;
    return random_f32(rng_key, rng_dim);
}

fn finite(v: vec3<f32>) -> bool {
    let exponent = bitcast<vec3<u32>>(v) & vec3(0x7f800000u);
    return all(exponent != vec3(0x7f800000u));
}

// a² / (a² + b²), written with the ratio b / a: a tiny rect light's area
// pdf (d² / (area · cos), past 1e19) squared is infinite in f32, and
// inf / inf made every sample that saw it NaN, which the guard in
// `path_trace` then dropped as black. a = 0 gives b / a = inf and weight 0.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let r = b / a;
    return select(1.0 / (1.0 + r * r), 1.0, b <= 0.0);
}

fn max3(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// A point just off the surface on the side `dir` leaves to.
fn offset(p: vec3<f32>, ng: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let scale = 1e-4 * max(1.0, max3(abs(p)));
    return p + ng * select(-scale, scale, dot(ng, dir) > 0.0);
}

// ---- media ----------------------------------------------------------------

// A bound on the extinction anywhere: densities are at most 1. A medium
// that emits counts at least 1 per unit length: its emission is collected
// at tentative collisions, and where it neither absorbs nor scatters a
// bound of 0 made none, so an emission-only medium was invisible (the
// extra null collisions keep both trackers unbiased).
fn majorant() -> f32 {
    var m = 0.0;
#ifdef MEDIA
    for (var i = 0u; i < view.counts.y; i++) {
        let emits = max3(media[i].emission.rgb) > 0.0;
        m += max(max3(media[i].scattering.rgb + media[i].absorption.rgb), select(0.0, 1.0, emits));
    }
#endif
    return m;
}

// Transmittance along a shadow ray, by ratio tracking.
fn medium_transmittance(origin: vec3<f32>, dir: vec3<f32>, dist: f32) -> vec3<f32> {
    var tr = vec3(1.0);
#ifdef MEDIA
    let bound = majorant();
    let span = media_span(origin, dir, dist);
    if bound <= 0.0 || span.x >= span.y {
        return tr;
    }
    var t = span.x;
    for (var i = 0u; i < MAX_MEDIUM_STEPS; i++) {
        t -= log(1.0 - rand()) / bound;
        if t >= span.y || max3(tr) < 1e-6 {
            break;
        }
        tr *= max(vec3(0.0), 1.0 - coefficients(origin + dir * t).extinction / bound);
    }
#endif
    return tr;
}

// What a free flight along the ray found before `t_max`.
struct Flight {
    // A scattering event at `t`; otherwise the ray reached t_max.
    scattered: bool,
    // The walk ended in absorption.
    absorbed: bool,
    t: f32,
    // The throughput's factor over the flight.
    weight: vec3<f32>,
    // Emission collected on the way (already weighted, not by throughput).
    emitted: vec3<f32>,
}

fn fly(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> Flight {
    var f = Flight(false, false, t_max, vec3(1.0), vec3(0.0));
#ifdef MEDIA
    let bound = majorant();
    let span = media_span(origin, dir, t_max);
    if bound <= 0.0 || span.x >= span.y {
        return f;
    }
    var t = span.x;
    for (var i = 0u; i < MAX_MEDIUM_STEPS; i++) {
        t -= log(1.0 - rand()) / bound;
        if t >= span.y {
            break;
        }
        let c = coefficients(origin + dir * t);
        f.emitted += f.weight * c.emission / bound;
        let absorption = c.extinction - c.scattering;
        let null_part = max(vec3(bound) - c.extinction, vec3(0.0));
        let p_scatter = (c.scattering.x + c.scattering.y + c.scattering.z) / (3.0 * bound);
        let p_absorb = (absorption.x + absorption.y + absorption.z) / (3.0 * bound);
        let u = rand();
        if u < p_scatter {
            f.weight *= c.scattering / (bound * p_scatter);
            f.scattered = true;
            f.t = t;
            return f;
        }
        if u < p_scatter + p_absorb {
            f.absorbed = true;
            f.weight = vec3(0.0);
            return f;
        }
        f.weight *= null_part / (bound * max(1.0 - p_scatter - p_absorb, 1e-6));
    }
#endif
    return f;
}

// ---- lights ---------------------------------------------------------------

// Where a rect light's plane meets the ray, and whether it emits that way.
struct RectHit {
    t: f32,
    // Solid-angle pdf of area sampling for this direction (0: no hit).
    pdf: f32,
    radiance: vec3<f32>,
}

fn hit_rect(light: Light, origin: vec3<f32>, dir: vec3<f32>) -> RectHit {
    let none = RectHit(-1.0, 0.0, vec3(0.0));
    let n = light.direction.xyz;
    let denom = dot(dir, n);
    let area = rect_area(light);
    if abs(denom) < 1e-8 || area <= 0.0 {
        return none;
    }
    let t = dot(light.position.xyz - origin, n) / denom;
    if t <= 0.0 {
        return none;
    }
    let q = origin + dir * t - light.position.xyz;
    if abs(dot(q, light.right.xyz)) > light.extra.x || abs(dot(q, light.up.xyz)) > light.extra.y {
        return none;
    }
    let cosine = rect_cosine(light, dir);
    if cosine <= 0.0 {
        return none;
    }
    return RectHit(t, t * t / (area * cosine), light.color.rgb);
}

// Light emitted toward a ray that travelled `t_max` from the last vertex
// (whose BRDF or phase pdf for this direction was `bsdf_pdf`; 0 for camera
// rays, which take it unweighted): rect lights in front of t_max. The
// media between are the caller's: its free flight reached t_max.
fn rect_emission(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, bsdf_pdf: f32) -> vec3<f32> {
    var sum = vec3(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let light = lights[i];
        if light_type(light) != LIGHT_RECT {
            continue;
        }
        let h = hit_rect(light, origin, dir);
        if h.t > 0.0 && h.t < t_max {
            let w = select(power_heuristic(bsdf_pdf, h.pdf), 1.0, bsdf_pdf <= 0.0);
            sum += h.radiance * w;
        }
    }
    return sum;
}

// The shading point: a surface (its material) or a medium (isotropic
// phase; `surface` unused).
struct Vertex {
    p: vec3<f32>,
    // Geometric normal (facing the incoming ray); zero in a medium.
    ng: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    surface: Surface,
    in_medium: bool,
}

// A vertex in a medium at p, reached travelling along dir.
fn medium_vertex(p: vec3<f32>, dir: vec3<f32>) -> Vertex {
    var x: Vertex;
    x.p = p;
    x.n = vec3(0.0, 1.0, 0.0);
    x.v = -dir;
    x.in_medium = true;
    return x;
}

fn scatter(x: Vertex, l: vec3<f32>) -> vec3<f32> {
    if x.in_medium {
        return vec3(ISOTROPIC);
    }
    if dot(l, x.ng) <= 0.0 {
        return vec3(0.0);
    }
    return material_eval(x.surface, x.n, x.v, l);
}

fn scatter_pdf(x: Vertex, l: vec3<f32>) -> f32 {
    if x.in_medium {
        return ISOTROPIC;
    }
    return material_pdf(x.surface, x.n, x.v, l);
}

// How much of the light along `l` for `dist` arrives: surfaces block it,
// media attenuate it.
fn visible(x: Vertex, l: vec3<f32>, dist: f32) -> vec3<f32> {
    let origin = select(offset(x.p, x.ng, l), x.p, x.in_medium);
    if occluded(origin, l, 0.0, dist * 0.9999) {
        return vec3(0.0);
    }
    return medium_transmittance(origin, l, dist);
}

// The environment's direction sample at a vertex: cosine about the normal
// on surfaces, uniform on the sphere in media.
fn environment_pdf(x: Vertex, l: vec3<f32>) -> f32 {
    if x.in_medium {
        return ISOTROPIC;
    }
    return max(dot(x.n, l), 0.0) / PI;
}

fn environment_on() -> bool {
    return max3(view.environment_top.rgb) > 0.0 || max3(view.environment_bottom.rgb) > 0.0;
}

// Next-event estimation: light reaching x directly, from every light.
fn direct(x: Vertex) -> vec3<f32> {
    var sum = vec3(0.0);
    for (var i = 0u; i < view.counts.x; i++) {
        let light = lights[i];
        if light_type(light) == LIGHT_RECT {
            let u = vec2(rand(), rand());
            let area = rect_area(light);
            if area <= 0.0 {
                continue;
            }
            let q = light.position.xyz + light.right.xyz * light.extra.x * (2.0 * u.x - 1.0) + light.up.xyz * light.extra.y * (2.0 * u.y - 1.0);
            let to = q - x.p;
            let d = length(to);
            let l = to / max(d, 1e-8);
            let cosine = rect_cosine(light, l);
            if cosine <= 0.0 || d <= 1e-6 {
                continue;
            }
            let pdf = d * d / (area * cosine);
            let f = scatter(x, l);
            if max3(f) <= 0.0 {
                continue;
            }
            let w = power_heuristic(pdf, scatter_pdf(x, l));
            sum += f * light.color.rgb * w / pdf * visible(x, l, d);
            continue;
        }
        let inc = incident(light, x.p);
        let f = scatter(x, inc.l);
        if max3(f) > 0.0 && max3(inc.radiance) > 0.0 {
            sum += f * inc.radiance * visible(x, inc.l, min(inc.distance, 1e30));
        }
    }
    if environment_on() {
        let u = vec2(rand(), rand());
        var l: vec3<f32>;
        if x.in_medium {
            l = sphere_direction(u);
        } else {
            l = cosine_direction(basis(x.n), u);
        }
        let pdf = environment_pdf(x, l);
        let f = scatter(x, l);
        if pdf > 0.0 && max3(f) > 0.0 {
            let w = power_heuristic(pdf, scatter_pdf(x, l));
            sum += f * environment_radiance(l) * w / pdf * visible(x, l, 1e30);
        }
    }
    return sum;
}

// A uniform direction on the sphere (pdf 1 / 4π): the isotropic phase
// function's sample, and the environment's in a medium.
fn sphere_direction(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(0.0, 1.0 - z * z));
    return vec3(r * cos(2.0 * PI * u.y), r * sin(2.0 * PI * u.y), z);
}

// ---- the path -------------------------------------------------------------

struct Sample {
    radiance: vec3<f32>,
    albedo: vec3<f32>,
    normal: vec3<f32>,
    // 1 when the camera ray saw a rect light directly.
    emitter: f32,
}

fn shade_hit(tri: u32, u: f32, v: f32, p: vec3<f32>, dir: vec3<f32>) -> Vertex {
    let t = triangles[tri];
    var ng = normalize(cross(t.b.xyz - t.a.xyz, t.c.xyz - t.a.xyz));
    if !finite(ng) {
        ng = -dir;
    }
    ng = select(-ng, ng, dot(ng, dir) < 0.0);
    let s = shading[tri];
    var n = s.na.xyz * (1.0 - u - v) + s.nb.xyz * u + s.nc.xyz * v;
    let len = length(n);
    n = select(ng, n / len, len > 1e-6 && finite(n / len));
    // Shading normals on the geometric normal's side.
    n = select(-n, n, dot(n, ng) >= 0.0);
    // Textures at level 0 (no ray differentials yet).
    let w = vec3(1.0 - u - v, u, v);
    let uv = s.uv_ab.xy * w.x + s.uv_ab.zw * w.y + s.uv_c.xy * w.z;
    let tangent = s.ta.xyz * w.x + s.tb.xyz * w.y + s.tc.xyz * w.z;
    let point = material_point(uv, vec4(tangent, s.ta.w));
    return Vertex(p, ng, n, -dir, material_init_at(u32(s.na.w), n, -dir, point), false);
}

#ifdef MATERIAL_TRANSMISSION
// Whether the ray met the triangle's back face: from inside the solid, on
// a closed mesh (its triangles wind outward, as geometric normals say).
fn from_inside(tri: u32, dir: vec3<f32>) -> bool {
    let t = triangles[tri];
    return dot(cross(t.b.xyz - t.a.xyz, t.c.xyz - t.a.xyz), dir) > 0.0;
}
#endif

// The selected pixel's `path end` line: at which depth and why the path
// ended, what the segment it ended on still added (throughput applied:
// an escape's environment and the emission met on the way), and the pdfs
// of that segment's direction by the last vertex's BSDF (or phase)
// sampling and by its environment sampling, whose power heuristic weighs
// an escape's environment (0 and 0 where the path ended at a vertex).
fn path_end(depth: u32, reason: u32, emitted: vec3<f32>, bsdf_pdf: f32, light_pdf: f32) {
    debugPrintf("path end %u: reason %u emitted %v3f bsdf_pdf %f light_pdf %f", depth, reason, emitted, bsdf_pdf, light_pdf);
}

fn path(pixel: vec2<u32>) -> Sample {
    let jitter = vec2(rand(), rand());
    var origin = view.position.xyz;
    var dir = normalize(world_position(vec2<f32>(pixel) + jitter, 1.0) - origin);
    var out = Sample(vec3(0.0), vec3(0.0), vec3(0.0), 0.0);
    var throughput = vec3(1.0);
    // The pdf the last vertex sampled `dir` with, for MIS against light
    // sampling; 0 for the camera ray.
    var last_pdf = 0.0;
    var last = medium_vertex(origin, vec3(0.0));
    let bounces = params.y;
    for (var depth = 0u; depth <= bounces + 1u; depth++) {
        let hit = trace(origin, dir, 0.0, 1e30);
        let flight = fly(origin, dir, hit.t);
        let t_end = select(hit.t, flight.t, flight.scattered);
        let lights_met = rect_emission(origin, dir, t_end, last_pdf);
        if depth == 0u && max3(lights_met) > 0.0 {
            out.emitter = 1.0;
        }
        // What the segment and the point it reaches emit toward the
        // camera, throughput applied: the prints' `emitted`.
        var emitted = throughput * flight.emitted + throughput * flight.weight * lights_met;
        throughput *= flight.weight;
        if flight.absorbed {
            out.radiance += emitted;
            path_end(depth, END_ABSORBED, emitted, last_pdf, 0.0);
            break;
        }
        var x: Vertex;
        var material = MEDIUM_MATERIAL;
        if flight.scattered {
            x = medium_vertex(origin + dir * flight.t, dir);
        } else if hit.triangle == NO_HIT {
            // From the camera or through a transmission the environment
            // counts at full weight: no light sampling competes.
            let light_pdf = select(environment_pdf(last, dir), 0.0, last_pdf <= 0.0);
            let w = select(power_heuristic(last_pdf, light_pdf), 1.0, last_pdf <= 0.0);
            emitted += throughput * environment_radiance(dir) * w;
            out.radiance += emitted;
            path_end(depth, END_ESCAPED, emitted, last_pdf, light_pdf);
            break;
        } else {
            x = shade_hit(hit.triangle, hit.u, hit.v, origin + dir * hit.t, dir);
            material = u32(shading[hit.triangle].na.w);
#ifdef MATERIAL_TRANSMISSION
            // The segment just travelled lay inside the solid: Beer–Lambert
            // over its length; and the interface is crossed outward.
            if from_inside(hit.triangle, dir) {
                throughput *= pow(max(material_medium(x.surface), vec3(1e-6)), vec3(hit.t));
                x.surface = material_inside(x.surface);
            }
#endif
            // Emissive surfaces are not sampled by next-event estimation:
            // a path finds them by its own direction, at full weight.
            emitted += throughput * material_emission(x.surface);
            if depth == 0u {
                out.albedo = material_base_color(x.surface);
                out.normal = x.n;
            }
        }
        out.radiance += emitted;
        // A vertex beyond the last bounce adds no light it reflects: that
        // light would be one bounce more than asked for.
        var nee = vec3(0.0);
        if depth <= bounces {
            nee = direct(x);
            out.radiance += throughput * nee;
        }
        debugPrintf("path vertex %u: p %v3f material %u throughput %v3f emitted %v3f nee %v3f bsdf_pdf %f", depth, x.p, material, throughput, emitted, nee, last_pdf);
        if depth > bounces {
            path_end(depth, END_MAX_DEPTH, vec3(0.0), 0.0, 0.0);
            break;
        }
        // Continue with a BRDF (or phase) sample.
        var l: vec3<f32>;
        var pdf: f32;
        if x.in_medium {
            l = sphere_direction(vec2(rand(), rand()));
            pdf = ISOTROPIC;
        } else {
            let s = material_sample(x.surface, x.n, x.v, vec3(rand(), rand(), rand()));
            // Reflected above both normals or transmitted below both; a
            // direction between them (shading normals) ends the path.
            if s.pdf <= 0.0 || (dot(s.l, x.ng) > 0.0) != (dot(s.l, x.n) > 0.0) {
                path_end(depth, END_NO_SAMPLE, vec3(0.0), 0.0, 0.0);
                break;
            }
            l = s.l;
            pdf = s.pdf;
            throughput *= s.weight;
        }
        if depth >= ROULETTE_AFTER {
            let keep = min(max3(throughput), 0.95);
            if rand() >= keep {
                path_end(depth, END_ROULETTE, vec3(0.0), 0.0, 0.0);
                break;
            }
            throughput /= keep;
        }
        if !finite(throughput) || max3(throughput) <= 0.0 {
            path_end(depth, END_THROUGHPUT, vec3(0.0), 0.0, 0.0);
            break;
        }
        origin = select(offset(x.p, x.ng, l), x.p, x.in_medium);
        dir = l;
        // Light sampling never draws a direction below a surface: one that
        // was transmitted takes what it finds unweighted.
        last_pdf = select(pdf, 0.0, dot(l, x.ng) < 0.0);
        last = x;
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(view.params.xy);
    if any(id.xy >= size) {
        return;
    }
    let index = id.y * size.x + id.x;
    var acc = accumulated[index];
    let done = u32(acc.color.w);
    if done < params.x {
        rng_key = random_key(id.xy, done);
        rng_dim = 0u;
        let s = path(id.xy);
        // A sample that went non-finite counts as black: one bad path must
        // not poison the pixel for the rest of the accumulation.
        let radiance = select(vec3(0.0), s.radiance, finite(s.radiance));
        acc = Accumulated(acc.color + vec4(radiance, 1.0), acc.albedo + vec4(s.albedo, s.emitter), acc.normal + vec4(s.normal, 0.0));
        accumulated[index] = acc;
    }
    let n = max(acc.color.w, 1.0);
    textureStore(out_color, id.xy, vec4(acc.color.rgb / n, 1.0));
    textureStore(out_albedo, id.xy, acc.albedo / n);
    let normal = acc.normal.xyz;
    textureStore(out_normal, id.xy, vec4(select(vec3(0.0), normalize(normal), length(normal) > 0.0), 1.0));
    textureStore(out_samples, id.xy, vec4(acc.color.w, 0.0, 0.0, 0.0));
}
