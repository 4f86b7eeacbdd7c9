//! The volume passes on the device (lavapipe without a GPU), through a
//! `Session`:
//! - stability: on `volume.toml`, 1,024 steps agree with 512 and 768 at
//!   the default and the most shadow steps, with both estimators, and the
//!   estimators agree with each other; every step of every march ran
//!   (`volume_march/transmittance` alpha and `volume_shadows/transmittance`
//!   channel 3 count them), and where a scene does ask llvmpipe for more
//!   loop iterations than it allows, that count shows it;
//! - the upsample: half and quarter resolution stay close to full across a
//!   silhouette;
//! - hard cases: density 0 (the lit frame unchanged), density 1e6 (opaque,
//!   finite in-scattering within the single-scattering bound), a step far
//!   longer than the medium, and camera and light inside a homogeneous
//!   medium (Beer–Lambert, and the in-scattering against quadrature here).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::render::capture::CapturedImage;
use crate::render::frame::FrameResult;
use crate::render::session::Session;
use crate::scene::overrides::Overrides;
use crate::loaded::Loaded;
use crate::scene::Estimator;

const COLOR: &str = "volumes/color";
const TRANSMITTANCE: &str = "volumes/transmittance";
const LIT: &str = "lighting/color";
const GRID: &str = "volume_shadows/transmittance";
const MARCHED: &str = "volume_march/transmittance";

fn session(loaded: &Loaded) -> Session {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let lib = crate::shader::library::read_tree(&root).unwrap();
    let mut s = Session::new(crate::gpu::testing::device(), &root, lib, loaded);
    assert_eq!(s.install_missing(), vec![], "the frame's shaders build");
    s
}

fn parsed(text: &str) -> Loaded {
    let scene = crate::scene::parse("volume_test.toml", text).unwrap_or_else(|d| panic!("{d}"));
    Loaded { materials: crate::loaded::materials_of(&scene), scene, meshes: BTreeMap::new(), denoiser: None, files: vec![], reports: Default::default(), warnings: vec![] }
}

/// Renders `loaded` in `s` (its pipelines built on first use), capturing
/// the march's inputs and outputs and the grid.
fn render(s: &mut Session, loaded: &Loaded) -> FrameResult {
    assert_eq!(s.set_scene_now(loaded), vec![], "the frame's shaders build");
    let wanted: BTreeSet<String> = [COLOR, TRANSMITTANCE, LIT, GRID, MARCHED].map(str::to_owned).into();
    let pending = s.submit(Some(&wanted), 1.0 / 30.0);
    let r = s.wait(pending);
    assert_eq!(s.take_uncaptured(), Vec::<String>::new());
    r
}

fn image<'a>(r: &'a FrameResult, key: &str) -> &'a CapturedImage {
    r.captures.iter().find(|c| c.key() == key).unwrap_or_else(|| panic!("{key} is captured"))
}

fn pixels(image: &CapturedImage) -> impl Iterator<Item = &[f32]> {
    image.data.chunks_exact(4)
}

/// The fraction of the grid's shadow marches and of the pixels' marches
/// whose every step ran (1 where no loop was cut short).
fn steps_ran(r: &FrameResult) -> (f64, f64) {
    let grid = r.tensors.iter().find(|t| t.key() == GRID).expect("the grid is captured");
    let full = |v: &[f32]| v.iter().filter(|&&x| x == 1.0).count() as f64 / v.len() as f64;
    let grid_ran: Vec<f32> = grid.data.chunks_exact(4).map(|c| c[3]).collect();
    let march_ran: Vec<f32> = pixels(image(r, MARCHED)).map(|p| p[3]).collect();
    (full(&grid_ran), full(&march_ran))
}

fn mean_rgb(image: &CapturedImage) -> f64 {
    let sum: f64 = pixels(image).map(|p| p[..3].iter().map(|&c| f64::from(c)).sum::<f64>()).sum();
    sum / (3 * image.data.len() / 4) as f64
}

