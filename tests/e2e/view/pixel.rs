//! The Pixel panel of `loupe view`'s window against a real daemon: a
//! texel of the knot clicked in the Inspector pins that pixel on the
//! daemon; the panel lists its history through the frame as the daemon's
//! `pixel_history` event of that frame holds it, and a print of the
//! tonemap shader, following an edit; a click on the pinned texel,
//! Escape, or the panel's Unpin clears the daemon's selection.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use egui_kittest::kittest::{NodeT, Queryable, by};
use loupe::protocol::ServerEvent;
use loupe::serve::viewer::InProcess;
use loupe_tests::reload::TONEMAP;
use loupe_view::egui::accesskit::Role;
use loupe_view::{Link, egui};
use serde_json::Value;
use tokio::sync::broadcast::{self, error::TryRecvError};

use super::{Window, small_minimal};
use crate::printf::with_print;

/// The daemon's events as a WebSocket client reads them.
struct Events {
    rx: broadcast::Receiver<ServerEvent>,
    /// The newest `pixel_history` events, oldest first.
    histories: Vec<Value>,
    /// `prints` and `pixel_history` events, and frames, since the last
    /// [`Events::forget`].
    pixel_events: usize,
    frames: usize,
}

/// How many `pixel_history` events are kept to compare with.
const KEPT: usize = 64;

impl Events {
    fn new(w: &Window) -> Events {
        Events { rx: w.shared.events.subscribe(), histories: Vec::new(), pixel_events: 0, frames: 0 }
    }

    /// Reads what arrived.
    fn drain(&mut self) {
        loop {
            let event = match self.rx.try_recv() {
                Ok(e) => serde_json::to_value(e).expect("events are JSON"),
                Err(TryRecvError::Lagged(_)) => continue,
                Err(TryRecvError::Empty | TryRecvError::Closed) => return,
            };
            match event["type"].as_str() {
                Some("frame") => self.frames += 1,
                Some("prints") => self.pixel_events += 1,
                Some("pixel_history") => {
                    self.pixel_events += 1;
                    self.histories.push(event);
                    if self.histories.len() > KEPT {
                        self.histories.remove(0);
                    }
                }
                _ => {}
            }
        }
    }

    fn forget(&mut self) {
        self.drain();
        (self.pixel_events, self.frames) = (0, 0);
    }

    /// The daemon's history of `pixel` through `frame`, if it is kept.
    fn history(&self, pixel: [u32; 2], frame: u64) -> Option<&Value> {
        self.histories.iter().find(|h| h["pixel"] == serde_json::json!(pixel) && h["frame"] == frame)
    }
}

/// Every label's text, in the order the window lays them out.
fn texts(w: &Window) -> Vec<String> {
    w.harness.query_all(by().role(Role::Label)).filter_map(|n| n.accesskit_node().value()).collect()
}

/// A click of the primary button at `at`.
fn click(w: &mut Window, at: egui::Pos2) {
    w.harness.hover_at(at);
    w.harness.step();
    w.harness.drag_at(at);
    w.harness.step();
    w.harness.drop_at(at);
    w.harness.step();
}

/// A value of the protocol's RGBA as the panel shows it: each channel's
/// shortest decimal as a 32-bit float.
fn rgba(v: &Value) -> String {
    let channel = |c: &Value| c.as_f64().map_or("not finite".to_owned(), |c| (c as f32).to_string());
    v.as_array().expect("RGBA").iter().map(channel).collect::<Vec<_>>().join(", ")
}

