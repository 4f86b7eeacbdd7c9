//! Snapshot tests of the window's main panels: the default view (Frame,
//! Passes, Problems), the Scene and Timings tabs, the Inspector with a
//! texel hovered, bare and under the quad overdraw map, and the Pixel
//! panel of a pinned pixel, each compared with its PNG in `snapshots/`
//! (`UPDATE_SNAPSHOTS=1` rewrites them: README, "Tests").
//!
//! A live daemon's pixels vary (frame numbers, times, lavapipe's pace), so
//! the window here reads a fixed input: [`Replay`], a link replaying events
//! recorded once from a real daemon, with a fixed gradient as the frame and
//! the inspected image. It is an input for the layout, not a stand-in for
//! the daemon: the other view tests drive a real one.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use egui_kittest::kittest::Queryable;
use egui_kittest::{Harness, SnapshotOptions, wgpu::WgpuTestRenderer};
use loupe_tests::reload::srgb;
use loupe_view::{Command, DisplayImage, Inspect, Inspected, Link, Probe, Probed, QuadMap, Range, Viewer, egui, egui_wgpu};

/// `loupe serve --scene scenes/minimal.toml` on lavapipe, on a copy of the
/// repository, as a WebSocket client of `/ws` read it: the `hello`, then
/// the state a link starts from (`GET /api/passes`, `/api/controls` and
/// `/api/nan` as the `passes`, `controls` and `nan` events
/// `Shared::state_events` sends), eight frames; then
/// `shaders/post/tonemap.wgsl` saved with line 16's `max(` made `mux(`:
/// the reload's events, its diagnostics (located in the repository's own
/// file, so the excerpt shows its line 16), the pass list with `tonemap`
/// stale, and four more frames. One event a line.
const EVENTS: &str = include_str!("snapshot_events.json");

/// `loupe render --scene scenes/minimal.toml --debug-pixel 320,200` on a
/// copy of the repository whose tonemap shader prints (as [`printing`]
/// makes it): the report's `history` and `prints` as the `pixel_history`
/// and `prints` events a daemon sends (the same serialisation, with their
/// `type` and the frame after the recorded ones). A pixel of the knot, in
/// front of itself.
const PIXEL_EVENTS: &str = include_str!("snapshot_pixel.json");

/// The tonemap shader [`PIXEL_EVENTS`] were recorded with: the directive
/// on its blank line 5 and the print after its `c` (line 17), so that the
/// lines the recorded error's excerpt shows (15 and 16) are the
/// repository's.
fn printing(tonemap: &str) -> String {
    let mut lines: Vec<&str> = tonemap.split('\n').collect();
    assert_eq!((lines[4], lines[15]), ("", "    let c = max(texel.rgb, vec3(0.0));"), "the premise: tonemap.wgsl's lines 5 and 16");
    lines[4] = "enable wgpu_debug_printf;";
    lines.insert(16, "    debugPrintf(\"at %v2f\", in.position.xy);");
    lines.join("\n")
}

/// The recorded frame's size (the minimal scene's output): the fixed image
/// is the frame and the inspected `tonemap/color` alike.
const IMAGE: [u32; 2] = [640, 360];

/// One window size for every snapshot.
const WINDOW: egui::Vec2 = egui::vec2(1024.0, 640.0);

/// How a snapshot may differ from its PNG and still pass (docs/view.md,
/// "Tests", has the measurements).
///
/// `threshold` is per pixel, in dify's weighted squared YIQ distance of
/// 8-bit values: a step of 1 in R, G and B together is 0.5, of 2 is 2.0;
/// text or a panel edge against the background is thousands. lavapipe
/// rounds filtering and blending by the CPU features it finds: held to
/// AVX, SSE4.1, SSSE3, SSE2 or no SIMD (`GALLIUM_OVERRIDE_CPU_CAPS`), up
/// to 671 pixels changed here, every one by under 0.6. 2.0 leaves a margin
/// over that.
///
/// `max_failed_pixels`: none. Nothing measured exceeds the threshold, and
/// the smallest change tried, one digit of a button's label ("1:1" made
/// "1:2"), is only 12 pixels, over the threshold at any setting: an
/// allowance of pixels would hide such changes first.
fn options() -> SnapshotOptions {
    SnapshotOptions::new()
        .threshold(2.0)
        .max_failed_pixels(0)
        .output_path(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("e2e/view/snapshots"))
}

