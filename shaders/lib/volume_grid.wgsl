// The grid of light transmittance the volume march samples
// (`passes/volume_shadows.wgsl` fills it): points spaced evenly over the
// box around every medium, corners included, and per light and point the
// transmittance through the media toward that light. Computing it once per
// point instead of once per march step keeps each invocation's loops short
// (llvmpipe stops every loop of an invocation after 65,535 iterations in
// all) and the march's cost independent of the shadow steps.
#define_import_path loupe::volume_grid

struct VolumeGrid {
    // xyz: the box's lower corner, the first point; w: unused.
    lo: vec4<f32>,
    // xyz: the distance between neighbouring points per axis; w: unused.
    spacing: vec4<f32>,
    // xyz: points per axis (at least 2); w: lights.
    dims: vec4<u32>,
}

fn grid_point(grid: VolumeGrid, cell: vec3<u32>) -> vec3<f32> {
    return grid.lo.xyz + vec3<f32>(cell) * grid.spacing.xyz;
}

// Where `light`'s value at `cell` is stored: lights outermost, then z, y, x.
fn grid_index(grid: VolumeGrid, light: u32, cell: vec3<u32>) -> u32 {
    return ((light * grid.dims.z + cell.z) * grid.dims.y + cell.y) * grid.dims.x + cell.x;
}
