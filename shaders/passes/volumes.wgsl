// The volume march (`volume_march`, at `volume_resolution`) brought to the
// frame's resolution and composited over the lit frame: colour =
// opaque × transmittance + in-scattered light. Each pixel blends the four
// march pixels around it, bilinear weights times how close each one's
// marched distance is to this pixel's own, so light from a surface in
// front does not bleed onto one behind (and the reverse). At full
// resolution the one march pixel is the pixel itself.
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::view::{view, world_position}

// x: the scale, 1, 2 or 4.
@group(0) @binding(1) var<uniform> params: vec4<u32>;
@group(0) @binding(2) var opaque: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var scattered: texture_2d<f32>;
@group(0) @binding(5) var marched: texture_2d<f32>;

struct Out {
    @location(0) color: vec4<f32>,
    @location(1) transmittance: vec4<f32>,
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

// How fast a march pixel's weight falls with the relative difference
// between its marched distance and this pixel's: 5 % apart weighs e^-1.
const DEPTH_FALLOFF: f32 = 20.0;

@fragment
fn fs_main(in: FullscreenOut) -> Out {
    let pixel = vec2<i32>(in.position.xy);
    let background = textureLoad(opaque, pixel, 0);
    let z = textureLoad(depth, pixel, 0);
    var distance = view.params.z;
    if z < 1.0 {
        distance = length(world_position(in.position.xy, z) - view.position.xyz);
    }
    // Where this pixel lies among the march pixels, whose rays go through
    // the frame's pixels scale × i + scale / 2.
    let scale = i32(params.x);
    let at = vec2<f32>(pixel - scale / 2) / f32(scale);
    let base = vec2<i32>(floor(at));
    let f = at - vec2<f32>(base);
    let last = vec2<i32>(textureDimensions(scattered)) - 1;
    var light = vec3(0.0);
    var transmittance = vec3(0.0);
    var total = 0.0;
    var ran = 1.0;
    for (var i = 0; i < 4; i++) {
        let offset = vec2(i & 1, i >> 1u);
        let tap = clamp(base + offset, vec2(0), last);
        let bilinear = select(1.0 - f.x, f.x, offset.x == 1) * select(1.0 - f.y, f.y, offset.y == 1);
        let s = textureLoad(scattered, tap, 0);
        let t = textureLoad(marched, tap, 0);
        // A floor keeps the sum above 0 where every tap lies at another depth.
        let w = bilinear * (exp(-DEPTH_FALLOFF * abs(s.a - distance) / max(distance, 1e-6)) + 1e-6);
        light += w * s.rgb;
        transmittance += w * t.rgb;
        total += w;
        if bilinear > 0.0 {
            ran = min(ran, t.a);
        }
    }
    transmittance /= total;
    return Out(vec4(background.rgb * transmittance + light / total, background.a), vec4(transmittance, ran));
}