/// Root-mean-square difference over every pixel's rgb.
fn rmse(a: &CapturedImage, b: &CapturedImage) -> f64 {
    let sum: f64 = pixels(a).zip(pixels(b)).flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).powi(2))).sum();
    (sum / (3 * a.data.len() / 4) as f64).sqrt()
}

fn assert_finite(r: &FrameResult, key: &str) {
    let i = image(r, key);
    assert!(!i.stats.has_non_finite(), "{key} holds NaN/Inf: {:?}", i.stats);
}

/// `volume.toml` at the 96×54 with `set` applied.
fn volume_scene(set: &[(&str, crate::scene::settings::Value)]) -> Loaded {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/volume.toml");
    let overrides: Overrides = set.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect();
    let mut loaded = crate::loaded::load_with(&path, &overrides).unwrap_or_else(|d| panic!("{d}"));
    (loaded.scene.width, loaded.scene.height) = (96, 54);
    loaded
}

/// Relative difference of the mean of `volumes/color` allowed between
/// 512 or 768 steps and 1,024. Before the grid, llvmpipe's loop cap made
/// 1,024 steps 5 % brighter than 512 at the default shadow steps; now the
/// constant estimator, whose error falls as 1/steps, moves 2.8e-4 from
/// 512 to 1,024 and the analytic one 1e-5.
const MEAN_BOUND: f64 = 5e-4;
/// The per-pixel RMSE allowed between those, relative to the mean (the
/// constant estimator: 1.2e-3 at 512 steps).
const RMSE_BOUND: f64 = 2e-3;
/// The two estimators' means at 1,024 steps (2.4e-4 apart: the constant
/// one's remaining bias).
const ESTIMATORS_BOUND: f64 = 5e-4;

/// 1,024 steps agree with 512 and 768 within the bounds above, at the
/// default and the most shadow steps, with both estimators; the two
/// estimators agree with each other; and every march ran every step.
#[test]
fn more_steps_converge_instead_of_drifting() {
    use crate::scene::settings::Value::{Int, Text};
    let mut s = session(&volume_scene(&[]));
    let default_shadow = i64::from(crate::scene::Quality::default().volume_shadow_steps);
    for shadow in [default_shadow, 64] {
        let mut at_most = Vec::new();
        for name in Estimator::NAMES {
            let frames: Vec<(i64, FrameResult)> = [512, 768, 1024]
                .into_iter()
                .map(|steps| {
                    let set = [
                        ("quality.volume_steps", Int(steps)),
                        ("quality.volume_shadow_steps", Int(shadow)),
                        ("quality.volume_estimator", Text((*name).to_owned())),
                    ];
                    (steps, render(&mut s, &volume_scene(&set)))
                })
                .collect();
            let last = image(&frames[2].1, COLOR);
            let reference = mean_rgb(last);
            for (steps, r) in &frames {
                assert_finite(r, COLOR);
                assert_eq!(steps_ran(r), (1.0, 1.0), "every step ran: {name}, {steps} steps, {shadow} shadow steps");
                let c = image(r, COLOR);
                let (mean, error) = ((mean_rgb(c) - reference).abs() / reference, rmse(c, last) / reference);
                assert!(
                    mean <= MEAN_BOUND && error <= RMSE_BOUND,
                    "{name}, {shadow} shadow steps: {steps} against 1024 steps: mean {mean:.2e}, rmse {error:.2e}"
                );
            }
            at_most.push(reference);
        }
        let apart = (at_most[0] - at_most[1]).abs() / at_most[0];
        assert!(apart <= ESTIMATORS_BOUND, "{shadow} shadow steps: the estimators' means at 1024 steps differ by {apart:.2e}");
    }
}

