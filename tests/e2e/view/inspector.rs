//! The Inspector of `loupe view`'s window against a real daemon: a pass's
//! output drawn by the display pass, the exact value of the texel under
//! the cursor, a channel of it, and depth fitted to its values.

use std::time::{Duration, Instant};

use egui_kittest::kittest::{By, NodeT, Queryable};
use loupe::serve::shared::read;
use loupe_view::egui;
use loupe_view::presets::{Channel, QuadOverlay};
use loupe_view::viewer::Centre;

use super::{Window, open_small, small_minimal};

/// The whole text of the first label holding `part` (a wrapped label's
/// lines are nodes of their own too).
fn text_with(w: &Window, part: &str) -> Option<String> {
    let by = By::new().predicate(move |n| n.value().is_some_and(|v| v.contains(part)));
    w.harness.query_all(by).next()?.accesskit_node().value()
}

/// The readout under the image: `((x, y), values, frame)`.
fn readout(w: &Window) -> Option<([u32; 2], Vec<f32>, u64)> {
    let text = text_with(w, "· frame")?;
    let (place, rest) = text.strip_prefix('(')?.split_once(") ")?;
    let (x, y) = place.split_once(", ")?;
    let (values, frame) = rest.rsplit_once("· frame ")?;
    let values = values.split("  ").filter_map(|v| v.split_once(' ')?.1.trim().parse().ok()).collect();
    Some(([x.parse().ok()?, y.parse().ok()?], values, frame.trim().parse().ok()?))
}

