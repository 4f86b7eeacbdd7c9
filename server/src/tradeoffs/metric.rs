//! How far an image is from its reference: relative MSE on the HDR image
//! (what the renderer computed), and PSNR and SSIM on the tonemapped one
//! (what the user looks at). SSIM is Wang et al. 2004's, on luminance,
//! with their Gaussian window (σ = 1.5, 11 taps) and constants. FLIP, the
//! field's perceptual metric, is `crate::flip`; the image gate
//! (`check::images`) reports relMSE from here beside it.

/// An RGBA f32 image, rows top first (a capture's layout).
pub struct Rgba<'a> {
    pub width: usize,
    pub height: usize,
    pub data: &'a [f32],
}

/// Σ(a − b)² / Σb² over the colour channels: 0 for the reference itself,
/// 1 for a black image. Non-finite values count as the largest error.
pub fn relative_mse(a: &Rgba, reference: &Rgba) -> f64 {
    let (mut err, mut energy) = (0.0f64, 0.0f64);
    for (pa, pb) in a.data.chunks_exact(4).zip(reference.data.chunks_exact(4)) {
        for c in 0..3 {
            let (x, y) = (f64::from(pa[c]), f64::from(pb[c]));
            err += if x.is_finite() { (x - y).powi(2) } else { f64::MAX / 1e6 };
            energy += y * y;
        }
    }
    if energy > 0.0 { err / energy } else { err }
}

/// PSNR in dB of display values in [0, 1] (peak 1); `inf` when equal.
pub fn psnr(a: &Rgba, reference: &Rgba) -> f64 {
    let mut err = 0.0f64;
    for (pa, pb) in a.data.chunks_exact(4).zip(reference.data.chunks_exact(4)) {
        for c in 0..3 {
            err += f64::from(pa[c] - pb[c]).powi(2);
        }
    }
    let mse = err / (3 * a.width * a.height) as f64;
    if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() }
}

/// Mean SSIM of the display images' luminance: 1 when equal.
pub fn ssim(a: &Rgba, reference: &Rgba) -> f64 {
    let (w, h) = (a.width, a.height);
    let luma = |img: &Rgba| -> Vec<f64> {
        img.data.chunks_exact(4).map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])).collect()
    };
    let (x, y) = (luma(a), luma(reference));
    let product = |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(a, b)| a * b).collect() };
    let (mx, my) = (blur(&x, w, h), blur(&y, w, h));
    let (sxx, syy, sxy) = (blur(&product(&x, &x), w, h), blur(&product(&y, &y), w, h), blur(&product(&x, &y), w, h));
    const C1: f64 = 0.01 * 0.01;
    const C2: f64 = 0.03 * 0.03;
    let sum: f64 = (0..w * h)
        .map(|i| {
            let (vx, vy, cov) = (sxx[i] - mx[i] * mx[i], syy[i] - my[i] * my[i], sxy[i] - mx[i] * my[i]);
            ((2.0 * mx[i] * my[i] + C1) * (2.0 * cov + C2)) / ((mx[i] * mx[i] + my[i] * my[i] + C1) * (vx + vy + C2))
        })
        .sum();
    sum / (w * h) as f64
}

/// The Gaussian window, separable, the image's edge repeated beyond it.
fn blur(v: &[f64], w: usize, h: usize) -> Vec<f64> {
    const RADIUS: isize = 5;
    let weights: Vec<f64> = (-RADIUS..=RADIUS).map(|i| (-(i * i) as f64 / (2.0 * 1.5 * 1.5)).exp()).collect();
    let total: f64 = weights.iter().sum();
    let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                (-RADIUS..=RADIUS)
                    .zip(&weights)
                    .map(|(d, k)| {
                        let (sx, sy) =
                            if horizontal { ((x + d).clamp(0, w as isize - 1), y) } else { (x, (y + d).clamp(0, h as isize - 1)) };
                        k * src[sy as usize * w + sx as usize]
                    })
                    .sum::<f64>()
                    / total
            })
            .collect()
    };
    pass(&pass(v, true), false)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        (0..w * h)
            .flat_map(|i| {
                let v = f(i % w, i / w);
                [v, v, v, 1.0]
            })
            .collect()
    }

    #[test]
    fn identical_images_are_perfect_and_worse_ones_score_worse() {
        let (w, h) = (32, 24);
        let reference = image(w, h, |x, y| ((x * 7 + y * 3) % 11) as f32 / 11.0);
        let slightly = image(w, h, |x, y| ((x * 7 + y * 3) % 11) as f32 / 11.0 + if (x + y) % 2 == 0 { 0.01 } else { -0.01 });
        let badly = image(w, h, |x, y| ((x * 5 + y * 9) % 13) as f32 / 13.0);
        let r = Rgba { width: w, height: h, data: &reference };
        let (s, b) = (Rgba { width: w, height: h, data: &slightly }, Rgba { width: w, height: h, data: &badly });
        assert_eq!((relative_mse(&r, &r), psnr(&r, &r), ssim(&r, &r)), (0.0, f64::INFINITY, 1.0));
        assert!((psnr(&s, &r) - 40.0).abs() < 1e-4, "an error of 0.01 everywhere is 40 dB: {}", psnr(&s, &r));
        assert!(relative_mse(&s, &r) < relative_mse(&b, &r));
        assert!(ssim(&s, &r) > 0.9 && ssim(&b, &r) < 0.5, "{} {}", ssim(&s, &r), ssim(&b, &r));
        let black = vec![0.0; w * h * 4];
        assert_eq!(relative_mse(&Rgba { width: w, height: h, data: &black }, &r), 1.0);
    }
}