/// A scene that asks for more loop iterations per invocation than llvmpipe
/// runs (1,024 steps through 8 media of 16 shapes and 8 octaves each:
/// about 200 iterations a step) shows it in the step count the march
/// writes: on a CPU adapter some pixel's march stopped early; elsewhere
/// every step ran.
#[test]
fn the_step_count_shows_a_loop_the_driver_cut_short() {
    let spheres: Vec<String> = (0..16).map(|i| format!("{{ type = \"sphere\", center = [{}, 1, 0], radius = 0.3 }}", f64::from(i) * 0.1 - 0.8)).collect();
    let medium = format!(
        "[[media]]\nabsorption = [0.01, 0.01, 0.01]\nscattering = [0.05, 0.05, 0.05]\nshapes = [{}]\nnoise = {{ octaves = 8, frequency = 2.0, amplitude = 0.5 }}\n",
        spheres.join(", ")
    );
    let text = format!(
        "[output]\nwidth = 16\nheight = 9\n[camera]\nposition = [0, 1, 4]\ntarget = [0, 1, 0]\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\n{}[quality]\nvolume_steps = 1024\n",
        medium.repeat(crate::scene::MAX_MEDIA)
    );
    let loaded = parsed(&text);
    let mut s = session(&loaded);
    let r = render(&mut s, &loaded);
    let (grid, march) = steps_ran(&r);
    assert_eq!(grid, 1.0, "the grid's marches are short enough to run whole");
    if s.gpu().is_cpu() {
        assert!(march < 1.0, "llvmpipe cut the march short, and the step count shows it");
    } else {
        assert_eq!(march, 1.0, "every step ran");
    }
}

/// A camera looking down at a floor (and at the top of a box of half-size
/// 0.5 at (0, 1, 0) through the middle pixel) under a directional light of
/// radiance 2, through `medium` (a `[[media]]` table) with `quality`.
fn hard_case(medium: &str, quality: &str) -> Loaded {
    parsed(&format!(
        "[output]\nwidth = 33\nheight = 33\n[camera]\nposition = [0, 3, 3]\ntarget = [0, 1.5, 0]\n\
         [[materials]]\nname = \"floor\"\n[[objects]]\nshape = \"plane\"\nmaterial = \"floor\"\nscale = 10.0\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nintensity = 2.0\n{medium}[quality]\n{quality}\n"
    ))
}

/// Single scattering without emission, an albedo σs/σt ≤ 1 and the
/// analytic estimator adds at most (1 − T)·E/(4π) over the background,
/// E = 2 the light's radiance; f16 outputs round to 1e-3 here.
fn assert_single_scattering_bound(r: &FrameResult, case: &str) {
    let bound = 2.0 / (4.0 * std::f32::consts::PI);
    for ((c, l), t) in pixels(image(r, COLOR)).zip(pixels(image(r, LIT))).zip(pixels(image(r, TRANSMITTANCE))) {
        for k in 0..3 {
            assert!((0.0..=1.0).contains(&t[k]), "{case}: transmittance {t:?}");
            let added = c[k] - l[k] * t[k];
            assert!(added >= -1e-3 && added <= (1.0 - t[k]) * bound + 1e-3, "{case}: {added} added over the background, transmittance {}", t[k]);
        }
    }
}

/// A medium of density 0 leaves the lit frame exactly as it was.
#[test]
fn density_zero_leaves_the_lit_frame_unchanged() {
    let medium = "[[media]]\nabsorption = [0, 0, 0]\nscattering = [0, 0, 0]\nshapes = [{ type = \"box\", center = [0, 1, 0], half_extents = [1, 1, 1] }]\n";
    let loaded = hard_case(medium, "volume_steps = 64");
    let mut s = session(&loaded);
    let r = render(&mut s, &loaded);
    assert_eq!(image(&r, COLOR).data, image(&r, LIT).data);
    assert!(pixels(image(&r, TRANSMITTANCE)).all(|t| t == [1.0; 4]));
}