/// What the panel must show of a `pixel_history` event's passes, in order.
fn expected(history: &Value) -> Vec<String> {
    let mut out = Vec::new();
    for p in history["passes"].as_array().expect("passes") {
        out.push(p["pass"].as_str().expect("pass").to_owned());
        out.push(p["kind"].as_str().expect("kind").to_owned());
        if let Some(id) = p["invocation"].as_array() {
            out.push(format!("invocation ({}, {}, {})", id[0], id[1], id[2]));
        }
        let inputs: Vec<&str> = p["inputs"].as_array().expect("inputs").iter().map(|i| i.as_str().expect("input")).collect();
        if !inputs.is_empty() {
            out.push(format!("reads {}", inputs.join(", ")));
        }
        for o in p["outputs"].as_array().expect("outputs") {
            out.push(format!("{} [{}, {}]", o["output"].as_str().expect("output"), o["texel"][0], o["texel"][1]));
            out.push(match o["origin"].as_str().expect("origin") {
                "read" => rgba(&o["before"]),
                "cleared" => "cleared".to_owned(),
                "undefined" => "undefined (first write)".to_owned(),
                _ => "not read".to_owned(),
            });
            out.push(if o["after"].is_null() { "not read".to_owned() } else { rgba(&o["after"]) });
        }
        for d in p["draws"].as_array().into_iter().flatten() {
            for f in d["fragments"].as_array().expect("fragments") {
                out.push(d["name"].as_str().expect("name").to_owned());
                out.push(f["primitive"].to_string());
                out.push(f["depth"].as_f64().map_or("—".to_owned(), |d| (d as f32).to_string()));
                let verdict = f["verdict"].as_str().expect("verdict").replace('_', " ");
                let kept = f["helper"] == false && p["survivor"]["draw"] == d["name"] && p["survivor"]["primitive"] == f["primitive"];
                out.push(match (f["helper"] == true, kept) {
                    (true, _) => format!("{verdict} (helper lane)"),
                    (false, true) => format!("{verdict}, wrote the pixel"),
                    (false, false) => verdict,
                });
            }
        }
    }
    out
}

/// Whether `shown` holds every one of `wanted`, in order.
fn in_order(shown: &[String], wanted: &[String]) -> Result<(), String> {
    let mut rest = shown.iter();
    for w in wanted {
        if !rest.any(|s| s == w) {
            return Err(format!("`{w}` is missing, or out of order"));
        }
    }
    Ok(())
}

/// The fragments the daemon listed for `pass`: `(draw, verdict)`.
fn fragments(history: &Value, pass: &str) -> Vec<(String, String)> {
    let p = history["passes"].as_array().expect("passes").iter().find(|p| p["pass"] == pass);
    let draws = p.and_then(|p| p["draws"].as_array()).into_iter().flatten();
    draws
        .flat_map(|d| {
            let name = d["name"].as_str().expect("name").to_owned();
            d["fragments"]
                .as_array()
                .expect("fragments")
                .iter()
                .map(move |f| (name.clone(), f["verdict"].as_str().expect("verdict").to_owned()))
        })
        .collect()
}

/// After the pin is gone, the frames in flight land with their events;
/// then frames come and no history or prints with them.
fn assert_the_daemon_stopped(w: &mut Window, events: &mut Events, how: &str) {
    assert_eq!(w.harness.state().model().pixel, None, "{how} unpins");
    events.forget();
    // At most two frames are in flight, and one may be recorded as the
    // command arrives.
    w.step_until("the frames in flight", |_| {
        events.drain();
        events.frames >= 3
    });
    events.forget();
    w.step_until("five more frames", |_| {
        events.drain();
        events.frames >= 5
    });
    assert_eq!(events.pixel_events, 0, "{how}: the daemon records the pixel no more");
    assert!(w.harness.query_by_label_contains("Click a texel in the Inspector").is_some(), "{how}: the panel says how to pin");
}

