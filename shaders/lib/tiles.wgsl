// Tile classification's shared terms (`render/passes/classify.rs`): 8×8
// tiles, their four classes from cheapest to dearest, and where the
// classify pass keeps each class's tile list and tile count.
#define_import_path loupe::tiles

// Pixels per side of a tile: one workgroup of the classify and lighting
// passes.
const TILE_SIZE: u32 = 8u;
// Tile (and pixel) classes: a tile's is the dearest of its pixels'.
// Empty is no geometry (environment only); the others are the material
// buffer's storage class plus one.
const TILE_EMPTY: u32 = 0u;
const TILE_SIMPLE: u32 = 1u;
const TILE_SINGLE: u32 = 2u;
const TILE_COMPLEX: u32 = 3u;
const TILE_CLASSES: u32 = 4u;
// The statistics buffer: pixels per class at [0, 4), tiles per class at
// [4, 8).
const STATS_TILES: u32 = 4u;
// The most workgroups one indirect dispatch asks for along x (WebGPU's
// limit is 65535): a lighting workgroup walks its list in strides of it.
const MAX_GROUPS: u32 = 65535u;

// Tiles per row and in all for a target of `size` pixels.
fn tiles_across(size: vec2<u32>) -> u32 {
    return (size.x + TILE_SIZE - 1u) / TILE_SIZE;
}

fn tile_count(size: vec2<u32>) -> u32 {
    return tiles_across(size) * ((size.y + TILE_SIZE - 1u) / TILE_SIZE);
}

// The first pixel of tile `tile` (row-major).
fn tile_origin(tile: u32, size: vec2<u32>) -> vec2<u32> {
    let across = tiles_across(size);
    return vec2(tile % across, tile / across) * TILE_SIZE;
}
