//! The numerical stability suite: hard cases of sampling and shading, run
//! through the real WGSL modules on the device (lavapipe without a GPU),
//! each failing on a NaN or Inf or on leaving its stated bound. The cases
//! and their bounds are in docs/stability.md; each test below names its
//! module. `the_suite_fails_when_it_should` shows the checks failing on
//! purpose.
//!
//! It drives the WGSL through `loupe::gpu::testing::Kernel` and the path
//! tracer through `loupe::render::passes::path_trace::testing`: test
//! fixtures the library makes public under its `testing` feature.

mod chi2;
mod furnace;
mod half;
mod inputs;
mod library;
mod path_vertices;
mod sampling;
mod scenes;
mod thin_film;
mod transmission;

use loupe::gpu::testing;
use loupe::scene::settings::{self, Value};

/// A bound: `value` must be a number no larger than `bound` (NaN fails).
fn at_most(what: &str, value: f64, bound: f64) -> Result<(), String> {
    if value <= bound { Ok(()) } else { Err(format!("{what}: {value}, bound {bound}")) }
}

/// Asserts no check failed, listing the first 20 that did.
fn all_pass(failures: &[String]) {
    assert!(failures.is_empty(), "{} checks failed, the first:\n{}", failures.len(), failures[..failures.len().min(20)].join("\n"));
}

/// The significance of the whole chi-square family.
const SIGNIFICANCE: f64 = 0.01;
/// The largest weight a sample may carry: the specular lobe is drawn at
/// least 5 % of the time, and the diffuse one, when there is any diffuse,
/// at least 5 % (brdf.wgsl's `specular_probability`), so no lobe's
/// brdf_cos / pdf exceeds 1 / 0.05 for a base colour ≤ 1.
const MAX_WEIGHT: f64 = 20.0;
/// How far the pdf's and brdf_cos's integrals may sit from what the
/// samples show. At n·v = 0.001 and the smallest roughness, v + l (the
/// half vector's direction) loses about 1 % of its tangential part to
/// f32 cancellation (both are within 1e-3 of the horizon and nearly
/// opposite), so D is evaluated slightly off: measured 1.8e-3 of the
/// mass.
const GRAZING: f64 = 3e-3;
/// How far f(v, l) and f(l, v) may differ, relative: the model is
/// reciprocal where n·v, n·l ≥ 1e-4, and in f32 Fresnel's v·h and l·h
/// round apart, which its fifth power amplifies (measured 8e-6).
const RECIPROCAL: f64 = 1e-4;
/// The quadrature's error in the albedo: the warped grid resolves the
/// lobes to a few parts in 10⁴.
const ALBEDO_SLACK: f64 = 1e-3;

