// Tile classification (Substrate's): one workgroup per 8×8 tile reads each
// pixel's depth and material header and gives the tile the dearest kind
// among its pixels (`loupe::tiles`). Outputs: each tile's kind and
// material bytes, each kind's tile list with its indirect dispatch
// arguments (x = tiles, at most MAX_GROUPS; y = z = 1), and the frame's
// pixels and tiles per kind. The pass clears the counters first.
#import loupe::material::material_word_count
#import loupe::tiles::{TILE_EMPTY, TILE_COMPLEX, TILE_CLASSES, STATS_TILES, MAX_GROUPS, tile_count}

@group(0) @binding(0) var depth: texture_depth_2d;
@group(0) @binding(1) var<storage, read> material_words: array<u32>;
@group(0) @binding(2) var<storage, read_write> tile_classes: array<u32>;
@group(0) @binding(3) var<storage, read_write> tile_bytes: array<u32>;
@group(0) @binding(4) var<storage, read_write> tile_lists: array<u32>;
@group(0) @binding(5) var<storage, read_write> dispatch: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> stats: array<atomic<u32>>;
// Per class, the class whose pass lights it (the next dearer one a class
// the scene's materials cannot make, `Classes::promotion`).
@group(0) @binding(7) var<uniform> promotion: vec4<u32>;

var<workgroup> dearest: atomic<u32>;
var<workgroup> pixels: array<atomic<u32>, 4>;
var<workgroup> bytes: atomic<u32>;

@compute @workgroup_size(8, 8)
fn classify(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    if local < TILE_CLASSES {
        atomicStore(&pixels[local], 0u);
    }
    if local == 0u {
        atomicStore(&dearest, TILE_EMPTY);
        atomicStore(&bytes, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(depth);
    if all(id.xy < size) {
        var kind = TILE_EMPTY;
        // Pixels without geometry write no words: theirs are stale.
        if textureLoad(depth, vec2<i32>(id.xy), 0) < 1.0 {
            let header = material_words[id.y * size.x + id.x];
            kind = min((header & 3u) + 1u, TILE_COMPLEX);
            atomicAdd(&bytes, material_word_count(header) * 4u);
        }
        atomicMax(&dearest, kind);
        atomicAdd(&pixels[kind], 1u);
    }
    workgroupBarrier();
    if local != 0u {
        return;
    }
    let kind = promotion[atomicLoad(&dearest)];
    let tile = group.y * groups.x + group.x;
    tile_classes[tile] = kind;
    tile_bytes[tile] = atomicLoad(&bytes);
    let slot = atomicAdd(&stats[STATS_TILES + kind], 1u);
    tile_lists[kind * tile_count(size) + slot] = tile;
    if slot < MAX_GROUPS {
        atomicAdd(&dispatch[kind * 3u], 1u);
    }
    for (var c = 0u; c < TILE_CLASSES; c++) {
        atomicAdd(&stats[c], atomicLoad(&pixels[c]));
        if tile == 0u {
            atomicStore(&dispatch[c * 3u + 1u], 1u);
            atomicStore(&dispatch[c * 3u + 2u], 1u);
        }
    }
}
