// Tonemapping: exposed HDR in, display-referred out (the target is an sRGB
// format, so the hardware applies the transfer function on write).
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::color::{tonemap_aces, tonemap_reinhard}

@group(0) @binding(0) var hdr: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let texel = textureLoad(hdr, vec2<i32>(in.position.xy), 0);
    let c = max(texel.rgb, vec3(0.0));
#ifdef TONEMAP_REINHARD
    return vec4(tonemap_reinhard(c), texel.a);
#else
    return vec4(tonemap_aces(c), texel.a);
#endif
}