#[test]
fn brdf_sample_draws_from_brdf_pdf() {
    let gpu = testing::device();
    let kernels = sampling::Kernels::new(&gpu);
    let cases = sampling::cases();
    let threshold = chi2::sidak(SIGNIFICANCE, cases.len());
    let u = loupe::testing::uniforms(sampling::SAMPLES);
    let mut failures = Vec::new();
    let (mut worst_p, mut worst_weight, mut largest_weight, mut max_albedo) = (1.0f64, 0.0f64, 0.0f64, 0.0f64);
    for case in &cases {
        let density = sampling::density(&gpu, &kernels, case);
        let drawn = sampling::draw(&gpu, &kernels, case, &u);
        let bad = drawn.iter().filter(|d| d.iter().flatten().any(|x| !x.is_finite())).count();
        failures.extend((bad > 0).then(|| format!("{case}: {bad} samples hold a NaN or Inf")));
        let fit = sampling::fit(case, &drawn, &density);
        let (error, largest) = sampling::weight_error(&drawn);
        let mean = sampling::mean_weight(&drawn);
        let integral: f64 = density.cells.iter().sum();
        let kept = drawn.iter().filter(|d| d[0][3] > 0.0).count() as f64 / drawn.len() as f64;
        eprintln!(
            "{case}: chi² {:.0} over {} dof ({} pooled), p = {:.3e}; weight error {error:.1e}, largest {largest:.3}; albedo {:.5} (sampled {:.5} ± {:.1e}); kept {kept:.5}, ∫pdf {integral:.5}",
            fit.statistic, fit.dof, fit.pooled, fit.p_value, density.albedo[0], mean[0].0, mean[0].1
        );
        if fit.p_value < threshold {
            failures.push(format!("{case}: chi-square p = {:e} < {threshold:e}: the samples do not follow brdf_pdf", fit.p_value));
        }
        failures.extend(at_most(&format!("{case}: relative weight error"), error, 1e-3).err());
        failures.extend(at_most(&format!("{case}: largest weight"), largest, MAX_WEIGHT).err());
        let sigma = (kept * (1.0 - kept) / drawn.len() as f64).sqrt();
        failures.extend(
            at_most(&format!("{case}: kept share {kept} against ∫pdf {integral}"), (kept - integral).abs(), GRAZING + 4.0 * sigma).err(),
        );
        for (c, (a, (m, se))) in density.albedo.into_iter().zip(mean).enumerate() {
            failures.extend(at_most(&format!("{case}, channel {c}: albedo"), a, 1.0 + ALBEDO_SLACK).err());
            failures.extend(
                at_most(&format!("{case}, channel {c}: sampled albedo {m} against quadrature {a}"), (m - a).abs(), 4.0 * se + GRAZING)
                    .err(),
            );
            max_albedo = max_albedo.max(a);
        }
        worst_p = worst_p.min(fit.p_value);
        worst_weight = worst_weight.max(error);
        largest_weight = largest_weight.max(largest);
    }
    eprintln!(
        "{} cases: worst p {worst_p:.3e} (threshold {threshold:.3e}), worst weight error {worst_weight:.1e}, largest weight {largest_weight:.3}, max albedo {max_albedo:.5}",
        cases.len()
    );
    all_pass(&failures);
}

/// How far a white metal's compensated albedo may sit from 1: the fit's
/// error (2e-3, `shaders/lib/multiscatter.wgsl`) and the quadrature's.
const FURNACE: f64 = 5e-3;

/// The white furnace of the energy compensation: a white metal (f0 = 1)
/// returns 1 within `FURNACE` (uncompensated it keeps only
/// `render::dfg::albedo`: 0.31 at roughness 1 seen head-on); a white
/// dielectric (f0 = 0.04, with its diffuse) at most 1.
#[test]
fn energy_compensation_returns_a_white_metals_light() {
    let gpu = testing::device();
    let mut failures = Vec::new();
    let (mut worst, mut max_dielectric) = (0.0f64, 0.0f64);
    let kernel = furnace::kernel(&gpu);
    for case in furnace::cases(1.0) {
        let albedo = furnace::compensated(&gpu, &kernel, &case).albedo[0];
        eprintln!("{case}: compensated {albedo:.5}");
        failures.extend(at_most(&format!("{case}: compensated albedo against 1"), (albedo - 1.0).abs(), FURNACE).err());
        worst = worst.max((albedo - 1.0).abs());
    }
    for case in furnace::cases(0.0) {
        let albedo = furnace::compensated(&gpu, &kernel, &case).albedo[0];
        failures.extend(at_most(&format!("{case}: compensated albedo"), albedo, 1.0 + ALBEDO_SLACK).err());
        max_dielectric = max_dielectric.max(albedo);
    }
    eprintln!("furnace: white metal within {worst:.1e} of 1; white dielectric at most {max_dielectric:.5}");
    all_pass(&failures);
}

/// How far a clear smooth interface's albedo may sit from 1: the 0.5 % of
/// the furnace (the single-scattering GGX lobes lose G2/G1 of the
/// light, about 1e-4 at the clamped roughness, and f32 rounding the rest).
const CLEAR: f64 = 5e-3;