/// The 8-bit sRGB encoding of linear `v`, as the display pass writes it.
fn encoded(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// Hovers `at` until the readout names a texel of a frame whose capture
/// of `tonemap/color` the daemon also holds; returns the texel, the
/// readout's values and the capture's.
fn value_under(w: &mut Window, at: egui::Pos2) -> ([u32; 2], Vec<f32>, [f32; 4]) {
    let start = Instant::now();
    loop {
        w.harness.hover_at(at);
        w.harness.step();
        if let Some((texel, values, frame)) = readout(w) {
            let captures = read(&w.shared.captures);
            let capture = captures.get("tonemap/color").expect("the final output is always captured");
            if capture.frame == frame {
                return (texel, values, capture.pixel(texel[0], texel[1]));
            }
        }
        assert!(start.elapsed() < Duration::from_secs(120), "no readout matched a capture of its frame");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_pass_output_shows_with_the_exact_value_under_the_cursor() {
    let p = small_minimal("view-inspector", "");
    let mut w = open_small(&p, None);
    w.step_until("a frame", |h| h.state().model().frame.is_some());

    // Clicking a pass opens its output in the Inspector, with its preset.
    w.harness.get_by_label("tonemap").click();
    w.step_until("the Inspector", |h| h.state().inspected() == Some("tonemap/color"));
    assert_eq!(w.harness.state().centre(), Centre::Inspector);
    let options = w.harness.state().display_options().expect("a preset");
    assert_eq!((options.channel, options.srgb, options.min, options.max), (Channel::Rgb, true, 0.0, 1.0), "colour's preset");

    // Two texels apart: each readout is the capture's value at the texel
    // it names, exactly, and the screen shows that value under the cursor.
    let (a, b) = (egui::pos2(200.0, 220.0), egui::pos2(240.0, 230.0));
    let (ta, va, ca) = value_under(&mut w, a);
    let (tb, vb, cb) = value_under(&mut w, b);
    assert!(tb[0] > ta[0] && tb[1] >= ta[1], "moving right and down moves the texel so: {ta:?} → {tb:?}");
    assert_eq!(va, ca, "the readout at {ta:?}");
    assert_eq!(vb, cb, "the readout at {tb:?}");
    let shot = w.harness.render().expect("renders");
    for (at, value) in [(a, ca), (b, cb)] {
        let px = shot.get_pixel(at.x as u32, at.y as u32).0;
        for c in 0..3 {
            assert!(px[c].abs_diff(encoded(value[c])) <= 2, "channel {c} at {at:?}: shown {px:?}, the value {value:?}");
        }
    }
    assert_ne!(ca, cb, "two texels of the lit frame differ, or this test could not tell them apart");

    // The red channel alone: grey at the red value.
    w.harness.get_by_label("channel").click();
    w.harness.run_steps(3);
    w.harness.get_by_label("R").click();
    w.step_until("the red channel", |h| h.state().display_options().is_some_and(|o| o.channel == Channel::R));
    let (_, _, value) = value_under(&mut w, a);
    let start = Instant::now();
    loop {
        let px = w.harness.render().expect("renders").get_pixel(a.x as u32, a.y as u32).0;
        let want = encoded(value[0]);
        if px[..3].iter().all(|c| c.abs_diff(want) <= 2) {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "red alone shows {px:?}, not grey {want}");
        w.harness.step();
    }
    w.close();
}

#[test]
fn depth_opens_linearised_and_fitted_to_its_values() {
    let p = small_minimal("view-inspector-depth", "");
    let mut w = open_small(&p, None);
    w.step_until("a frame", |h| h.state().model().frame.is_some());
    let depth = w
        .harness
        .state()
        .model()
        .textures()
        .find(|(_, o)| o.meaning.as_deref() == Some("depth") && o.planes().is_some())
        .map(|(n, o)| (n, o.planes().expect("planes")));
    let (output, planes) = depth.expect("the minimal scene has a camera depth");
    let pass = output.split_once('/').expect("pass/output").0.to_owned();
    w.harness.get_by_label(&pass).click();
    // Fitted: the range measured on the GPU replaces the preset's 0…1.
    w.step_until("the fitted range", |h| h.state().display_options().is_some_and(|o| (o.min, o.max) != (0.0, 1.0)));
    let o = w.harness.state().display_options().expect("options");
    assert_eq!(o.linearize, Some(planes), "shown as distance");
    // The knot lies within 5 units of the camera: the clear value (1, the
    // far plane, 200 units away) is left out.
    assert!(
        planes.near <= o.min && o.min < o.max && o.max < 5.0,
        "the range {} … {} is the knot's, between the planes {planes:?}",
        o.min,
        o.max
    );
    // A texel of the knot, read in a frame after the one measured: its
    // distance lies in the fitted range. The pointer sweeps the image
    // until it is over the knot.
    let fitted = w.harness.state().model().frame.expect("a frame").0;
    let start = Instant::now();
    let mut sweep = (0..).map(|i: u32| egui::pos2(100.0 + (i % 20) as f32 * 15.0, 120.0 + (i / 20 % 12) as f32 * 15.0));
    let text = loop {
        let at = sweep.next().expect("endless");
        let mut last = None;
        for _ in 0..10 {
            w.harness.hover_at(at);
            w.harness.step();
            last = readout(&w).filter(|(_, _, frame)| *frame > fitted).and(text_with(&w, "· frame"));
            if last.is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        if let Some(text) = last.as_ref().filter(|t| t.contains("(distance ")) {
            break text.clone();
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no distance under the cursor; the last readout: {last:?}");
    };
    let distance: f32 = text.split("(distance ").nth(1).and_then(|r| r.split(')').next()).and_then(|d| d.parse().ok()).expect("a distance");
    assert!(o.min <= distance && distance <= o.max, "{distance} in {} … {}: {text}", o.min, o.max);
    w.close();
}

/// The count line under the readout: `(map name, count)`.
fn count_line(w: &Window) -> Option<(String, f32)> {
    let text = text_with(w, " · quads launched over").or_else(|| text_with(w, " · times this pixel ran"))?;
    let (head, _) = text.split_once(" · ")?;
    let (name, n) = head.rsplit_once(' ')?;
    Some((name.to_owned(), n.parse().ok()?))
}

/// Picks `item` of the combo box labelled `combo`.
fn choose(w: &mut Window, combo: &str, item: &str) {
    w.harness.get_by_label(combo).click();
    w.harness.run_steps(3);
    w.harness.get_by_label(item).click();
    w.harness.run_steps(3);
}

#[test]
fn quad_statistics_total_each_raster_pass_and_lay_its_maps_over_its_output() {
    let p = small_minimal("view-inspector-quads", "");
    // Room for the pass list with each raster pass's totals under it.
    let mut w = Window::open(&p, "scenes/minimal.toml", 30.0, None, egui::vec2(1024.0, 768.0));
    w.step_until("a frame", |h| h.state().model().frame.is_some());

    // On, every raster pass of a frame's statistics states its totals as
    // the daemon computed them.
    w.harness.get_by_label("quad statistics").click();
    w.step_until("the passes' quad totals", |h| h.state().model().passes.iter().any(|p| p.quads.is_some()));
    let report = read(&w.shared.quads).clone().expect("the daemon computes quad statistics while the window asks");
    let gbuffer = report.passes.iter().find(|p| p.quads.pass == "gbuffer").expect("the G-buffer is a raster pass");
    // A static scene: every frame's statistics are the same.
    let digits = gbuffer.quads.quads.shaded.quads.to_string();
    let groups: Vec<&str> = digits.as_bytes().rchunks(3).rev().map(|c| std::str::from_utf8(c).expect("digits")).collect();
    let stated = format!("{} quads · ", groups.join(","));
    w.step_until("the G-buffer's quads", |h| h.query_by_label_contains(&stated).is_some());

    // The G-buffer's output under its quad maps: the count under the
    // cursor is the daemon's map at that texel, and the screen shows the
    // count's colour over the image.
    w.harness.get_by_label("gbuffer").click();
    w.step_until("the Inspector", |h| h.state().inspected().is_some_and(|o| o.starts_with("gbuffer/")));
    choose(&mut w, "quad map", "quad overdraw");
    assert_eq!(w.harness.state().quad_overlay().map(|(o, _)| o), Some(QuadOverlay::Overdraw));
    // The daemon's maps (a static scene: every frame's are the same).
    let report = read(&w.shared.quads).clone().expect("statistics");
    let (width, _, overdraw, helpers) =
        report.passes.iter().find(|p| p.quads.pass == "gbuffer").and_then(|p| p.quads.first_maps()).expect("maps");
    // The pointer sweeps the image until it is over a drawn texel whose
    // two counts differ (so the maps cannot be told apart by accident),
    // waiting at each place for its value; the knot lies in the middle.
    let start = Instant::now();
    let mut sweep = (0..).map(|i: u32| egui::pos2(200.0 + (i % 16) as f32 * 20.0, 300.0 + (i / 16 % 14) as f32 * 20.0));
    let (at, texel, count) = loop {
        let at = sweep.next().expect("endless");
        let mut read = None;
        for _ in 0..20 {
            w.harness.hover_at(at);
            w.harness.step();
            read = readout(&w).zip(count_line(&w));
            if read.is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        if let Some(((texel, _, _), (name, n))) = &read
            && name == "quad overdraw"
            && *n >= 1.0
            && overdraw[(texel[1] * width + texel[0]) as usize] != helpers[(texel[1] * width + texel[0]) as usize]
        {
            break (at, *texel, *n);
        }
        assert!(start.elapsed() < Duration::from_secs(90), "no texel under a quad; the last readout: {read:?}");
    };
    let (overlay, map) = w.harness.state().quad_overlay().expect("shown");
    let map = map.expect("the maps painted").clone();
    assert_eq!(map.pass, "gbuffer");
    let i = (texel[1] * width + texel[0]) as usize;
    assert_eq!(count, overdraw[i], "the count at {texel:?} is the daemon's");
    assert_eq!(map.overdraw[i], overdraw[i]);
    assert_eq!(map.helpers, helpers);

    let colour = overlay.colour(count, texel[0], texel[1]).expect("a colour for a count");
    let distance = |px: [u8; 4]| (0..3).map(|c| i32::from(px[c]).abs_diff(i32::from(colour[c]))).sum::<u32>();
    let shown = w.harness.render().expect("renders").get_pixel(at.x as u32, at.y as u32).0;
    choose(&mut w, "quad map", "none");
    assert!(w.harness.state().quad_overlay().is_none());
    let bare = w.harness.render().expect("renders").get_pixel(at.x as u32, at.y as u32).0;
    assert!(
        distance(shown) + 60 < distance(bare),
        "at {at:?} the overlay's colour {colour:?} shows: {shown:?} under it, {bare:?} without it"
    );

    // The helper-lane map reads its own counts.
    choose(&mut w, "quad map", "helper lanes");
    let start = Instant::now();
    while readout(&w).is_none_or(|(t, _, _)| t != texel) {
        w.harness.hover_at(at);
        w.harness.step();
        assert!(start.elapsed() < Duration::from_secs(30), "the texel's value never came back");
        std::thread::sleep(Duration::from_millis(20));
    }
    let (name, n) = count_line(&w).expect("the count line");
    assert_eq!((name.as_str(), n), ("helper lanes", helpers[i]));

    // Off, the totals and maps are gone and the daemon stops computing them.
    w.harness.get_by_label("quad statistics").click();
    w.step_until("no quad totals", |h| h.state().model().passes.iter().all(|p| p.quads.is_none()));
    let shared = w.shared.clone();
    w.step_until("the daemon to stop", |_| read(&shared.quads).is_none());
    w.close();
}
