// The transmittance from every point of the volume grid toward every light
// through the media (self-shadowing), marched in `volume_shadow_steps`
// steps, one invocation per point and light. Stores rgb: transmittance,
// a: the fraction of the march's steps that ran (1 unless the driver cut
// the loop short).
#import loupe::view::view
#import loupe::lights::{lights, incident}
#import loupe::media::optical_depth
#import loupe::volume_grid::{VolumeGrid, grid_point, grid_index}

@group(0) @binding(2) var<uniform> grid: VolumeGrid;
@group(0) @binding(3) var<storage, read_write> cells: array<vec4<f32>>;

@compute @workgroup_size(4, 4, 4)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    // z runs over the points' z for the first light, then the second…
    if id.x >= grid.dims.x || id.y >= grid.dims.y || id.z >= grid.dims.z * grid.dims.w {
        return;
    }
    let light = id.z / grid.dims.z;
    let cell = vec3(id.xy, id.z % grid.dims.z);
    let p = grid_point(grid, cell);
    let inc = incident(lights[light], p);
    let steps = max(view.counts.w, 1u);
    let depth = optical_depth(p, inc.l, min(inc.distance, view.params.z), steps);
    cells[grid_index(grid, light, cell)] = vec4(exp(-depth.optical), f32(depth.completed) / f32(steps));
}
