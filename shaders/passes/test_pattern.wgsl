// A test pattern with known values: an HDR ramp (0..4) on top, colour bars in
// the middle, a 1-pixel checker at the bottom (aliasing shows at once).
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::color::srgb_to_linear

struct Frame {
    size: vec2<f32>,
    time: f32,
    frame: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    // From the target size the renderer binds, not the interpolated uv:
    // the pattern's bands then sit at exact pixel rows.
    let uv = in.position.xy / frame.size;
    if uv.y < 0.33 {
        return vec4(vec3(uv.x * 4.0), 1.0);
    }
    if uv.y < 0.66 {
        let bar = u32(uv.x * 8.0);
        let rgb = vec3(f32(bar & 1u), f32((bar >> 1u) & 1u), f32((bar >> 2u) & 1u));
        return vec4(srgb_to_linear(rgb * 0.75), 1.0);
    }
    let p = vec2<u32>(in.position.xy);
    let checker = f32((p.x + p.y) & 1u);
    return vec4(vec3(checker), 1.0);
}