/// `dielectric_direction` draws from `dielectric_pdf` over the whole
/// sphere (reflection and refraction, total internal reflection inside,
/// thin walls straight through); a sample's weight never exceeds 1 (it is
/// G2/G1); the albedo stays at or below 1.
#[test]
fn transmission_samples_follow_their_pdf() {
    let gpu = testing::device();
    let kernels = transmission::Kernels::new(&gpu);
    let cases = transmission::cases();
    let threshold = chi2::sidak(SIGNIFICANCE, cases.len());
    let u = loupe::testing::uniforms(transmission::SAMPLES);
    let mut failures = Vec::new();
    let (mut worst_p, mut largest_weight, mut max_albedo) = (1.0f64, 0.0f64, 0.0f64);
    for case in &cases {
        let density = transmission::density(&gpu, &kernels, case);
        let drawn = transmission::draw(&gpu, &kernels, case, &u);
        let bad = drawn.iter().filter(|d| d.iter().flatten().any(|x| !x.is_finite())).count();
        failures.extend((bad > 0).then(|| format!("{case}: {bad} samples hold a NaN or Inf")));
        let fit = transmission::fit(case, &drawn, &density);
        let largest = drawn.iter().map(|d| f64::from(d[1][0])).fold(0.0, f64::max);
        let integral: f64 = density.cells.iter().sum();
        let kept = drawn.iter().filter(|d| d[0][3] > 0.0).count() as f64 / drawn.len() as f64;
        let (mean, se) = transmission::mean_weight(&drawn);
        eprintln!(
            "{case}: chi² {:.0} over {} dof ({} pooled), p = {:.3e}; largest weight {largest:.4}; albedo {:.5} (sampled {mean:.5} ± {se:.1e}); kept {kept:.5}, ∫pdf {integral:.5}",
            fit.statistic, fit.dof, fit.pooled, fit.p_value, density.albedo[0]
        );
        if fit.p_value < threshold {
            failures.push(format!("{case}: chi-square p = {:e} < {threshold:e}: the samples do not follow dielectric_pdf", fit.p_value));
        }
        failures.extend(at_most(&format!("{case}: largest weight"), largest, 1.0 + ALBEDO_SLACK).err());
        failures.extend(at_most(&format!("{case}: albedo"), density.albedo[0], 1.0 + ALBEDO_SLACK).err());
        let sigma = (kept * (1.0 - kept) / drawn.len() as f64).sqrt();
        failures.extend(
            at_most(&format!("{case}: kept share {kept} against ∫pdf {integral}"), (kept - integral).abs(), GRAZING + 4.0 * sigma).err(),
        );
        worst_p = worst_p.min(fit.p_value);
        largest_weight = largest_weight.max(largest);
        max_albedo = max_albedo.max(density.albedo[0]);
    }
    eprintln!(
        "{} cases: worst p {worst_p:.3e} (threshold {threshold:.3e}), largest weight {largest_weight:.4}, max albedo {max_albedo:.5}",
        cases.len()
    );
    all_pass(&failures);
}

/// The transmission furnace: a clear, smooth interface (a solid seen from
/// outside and from inside, a thin wall) reflects and transmits all the
/// light, within `CLEAR`: the mean sample weight, Fresnel splitting it.
#[test]
fn a_clear_smooth_interface_returns_all_the_light() {
    let gpu = testing::device();
    let kernels = transmission::Kernels::new(&gpu);
    let u = loupe::testing::uniforms(transmission::SAMPLES);
    let mut failures = Vec::new();
    let mut worst = 0.0f64;
    for case in transmission::smooth() {
        let (mean, se) = transmission::mean_weight(&transmission::draw(&gpu, &kernels, &case, &u));
        eprintln!("{case}: albedo {mean:.5} ± {se:.1e}");
        failures.extend(at_most(&format!("{case}: albedo against 1"), (mean - 1.0).abs(), CLEAR).err());
        worst = worst.max((mean - 1.0).abs());
    }
    eprintln!("transmission furnace: within {worst:.1e} of 1");
    all_pass(&failures);
}

#[test]
fn brdf_cos_is_reciprocal() {
    let gpu = testing::device();
    let kernels = sampling::Kernels::new(&gpu);
    let mut failures = Vec::new();
    let mut worst = 0.0f64;
    for case in sampling::cases().iter().filter(|c| c.cos_v == 1.0) {
        let (error, _) = sampling::reciprocity(&gpu, &kernels, case, 1 << 16);
        failures.extend(
            at_most(&format!("roughness {}, metallic {}: f(v, l) against f(l, v)", case.roughness, case.metallic), error, RECIPROCAL).err(),
        );
        worst = worst.max(error);
    }
    eprintln!("reciprocity: worst relative difference {worst:.1e}");
    all_pass(&failures);
}

