// Debug view: one G-buffer channel (or depth) as a displayable image, in
// place of the lit frame.
#import loupe::fullscreen::{FullscreenOut, fullscreen}

const VIEW_NORMAL: u32 = 0u;
const VIEW_ALBEDO: u32 = 1u;
const VIEW_ROUGHNESS: u32 = 2u;
const VIEW_METALLIC: u32 = 3u;
const VIEW_UV: u32 = 4u;

struct DebugView {
    // VIEW_*; ignored for depth.
    mode: u32,
    near: f32,
    far: f32,
    _pad: f32,
}

@group(0) @binding(0) var<uniform> debug: DebugView;
#ifdef DEBUG_DEPTH
@group(1) @binding(0) var source: texture_depth_2d;
#else
@group(1) @binding(0) var source: texture_2d<f32>;
#endif

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(in.position.xy);
#ifdef DEBUG_DEPTH
    // Linear distance, on a log scale between the near and far planes.
    let z = textureLoad(source, pixel, 0);
    let linear = debug.near * debug.far / (debug.far - z * (debug.far - debug.near));
    let t = log2(linear / debug.near) / log2(debug.far / debug.near);
    return vec4(vec3(1.0 - t), 1.0);
#else
    let s = textureLoad(source, pixel, 0);
    switch debug.mode {
        case VIEW_NORMAL: {
            return vec4(s.xyz * 0.5 + 0.5, 1.0);
        }
        case VIEW_ALBEDO: {
            return vec4(s.rgb, 1.0);
        }
        case VIEW_ROUGHNESS: {
            return vec4(vec3(s.x), 1.0);
        }
        case VIEW_UV: {
            // Tiled UVs repeat the 0..1 square: its fractional part.
            return vec4(fract(s.xy), 0.0, 1.0);
        }
        default: {
            return vec4(vec3(s.y), 1.0);
        }
    }
#endif
}
