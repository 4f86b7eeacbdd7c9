//! The path tracer's prints at a selected pixel (`path vertex` and `path
//! end`, docs/printf.md) against what it accumulates there: over many
//! frames, one path a frame, the radiance each printed path adds up to
//! (the lines' `emitted`, plus `throughput × nee` at each vertex) averages
//! to the pixel's accumulated value within 4 standard errors. The printed
//! path is the frame's own sample (the same random numbers), so the mean
//! also agrees with the accumulation to f32 rounding.
//!
//! The scene has every kind of light a path meets: a point light (next-event
//! estimation only), a rect light (sampled by next-event estimation and hit
//! by the path, weighed by MIS) and the environment (sampled, and hit by an
//! escaping path); four bounces, so Russian roulette and the last bounce
//! both end paths.

use std::collections::BTreeMap;

use loupe::render::debug_print::PrintLine;
use loupe::render::passes::path_trace::testing::{COLOR, SAMPLES, image, loaded, session};
use serde_json::Value;

/// Frames (one path each) at the pixel.
const FRAMES: u32 = 400;
/// A floor pixel beside the ball, lit by both lights and the environment.
const PIXEL: [u32; 2] = [7, 18];
const SIZE: u32 = 24;

fn scene() -> String {
    format!(
        "[output]\nwidth = {SIZE}\nheight = {SIZE}\n\
         [camera]\nposition = [0.0, 1.2, 3.0]\ntarget = [0.0, 0.4, 0.0]\nfov_deg = 45.0\n\
         [[materials]]\nname = \"floor\"\nbase_color = [0.6, 0.6, 0.6]\nroughness = 0.8\n\
         [[materials]]\nname = \"ball\"\nbase_color = [0.8, 0.3, 0.2]\nroughness = 0.4\n\
         [[objects]]\nshape = \"plane\"\nmaterial = \"floor\"\nscale = 3.0\n\
         [[objects]]\nshape = \"sphere\"\nmaterial = \"ball\"\nposition = [0.0, 0.5, 0.0]\nscale = 0.5\n\
         [[lights]]\ntype = \"point\"\nposition = [1.5, 2.5, 1.0]\nintensity = 8.0\n\
         [[lights]]\ntype = \"rect\"\nposition = [-1.2, 1.4, 0.6]\ndirection = [0.6, -1.0, -0.2]\nsize = [0.8, 0.5]\nintensity = 6.0\n\
         [environment]\ntop = [0.4, 0.5, 0.7]\nbottom = [0.1, 0.1, 0.1]\nintensity = 1.0\n\
         [quality]\nrenderer = \"path\"\npath_spp = {FRAMES}\npath_bounces = 4\n"
    )
}

/// `path end`'s reasons, as path_trace.wgsl numbers them.
const REASONS: [&str; 6] = ["escaped", "absorbed", "max depth", "no sample", "roulette", "throughput"];

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn vector(v: &Value) -> [f64; 3] {
    let parts = v.as_array().map(Vec::as_slice).unwrap_or_default();
    [0, 1, 2].map(|i| parts.get(i).map_or(f64::NAN, number))
}

