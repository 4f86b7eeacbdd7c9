// 64-bit floats need the float64 capability.
fn twice(x: f64) -> f64 {
    return x * 2.0;
}

@compute @workgroup_size(1)
fn main() {
    _ = twice(1.0);
}