/// The linear value of the fixed image at a texel: red rising to the
/// right, green downward, blue a checker of 40-texel squares, opaque.
fn texel(x: u32, y: u32) -> [f32; 4] {
    let blue = if (x / 40 + y / 40).is_multiple_of(2) { 0.2 } else { 0.7 };
    [x as f32 / (IMAGE[0] - 1) as f32, y as f32 / (IMAGE[1] - 1) as f32, blue, 1.0]
}

/// The fixed quad overdraw at a texel: bands of 1 to 6 quads, 60 texels
/// wide, so every solid step and the hatch show; one helper lane a texel
/// in every other band.
fn quad_counts(x: u32, _: u32) -> (f32, f32) {
    let band = x / 60 % 6;
    ((band + 1) as f32, (band % 2) as f32)
}

/// The fixed image as the display pass writes one: `Rgba8Unorm` holding
/// sRGB-encoded values, on the window's device.
fn fixed_image(render: &egui_wgpu::RenderState) -> DisplayImage {
    let size = wgpu::Extent3d { width: IMAGE[0], height: IMAGE[1], depth_or_array_layers: 1 };
    let texture = render.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("snapshot image"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let encode = |v: f32| (srgb(v) * 255.0).round() as u8;
    let bytes: Vec<u8> = (0..IMAGE[1]).flat_map(|y| (0..IMAGE[0]).flat_map(move |x| texel(x, y).map(encode))).collect();
    let layout = wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * IMAGE[0]), rows_per_image: None };
    render.queue.write_texture(texture.as_image_copy(), &bytes, layout, size);
    DisplayImage { view: texture.create_view(&wgpu::TextureViewDescriptor::default()), size: IMAGE, generation: 1 }
}

/// The link the snapshots read: the recorded events on the first poll,
/// the fixed image as the frame and as whatever is inspected, the fixed
/// image's value at any texel probed and its range when measured, and,
/// while quad statistics are asked for, fixed ones for `tonemap` (a
/// `quads` event and [`quad_counts`] as its maps), all "after" the last
/// recorded frame, and while the pixel of [`PIXEL_EVENTS`] is selected,
/// those events. Commands are recorded, not carried out.
struct Replay {
    events: Vec<serde_json::Value>,
    frame: u64,
    /// The pixel selected (`debug_pixel`).
    pixel: Mutex<Option<[u32; 2]>>,
    image: DisplayImage,
    sent: Arc<Mutex<Vec<Command>>>,
    inspect: Mutex<Option<Inspect>>,
    probe: Mutex<Option<Probe>>,
    measure: Mutex<Option<Inspect>>,
    quads: AtomicBool,
}

impl Replay {
    fn new(image: DisplayImage, sent: Arc<Mutex<Vec<Command>>>) -> Replay {
        let events: Vec<serde_json::Value> = serde_json::from_str(EVENTS).expect("the recorded events are JSON");
        let frame = events.iter().filter(|e| e["type"] == "frame").filter_map(|e| e["frame"].as_u64()).next_back();
        let frame = frame.expect("the recording has frames");
        let (inspect, probe, measure) = (Mutex::default(), Mutex::default(), Mutex::default());
        Replay { events, frame, pixel: Mutex::default(), image, sent, inspect, probe, measure, quads: AtomicBool::new(false) }
    }
}

impl Link for Replay {
    fn poll(&mut self) -> Vec<serde_json::Value> {
        let mut events = std::mem::take(&mut self.events);
        if self.quads.load(Ordering::Relaxed) {
            let totals = serde_json::json!({"name": "total", "cull_mode": "none", "triangles": 1, "culled_triangles": 0,
                "pixels": 230400, "quads": 57840, "helper_lanes": 960, "quad_efficiency": 0.9959, "rasterized": null});
            events.push(serde_json::json!({"type": "quads", "frame": self.frame, "adapter": "llvmpipe",
                "passes": [{"pass": "tonemap", "draws": [], "quads": totals, "what_if": null, "fragment_invocations": null}]}));
        }
        let recorded: Vec<serde_json::Value> = serde_json::from_str(PIXEL_EVENTS).expect("the recorded pixel events are JSON");
        let pixel = *self.pixel.lock().expect("pixel");
        events.extend(recorded.into_iter().filter(|e| pixel.is_some_and(|p| e["pixel"] == serde_json::json!(p))));
        events
    }

