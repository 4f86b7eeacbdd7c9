//! `bench-flip`: what FLIP (`loupe::flip`) costs per megapixel on the CPU,
//! LDR-FLIP and HDR-FLIP, on a pair of 1024×1024 images.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-flip
//! ```
//!
//! The pair is made here: an exponential HDR ramp (1/16 to 64, so HDR-FLIP
//! evaluates one exposure per stop from the median to the brightest) with
//! a 1-pixel checker over it, and the same shifted a pixel; the LDR pair is
//! both clamped and encoded to sRGB. Median of 9 runs after 1 unmeasured, each the whole comparison
//! (the binding's image copies, the filters, for HDR every exposure).

use std::time::Instant;

use loupe::flip::{self, Linear, Srgb8};
use loupe_tests::machine;

const SIDE: u32 = 1024;

fn image(shift: u32) -> Vec<f32> {
    (0..SIDE * SIDE)
        .flat_map(|i| {
            let (x, y) = (i % SIDE + shift, i / SIDE);
            let ramp = (10.0 * x as f32 / SIDE as f32 - 4.0).exp2();
            let v = ramp * if (x + y) % 2 == 0 { 1.0 } else { 0.8 };
            [v, v * 0.9, v * (y as f32 / SIDE as f32), 1.0]
        })
        .collect()
}

fn median_ms(f: impl Fn()) -> f64 {
    f();
    let mut times: Vec<f64> = (0..9)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1000.0
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let (reference, test) = (image(0), image(1));
    let (r8, t8) = (flip::encode_srgb8(&reference), flip::encode_srgb8(&test));
    let megapixels = f64::from(SIDE * SIDE) / 1e6;
    let ldr = median_ms(|| {
        let srgb = |rgb| Srgb8 { width: SIDE, height: SIDE, rgb };
        flip::ldr(srgb(&r8), srgb(&t8)).expect("one size");
    });
    let linear = |rgba| Linear { width: SIDE, height: SIDE, rgba };
    let exposures = flip::exposures(linear(&reference)).count;
    let hdr = median_ms(|| {
        flip::hdr(linear(&reference), linear(&test)).expect("one size");
    });
    println!("{}", machine());
    println!("LDR-FLIP: {:.1} ms per megapixel", ldr / megapixels);
    println!("HDR-FLIP ({exposures} exposures): {:.1} ms per megapixel", hdr / megapixels);
}
