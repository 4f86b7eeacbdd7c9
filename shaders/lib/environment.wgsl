// The scene's environment (`[environment]`): the radiance arriving from
// infinitely far away along each direction, a vertical gradient already
// scaled by its intensity, held in the view uniform. The raster shows it as
// the background and lights surfaces with it (`loupe::material`'s
// `material_ambient`, through `loupe::ambient`); a path tracer sees the same
// radiance through `environment_radiance`.
#define_import_path loupe::environment

#import loupe::view::view
#import loupe::ambient::gradient_radiance

// Radiance arriving from the unit direction d (travelling along -d).
fn environment_radiance(d: vec3<f32>) -> vec3<f32> {
    return gradient_radiance(view.environment_top.rgb, view.environment_bottom.rgb, d);
}
