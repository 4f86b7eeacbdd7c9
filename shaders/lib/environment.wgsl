// The scene's environment (`[environment]`): the radiance arriving from
// infinitely far away along each direction, a vertical gradient already
// scaled by its intensity, held in the view uniform. The raster shows it as
// the background and lights surfaces with it; a path tracer sees the same
// radiance through `environment_radiance`.
#define_import_path loupe::environment

#import loupe::view::view
#import loupe::ambient::{gradient_radiance, ambient_light}
#import loupe::brdf::specular_f0

// Radiance arriving from the unit direction d (travelling along -d).
fn environment_radiance(d: vec3<f32>) -> vec3<f32> {
    return gradient_radiance(view.environment_top.rgb, view.environment_bottom.rgb, d);
}

// Radiance a surface at normal n sends toward v from the environment.
fn environment_light(n: vec3<f32>, v: vec3<f32>, base_color: vec3<f32>, metallic: f32, roughness: f32, dfg_table: texture_2d<f32>) -> vec3<f32> {
    let f0 = specular_f0(base_color, metallic);
    return ambient_light(view.environment_top.rgb, view.environment_bottom.rgb, n, v, base_color, metallic, f0, roughness, dfg_table);
}