#[test]
fn a_pinned_knot_pixel_shows_its_history_and_prints_until_unpinned() {
    let p = small_minimal("view-pixel", "");
    let good = p.read(TONEMAP);
    p.write(TONEMAP, with_print(&good, "debugPrintf(\"at %v2f\", in.position.xy);"));
    let mut w = Window::open(&p, "scenes/minimal.toml", 30.0, None, egui::vec2(1024.0, 768.0));
    let mut events = Events::new(&w);
    w.step_until("a frame", |h| h.state().model().frame.is_some());
    w.harness.get_by_label("tonemap").click();
    w.step_until("the Inspector", |h| h.state().inspected() == Some("tonemap/color"));

    // Texels are clicked about the image's middle, where the knot lies,
    // until one of the knot in front of itself is pinned: the G-buffer's
    // fragments there pass and fail the depth test.
    let mut sweep = (0..36).map(|i: i32| egui::pos2(300.0 + (i % 6 * 25) as f32, 250.0 + (i / 6 * 25) as f32));
    let (at, pixel) = loop {
        let at = sweep.next().expect("a knot pixel in front of itself is clicked");
        click(&mut w, at);
        let Some(pixel) = w.harness.state().model().pixel else { panic!("a click at {at:?} pins nothing") };
        w.step_until("the pinned pixel's history", |h| h.state().model().history.is_some());
        let frame = w.harness.state().model().history.as_ref().expect("history").frame;
        w.step_until("the daemon's event", |_| {
            events.drain();
            events.history(pixel, frame).is_some()
        });
        let verdicts: Vec<String> = fragments(events.history(pixel, frame).expect("kept"), "gbuffer").into_iter().map(|f| f.1).collect();
        if verdicts.iter().any(|v| v == "passed") && verdicts.iter().any(|v| v == "failed_depth") {
            break (at, pixel);
        }
    };
    assert!(w.display.inspected().is_some(), "the Inspector shows tonemap/color");

    // The panel shows the pixel and frame the daemon's event is of, and
    // every pass's values and fragments as it holds them, in its order.
    // (The panel and the model are of the same step: the newest frame.)
    let shown = texts(&w);
    let frame = w.harness.state().model().history.as_ref().expect("history").frame;
    events.drain();
    let daemon = events.history(pixel, frame).expect("the daemon sent the history the panel shows").clone();
    let head = format!("({}, {}) through frame {frame}", pixel[0], pixel[1]);
    assert!(shown.contains(&head), "the panel names the pixel and frame: {shown:?}");
    let history = shown.iter().position(|t| t == "History").expect("the history's heading");
    let wanted = expected(&daemon);
    if let Err(e) = in_order(&shown[history..], &wanted) {
        panic!("{e}: the panel shows {:?}, the daemon's event {wanted:?}", &shown[history..]);
    }
    let gbuffer = fragments(&daemon, "gbuffer");
    assert!(gbuffer.iter().all(|(draw, _)| draw == "object0"), "the knot is the minimal scene's one object: {gbuffer:?}");
    assert!(shown.iter().any(|t| t == "failed depth") && shown.iter().any(|t| t == "passed"), "{shown:?}");
    assert_eq!(fragments(&daemon, "tonemap"), [("fullscreen triangle".to_owned(), "not_tested".to_owned())], "one fragment");

    // The print: its text at the pixel's centre, under its call's source
    // line; an edit to it shows in both.
    let text = format!("at {}.500000, {}.500000", pixel[0], pixel[1]);
    w.step_until("the print", |h| h.query_by_label(&text).is_some());
    assert!(w.harness.query_by_label("debugPrintf(\"at %v2f\", in.position.xy);").is_some(), "the call's source line");
    p.write(TONEMAP, with_print(&good, "debugPrintf(\"now %.1v2f\", in.position.xy);"));
    let text = format!("now {}.5, {}.5", pixel[0], pixel[1]);
    w.step_until("the edited print", |h| h.query_by_label(&text).is_some());
    w.step_until("its source line", |h| h.query_by_label("debugPrintf(\"now %.1v2f\", in.position.xy);").is_some());

    // The pinned texel clicked again: the daemon no longer records it.
    w.harness.run_steps(30);
    click(&mut w, at);
    assert_the_daemon_stopped(&mut w, &mut events, "a click on the pinned texel");

    // Pinned again, then Escape.
    click(&mut w, at);
    assert_eq!(w.harness.state().model().pixel, Some(pixel));
    w.step_until("the history again", |h| h.state().model().history.is_some());
    w.harness.key_press(egui::Key::Escape);
    w.harness.step();
    assert_the_daemon_stopped(&mut w, &mut events, "Escape");

    // Pinned again, then the panel's Unpin.
    w.harness.run_steps(30);
    click(&mut w, at);
    w.step_until("the history again", |h| h.state().model().history.is_some());
    w.harness.get_by_label("Unpin").click();
    w.harness.step();
    assert_the_daemon_stopped(&mut w, &mut events, "Unpin");

    // A pixel outside the frame is refused by the link itself.
    let link = InProcess::new(w.shared.clone(), w.display.clone(), Arc::new(AtomicBool::new(false)));
    let refused = link.debug_pixel(Some([64, 0])).expect_err("(64, 0) is outside the 64x36 frame");
    assert!(refused.contains("outside the 64x36 frame"), "{refused}");
    w.close();
}
