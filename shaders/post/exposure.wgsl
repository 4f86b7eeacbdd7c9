// Exposure: scales the HDR image by 2^EV. Its own pass, so the inspector
// shows the exposed HDR values the tonemapper receives.
#import loupe::fullscreen::{FullscreenOut, fullscreen}

struct Exposure {
    // Linear multiplier, 2^EV; the rest pads the struct to 16 bytes.
    scale: f32,
    _pad0: f32,
    _pad1: vec2<f32>,
}

@group(0) @binding(0) var<uniform> exposure: Exposure;
@group(0) @binding(1) var hdr: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let texel = textureLoad(hdr, vec2<i32>(in.position.xy), 0);
    return vec4(texel.rgb * exposure.scale, texel.a);
}
