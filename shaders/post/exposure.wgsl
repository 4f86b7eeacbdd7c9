// Exposure: scales the HDR image by 2^EV. Its own pass, so the inspector
// shows the exposed HDR values the tonemapper receives. With
// AUTO_EXPOSURE, the EV the auto-exposure passes adapted is added to the
// manual one, which then acts as compensation.
#import loupe::fullscreen::{FullscreenOut, fullscreen}

struct Exposure {
    // Linear multiplier, 2^EV; the rest pads the struct to 16 bytes.
    scale: f32,
    _pad0: f32,
    _pad1: vec2<f32>,
}

@group(0) @binding(0) var<uniform> exposure: Exposure;
@group(0) @binding(1) var hdr: texture_2d<f32>;

#ifdef AUTO_EXPOSURE
// The first four floats of the adapt pass's `ExposureState`: the applied
// EV comes first.
@group(1) @binding(0) var<storage, read> adapted: array<f32, 4>;

fn scale() -> f32 {
    return exposure.scale * exp2(adapted[0]);
}
#else
fn scale() -> f32 {
    return exposure.scale;
}
#endif

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let texel = textureLoad(hdr, vec2<i32>(in.position.xy), 0);
    return vec4(texel.rgb * scale(), texel.a);
}