    fn debug_pixel(&self, pixel: Option<[u32; 2]>) -> Result<(), String> {
        *self.pixel.lock().expect("pixel") = pixel;
        Ok(())
    }

    fn send(&self, command: Command) -> Result<(), String> {
        self.sent.lock().expect("the command log").push(command);
        Ok(())
    }

    fn source(&self, file: &str) -> Option<String> {
        let text = std::fs::read_to_string(loupe_tests::repo().join(file)).ok()?;
        Some(if file == loupe_tests::reload::TONEMAP { printing(&text) } else { text })
    }

    fn display(&self) -> Option<DisplayImage> {
        Some(self.image.clone())
    }

    // The fixed image needs no copy to be shown, and nothing renders.
    fn set_shown(&self, _: bool) {}

    fn set_minimised(&self, _: bool) {}

    // The harness steps the window itself.
    fn wake_with(&mut self, _: Box<dyn Fn() + Send + Sync>) {}

    // The snapshots show no tensor.
    fn tensors(&self, _: std::collections::BTreeSet<String>) -> Result<(), String> {
        Ok(())
    }

    fn tensor(&self, _: &str) -> Option<loupe_view::Tensor> {
        None
    }

    fn quad_statistics(&self, on: bool) -> Result<(), String> {
        self.quads.store(on, Ordering::Relaxed);
        Ok(())
    }

    fn quad_map(&self, pass: &str) -> Option<QuadMap> {
        if pass != "tonemap" || !self.quads.load(Ordering::Relaxed) {
            return None;
        }
        let counts: Vec<(f32, f32)> = (0..IMAGE[1]).flat_map(|y| (0..IMAGE[0]).map(move |x| quad_counts(x, y))).collect();
        let (overdraw, helpers) = counts.into_iter().unzip();
        Some(QuadMap { pass: pass.into(), frame: self.frame, width: IMAGE[0], height: IMAGE[1], overdraw, helpers })
    }

    fn inspect(&self, inspect: Option<Inspect>) {
        *self.inspect.lock().expect("inspect") = inspect;
    }

    fn inspected(&self) -> Option<Inspected> {
        let inspect = self.inspect.lock().expect("inspect").clone()?;
        Some(Inspected { image: self.image.clone(), inspect, frame: self.frame })
    }

    fn probe(&self, probe: Option<Probe>) {
        *self.probe.lock().expect("probe") = probe;
    }

    fn probed(&self) -> Option<Probed> {
        let probe = self.probe.lock().expect("probe").clone()?;
        let value = texel(probe.x, probe.y);
        Some(Probed { probe, frame: self.frame, value })
    }

    fn measure(&self, inspect: Inspect) {
        *self.measure.lock().expect("measure") = Some(inspect);
    }

    fn measured(&self) -> Option<Range> {
        let output = self.measure.lock().expect("measure").as_ref()?.output.clone();
        // Red and green span 0…1, blue the checker's two values; opaque;
        // luminance (Rec. 709) from the darkest corner to the brightest.
        let luminance = |[r, g, b, _]: [f32; 4]| 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let (dark, bright) = (texel(0, 0), texel(IMAGE[0] - 1, IMAGE[1] - 1));
        let channels = [Some((0.0, 1.0)), Some((0.0, 1.0)), Some((0.2, 0.7)), Some((1.0, 1.0)), Some((luminance(dark), luminance(bright)))];
        Some(Range { output, frame: self.frame, channels })
    }

    fn closed(&self) -> bool {
        false
    }
}

/// The window over [`Replay`], settled, and the log of what it sent.
fn open() -> (Harness<'static, Viewer>, Arc<Mutex<Vec<Command>>>) {
    // kittest's own adapter choice: a CPU one (lavapipe) wherever there is
    // one, so a machine's GPU does not change the pixels.
    let render = egui_kittest::wgpu::create_render_state(egui_kittest::wgpu::default_wgpu_setup(), egui_wgpu::RendererOptions::PREDICTABLE);
    let sent = Arc::new(Mutex::new(Vec::new()));
    let viewer = Viewer::new(Box::new(Replay::new(fixed_image(&render), sent.clone())), None);
    let r = render.clone();
    let mut harness = Harness::builder()
        .with_size(WINDOW)
        .with_render_cursor(false)
        .renderer(WgpuTestRenderer::from_render_state(render))
        .build_ui_state(move |ui, viewer: &mut Viewer| viewer.ui(ui, Some(&r)), viewer);
    settle(&mut harness);
    (harness, sent)
}

