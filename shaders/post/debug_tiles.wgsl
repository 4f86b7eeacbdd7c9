// Debug views of the material buffer and tile classification, after
// Substrate's: each 8×8 tile coloured by its class (TILE_CLASS_VIEW, from
// the classify pass), or per pixel its closure count or its material
// bytes, decoded from the header. Background pixels are black.
#import loupe::fullscreen::{FullscreenOut, fullscreen}
#import loupe::material::{MATERIAL_WORDS, material_word_count}
#import loupe::tiles::{TILE_SIZE, tiles_across}

const VIEW_CLOSURES: u32 = 0u;
const VIEW_BYTES: u32 = 1u;

// x: VIEW_*; ignored for the tile classes.
@group(0) @binding(0) var<uniform> debug: vec4<u32>;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var<storage, read> material_words: array<u32>;
#ifdef TILE_CLASS_VIEW
@group(1) @binding(0) var<storage, read> tile_classes: array<u32>;
#endif

// Cheapest to dearest: empty grey, simple green, single yellow, complex
// red (closures: 1 green, 2 yellow, 3 or more red).
fn ramp(i: u32) -> vec3<f32> {
    switch min(i, 3u) {
        case 0u: { return vec3(0.05); }
        case 1u: { return vec3(0.1, 0.7, 0.2); }
        case 2u: { return vec3(0.9, 0.8, 0.1); }
        default: { return vec3(0.9, 0.15, 0.1); }
    }
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenOut {
    return fullscreen(vertex_index);
}

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(in.position.xy);
    let size = textureDimensions(depth);
#ifdef TILE_CLASS_VIEW
    let tile = pixel / TILE_SIZE;
    var c = ramp(tile_classes[tile.y * tiles_across(size) + tile.x]);
    // The tile grid, faintly.
    if any(pixel % TILE_SIZE == vec2(0u)) {
        c *= 0.7;
    }
    return vec4(c, 1.0);
#else
    if textureLoad(depth, vec2<i32>(pixel), 0) >= 1.0 {
        return vec4(0.0, 0.0, 0.0, 1.0);
    }
    let header = material_words[pixel.y * size.x + pixel.x];
    if debug.x == VIEW_CLOSURES {
        return vec4(ramp(select((header >> 2u) & 7u, 1u, (header & 3u) == 0u)), 1.0);
    }
    // Bytes, as a share of the most a pixel of these materials takes.
    let share = f32(material_word_count(header)) / f32(MATERIAL_WORDS);
    return vec4(vec3(share), 1.0);
#endif
}