/// Density 1e6: the medium is opaque (transmittance 0 through it) and its
/// in-scattering finite, within the single-scattering bound with the
/// analytic estimator, finite and non-negative with the constant one.
#[test]
fn density_a_million_is_opaque_with_finite_in_scattering() {
    let medium = "[[media]]\nabsorption = [0, 0, 0]\nscattering = [1e6, 1e6, 1e6]\nedge = 0.01\n\
                  shapes = [{ type = \"box\", center = [0, 1, 0], half_extents = [0.5, 0.5, 0.5] }]\n";
    let mut s = session(&hard_case(medium, ""));
    for estimator in ["analytic", "constant"] {
        let r = render(&mut s, &hard_case(medium, &format!("volume_estimator = \"{estimator}\"")));
        assert_finite(&r, COLOR);
        assert_finite(&r, TRANSMITTANCE);
        assert!(!r.tensors.iter().any(|t| t.stats.has_non_finite()), "{estimator}: the grid holds NaN/Inf");
        assert_eq!(&image(&r, TRANSMITTANCE).pixel(16, 16)[..3], &[0.0; 3], "{estimator}: opaque through the middle");
        assert!(pixels(image(&r, COLOR)).all(|c| c[..3].iter().all(|&v| v >= 0.0)), "{estimator}: negative light");
        let seen = image(&r, COLOR).pixel(16, 16)[0];
        // The lit top face scatters light (0.118 analytic, of the bound's
        // 0.159; the constant estimator's one step over-counts: 564).
        assert!(seen > 0.05, "{estimator}: the lit top scatters light: {seen}");
        if estimator == "analytic" {
            assert_single_scattering_bound(&r, "density 1e6");
        }
    }
}

/// Two steps across a 12 m haze holding a dense sphere of 0.2 m: a step 30
/// times longer than the sphere stays finite and, analytic, within the
/// single-scattering bound.
#[test]
fn a_step_longer_than_the_medium_stays_bounded() {
    let media = "[[media]]\nabsorption = [0, 0, 0]\nscattering = [0.05, 0.05, 0.05]\nshapes = [{ type = \"box\", center = [0, 1, 0], half_extents = [6, 1, 6] }]\n\
                 [[media]]\nabsorption = [1, 1, 1]\nscattering = [50, 50, 50]\nedge = 0.01\nshapes = [{ type = \"sphere\", center = [0, 1, 0], radius = 0.1 }]\n";
    let mut s = session(&hard_case(media, ""));
    for estimator in ["analytic", "constant"] {
        let r = render(&mut s, &hard_case(media, &format!("volume_steps = 2\nvolume_estimator = \"{estimator}\"")));
        assert_finite(&r, COLOR);
        assert_finite(&r, TRANSMITTANCE);
        if estimator == "analytic" {
            assert_single_scattering_bound(&r, "a step longer than the medium");
        }
    }
}