/// Steps until the layout is stable: the viewer asks for a repaint every
/// frame (the daemon's frames arrive at their own rate), so `run` would
/// never settle; panels and grids size themselves in their first frames.
fn settle(harness: &mut Harness<'static, Viewer>) {
    harness.run_steps(4);
}

/// Compares the window with its snapshot `name`; the panels showed, and
/// sent nothing to the daemon.
fn snapshot(harness: &mut Harness<'static, Viewer>, sent: &Mutex<Vec<Command>>, name: &str) {
    if let Err(e) = harness.try_snapshot_options(name, &options()) {
        panic!("{e}");
    }
    let sent = sent.lock().expect("the command log");
    assert!(sent.is_empty(), "showing the panels sends nothing: {sent:?}");
}

#[test]
fn snapshots_the_default_view() {
    let (mut harness, sent) = open();
    assert!(harness.query_by_label_contains("shaders/post/tonemap.wgsl:16:13").is_some(), "the recorded error is shown");
    snapshot(&mut harness, &sent, "default");
}

/// Snapshot `name`: the window with the right-hand panel's `tab` open.
fn snapshot_tab(tab: &str, name: &str) {
    let (mut harness, sent) = open();
    harness.get_by_label(tab).click();
    settle(&mut harness);
    snapshot(&mut harness, &sent, name);
}

#[test]
fn snapshots_the_scene_tab() {
    snapshot_tab("Scene", "scene");
}

#[test]
fn snapshots_the_timings_tab() {
    snapshot_tab("Timings", "timings");
}

#[test]
fn snapshots_the_inspector_with_a_texel_hovered() {
    let (mut harness, sent) = open();
    harness.get_by_label("tonemap").click();
    settle(&mut harness);
    harness.hover_at(egui::pos2(300.0, 250.0));
    settle(&mut harness);
    assert!(harness.query_by_label_contains("· frame 42").is_some(), "the readout names the hovered texel's value");
    snapshot(&mut harness, &sent, "inspector");
}

#[test]
fn snapshots_the_inspector_under_the_quad_overdraw_map() {
    let (mut harness, sent) = open();
    harness.get_by_label("quad statistics").click();
    settle(&mut harness);
    assert!(harness.query_by_label_contains("57,840 quads").is_some(), "the pass list states tonemap's quads");
    harness.get_by_label("tonemap").click();
    settle(&mut harness);
    harness.get_by_label("quad map").click();
    settle(&mut harness);
    harness.get_by_label("quad overdraw").click();
    settle(&mut harness);
    harness.hover_at(egui::pos2(300.0, 250.0));
    settle(&mut harness);
    assert!(harness.query_by_label_contains("quads launched over this pixel's 2×2 block").is_some(), "the count under the cursor");
    snapshot(&mut harness, &sent, "inspector_quads");
}

/// The pixel [`PIXEL_EVENTS`] are of, and where the Inspector shows its
/// texel of `tonemap/color` in the window.
const PINNED: [u32; 2] = [320, 200];
const PINNED_AT: egui::Pos2 = egui::pos2(336.0, 347.8);

#[test]
fn snapshots_the_pixel_panel_of_a_pinned_pixel() {
    let (mut harness, sent) = open();
    harness.get_by_label("tonemap").click();
    settle(&mut harness);
    harness.hover_at(PINNED_AT);
    harness.step();
    harness.drag_at(PINNED_AT);
    harness.step();
    harness.drop_at(PINNED_AT);
    settle(&mut harness);
    assert_eq!(harness.state().model().pixel, Some(PINNED), "the click pins the recorded pixel");
    assert!(harness.query_by_label_contains("through frame").is_some(), "the panel shows the recorded history");
    assert!(harness.query_all_by_label("failed depth").next().is_some(), "and its fragments");
    snapshot(&mut harness, &sent, "pixel");
}