#[test]
fn degenerate_inputs_stay_finite_and_bounded() {
    let gpu = testing::device();
    let (failures, ran) = inputs::run(&gpu);
    eprintln!("degenerate inputs: {ran} queries, {} failures", failures.len());
    all_pass(&failures);
}

/// Bound: every capture finite at 1, 2 and 8 samples per pixel, and the
/// walls lit (mean colour above 0.01).
#[test]
fn a_camera_inside_a_closed_mesh_sees_no_nan() {
    use loupe::render::passes::path_trace::testing as path;
    let mut s = path::session(&path::loaded(inputs::INSIDE, Default::default()));
    path::without_guard(&mut s);
    let color = path::assert_finite(&mut s, "inside a closed sphere", &[1, 2, 8]);
    let mean = path::mean(&color) / 3.0;
    eprintln!("inside a closed sphere: mean colour {mean:.4}");
    at_most("inside a closed sphere: the mean colour, negated", -mean, -0.01).unwrap();
}

#[test]
fn ggx_in_half_precision() {
    let gpu = testing::device();
    let e = half::run(&gpu);
    eprintln!(
        "GGX near n·h = 1, alpha 0.045² (adapter SHADER_F16: {}): worst relative error f32 {:.1e}, f16-stored normal {:.1e}, f16 module form {:.1e} (non-finite {}), f16 textbook form {:.1e} (non-finite {}); peak D f32 {:.0}, f16 {:.0}",
        gpu.device.features().contains(wgpu::Features::SHADER_F16),
        e.worst[0],
        e.worst[1],
        e.worst[2],
        e.non_finite[2],
        e.worst[3],
        e.non_finite[3],
        e.peak[0],
        e.peak[1]
    );
    let mut failures = Vec::new();
    for (k, what, bound) in [(0, "in f32", 1e-4), (1, "with the G-buffer's f16 normal", 0.25), (2, "in f16 arithmetic", 0.05)] {
        failures.extend(at_most(&format!("GGX {what}: relative error"), e.worst[k], bound).err());
        failures.extend(at_most(&format!("GGX {what}: non-finite values"), e.non_finite[k] as f64, 0.0).err());
    }
    all_pass(&failures);
}

#[test]
fn every_pass_at_every_quality_extreme_is_finite() {
    use loupe::render::passes::path_trace::testing as path;
    let mut all = scenes::bundled();
    all.push(("bright light on a mirror".into(), path::loaded(scenes::BRIGHT, Default::default())));
    let mut failures = Vec::new();
    let mut rendered = 0;
    for (name, loaded) in &all {
        let mut s = path::session(loaded);
        for (variant, scene) in scenes::variants(&loaded.scene) {
            failures.extend(scenes::scan(&mut s, loaded, &scene).into_iter().map(|b| format!("{name}, {variant}: {b}")));
            rendered += 1;
        }
    }
    eprintln!("{} scenes, {rendered} variants, {} failures", all.len(), failures.len());
    all_pass(&failures);
}

/// The material buffer at the edges of the fields' ranges
/// (`scenes::EXTREME_MAT`): every capture finite, raster and path traced,
/// at the budget's extremes (the smallest simplifies the material to one
/// slab) and with the path tracer on the simplified material.
#[test]
fn extreme_materials_pack_and_light_finite() {
    use loupe::render::passes::path_trace::testing as path;
    let loaded = scenes::extreme();
    let mut s = path::session(&loaded);
    let mut failures = Vec::new();
    let variants = [
        ("quality.material_bytes", Value::Int(256)),
        ("quality.material_bytes", Value::Int(24)),
        ("quality.renderer", Value::Text("path".into())),
        ("quality.path_simplified_materials", Value::Bool(true)),
    ];
    let mut scene = loaded.scene.clone();
    for (path, value) in variants {
        settings::find(path).expect("a table setting").set(&mut scene, &value).expect("a valid value");
        failures.extend(scenes::scan(&mut s, &loaded, &scene).into_iter().map(|b| format!("{path} = {value}: {b}")));
    }
    all_pass(&failures);
}