/// One frame's path as its lines print it: the radiance it adds up to and
/// why it ended. Checks the lines' order: vertices from depth 0 up, each
/// once, the first reached from the camera (no BSDF pdf), then one end, at
/// the last vertex's depth (it ended there) or one past it (it ended on the
/// way to the next).
fn path(lines: &[PrintLine]) -> Result<([f64; 3], usize), String> {
    let (end, vertices) = lines.split_last().ok_or("no line")?;
    let mut radiance = [0.0; 3];
    for (depth, line) in vertices.iter().enumerate() {
        let v = &line.values;
        if !line.text.starts_with("path vertex") || v.len() != 7 || number(&v[0]) != depth as f64 {
            return Err(format!("vertex {depth} expected: {}", line.text));
        }
        if depth == 0 && number(&v[6]) != 0.0 {
            return Err(format!("the camera ray has no BSDF pdf: {}", line.text));
        }
        let (throughput, emitted, nee) = (vector(&v[3]), vector(&v[4]), vector(&v[5]));
        for c in 0..3 {
            radiance[c] += emitted[c] + throughput[c] * nee[c];
        }
    }
    let v = &end.values;
    if !end.text.starts_with("path end") || v.len() != 5 {
        return Err(format!("an end expected last: {}", end.text));
    }
    let reason = number(&v[1]) as usize;
    let on_the_way = matches!(REASONS.get(reason), Some(&"escaped" | &"absorbed"));
    let at = if on_the_way { vertices.len() } else { vertices.len().checked_sub(1).ok_or("an end at a vertex without one")? };
    if number(&v[0]) != at as f64 || reason >= REASONS.len() {
        return Err(format!("after {} vertices: {}", vertices.len(), end.text));
    }
    let emitted = vector(&v[2]);
    for c in 0..3 {
        radiance[c] += emitted[c];
    }
    // As the shader counts a sample that went non-finite: black.
    Ok((if radiance.iter().all(|x| x.is_finite()) { radiance } else { [0.0; 3] }, reason))
}

#[test]
fn the_printed_path_adds_up_to_what_the_path_tracer_accumulates() {
    let mut s = session(&loaded(&scene(), BTreeMap::new()));
    s.set_debug_pixel(Some(PIXEL));
    s.reset_history();
    let (nothing, outputs) = (Default::default(), [COLOR, SAMPLES].map(str::to_owned).into());
    let mut samples = Vec::new();
    let mut reasons = [0u32; REASONS.len()];
    let mut last = None;
    for frame in 1..=FRAMES {
        let pending = s.submit(Some(if frame == FRAMES { &outputs } else { &nothing }), 1.0 / 30.0);
        let r = s.wait(pending);
        let printed = r.prints.as_ref().expect("a pixel is selected");
        assert_eq!(printed.dropped, 0, "frame {frame}");
        let (radiance, reason) = path(&printed.lines).unwrap_or_else(|e| panic!("frame {frame}: {e}\n{:#?}", printed.lines));
        samples.push(radiance);
        reasons[reason] += 1;
        last = Some(r);
    }
    let last = last.expect("frames ran");
    let at = 4 * (PIXEL[1] * SIZE + PIXEL[0]) as usize;
    assert_eq!(image(&last, SAMPLES).data[at], FRAMES as f32, "one sample a frame");
    let accumulated = &image(&last, COLOR).data[at..at + 3];
    let seen: Vec<String> = REASONS.iter().zip(reasons).filter(|(_, n)| *n > 0).map(|(r, n)| format!("{r} {n}")).collect();
    let n = f64::from(FRAMES);
    for c in 0..3 {
        let mean = samples.iter().map(|s| s[c]).sum::<f64>() / n;
        let variance = samples.iter().map(|s| (s[c] - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let error = (variance / n).sqrt();
        let want = f64::from(accumulated[c]);
        eprintln!("channel {c}: printed paths {mean:.6} ± {error:.6}, accumulated {want:.6}; ends: {}", seen.join(", "));
        assert!(error > 0.0, "channel {c}: the pixel is noisy");
        assert!(
            (mean - want).abs() <= 4.0 * error,
            "channel {c}: the printed paths average {mean} ± {error}, the pixel accumulated {want}"
        );
        // The same samples: equal but for f32 rounding (the accumulation's
        // sum over the frames, the prints' products).
        assert!(
            (mean - want).abs() <= 1e-4 * want.abs() + 1e-6,
            "channel {c}: the printed paths average {mean}, the pixel accumulated {want}"
        );
    }
    // Both kinds of end: on the way (the environment's light in the end's
    // `emitted`) and at a vertex.
    assert!(reasons[0] > 0 && reasons[2..].iter().any(|n| *n > 0), "ends: {}", seen.join(", "));
}
