//! `loupe view`: its failures as the binary reports them, and the window's
//! contents driven by egui_kittest against a real daemon on a temporary
//! project, rendering on the daemon's own device (lavapipe here).

mod inspector;
mod pixel;
mod snapshots;
mod tensors;

use std::sync::Arc;
use std::time::{Duration, Instant};

use egui_kittest::kittest::{Queryable, by};
use egui_kittest::{Harness, wgpu::WgpuTestRenderer};
use loupe::serve::display::Display;
use loupe::serve::shared::Shared;
use loupe::serve::viewer::{self, InProcess};
use loupe::serve::{Attached, ServeOptions, daemon::RenderMode};
use loupe_tests::reload::{TONEMAP, broken, constant_colour};
use loupe_tests::xvfb::Xvfb;
use loupe_tests::{Project, Server, loupe_bin, loupe_with_env, repo};
use loupe_view::egui::accesskit::Role;
use loupe_view::{Viewer, egui, egui_wgpu};

#[test]
fn without_a_display_view_names_serve_and_exits_2() {
    let p = Project::empty("view-no-display");
    let root = repo().display().to_string();
    let run = loupe_with_env(&p.root, &["view", "--root", &root, "--port", "0"], &[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")]);
    run.code(2).stderr_has("no display").stderr_has("`loupe serve`");
    assert!(!run.stderr.contains("panicked"), "{}", run.stderr);
}

/// The colour the test's tonemap shader writes everywhere (linear), and
/// the 8-bit sRGB value the window must show for it.
const COLOUR: [f32; 3] = [0.8, 0.05, 0.6];
const SHOWN: [u8; 3] = [231, 63, 203];

/// How many pixels of `image` are `SHOWN` (within 3 per channel).
fn frame_pixels(image: &image::RgbaImage) -> usize {
    image.pixels().filter(|p| p.0[..3].iter().zip(SHOWN).all(|(a, b)| a.abs_diff(b) <= 3)).count()
}

/// A daemon on a temporary project rendering at 30 fps, and the window's
/// contents over it in an egui_kittest harness, on the daemon's device.
pub struct Window {
    pub harness: Harness<'static, Viewer>,
    pub shared: Arc<Shared>,
    /// What the daemon draws for the window.
    pub display: Arc<Display>,
    /// Where the daemon's port is bound.
    pub addr: std::net::SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    http: Option<std::thread::JoinHandle<Result<(), loupe::serve::ServeError>>>,
}

impl Window {
    /// Opens `scene` of `p` rendering up to `max_fps` in a window of
    /// `size`; `editor`: what problems open in.
    pub fn open(p: &Project, scene: &str, max_fps: f64, editor: Option<String>, size: egui::Vec2) -> Window {
        let gpu = loupe::gpu::open().unwrap_or_else(|e| panic!("needs a device (lavapipe will do): {e}"));
        let display = Display::new(&gpu);
        let opts = ServeOptions {
            root: p.root.clone(),
            scene: p.path(scene),
            bind: std::net::Ipv4Addr::LOCALHOST.into(),
            port: 0,
            mode: RenderMode::Continuous,
            max_fps,
            debug_api: false,
        };
        let setup = viewer::window_device(&gpu);
        let running = loupe::serve::start(opts, Some(Attached { gpu, display: display.clone() })).expect("the daemon starts");
        let (shared, addr) = (running.shared().clone(), running.local());
        // The link made at once, as `loupe view` makes it: what it starts
        // from is what the daemon published before it listened.
        let link = InProcess::new(shared.clone(), display.clone(), Arc::new(std::sync::atomic::AtomicBool::new(false)));
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let http = std::thread::spawn(move || {
            running.serve(async {
                let _ = stopped.await;
            })
        });
        let render =
            egui_kittest::wgpu::create_render_state(egui_wgpu::WgpuSetup::Existing(setup), egui_wgpu::RendererOptions::PREDICTABLE);
        let viewer = Viewer::new(Box::new(link), editor);
        let r = render.clone();
        let harness = Harness::builder()
            .with_size(size)
            // Screens are compared at the pointer: it is not drawn.
            .with_render_cursor(false)
            .renderer(WgpuTestRenderer::from_render_state(render))
            .build_ui_state(move |ui, viewer: &mut Viewer| viewer.ui(ui, Some(&r)), viewer);
        Window { harness, shared, display, addr, stop: Some(stop), http: Some(http) }
    }

    /// Steps the window until `done` holds, for at most two minutes
    /// (lavapipe compiles the first pipelines slowly; this is a bound, not
    /// a timing).
    pub fn step_until(&mut self, what: &str, mut done: impl FnMut(&mut Harness<'static, Viewer>) -> bool) {
        let start = Instant::now();
        loop {
            self.harness.step();
            if done(&mut self.harness) {
                return;
            }
            assert!(start.elapsed() < Duration::from_secs(120), "the window never showed {what}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Closes the window and stops the daemon, which must stop cleanly.
    pub fn close(mut self) {
        let _ = self.stop.take().expect("open").send(());
        self.http.take().expect("open").join().expect("the HTTP thread").expect("the daemon stops cleanly");
    }
}

/// A copy of the repository whose `scenes/minimal.toml` renders at 64×36
/// (cheap on lavapipe), plus `extra` TOML.
pub fn small_minimal(name: &str, extra: &str) -> Project {
    let p = Project::copy_of_repo(name);
    let scene = p.read("scenes/minimal.toml").replace("width = 640\nheight = 360", "width = 64\nheight = 36");
    p.write("scenes/minimal.toml", format!("{scene}{extra}"));
    p
}

/// The window of the tests that need no more: 640×480 at 30 fps.
pub fn open_small(p: &Project, editor: Option<String>) -> Window {
    Window::open(p, "scenes/minimal.toml", 30.0, editor, egui::vec2(640.0, 480.0))
}

#[test]
fn the_window_shows_the_daemons_passes_frame_and_problems() {
    let p = small_minimal("view-window", "");
    let good = constant_colour(&p.read(TONEMAP), COLOUR);
    p.write(TONEMAP, &good);
    // An "editor" that records how it was called: named `vim`, so it gets
    // vim's `+LINE FILE`.
    p.write("bin/vim", format!("#!/bin/sh\necho \"$@\" > {}\n", p.path("opened").display()));
    std::process::Command::new("chmod").arg("+x").arg(p.path("bin/vim")).status().expect("chmod");
    let mut w = open_small(&p, Some(p.path("bin/vim").display().to_string()));

    // The pass list: every pass the daemon reports, by name.
    w.step_until("a frame", |h| h.state().model().frame.is_some());
    let status = &w.harness.state().model().status;
    assert!(status.scene.ends_with("minimal.toml") && !status.adapter.is_empty(), "the toolbar names the scene and adapter: {status:?}");
    let passes = loupe::serve::shared::read(&w.shared.passes);
    assert!(passes.len() > 3, "the minimal scene has its passes: {passes:?}");
    for pass in &passes {
        assert!(w.harness.query_by_label(&pass.name).is_some(), "the Passes panel lists `{}`", pass.name);
    }
    // The frame, on screen: the shader's colour fills the Frame panel.
    w.step_until("the frame", |h| frame_pixels(&h.render().expect("renders")) > 10_000);

    // A broken shader: its error in Problems, at its line.
    let bad = broken(&good);
    let line = bad.lines().position(|l| l.contains("mux(")).expect("the broken line") + 1;
    p.write(TONEMAP, &bad);
    let place = format!("shaders/post/tonemap.wgsl:{line}:");
    w.step_until("the error", |h| h.query_by_label_contains(&place).is_some());
    assert!(w.harness.query_by_label_contains(&format!("{line} |     let c = mux(")).is_some(), "the excerpt shows the broken line");
    // Clicking it (as assistive technology clicks: a pointer click at the
    // wrapped link's centre did not register in kittest) opens the editor
    // at that line, without waiting for it.
    w.harness.get_by_label_contains(&place).click_accesskit();
    w.step_until("the editor's start", |_| std::fs::read_to_string(p.path("opened")).is_ok_and(|s| s.ends_with('\n')));
    let opened = std::fs::read_to_string(p.path("opened")).expect("the editor ran");
    assert!(opened.starts_with(&format!("+{line} ")) && opened.trim_end().ends_with("tonemap.wgsl"), "{opened}");

    // The diff against the version that last compiled: the changed line
    // removed and added, numbered.
    w.step_until("the diff", |h| h.query_by_label_contains("tonemap.wgsl changed since it last compiled").is_some());
    let added = format!("{line} + {}", bad.lines().nth(line - 1).expect("the line"));
    assert!(w.harness.query_by_label_contains(&added).is_some(), "the diff adds `{added}`");
    assert!(w.harness.query_by_label_contains(&format!("{line}    - ")).is_some(), "the diff removes the last good line");

    // "revert to last good", cancelled: nothing written.
    w.harness.get_by_label("revert to last good").click_accesskit();
    w.harness.run_steps(2);
    w.harness.get_by_label("Cancel").click_accesskit();
    w.harness.run_steps(2);
    assert_eq!(p.read(TONEMAP), bad, "a cancelled revert writes nothing");
    // Confirmed: the last good text is back, and the problem goes.
    w.harness.get_by_label("revert to last good").click_accesskit();
    w.harness.run_steps(2);
    w.harness.get_by_label("Revert").click_accesskit();
    w.harness.run_steps(2);
    assert_eq!(p.read(TONEMAP), good, "reverted to the last good text");
    w.step_until("the fix", |h| h.query_by_label_contains("tonemap.wgsl:").is_none());
    w.step_until("no diff", |h| h.query_by_label_contains("changed since it last compiled").is_none());
    w.close();
}

/// The Frame panel's pixels as the window draws them (the frame image's
/// rectangle in the rendered window).
fn shown_frame(harness: &mut Harness<'_, Viewer>) -> image::RgbaImage {
    let rect = harness.get_by_role(Role::Image).rect();
    let window = harness.render().expect("renders");
    let scale = window.width() as f32 / harness.ctx.content_rect().width();
    let (x, y) = ((rect.min.x * scale).ceil() as u32, (rect.min.y * scale).ceil() as u32);
    let (w, h) = ((rect.width() * scale).floor() as u32 - 1, (rect.height() * scale).floor() as u32 - 1);
    image::imageops::crop_imm(&window, x, y, w, h).to_image()
}

/// The mean of every channel but alpha.
fn mean(image: &image::RgbaImage) -> f64 {
    let sum: u64 = image.pixels().flat_map(|p| p.0[..3].iter().map(|v| u64::from(*v))).sum();
    sum as f64 / (image.width() * image.height() * 3) as f64
}

/// The Scene panel's controls drive the daemon: an exposure typed into the
/// window brightens the frame it shows, the renderer switch path traces
/// and shows the samples, and "Reset history" starts them over. The
/// Timings tab plots the passes the frames ran.
#[test]
fn the_scene_panel_drives_the_daemon_and_the_timings_tab_plots_the_passes() {
    let p = small_minimal("view-scene", "\n[quality]\npath_spp = 8\n");
    let mut w = Window::open(&p, "scenes/minimal.toml", 10.0, None, egui::vec2(800.0, 600.0));
    w.step_until("a frame", |h| h.state().model().frame.is_some() && h.query_by_role(Role::Image).is_some());

    // Timings: each pass the frames ran and timed has its line, named in
    // the legend (the Passes tab, which names them too, is hidden).
    w.harness.get_by_label("Timings").click();
    let timed: Vec<String> =
        loupe::serve::shared::read(&w.shared.passes).into_iter().filter(|p| p.time.time_ms.is_some()).map(|p| p.name).collect();
    assert!(timed.len() > 3, "the minimal scene's frames time their passes: {timed:?}");
    w.step_until("the timings plot", |h| timed.iter().all(|name| h.query_by_label(name).is_some()));

    // Scene: an exposure set exactly in the entry beside its slider.
    w.harness.get_by_label("Scene").click();
    w.harness.step();
    let before = shown_frame(&mut w.harness);
    let exposure = w.harness.get(by().role(Role::SpinButton).label_contains("Exposure"));
    exposure.set_value_accesskit(2.0);
    w.step_until("the override", |h| h.state().model().controls.overrides.get("post.exposure_ev") == Some(&2.0.into()));
    w.step_until("a brighter frame", |h| mean(&shown_frame(h)) > mean(&before) + 10.0);
    assert!(w.harness.query_by_label_contains("1 unsaved").is_some(), "the override is counted");

    // The renderer switch: path traced, its samples shown up to the target.
    w.harness.get_by_label("path").click();
    w.step_until("the samples converged", |h| h.query_by_label("8 / 8 samples · converged").is_some());
    // Reset history: the samples start over.
    w.harness.get_by_label("Reset history").click();
    w.step_until("the samples restarted", |h| h.state().model().samples.is_some_and(|s| s < 8));
    let restarted = w.harness.state().model().samples.expect("samples");
    assert!(w.harness.query_by_label(&format!("{restarted} / 8 samples")).is_some(), "the panel shows {restarted} samples");
    w.close();
}

/// The newest frame the daemon rendered.
fn frame_of(shared: &Shared) -> u64 {
    loupe::serve::shared::read(&shared.status).frame
}

/// Steps the window for `time` and returns how many frames the daemon
/// rendered meanwhile.
fn frames_over(w: &mut Window, time: Duration, minimised: bool) -> u64 {
    let start = frame_of(&w.shared);
    let until = Instant::now() + time;
    while Instant::now() < until {
        if minimised {
            w.harness.state_mut().hidden();
        } else {
            w.harness.step();
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    frame_of(&w.shared) - start
}

/// A minimised window with no browser connected stops the continuous
/// frames; a browser connecting, or the window showing again, starts them.
#[test]
fn a_minimised_window_renders_only_for_a_browser() {
    let p = small_minimal("view-minimised", "");
    let mut w = open_small(&p, None);
    w.step_until("a frame", |h| h.state().model().frame.is_some());
    assert!(frames_over(&mut w, Duration::from_secs(1), false) > 3, "a shown window renders continuously");
    // Minimised: the frames in flight land, then none.
    frames_over(&mut w, Duration::from_millis(500), true);
    assert_eq!(frames_over(&mut w, Duration::from_secs(1), true), 0, "a minimised window with no browser renders nothing");
    let browser = loupe_tests::ws::Ws::connect(&w.addr.to_string()).expect("a WebSocket client connects");
    assert!(frames_over(&mut w, Duration::from_secs(1), true) > 3, "a browser sees the frames");
    drop(browser);
    frames_over(&mut w, Duration::from_millis(500), true);
    assert_eq!(frames_over(&mut w, Duration::from_secs(1), true), 0, "the browser gone, the frames stop again");
    assert!(frames_over(&mut w, Duration::from_secs(1), false) > 3, "shown again, the window renders");
    w.close();
}

/// A window resized to nothing shows nothing, so the daemon draws nothing
/// for it: no frame copy, no display pass, and no error; resized back, it
/// shows both again.
#[test]
fn a_window_resized_to_nothing_asks_the_daemon_for_nothing() {
    let p = small_minimal("view-zero", "");
    let mut w = open_small(&p, None);
    w.step_until("a frame", |h| h.state().model().frame.is_some());
    assert!(w.display.shown(), "the Frame tab shows the frame");
    w.harness.set_size(egui::vec2(0.0, 0.0));
    w.harness.run_steps(3);
    assert!(!w.display.shown(), "nothing of the frame is on screen: no copy");

    // The Inspector, from the same size: its output is drawn only once
    // there is room for it.
    w.harness.set_size(egui::vec2(640.0, 480.0));
    w.harness.run_steps(3);
    w.harness.get_by_label("tonemap").click();
    let display = w.display.clone();
    w.step_until("the display pass", |_| display.inspected().is_some());
    w.harness.set_size(egui::vec2(0.0, 0.0));
    w.harness.run_steps(3);
    // Frames in flight land, then the display pass draws no more.
    frames_over(&mut w, Duration::from_millis(500), false);
    let drawn = w.display.inspected().expect("drawn before").frame;
    let rendered = frames_over(&mut w, Duration::from_secs(1), false);
    assert!(rendered > 3, "the daemon keeps rendering ({rendered} frames)");
    assert_eq!(w.display.inspected().expect("drawn before").frame, drawn, "no display pass for an unseen Inspector");
    w.harness.set_size(egui::vec2(640.0, 480.0));
    w.step_until("the display pass again", |_| display.inspected().is_some_and(|i| i.frame > drawn));
    // A wgpu validation error would be a problem (located where the daemon
    // can) or a notice.
    assert_eq!(w.harness.state().model().notice, None, "no error reached the window");
    assert!(w.harness.state().model().problems.is_empty(), "no problem: {:?}", w.harness.state().model().problems);
    w.close();
}

/// The real binary's window under Xvfb: it opens, renders frames, and a
/// screenshot of the screen shows the window and, in it, the frame.
#[test]
fn the_real_window_shows_frames_under_xvfb() {
    let p = small_minimal("view-xvfb", "");
    p.write(TONEMAP, constant_colour(&p.read(TONEMAP), COLOUR));
    let xvfb = Xvfb::start(640, 480);
    let s = Server::start_command(&loupe_bin(), &p.root, "view", 0, &["--scene", "scenes/minimal.toml"], &[("DISPLAY", &xvfb.display)]);
    s.wait_for("frames", Duration::from_secs(120), || (s.get_json("/api/status")["frame"].as_u64()? >= 5).then_some(()));
    // The window draws what the daemon finished: give it a moment to.
    std::thread::sleep(Duration::from_secs(2));
    let shot = xvfb.screenshot();
    s.kill();
    let colours = shot.pixels().map(|p| p.0).collect::<std::collections::BTreeSet<_>>().len();
    // A blank or unrendered screen has one or two colours; the window's
    // text, panels and lit frame have hundreds.
    assert!(colours > 100, "the screenshot has {colours} colours");
    let frame = frame_pixels(&shot);
    assert!(frame > 10_000, "the frame's colour covers {frame} pixels of the screen");
}

/// The real window when the GPU device is lost: the daemon recovers on a
/// new device, and the window reopens on it and shows its frames.
#[test]
fn the_real_window_reopens_on_the_device_the_daemon_recovers_with() {
    let p = small_minimal("view-lost", "");
    p.write(TONEMAP, constant_colour(&p.read(TONEMAP), COLOUR));
    let xvfb = Xvfb::start(640, 480);
    let args = ["--scene", "scenes/minimal.toml", "--debug-api"];
    let s = Server::start_command(&loupe_bin(), &p.root, "view", 0, &args, &[("DISPLAY", &xvfb.display)]);
    let frames = || s.get_json("/api/status")["frame"].as_u64();
    s.wait_for("frames", Duration::from_secs(120), || (frames()? >= 5).then_some(()));
    assert_eq!(s.post("/api/debug/lose-device").0, 202);
    s.wait_for("the window to reopen", Duration::from_secs(60), || s.log().contains("reopening on the daemon's new device").then_some(()));
    let after = frames().expect("the daemon answers");
    s.wait_for("frames on the new device", Duration::from_secs(60), || (frames()? >= after + 5).then_some(()));
    let start = Instant::now();
    loop {
        let shown = frame_pixels(&xvfb.screenshot());
        if shown > 10_000 {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "the reopened window shows {shown} pixels of the frame; the log:\n{}", s.log());
        std::thread::sleep(Duration::from_millis(500));
    }
    s.kill();
}
