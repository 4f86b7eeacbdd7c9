//! The path tracer through the library's glass (`scenes/materials/glass.mat`),
//! at one bounce, on small frames:
//! - a thin clear pane shows what is behind it, straight through, times its
//!   colour and what the wall's Fresnel lets through;
//! - a solid sphere of absorbing glass keeps Beer–Lambert's share along
//!   its diameter, so a thicker one is darker.

use std::path::Path;

use super::testing::{COLOR, accumulate, image, session};
use crate::render::capture::CapturedImage;
use crate::render::session::Session;

/// A scene in a temporary directory with the repository's glass.mat as
/// its materials `thin` and `solid` (`params` for each), so that every
/// scene here composes the same material module: one session, one build
/// of the path tracer.
fn glass_scene(dir: &Path, body: &str, thin: &str, solid: &str) -> crate::loaded::Loaded {
    let glass = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials/glass.mat").canonicalize().unwrap();
    let file = format!("{:?}", glass.to_string_lossy());
    let text = format!(
        "[[materials]]\nname = \"thin\"\nfile = {file}\nmaterial = \"thin_glass\"\nparams = {{ {thin} }}\n\n\
         [[materials]]\nname = \"solid\"\nfile = {file}\nmaterial = \"solid_glass\"\nparams = {{ {solid} }}\n\n\
         [quality]\nrenderer = \"path\"\npath_bounces = 1\npath_spp = {SPP}\n\n{body}"
    );
    let path = dir.join("glass.toml");
    std::fs::write(&path, text).unwrap();
    crate::loaded::load(&path).unwrap_or_else(|d| panic!("{d}"))
}

const SPP: u32 = 32;

/// The mean colour of the pixels within `r` of the image's centre.
fn centre(c: &CapturedImage, r: u32) -> [f64; 3] {
    let (cx, cy) = (c.width / 2, c.height / 2);
    let mut sum = [0.0; 3];
    let mut n = 0.0;
    for y in cy - r..cy + r {
        for x in cx - r..cx + r {
            let p = c.pixel(x, y);
            for k in 0..3 {
                sum[k] += f64::from(p[k]);
            }
            n += 1.0;
        }
    }
    sum.map(|s| s / n)
}

fn render(s: &mut Session, loaded: &crate::loaded::Loaded) -> CapturedImage {
    assert_eq!(s.set_scene_now(loaded), vec![], "the frame's shaders build");
    let frames = accumulate(s, &[SPP], Some(&[COLOR]));
    image(&frames[0], COLOR).clone()
}

/// Fresnel of a dielectric at normal incidence: ((η − 1) / (η + 1))².
fn f0(ior: f64) -> f64 {
    ((ior - 1.0) / (ior + 1.0)).powi(2)
}

/// One test, one session: the path tracer's build is most of the cost.
#[test]
fn glass_in_the_path_tracer() {
    let dir = tempfile::tempdir().unwrap();
    // A thin pane: looking down through it at a white ground (the
    // environment's bottom; its top, which the pane reflects, is black).
    let tint = [0.5, 0.8, 1.0];
    let c = 0.3f64;
    let thin = format!("pane_color = {tint:?}, specular_roughness = 0.0");
    let solid = format!("glass_color = [{c:?}, {c:?}, {c:?}], specular_roughness = 0.0");
    let pane = glass_scene(
        dir.path(),
        "[output]\nwidth = 16\nheight = 16\n\n[camera]\nposition = [0.0, 3.0, 0.05]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = 10.0\n\n\
         [[objects]]\nshape = \"plane\"\nmaterial = \"thin\"\nscale = 4.0\n\n\
         [environment]\ntop = [0.0, 0.0, 0.0]\nbottom = [1.0, 1.0, 1.0]\nintensity = 1.0\n",
        &thin,
        &solid,
    );
    let mut s = session(&pane);
    let got = centre(&render(&mut s, &pane), 4);
    // Both faces and the light between them: 1 − 2R / (1 + R).
    let r = f0(1.5);
    let through = 1.0 - 2.0 * r / (1.0 + r);
    for k in 0..3 {
        let want = through * tint[k];
        assert!((got[k] - want).abs() < 0.02, "thin pane, channel {k}: {got:?}, want {want} (through {through} times {tint:?})");
    }
    // A solid sphere of radius s seen through its centre under a white
    // environment: the interface reflects F0, and the light through
    // crosses two interfaces and 2s of glass keeping `c` per unit.
    let mut seen = Vec::new();
    for radius in [0.5, 1.0] {
        let sphere = glass_scene(
            dir.path(),
            &format!(
                "[output]\nwidth = 16\nheight = 16\n\n[camera]\nposition = [0.0, 0.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = 30.0\n\n\
                 [[objects]]\nshape = \"sphere\"\nmaterial = \"solid\"\nscale = {radius:?}\n\n\
                 [environment]\ntop = [1.0, 1.0, 1.0]\nbottom = [1.0, 1.0, 1.0]\nintensity = 1.0\n"
            ),
            &thin,
            &solid,
        );
        let got = centre(&render(&mut s, &sphere), 1)[0];
        let want = r + (1.0 - r).powi(2) * c.powf(2.0 * radius);
        assert!((got - want).abs() < 0.03, "solid sphere of radius {radius}: {got}, want {want} (Beer–Lambert over {})", 2.0 * radius);
        seen.push(got);
    }
    assert!(seen[1] < seen[0], "the thicker sphere is darker: {seen:?}");
}
