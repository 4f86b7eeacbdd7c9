// The empty tiles' lighting (tile classification): a tile without
// geometry shows the environment behind it, and needs no material, no
// light and no shadow.
#import loupe::view::{view, world_position}
#import loupe::environment::environment_radiance
#import loupe::tiles::{TILE_EMPTY, STATS_TILES, tile_count, tile_origin}

@group(0) @binding(15) var lit: texture_storage_2d<rgba16float, write>;
@group(0) @binding(16) var<storage, read> tile_lists: array<u32>;
@group(0) @binding(17) var<storage, read> tile_stats: array<u32>;

@compute @workgroup_size(8, 8)
fn environment(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let size = textureDimensions(lit);
    for (var t = group.x; t < tile_stats[STATS_TILES + TILE_EMPTY]; t += groups.x) {
        let pixel = tile_origin(tile_lists[TILE_EMPTY * tile_count(size) + t], size) + local.xy;
        if all(pixel < size) {
            let p = world_position(vec2<f32>(pixel) + 0.5, 1.0);
            textureStore(lit, pixel, vec4(environment_radiance(normalize(p - view.position.xyz)), 1.0));
        }
    }
}
