#define_import_path demo::util

fn scale(x: f32) -> f32 {
    let k = 2u;
    return x * k;
}
