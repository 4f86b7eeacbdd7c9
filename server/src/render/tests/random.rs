//! `shaders/lib/random.wgsl` on the device: the numbers are in [0, 1),
//! uniform (a χ² test over 64 bins), the same for the same (pixel, sample,
//! dimension), and independent of neighbours (pixels, samples, dimensions:
//! the correlation of adjacent streams is near 0).

use crate::gpu::testing::Kernel;

const SHADER: &str = r#"
#import loupe::random::{random_f32, random_key}

@group(0) @binding(0) var<storage, read> input: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;

// input: (pixel x, pixel y, sample, dimension).
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    output[id.x] = random_f32(random_key(q.xy, q.z), q.w);
}
"#;

fn correlation(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len() as f64;
    let mean = |x: &[f32]| x.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(&x, &y)| (f64::from(x) - ma) * (f64::from(y) - mb)).sum::<f64>() / n;
    let var = |x: &[f32], m: f64| x.iter().map(|&v| (f64::from(v) - m).powi(2)).sum::<f64>() / n;
    cov / (var(a, ma) * var(b, mb)).sqrt()
}

#[test]
fn random_numbers_are_uniform_repeatable_and_uncorrelated() {
    let gpu = crate::gpu::testing::device();
    let kernel = Kernel::new(&gpu, SHADER, "main").unwrap_or_else(|e| panic!("{e}"));
    let run = |queries: &[[u32; 4]]| -> Vec<f32> { kernel.run(&gpu, queries, queries.len(), &[]).unwrap() };
    // A 256×256 target, one sample, dimension 0.
    let grid: Vec<[u32; 4]> = (0..256 * 256).map(|i| [i % 256, i / 256, 0, 0]).collect();
    let x = run(&grid);
    assert!(x.iter().all(|v| (0.0..1.0).contains(v)), "outside [0, 1)");
    assert_eq!(run(&grid), x, "the same keys give the same numbers");
    // χ² over 64 bins, 63 degrees of freedom: 1.5× the mean is far in the
    // tail (p < 10⁻³) for a uniform source.
    let mut bins = [0u32; 64];
    for v in &x {
        bins[(v * 64.0) as usize] += 1;
    }
    let expected = x.len() as f64 / 64.0;
    let chi2: f64 = bins.iter().map(|&o| (f64::from(o) - expected).powi(2) / expected).sum();
    assert!(chi2 < 95.0, "χ² = {chi2} over 64 bins");
    // Neighbouring streams: the next pixel, the next sample, the next
    // dimension. |r| of independent streams of 65,536 is about 0.004.
    let shifted = |f: fn([u32; 4]) -> [u32; 4]| run(&grid.iter().map(|&q| f(q)).collect::<Vec<_>>());
    for (what, other) in [
        ("pixel", shifted(|[x, y, s, d]| [x + 1, y, s, d])),
        ("row", shifted(|[x, y, s, d]| [x, y + 1, s, d])),
        ("sample", shifted(|[x, y, s, d]| [x, y, s + 1, d])),
        ("dimension", shifted(|[x, y, s, d]| [x, y, s, d + 1])),
    ] {
        let r = correlation(&x, &other);
        assert!(r.abs() < 0.02, "the next {what}'s numbers correlate: r = {r}");
        assert_ne!(other, x, "the next {what} gives other numbers");
    }
}