/// The camera and a point light inside a homogeneous box (σa 0.2, σs 0.6):
/// along the middle pixel's ray, which leaves the box after 1 m, the
/// transmittance is e^{-0.8} (Beer–Lambert) within 2e-3 and the light
/// scattered toward the camera is the single-scattering integral,
/// computed here by quadrature, within 2 %.
#[test]
fn camera_and_light_inside_the_medium_match_beer_lambert_and_quadrature() {
    let (sigma_a, sigma_s, intensity, light) = (0.2f64, 0.6f64, 2.0f64, [0.4f64, 0.0, -0.6]);
    let text = format!(
        "[output]\nwidth = 33\nheight = 33\n[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, -1]\n\
         [[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\nintensity = {intensity}\n\
         [[media]]\nabsorption = [{sigma_a}, {sigma_a}, {sigma_a}]\nscattering = [{sigma_s}, {sigma_s}, {sigma_s}]\nedge = 0.001\n\
         shapes = [{{ type = \"box\", center = [0, 0, 0], half_extents = [1, 1, 1] }}]\n[quality]\nvolume_steps = 256\n",
        light[0], light[1], light[2]
    );
    let loaded = parsed(&text);
    let mut s = session(&loaded);
    let r = render(&mut s, &loaded);
    assert_finite(&r, COLOR);
    let sigma_t = sigma_a + sigma_s;
    let t = f64::from(image(&r, TRANSMITTANCE).pixel(16, 16)[0]);
    assert!((t / (-sigma_t).exp() - 1.0).abs() <= 2e-3, "transmittance {t} against {}", (-sigma_t).exp());
    // ∫0^1 σs e^{-σt s} · I/r² · e^{-σt r} / (4π) ds, r from (0, 0, -s) to
    // the light: midpoints, far finer than the march.
    let n = 100_000;
    let expected: f64 = (0..n)
        .map(|i| {
            let s = (f64::from(i) + 0.5) / f64::from(n);
            let r2 = light[0].powi(2) + light[1].powi(2) + (light[2] + s).powi(2);
            sigma_s * (-sigma_t * s).exp() * intensity / r2 * (-sigma_t * r2.sqrt()).exp() / (4.0 * std::f64::consts::PI)
        })
        .sum::<f64>()
        / f64::from(n);
    let added = f64::from(image(&r, COLOR).pixel(16, 16)[0]) - f64::from(image(&r, LIT).pixel(16, 16)[0]) * t;
    assert!((added / expected - 1.0).abs() <= 0.02, "in-scattered {added} against {expected} by quadrature");
}

/// A sphere in front of a floor in a lit haze: along its silhouette the
/// in-scattered light jumps (short rays to the sphere, long ones past it).
fn silhouette(resolution: &str) -> Loaded {
    parsed(&format!(
        "[output]\nwidth = 96\nheight = 54\n[camera]\nposition = [0, 1.5, 5]\ntarget = [0, 1, 0]\n\
         [[materials]]\nname = \"grey\"\n\
         [[objects]]\nshape = \"plane\"\nmaterial = \"grey\"\nscale = 10.0\n\
         [[objects]]\nshape = \"sphere\"\nmaterial = \"grey\"\nposition = [0, 1, 1]\nscale = 0.6\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, -0.4]\nintensity = 3.0\n\
         [[media]]\nabsorption = [0, 0, 0]\nscattering = [0.3, 0.3, 0.3]\nshapes = [{{ type = \"box\", center = [0, 1.5, 0], half_extents = [5, 1.5, 5] }}]\n\
         [quality]\nvolume_steps = 64\nvolume_resolution = \"{resolution}\"\n"
    ))
}

/// Half and quarter resolution against full on `silhouette`: the mean
/// within 2e-3 and 3e-3 relative, the per-pixel RMSE within 6e-3 and
/// 1.5e-2 of the mean (measured 4.5e-4 / 3.3e-3 and 1.2e-3 / 9.7e-3; a
/// plain bilinear upsample, without the depth weights, makes 1.9e-2 and
/// 3.6e-2 RMSE), every march run whole.
#[test]
fn half_and_quarter_resolution_upsample_without_bleeding_across_silhouettes() {
    let mut s = session(&silhouette("full"));
    let full = render(&mut s, &silhouette("full"));
    let reference = image(&full, COLOR);
    for (resolution, mean_bound, rmse_bound) in [("half", 2e-3, 6e-3), ("quarter", 3e-3, 1.5e-2)] {
        let r = render(&mut s, &silhouette(resolution));
        assert_finite(&r, COLOR);
        assert_eq!(steps_ran(&r), (1.0, 1.0), "{resolution}: every step ran");
        let c = image(&r, COLOR);
        let (mean, error) = ((mean_rgb(c) / mean_rgb(reference) - 1.0).abs(), rmse(c, reference) / mean_rgb(reference));
        assert!(mean <= mean_bound && error <= rmse_bound, "{resolution} against full: mean {mean:.2e}, rmse {error:.2e}");
    }
}