/// The checks fail when they should: the chi-square test against a pdf
/// scaled by 5 %, and against the pdf of the other lobe mixture (a metal's
/// pdf for a dielectric's samples); a bound given a NaN.
#[test]
fn the_suite_fails_when_it_should() {
    let gpu = testing::device();
    let kernels = sampling::Kernels::new(&gpu);
    let threshold = chi2::sidak(SIGNIFICANCE, sampling::cases().len());
    let case = sampling::Case { cos_v: 0.5, roughness: 0.5, metallic: 0.0 };
    let drawn = sampling::draw(&gpu, &kernels, &case, &loupe::testing::uniforms(sampling::SAMPLES));
    let mut density = sampling::density(&gpu, &kernels, &case);
    let right = sampling::fit(&case, &drawn, &density);
    assert!(right.p_value >= threshold, "the right pdf: {right:?}");
    let metal = sampling::density(&gpu, &kernels, &sampling::Case { metallic: 1.0, ..case });
    let swapped = sampling::fit(&case, &drawn, &metal);
    assert!(swapped.p_value < threshold, "a metal's pdf for a dielectric's samples: {swapped:?}");
    density.cells.iter_mut().for_each(|p| *p *= 1.05);
    let scaled = sampling::fit(&case, &drawn, &density);
    assert!(scaled.p_value < threshold, "the pdf scaled by 1.05: {scaled:?}");
    eprintln!("p-values: right {:.3e}, lobes swapped {:.3e}, scaled {:.3e}", right.p_value, swapped.p_value, scaled.p_value);
    assert!(at_most("NaN", f64::NAN, 1.0).is_err());
    assert!(at_most("Inf", f64::INFINITY, 1.0).is_err());
    assert!(at_most("in bounds", 1.0, 1.0).is_ok());
}

/// How far the thin film's Fresnel may sit from the spectral reference, per
/// channel. Cutting the series after three round trips costs nothing
/// measurable (six moved no case by 2e-3); the error is Belcour & Barla's
/// Gaussian fit of the sensitivities against the tabulated observer, and
/// it is largest where the interference has full contrast: a film between
/// air and air (a soap bubble) at grazing views, measured 0.054 (1 µm,
/// IOR 1.33, cos 0.15); over glass and metal bases under 0.02.
const FILM: f64 = 0.06;
/// A film of thickness 0 gives back the base's Fresnel: f32 rounding only
/// (measured 9e-8).
const NO_FILM: f64 = 1e-5;

/// `thin_film_fresnel` (`shaders/lib/iridescence.wgsl`) against the exact
/// Airy reflectance summed over 380–780 nm with the CIE 1931 tables, over
/// `thin_film::cases`; a film of thickness 0 gives the base's own exact
/// Fresnel.
#[test]
fn thin_film_fresnel_matches_the_spectral_sum() {
    let gpu = testing::device();
    let cases = thin_film::cases();
    let got = thin_film::device(&gpu, &cases);
    // Worst errors: over air, over other bases, at thickness 0.
    let (mut failures, mut worst) = (Vec::new(), [0.0f64; 3]);
    for (case, got) in cases.iter().zip(&got) {
        let bare = case.thickness == 0.0;
        let want = if bare { case.base.map(|n| thin_film::fresnel(case.cos, n)) } else { thin_film::reference(case) };
        let which = if bare { 2 } else { usize::from(case.base != [1.0; 3]) };
        for k in 0..3 {
            let error = (got[k] - want[k]).abs();
            let bound = if bare { NO_FILM } else { FILM };
            failures.extend(at_most(&format!("{case}, channel {k}: {} against {}", got[k], want[k]), error, bound).err());
            worst[which] = worst[which].max(error);
        }
    }
    eprintln!(
        "{} films: worst {:.2e} over air, {:.2e} over other bases, against the spectral sum; thickness 0 within {:.1e} of Fresnel",
        cases.len(),
        worst[0],
        worst[1],
        worst[2]
    );
    all_pass(&failures);
}
