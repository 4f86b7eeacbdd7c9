//! The browser inspector in a real headless chromium, driven over WebDriver
//! (this module holds the harness: chromium, `until`, `shown`; each topic
//! adds a child module):
//! open the page, break a shader on disk, see the error with file:line while
//! the old frame stays, fix it, see it clear.

use std::os::unix::process::CommandExt;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{Client, ClientBuilder, Locator};
use loupe_tests::{Project, Server, reload, repo};

mod budget;
mod console;
mod difference;
mod layout;
mod materials;
mod presets;
mod prints;
mod readouts;
mod tiles;
mod timings;

const LIMIT: Duration = Duration::from_secs(60);
const TONEMAP: &str = "shaders/post/tonemap.wgsl";

/// chromedriver in a process group of its own, with the chromium it starts:
/// dropping it kills the whole group. Killing chromedriver alone leaves its
/// chromium running (re-parented to init), a browser per test that goes on
/// using the CPU for the rest of the run.
struct Driver(Child);

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = Command::new("kill").args(["-KILL", "--", &format!("-{}", self.0.id())]).status();
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

async fn browser() -> (Driver, Client) {
    browser_sized(1280, 800).await
}

/// Chromium with a window (and, headless, a page) of width × height.
async fn browser_sized(width: u32, height: u32) -> (Driver, Client) {
    browser_with(width, height, serde_json::json!({})).await
}

/// `browser_sized` that keeps the page's console (every level) for
/// chromedriver's log endpoint: what `console::browser_log` reads.
async fn browser_logging(width: u32, height: u32) -> (Driver, Client) {
    browser_with(width, height, serde_json::json!({ "goog:loggingPrefs": { "browser": "ALL" } })).await
}

/// Chromium at width × height with `extra` capabilities.
async fn browser_with(width: u32, height: u32, extra: serde_json::Value) -> (Driver, Client) {
    let port = free_port();
    let driver = Driver(
        Command::new("chromedriver")
            .arg(format!("--port={port}"))
            .process_group(0)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver is installed (tests/run installs chromium-driver)"),
    );
    let caps: serde_json::Map<String, serde_json::Value> = serde_json::from_value(serde_json::json!({
        "goog:chromeOptions": {
            "binary": "/usr/bin/chromium",
            "args": ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--disable-background-networking", "--disable-component-update", "--disable-sync",
                     "--no-first-run", format!("--window-size={width},{height}")]
        }
    }))
    .unwrap();
    let caps: serde_json::Map<String, serde_json::Value> =
        caps.into_iter().chain(serde_json::from_value::<serde_json::Map<_, _>>(extra).expect("capabilities are an object")).collect();
    let start = Instant::now();
    loop {
        match ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
            .capabilities(caps.clone())
            .connect(&format!("http://127.0.0.1:{port}"))
            .await
        {
            Ok(c) => return (driver, c),
            Err(e) if start.elapsed() > LIMIT => panic!("cannot start chromium through chromedriver: {e}"),
            Err(_) => tokio::time::sleep(Duration::from_millis(200)).await,
        }
    }
}

/// Chromium whose page (the viewport, which a screenshot shows) is
/// width × height: the window is larger than the page by the browser's own
/// bars, so it is grown by that much.
async fn browser_with_page(width: u32, height: u32) -> (Driver, Client) {
    let (driver, c) = browser_sized(width, height).await;
    let inner = c.execute("return [window.innerWidth, window.innerHeight];", vec![]).await.unwrap();
    let (w, h) = (inner[0].as_u64().unwrap() as u32, inner[1].as_u64().unwrap() as u32);
    c.set_window_size(2 * width - w, 2 * height - h).await.unwrap();
    (driver, c)
}

/// The image `#frame` shows, as drawn: its frame number, a hash of its
/// RGBA8 pixels and its centre pixel.
struct Shown {
    frame: u64,
    pixels: u64,
    centre: [u8; 3],
}

async fn shown(c: &Client) -> Shown {
    let js = "const img = document.querySelector('#frame');
        const canvas = document.createElement('canvas');
        canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
        const g = canvas.getContext('2d');
        g.drawImage(img, 0, 0);
        const d = g.getImageData(0, 0, canvas.width, canvas.height).data;
        let h = 2166136261;
        for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619) >>> 0;
        const at = 4 * ((canvas.height >> 1) * canvas.width + (canvas.width >> 1));
        return [Number(img.dataset.frame), h, d.length, d[at], d[at + 1], d[at + 2]];";
    let v = c.execute(js, vec![]).await.unwrap();
    let n = |i: usize| v[i].as_u64().unwrap_or_else(|| panic!("#frame: {v}"));
    assert!(n(2) > 0, "an image is shown");
    Shown { frame: n(0), pixels: n(1) << 32 | n(2), centre: [n(3) as u8, n(4) as u8, n(5) as u8] }
}

/// The showcase at 320×180 with a 256² shadow map (the quad model of a
/// debug build replays every shadow layer: small keeps it quick).
fn small_showcase(name: &str) -> (Project, Server) {
    let p = Project::copy_of_repo(name);
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", &small_showcase_scene(&p)]);
    (p, s)
}

/// Writes `scenes/small_showcase.toml`, the showcase at 320×180 with a
/// small shadow map (quick on lavapipe; the page reads every output whole);
/// returns its path for `--scene`.
fn small_showcase_scene(p: &Project) -> String {
    let small = p
        .read("scenes/showcase.toml")
        .replacen("width = 640", "width = 320", 1)
        .replacen("height = 360", "height = 180", 1)
        .replacen("shadow_map_size = 1024", "shadow_map_size = 256", 1);
    assert!(
        small.contains("width = 320") && small.contains("height = 180") && small.contains("= 256"),
        "the showcase's settings moved: update this test"
    );
    p.write("scenes/small_showcase.toml", small);
    "scenes/small_showcase.toml".to_owned()
}

/// What to print about the server when a wait times out.
trait Log {
    fn log(&self) -> String;
}

impl Log for Server {
    fn log(&self) -> String {
        Server::log(self)
    }
}

/// A server that was stopped: its last log.
struct Dead(String);

impl Log for Dead {
    fn log(&self) -> String {
        format!("(stopped)\n{}", self.0)
    }
}

/// The number right after `label` in a text the page shows.
fn number_after(text: &str, label: &str) -> f64 {
    text.split(label)
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no number after {label:?} in {text:?}"))
}

/// Polls a JS expression until it is truthy; returns its value.
async fn until(c: &Client, server: &impl Log, what: &str, js: &str) -> serde_json::Value {
    until_within(c, server, what, js, LIMIT).await
}

/// `until` for what takes longer than a page's usual wait (a path-traced
/// material preview on two busy cores).
async fn until_within(c: &Client, server: &impl Log, what: &str, js: &str, limit: Duration) -> serde_json::Value {
    let start = Instant::now();
    loop {
        if let Ok(v) = c.execute(&format!("return ({js});"), vec![]).await
            && !(v.is_null() || v == false || v == "" || v == 0)
        {
            return v;
        }
        if start.elapsed() > limit {
            let html = c.source().await.unwrap_or_default();
            panic!("timed out waiting for {what}\n--- page ---\n{}\n--- server ---\n{}", &html[..html.len().min(4000)], server.log());
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn page_shows_frame_and_errors_at_their_line_and_clears_them() {
    let p = Project::copy_of_repo("browser");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();

    until(&c, &s, "connected", "document.querySelector('#connection').textContent === 'connected'").await;
    let first = until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    assert!(first.as_u64().unwrap() >= 1);
    until(&c, &s, "the tonemap pass listed ok", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"ok\"]')").await;
    let before = shown(&c).await;
    // The inspector opens on the final output and, live, gets its exact
    // floats streamed over the WebSocket (a subscription of this page).
    until(
        &c,
        &s,
        "a streamed capture in the inspector",
        "window.loupe.state.inspector.streamedLoads >= 1 && window.loupe.state.inspector.output === 'color'",
    )
    .await;
    let alpha = c.execute("return window.loupe.valueAt(480, 270)[3];", vec![]).await.unwrap();
    assert_eq!(alpha, 1.0, "the streamed final image is opaque");
    let page = c.execute("const s = window.loupe.state; return [s.protocol, s.problems, document.querySelectorAll('#notices .notice:not([hidden])').length];", vec![]).await.unwrap();
    assert_eq!(page, serde_json::json!([3, [], 0]), "the page speaks the server's protocol, without problems or notices");

    // Break the shader as vim saves it.
    let good = p.read(TONEMAP);
    let broken = good.replace("let c = max(", "let c = mux(");
    let line = broken.lines().position(|l| l.contains("mux(")).unwrap() + 1;
    p.save_by_rename(TONEMAP, &broken);
    let sel = format!(".diagnostic[data-file=\"{TONEMAP}\"][data-line=\"{line}\"]");
    until(&c, &s, "the error at its line", &format!("document.querySelector('#diagnostics {sel}')")).await;
    let text = c.find(Locator::Css(&format!("#diagnostics {sel}"))).await.unwrap().text().await.unwrap();
    assert!(text.contains(&format!("{TONEMAP}:{line}:")), "diagnostic text names file:line: {text}");
    let hl = c.find(Locator::Css(&format!("#diagnostics {sel} .hl"))).await.unwrap().text().await.unwrap();
    assert!(hl.contains("mux("), "the highlighted excerpt line is the broken one: {hl}");
    until(&c, &s, "the pass marked stale", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"stale\"]')").await;
    // The old image stays on screen: a frame rendered while the diagnostic
    // is up (a rebuild asked for now fails again and renders one) is shown,
    // with the same pixels.
    let at_diagnostic = shown(&c).await.frame;
    let (code, _) = s.post("/api/reload");
    assert_eq!(code, 202);
    until(&c, &s, "a frame after the failed rebuild", &format!("Number(document.querySelector('#frame').dataset.frame) > {at_diagnostic}"))
        .await;
    let broken_shown = shown(&c).await;
    assert_eq!(
        broken_shown.pixels, before.pixels,
        "the image is unchanged while the shader is broken (frames {} and {})",
        before.frame, broken_shown.frame
    );

    // Fix it with a new colour: the error clears, the pass is ok again and
    // the image changes to that colour.
    let colour = reload::colour(5);
    p.write(TONEMAP, reload::constant_colour(&good, colour));
    until(&c, &s, "the error to clear", &format!("!document.querySelector('#diagnostics {sel}')")).await;
    until(&c, &s, "the pass ok again", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"ok\"]')").await;
    let start = Instant::now();
    let want = colour.map(|c| reload::srgb(c) * 255.0);
    let fixed = loop {
        let now = shown(&c).await;
        if want.iter().zip(now.centre).all(|(w, got)| (w - got as f32).abs() <= 2.0) {
            break now;
        }
        assert!(start.elapsed() < LIMIT, "the fixed colour {want:?} never showed: {:?} in frame {}\n{}", now.centre, now.frame, s.log());
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    assert_ne!(fixed.pixels, before.pixels);

    // A uniform larger than the renderer binds once reached the GPU and
    // blanked the frame; now pipeline creation refuses it at the binding's
    // line, and the page shows that like any other error.
    const PATTERN: &str = "shaders/passes/test_pattern.wgsl";
    let pattern = p.read(PATTERN);
    let bigger = pattern.replace("    frame: u32,\n}", "    frame: u32,\n    extra: vec4<f32>,\n}");
    p.save_by_rename(PATTERN, &bigger);
    let line = bigger.lines().position(|l| l.contains("var<uniform> frame")).unwrap() + 1;
    let mismatch = format!("#diagnostics .diagnostic[data-code=\"binding-mismatch\"][data-file=\"{PATTERN}\"][data-line=\"{line}\"]");
    until(&c, &s, "the uniform size error shown", &format!("document.querySelector('{mismatch}')")).await;
    until(&c, &s, "the pass stale", "document.querySelector('#passes li[data-pass=\"test_pattern\"][data-status=\"stale\"]')").await;
    p.save_by_rename(PATTERN, &pattern);
    until(&c, &s, "the uniform size error to clear", &format!("!document.querySelector('{mismatch}')")).await;
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn page_reconnects_by_itself_after_a_server_restart_and_shows_a_new_frame() {
    let p = Project::copy_of_repo("browser-reconnect");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let port = s.port();
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "connected", "document.querySelector('#connection').textContent === 'connected'").await;
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    assert_eq!(c.execute("return window.loupe.state.connections;", vec![]).await.unwrap(), 1);

    // The server dies without a close handshake (a crash, kill -9); nothing
    // listens on its port until the new one is up.
    let log = s.log();
    s.kill();
    let dead = Dead(log);
    until(&c, &dead, "the page to see the server gone", "document.querySelector('#connection').textContent === 'reconnecting'").await;
    let received: u64 = c.execute("return window.loupe.state.liveImages.received;", vec![]).await.unwrap().as_u64().unwrap();
    let src = c.find(Locator::Css("#frame")).await.unwrap().attr("src").await.unwrap();

    // A new server on the same port: the page reconnects by itself and
    // shows the new server's frame.
    let s = Server::start_on(&p.root, port, &["--render", "on-change"]);
    until(
        &c,
        &s,
        "connected again",
        "document.querySelector('#connection').textContent === 'connected' && window.loupe.state.connections === 2",
    )
    .await;
    until(&c, &s, "a new frame image", &format!("window.loupe.state.liveImages.received > {received}")).await;
    until(
        &c,
        &s,
        "the new frame on screen",
        &format!("document.querySelector('#frame').getAttribute('src') !== {}", serde_json::json!(src)),
    )
    .await;
    until(&c, &s, "the pass list again", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"ok\"]')").await;
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_controls_override_the_scene_and_save_keeps_its_comments() {
    let p = Project::copy_of_repo("browser-controls");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    // At 0 EV the exposure pass is culled; the control is there.
    until(&c, &s, "exposure culled", "document.querySelector('#passes li[data-pass=\"exposure\"][data-status=\"culled\"]')").await;
    let slider = "document.querySelector('#controls [data-path=\"post.exposure_ev\"]')";
    until(&c, &s, "the exposure control", slider).await;
    until(&c, &s, "the passes it affects on hover", &format!("{slider}.closest('label').title === 'affects: exposure'")).await;
    // Move the slider as a user does: set, then `change`.
    c.execute(&format!("const i = {slider}; i.value = '1'; i.dispatchEvent(new Event('change')); return true;"), vec![]).await.unwrap();
    until(&c, &s, "the override counted", "document.querySelector('#overrides-count').textContent === '1 unsaved'").await;
    until(&c, &s, "the exposure pass live", "document.querySelector('#passes li[data-pass=\"exposure\"][data-status=\"ok\"]')").await;
    let before = p.read("scenes/pattern.toml");
    assert!(before.contains("exposure_ev = 0.0\n"), "the file is untouched until saved");

    // Save: the value lands in the file, every comment stays.
    c.execute("document.querySelector('#save-scene').click(); return true;", vec![]).await.unwrap();
    until(&c, &s, "saved: nothing unsaved", "document.querySelector('#overrides-count').textContent === 'as in the file'").await;
    let after = p.read("scenes/pattern.toml");
    assert_eq!(after, before.replace("exposure_ev = 0.0\n", "exposure_ev = 1.0\n"), "only the value changed");
    // The reload of the saved file keeps the exposure pass live.
    until(
        &c,
        &s,
        "still exposed after the file reload",
        "document.querySelector('#passes li[data-pass=\"exposure\"][data-status=\"ok\"]')",
    )
    .await;
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn any_pass_output_is_inspectable_with_exact_values() {
    let p = Project::copy_of_repo("browser-gbuffer");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    until(&c, &s, "volumes culled with its reason", "document.querySelector('#passes li[data-pass=\"volumes\"][data-status=\"culled\"]')")
        .await;
    // A G-buffer target, not the final image: the knot covers the centre
    // of minimal.toml's frame, so the normal there is a unit vector.
    let loaded = c.execute_async("window.loupe.inspect('gbuffer', 'normal').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(loaded, true, "the inspector loaded gbuffer/normal");
    let v = c.execute("return window.loupe.valueAt(320, 180);", vec![]).await.unwrap();
    let n: Vec<f64> = v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    assert!((len - 1.0).abs() < 2e-3 && n[3] == 1.0, "an exact unit normal, w = 1: {n:?}");
    // The depth prepass's Depth32Float reads back too, in (0, 1) there.
    let loaded = c.execute_async("window.loupe.inspect('depth_prepass', 'depth').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(loaded, true);
    let d = c.execute("return window.loupe.valueAt(320, 180)[0];", vec![]).await.unwrap().as_f64().unwrap();
    assert!(d > 0.0 && d < 1.0, "depth {d}");
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_auto_exposure_histogram_is_a_plot_with_its_gpu_time() {
    let p = Project::copy_of_repo("browser-tensor");
    p.write("scenes/auto.toml", "[output]\nwidth = 320\nheight = 180\n\n[post]\nauto_exposure = true\n");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/auto.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    // The compute pass is listed with its GPU time, and its buffer output.
    let row = "#passes li[data-pass=\"exposure_histogram\"][data-status=\"ok\"]";
    until(&c, &s, "the histogram pass timed", &format!("document.querySelector('{row} .pass-time .ms')?.textContent.match(/[0-9]/)")).await;
    let chip = format!("{row} .chip[data-output=\"histogram\"]");
    let meta = until(&c, &s, "the histogram chip", &format!("document.querySelector('{chip}')?.textContent")).await;
    assert!(meta.as_str().unwrap().contains("u32 [256]"), "the chip says what the buffer is: {meta}");
    c.find(Locator::Css(&chip)).await.unwrap().click().await.unwrap();

    until(
        &c,
        &s,
        "the tensor view with 256 bars",
        "!document.querySelector('#tensor-panel').hidden && document.querySelector('#tensor-plot').dataset.bars === '256'",
    )
    .await;
    assert_eq!(
        c.execute("return document.querySelector('#inspector').hidden;", vec![]).await.unwrap(),
        true,
        "the tensor view takes the inspector's place"
    );
    let shape = c.find(Locator::Css("#tensor-shape")).await.unwrap().text().await.unwrap();
    assert!(shape.contains("[bin 256] u32"), "{shape}");
    // The plot reads the captured values: hovering the fullest bin shows
    // its exact count, and the counts add up to every pixel.
    let values = c
        .execute_async(
            "fetch('/api/tensors/exposure_histogram/histogram.f32').then(r => r.arrayBuffer()).then(b => arguments[0](Array.from(new Float32Array(b))));",
            vec![],
        )
        .await
        .unwrap();
    let values: Vec<f64> = values.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(values.iter().sum::<f64>(), 320.0 * 180.0, "every pixel metered once");
    let (top, count) = values.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
    let hover = format!(
        "const c = document.querySelector('#tensor-plot'); const r = c.getBoundingClientRect();
         c.dispatchEvent(new MouseEvent('mousemove', {{ clientX: r.left + ({top} + 0.5) * r.width / 256, clientY: r.top + r.height / 2 }}));
         return document.querySelector('#tensor-readout').textContent;"
    );
    let readout = c.execute(&hover, vec![]).await.unwrap();
    assert_eq!(readout, format!("[{top}] = {count}"), "the readout under the mouse is the captured value");
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_srgb_output_looks_in_the_inspector_as_in_the_live_frame() {
    let p = Project::copy_of_repo("browser-srgb");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "document.querySelector('#frame').complete && Number(document.querySelector('#frame').dataset.frame || 0)")
        .await;
    // The inspector opens on the final output, tonemap/color (Rgba8UnormSrgb).
    let loaded = c.execute_async("window.loupe.inspect('tonemap', 'color').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(loaded, true);
    // The live frame's pixels as the browser decodes its PNG, against what
    // the inspector displays at the same pixels (linear floats, encoded).
    let compared = c
        .execute(
            "const img = document.querySelector('#frame');
             const cv = document.createElement('canvas'); cv.width = img.naturalWidth; cv.height = img.naturalHeight;
             const g = cv.getContext('2d'); g.drawImage(img, 0, 0);
             const out = [];
             for (const fx of [0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95]) for (const fy of [0.1, 0.5, 0.9]) {
               const x = Math.floor(fx * cv.width), y = Math.floor(fy * cv.height);
               out.push([x, y, Array.from(g.getImageData(x, y, 1, 1).data).slice(0, 3), window.loupe.displayedAt(x, y, 'a').slice(0, 3)]);
             }
             return out;",
            vec![],
        )
        .await
        .unwrap();
    let mut differing = 0;
    for sample in compared.as_array().unwrap() {
        let live: Vec<i64> = sample[2].as_array().unwrap().iter().map(|v| v.as_i64().unwrap()).collect();
        let shown: Vec<i64> = sample[3].as_array().unwrap().iter().map(|v| v.as_i64().unwrap()).collect();
        assert!(
            live.iter().zip(&shown).all(|(a, b)| (a - b).abs() <= 1),
            "pixel ({}, {}): live {live:?}, inspector {shown:?}",
            sample[0],
            sample[1]
        );
        differing += usize::from(live.iter().any(|v| *v != live[0]));
    }
    assert!(differing > 0, "the samples include coloured pixels, not only greys: {compared}");
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_nan_made_by_a_pass_is_named_live_and_opened_at_its_pixel() {
    let p = Project::copy_of_repo("browser-nan");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    assert_eq!(
        c.execute("return document.querySelector('#nan-notice').hidden;", vec![]).await.unwrap(),
        true,
        "a clean frame shows no NaN notice"
    );

    // `view.environment_top.w` is always 0 (unused): a runtime divide by zero in lighting.
    const LIGHTING: &str = "shaders/passes/lighting.wgsl";
    let good = p.read(LIGHTING);
    let broken = good.replace("    return color;\n}", "    return color / view.environment_top.w;\n}");
    assert_ne!(broken, good, "the edit applies");
    p.save_by_rename(LIGHTING, &broken);
    let pass = until(
        &c,
        &s,
        "the NaN notice naming a pass",
        "!document.querySelector('#nan-notice').hidden && document.querySelector('#nan-notice').dataset.pass",
    )
    .await;
    assert_eq!(pass, "lighting", "the pass that divides by zero, not one it flowed into");
    let text = c.find(Locator::Css("#nan-text")).await.unwrap().text().await.unwrap();
    assert!(text.contains("lighting/color"), "{text}");

    // One click: that output, at that pixel, with the NaN overlay.
    c.find(Locator::Css("#nan-open")).await.unwrap().click().await.unwrap();
    until(
        &c,
        &s,
        "the inspector on lighting/color",
        "window.loupe.state.inspector.pass === 'lighting' && window.loupe.state.inspector.output === 'color'",
    )
    .await;
    let at = c.execute("return window.loupe.state.nan.origin.pixel;", vec![]).await.unwrap();
    let (x, y) = (at[0].as_u64().unwrap(), at[1].as_u64().unwrap());
    let v = until(&c, &s, "the value there", &format!("window.loupe.valueText({x}, {y})")).await;
    assert!(
        v.as_array().unwrap()[..3].iter().any(|c| c == "NaN" || c == "Infinity" || c == "-Infinity"),
        "the pixel named holds the bad value: {v}"
    );
    assert_eq!(c.execute("return document.querySelector('#overlay-nan').checked;", vec![]).await.unwrap(), true);

    // The fix clears it.
    p.save_by_rename(LIGHTING, &good);
    until(&c, &s, "the notice to clear", "document.querySelector('#nan-notice').hidden").await;
    c.close().await.unwrap();
}

/// Quad statistics in the page: with the toggle on, every raster pass of
/// the showcase gets its totals in the pass list, its per-draw table and
/// both maps over its output, each with a legend.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_raster_pass_has_its_quad_table_and_maps() {
    let (_p, s) = small_showcase("browser-quads");
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    c.find(Locator::Css("#quad-stats")).await.unwrap().click().await.unwrap();
    let raster = c
        .execute_async(
            "fetch('/api/passes').then(r => r.json()).then(l => arguments[0]((l.passes || l).filter(p => p.kind === 'raster' && p.status === 'ok').map(p => [p.name, p.writes[0].name])));",
            vec![],
        )
        .await
        .unwrap();
    let raster: Vec<(String, String)> =
        raster.as_array().unwrap().iter().map(|p| (p[0].as_str().unwrap().to_owned(), p[1].as_str().unwrap().to_owned())).collect();
    assert!(raster.len() >= 6, "the showcase's raster passes: {raster:?}");
    for (pass, _) in &raster {
        until(
            &c,
            &s,
            &format!("{pass}'s totals in the pass list"),
            &format!("document.querySelector('#passes li[data-pass=\"{pass}\"] .pass-quads')?.dataset.quads"),
        )
        .await;
    }
    for (pass, output) in &raster {
        let shown = c.execute_async(&format!("window.loupe.inspect('{pass}', '{output}').then(arguments[0]);"), vec![]).await.unwrap();
        assert_eq!(shown, true, "{pass}/{output}");
        let total = until(
            &c,
            &s,
            &format!("{pass}'s quad table"),
            &format!("document.querySelector('#quad-panel[data-pass=\"{pass}\"] #quad-table tr.total td[data-key=quads]')?.dataset.value"),
        )
        .await;
        let served = c
            .execute_async(
                &format!(
                    "fetch('/api/quads').then(r => r.json()).then(q => arguments[0](q.passes.find(p => p.pass === '{pass}').quads.quads));"
                ),
                vec![],
            )
            .await
            .unwrap();
        assert_eq!(total.as_str().unwrap(), served.to_string(), "{pass}: the table shows the server's figure");
        if pass == "tonemap" {
            assert_eq!(served, 160 * 90, "one fullscreen triangle over 320×180");
        }
        for kind in ["overdraw", "helpers"] {
            c.execute(
                &format!("const s = document.querySelector('#quad-overlay'); s.value = '{kind}'; s.dispatchEvent(new Event('change'));"),
                vec![],
            )
            .await
            .unwrap();
            let size = until(
                &c,
                &s,
                &format!("{pass}'s {kind} map"),
                &format!("(o => o && o.kind === '{kind}' && [o.width, o.height])(window.loupe.state.inspector.overlay)"),
            )
            .await;
            let a = c.execute("const i = window.loupe.state.inspector; return [i.width, i.height];", vec![]).await.unwrap();
            assert_eq!(size, a, "{pass}: the {kind} map covers the inspected output");
            let legend = c.find(Locator::Css("#quad-legend")).await.unwrap().text().await.unwrap();
            assert!(legend.contains(if kind == "overdraw" { "quads per 2×2 block" } else { "helper-lane runs" }), "{pass}: {legend}");
        }
    }
    c.close().await.unwrap();
}

/// The renderer switch in the page: path traced from its button, the
/// samples counted up to convergence, the difference from the raster image
/// the page kept equal to what the two captures give, and back to raster.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_renderer_switch_counts_samples_and_measures_path_against_raster() {
    let p = Project::copy_of_repo("browser-path");
    // Small, with few samples: lavapipe traces it in a few frames.
    let small = p.read("scenes/minimal.toml").replacen("width = 640", "width = 96", 1).replacen("height = 360", "height = 54", 1);
    assert!(
        small.contains("width = 96") && small.contains("height = 54") && !small.contains("[quality]"),
        "minimal.toml's settings moved: update this test"
    );
    p.write("scenes/small.toml", small + "\n[quality]\npath_spp = 8\n");
    // Continuous: the path tracer adds one sample per frame rendered.
    let s = Server::start(&p.root, &["--render", "continuous", "--scene", "scenes/small.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    until(&c, &s, "the switch showing raster", "document.querySelector('#renderer-raster').getAttribute('aria-pressed') === 'true'").await;
    assert_eq!(
        c.execute("return document.querySelector('#path-panel').hidden;", vec![]).await.unwrap(),
        true,
        "no path tracing panel while rastering"
    );
    until(&c, &s, "the raster image kept by the page", "window.loupe.state.path.reference").await;

    c.find(Locator::Css("#renderer-path")).await.unwrap().click().await.unwrap();
    until(&c, &s, "the switch showing path traced", "document.querySelector('#renderer-path').getAttribute('aria-pressed') === 'true'")
        .await;
    let control = c.execute("return document.querySelector('#controls [data-path=\"quality.renderer\"]').value;", vec![]).await.unwrap();
    assert_eq!(control, "path", "the Scene panel's control shows the override too");
    until(&c, &s, "the raster passes culled", "document.querySelector('#passes li[data-pass=\"lighting\"][data-status=\"culled\"]') && document.querySelector('#passes li[data-pass=\"path_trace\"][data-status=\"ok\"]')").await;
    let counted =
        until(&c, &s, "some samples counted", "(n => n >= 2 && n)(Number(document.querySelector('#path-samples').dataset.samples))").await;
    assert!(counted.as_u64().unwrap() <= 8);
    let text = until(&c, &s, "convergence", "document.querySelector('#path-samples[data-converged=\"true\"]')?.textContent").await;
    assert_eq!(text, "8 / 8 samples · converged");
    let served = s.get_json("/api/captures");
    let samples = served
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["pass"] == "path_trace" && c["output"] == "samples")
        .expect("path_trace/samples captured");
    assert_eq!(samples["stats"]["min"][0], 8.0, "the count shown is the capture's");

    // The difference, against the page's raster image. Converged, the
    // path-traced image stays as it is, and the raster one is the same in
    // every frame of this scene: the server's last captures of both are
    // what the page compared.
    c.find(Locator::Css("#path-difference")).await.unwrap().click().await.unwrap();
    until(&c, &s, "the difference", "document.querySelector('#path-difference-stats').dataset.rmse").await;
    let shown = c
        .execute(
            "const s = document.querySelector('#path-difference-stats');
             return [s.textContent, Number(s.dataset.rmse), Number(s.dataset.relative), Number(s.dataset.pixels)];",
            vec![],
        )
        .await
        .unwrap();
    let raster = s.capture_f32("lighting/color").expect("the last raster image is still captured");
    let traced = s.capture_f32("path_trace/color").expect("the path-traced image");
    assert!(raster.frame < traced.frame && (raster.width, raster.height) == (96, 54) && (traced.width, traced.height) == (96, 54));
    let (mut squares, mut relative, mut pixels) = (0.0f64, 0.0f64, 0.0f64);
    for (t, r) in traced.data.chunks_exact(4).zip(raster.data.chunks_exact(4)) {
        assert!(t.iter().chain(r).all(|v| v.is_finite()), "finite images");
        let mut pixel = 0.0;
        for ch in 0..3 {
            let d = (f64::from(t[ch]) - f64::from(r[ch])).abs();
            squares += d * d;
            pixel += d / (f64::from(r[ch]).abs() + 0.01);
        }
        relative += pixel / 3.0;
        pixels += 1.0;
    }
    let (rmse, relative) = ((squares / (3.0 * pixels)).sqrt(), relative / pixels);
    assert!(rmse > 0.0, "the path tracer and the raster differ");
    let text = shown[0].as_str().unwrap();
    let number = |after: &str| number_after(text, after);
    let close = |got: f64, want: f64, tolerance: f64| (got - want).abs() <= tolerance * want.abs();
    // Three significant digits shown: within half a unit of the third.
    assert!(
        close(number("RMSE "), rmse, 0.0051) && close(number("mean relative "), 100.0 * relative, 0.0051),
        "{text:?}: RMSE {rmse}, mean relative {}%",
        100.0 * relative
    );
    assert!(
        close(shown[1].as_f64().unwrap(), rmse, 1e-9) && close(shown[2].as_f64().unwrap(), relative, 1e-9),
        "exact figures {shown}: RMSE {rmse}, relative {relative}"
    );
    assert_eq!(shown[3].as_u64(), Some(96 * 54), "no mask chosen: every pixel counts");
    // The inspector's difference view, its statistics and masks: browser::difference.

    // Back to raster: the raster passes render again, and the page keeps
    // their image anew.
    let traced_frame = traced.frame;
    c.find(Locator::Css("#renderer-raster")).await.unwrap().click().await.unwrap();
    until(&c, &s, "the switch showing raster again", "document.querySelector('#renderer-raster').getAttribute('aria-pressed') === 'true'")
        .await;
    until(&c, &s, "lighting live again", "document.querySelector('#passes li[data-pass=\"lighting\"][data-status=\"ok\"]') && document.querySelector('#passes li[data-pass=\"path_trace\"][data-status=\"culled\"]')").await;
    until(&c, &s, "a new raster image kept", &format!("window.loupe.state.path.reference.frame > {traced_frame}")).await;
    assert_eq!(
        c.execute("return document.querySelector('#path-panel').hidden;", vec![]).await.unwrap(),
        true,
        "no samples or difference while rastering"
    );
    // Set in the Scene panel instead, the switch follows.
    c.execute("const s = document.querySelector('#controls [data-path=\"quality.renderer\"]'); s.value = 'path'; s.dispatchEvent(new Event('change')); return true;", vec![]).await.unwrap();
    until(
        &c,
        &s,
        "the switch following the Scene panel",
        "document.querySelector('#renderer-path').getAttribute('aria-pressed') === 'true'",
    )
    .await;
    // Converged again (in a frame after the switch: the capture of an
    // earlier one stays), "reset history" starts the samples over: a later
    // frame counts fewer than the target, which a converged, unchanged
    // scene never does by itself.
    let switched = s.get_json("/api/status")["frame"].as_u64().unwrap();
    let samples = || {
        let served = s.get_json("/api/captures");
        let c = served.as_array()?.iter().find(|c| c["pass"] == "path_trace" && c["output"] == "samples")?.clone();
        Some((c["frame"].as_u64()?, c["stats"]["min"][0].as_f64()?))
    };
    let converged = s.wait_for("convergence again", LIMIT, || samples().filter(|&(f, n)| f > switched && n == 8.0).map(|(f, _)| f));
    c.find(Locator::Css("#reset-history")).await.unwrap().click().await.unwrap();
    s.wait_for("the samples started over", LIMIT, || samples().filter(|&(f, n)| f > converged && n < 8.0));
    c.close().await.unwrap();
}

/// Writes `scenes/small.toml`, the minimal scene small, path traced with
/// few samples and denoised (lavapipe traces and denoises it in a few
/// frames); returns its path for `--scene`.
fn small_denoised_scene(p: &Project) -> String {
    let small = p.read("scenes/minimal.toml").replacen("width = 640", "width = 64", 1).replacen("height = 360", "height = 48", 1);
    assert!(
        small.contains("width = 64") && small.contains("height = 48") && !small.contains("[quality]"),
        "minimal.toml's settings moved: update this test"
    );
    // No weights named: the bundled LDR network for colour, albedo and normal.
    p.write("scenes/small.toml", small + "\n[quality]\nrenderer = \"path\"\npath_spp = 2\n\n[denoiser]\nmode = \"ldr\"\n");
    "scenes/small.toml".to_owned()
}

/// Every tensor the denoiser's passes write (but their `overflow` counts),
/// as "pass/output", in the order of `/api/passes`: the network's order.
fn denoiser_tensors(s: &Server) -> Vec<String> {
    s.get_json("/api/passes")
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["name"].as_str().unwrap().starts_with("denoise") && p["status"] == "ok")
        .flat_map(|p| {
            p["writes"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|w| w["kind"] == "buffer" && w["name"] != "overflow")
                .map(|w| format!("{}/{}", p["name"].as_str().unwrap(), w["name"].as_str().unwrap()))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A denoiser tensor in the page: every denoiser tensor listed with its
/// statistics, three picked channels as RGB equal to the values the server
/// serves (each mapped from its own min…max), the value of every channel
/// under the mouse exact, a grid cell and a histogram per channel.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_denoiser_tensor_shows_as_images_of_its_channels_with_exact_values() {
    let p = Project::copy_of_repo("browser-denoiser");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", &small_denoised_scene(&p)]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    until(&c, &s, "convergence", "document.querySelector('#path-samples[data-converged=\"true\"]')").await;
    let (pass, w, h) = ("denoise.enc_conv0", 64usize, 48usize);
    let chip = format!("#passes li[data-pass=\"{pass}\"][data-status=\"ok\"] .chip[data-output=\"tensor\"]");
    until(&c, &s, "the first convolution's chip", &format!("document.querySelector('{chip}')")).await;
    c.find(Locator::Css(&chip)).await.unwrap().click().await.unwrap();
    until(
        &c,
        &s,
        "the RGB view",
        &format!("!document.querySelector('#tensor-image').hidden && document.querySelector('#tensor-rgb').width === {w}"),
    )
    .await;

    // Every denoiser tensor the frame makes is listed.
    let tensors = denoiser_tensors(&s);
    assert!(tensors.len() > 10 && tensors.iter().any(|t| t == "denoise.pool1/tensor"), "{tensors:?}");
    until(&c, &s, "every denoiser tensor listed", &format!("document.querySelector('#tensor-list').dataset.count === '{}'", tensors.len()))
        .await;
    let listed = c.execute("return Array.from(document.querySelectorAll('#tensor-list tr[data-key]'), r => [r.dataset.key, ...Array.from(r.cells, d => d.textContent)]);", vec![]).await.unwrap();
    let listed = listed.as_array().unwrap();
    for t in &tensors {
        assert!(listed.iter().any(|r| r[0] == t.as_str()), "{t} listed: {listed:?}");
    }

    // The tensor the page shows is the one served (nothing renders once converged).
    let meta = s.get_json(&format!("/api/tensors/{pass}/tensor"));
    let channels = meta["layout"]["dims"][2][1].as_u64().unwrap() as usize;
    assert_eq!(meta["layout"]["dims"], serde_json::json!([["y", h], ["x", w], ["channel", channels]]));
    let (status, bytes) = s.get(&format!("/api/tensors/{pass}/tensor.f32"));
    assert_eq!(status, 200);
    let data: Vec<f32> = bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(data.len(), w * h * channels);
    until(
        &c,
        &s,
        "the page showing the served frame",
        &format!("document.querySelector('#tensor-shape').textContent.endsWith('frame {}')", meta["frame"]),
    )
    .await;
    assert_eq!(s.get_json(&format!("/api/tensors/{pass}/tensor"))["frame"], meta["frame"], "no frame rendered meanwhile");
    // The statistics table says which channels hold one value (a ReLU's
    // dead channels), as the served floats have it.
    let constant: Vec<usize> = (0..channels).filter(|&ch| data.iter().skip(ch).step_by(channels).all(|v| *v == data[ch])).collect();
    let labelled = c.execute("return Array.from(document.querySelectorAll('#tensor-stats tr'), (r, i) => [i, r.classList.contains('constant'), r.cells[0].textContent]).filter(r => r[1]).map(r => r[0] - 1);", vec![]).await.unwrap();
    assert_eq!(labelled, serde_json::json!(constant), "the channels labelled constant in #tensor-stats");
    let row = listed.iter().find(|r| r[0] == format!("{pass}/tensor").as_str()).unwrap();
    let lo = meta["stats"]["min"].as_array().unwrap();
    assert_eq!(row[2], format!("{h} × {w} × {channels}"));
    assert_eq!(row[3], "[y, x, channel] f32");
    let min = lo.iter().map(|v| v.as_f64().unwrap()).fold(f64::INFINITY, f64::min);
    assert!((row[4].as_str().unwrap().parse::<f64>().unwrap() - min).abs() <= 1e-3 * min.abs().max(1e-3), "listed min {} of {min}", row[4]);

    // Three channels picked as R, G, B: each pixel is the tensor's value
    // mapped from that channel's min…max. (serde_json may read a float
    // one ulp off: the same double, as far as JSON goes.)
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-15 * b.abs();
    let picked = [5usize, 0, channels - 5];
    c.execute(&format!("['#tensor-r', '#tensor-g', '#tensor-b'].forEach((id, k) => {{ const s = document.querySelector(id); s.value = String({picked:?}[k]); s.dispatchEvent(new Event('change')); }}); return true;"), vec![]).await.unwrap();
    let drawn = c.execute("const c = document.querySelector('#tensor-rgb'); return [JSON.parse(c.dataset.ranges), Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data)];", vec![]).await.unwrap();
    let pixels: Vec<u8> = drawn[1].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as u8).collect();
    assert_eq!(pixels.len(), w * h * 4);
    for (k, &ch) in picked.iter().enumerate() {
        let values = || data.iter().skip(ch).step_by(channels).map(|&v| f64::from(v));
        let (lo, hi) = (values().fold(f64::INFINITY, f64::min), values().fold(f64::NEG_INFINITY, f64::max));
        assert!(hi > lo, "channel {ch} varies");
        let range = [drawn[0][k][0].as_f64().unwrap(), drawn[0][k][1].as_f64().unwrap()];
        assert!(same(range[0], lo) && same(range[1], hi), "channel {ch}'s range {range:?} is its min…max {lo} … {hi}");
        for (i, v) in values().enumerate() {
            let want = ((v - lo) / (hi - lo) * 255.0).round();
            let got = f64::from(pixels[i * 4 + k]);
            assert!((got - want).abs() <= 1.0, "pixel {i} {}: {got}, want {want} (channel {ch} = {v})", ["R", "G", "B"][k]);
        }
    }

    // Fitted to the percentiles instead: each channel's 1st and 99th.
    let fitted = c.execute("const f = document.querySelector('#tensor-fit'); f.value = 'percentile'; f.dispatchEvent(new Event('change')); return JSON.parse(document.querySelector('#tensor-rgb').dataset.ranges);", vec![]).await.unwrap();
    for (k, &ch) in picked.iter().enumerate() {
        let mut values: Vec<f64> = data.iter().skip(ch).step_by(channels).map(|&v| f64::from(v)).collect();
        values.sort_by(f64::total_cmp);
        let at = |p: f64| values[(p * (values.len() - 1) as f64).round() as usize];
        let got = [fitted[k][0].as_f64().unwrap(), fitted[k][1].as_f64().unwrap()];
        assert!(same(got[0], at(0.01)) && same(got[1], at(0.99)), "channel {ch}'s percentiles: {got:?}, want {} … {}", at(0.01), at(0.99));
    }
    c.execute(
        "const f = document.querySelector('#tensor-fit'); f.value = 'minmax'; f.dispatchEvent(new Event('change')); return true;",
        vec![],
    )
    .await
    .unwrap();

    // Under the mouse: every channel's exact value at that pixel.
    let (x, y) = (41usize, 17usize);
    let hover = format!(
        "const c = document.querySelector('#tensor-rgb'); const r = c.getBoundingClientRect();
         c.dispatchEvent(new MouseEvent('mousemove', {{ clientX: r.left + ({x} + 0.5) * r.width / {w}, clientY: r.top + ({y} + 0.5) * r.height / {h} }}));
         const p = document.querySelector('#tensor-pixel'); return [Number(p.dataset.x), Number(p.dataset.y), JSON.parse(p.dataset.values)];"
    );
    let read = c.execute(&hover, vec![]).await.unwrap();
    assert_eq!((read[0].as_u64(), read[1].as_u64()), (Some(x as u64), Some(y as u64)));
    let values: Vec<f64> = read[2].as_array().unwrap().iter().map(|v| v.as_str().unwrap().parse().unwrap()).collect();
    let want: Vec<f64> = data[(y * w + x) * channels..][..channels].iter().map(|&v| f64::from(v)).collect();
    assert_eq!(values, want, "the readout is every channel's value at ({x}, {y})");

    // Small multiples: one cell per channel; a histogram per channel, of
    // every pixel; the colour map.
    let view =
        |v: &str| format!("const s = document.querySelector('#tensor-view'); s.value = '{v}'; s.dispatchEvent(new Event('change'));");
    let cells = c
        .execute(
            &format!("{} return document.querySelectorAll('#tensor-grid:not([hidden]) canvas[data-channel]').length;", view("grid")),
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(cells.as_u64(), Some(channels as u64), "one grid cell per channel");
    let bins = c.execute(&format!("{} return Array.from(document.querySelectorAll('#tensor-histograms:not([hidden]) canvas[data-channel]'), c => JSON.parse(c.dataset.bins).reduce((a, b) => a + b, 0));", view("histograms")), vec![]).await.unwrap();
    assert_eq!(bins, serde_json::json!(vec![w * h; channels]), "a histogram per channel, of every pixel");
    let cmap = c
        .execute(
            &format!(
                "{} return document.querySelector('#tensor-cmap').hidden ? 0 : document.querySelector('#tensor-cmap').width;",
                view("colormap")
            ),
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(cmap.as_u64(), Some(w as u64), "the colour map view");
    c.close().await.unwrap();
}

/// The accuracy-against-time chart: the project's `loupe bench tradeoffs`
/// results, a point per setting value with the scene's current settings
/// marked; hovering a point shows its settings, figures and image;
/// clicking it applies its settings as overrides, and the mark moves.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_tradeoffs_chart_shows_the_sweep_and_applies_a_point() {
    let p = Project::copy_of_repo("browser-tradeoffs");
    let sweep = [
        "bench",
        "tradeoffs",
        "--scene",
        "scenes/minimal.toml",
        "--size",
        "32x18",
        "--repeats",
        "1",
        "--reference-spp",
        "64",
        "--cache",
        "cache",
    ];
    p.run(&sweep).code(0);
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    // Series: shadow_map_size (128 … 2048), shadow_filter (0 … 3), path_spp
    // (1 … 64), two_triangles (true, false: the same image, on the bottom
    // edge). The scene's defaults are raster, a 1024 shadow map, a filter
    // of radius 1, one triangle: those points are current, the path
    // tracer's are not.
    until(&c, &s, "the points", "window.loupe.state.tradeoffs.points === 18").await;
    let current = until(&c, &s, "the current points marked", "JSON.stringify(window.loupe.state.tradeoffs.current)").await;
    assert_eq!(current, "[[0,3],[1,1],[3,1]]");

    let point = "document.querySelector('#tradeoffs-chart circle[data-series=\"2\"][data-index=\"2\"]')";
    c.execute(&format!("{point}.dispatchEvent(new MouseEvent('mouseenter')); return true;"), vec![]).await.unwrap();
    let text = until(
        &c,
        &s,
        "the tip",
        "!document.querySelector('#tradeoffs-tip').hidden && document.querySelector('#tradeoffs-text').textContent",
    )
    .await;
    let text = text.as_str().unwrap().to_owned();
    assert!(
        text.starts_with("path_spp: 4")
            && text.contains("quality.renderer = \"path\" · quality.path_spp = 4")
            && text.contains("relative MSE"),
        "{text}"
    );
    until(&c, &s, "its image", "document.querySelector('#tradeoffs-image').naturalWidth === 32").await;
    // Every point's tip, its image in, lies inside the window and off the
    // point it describes (the chart sits in the window's lower left).
    let placed = c
        .execute_async(
            "const done = arguments[0], out = [];
             const circles = Array.from(document.querySelectorAll('#tradeoffs-chart circle'));
             const tip = document.querySelector('#tradeoffs-tip'), image = document.querySelector('#tradeoffs-image');
             const settle = () => new Promise((r) => setTimeout(r, 50));
             (async () => {
               for (const circle of circles) {
                 circle.dispatchEvent(new MouseEvent('mouseenter'));
                 for (let i = 0; i < 100 && !(image.complete && image.naturalWidth); i++) await settle();
                 await settle();
                 const t = tip.getBoundingClientRect(), p = circle.getBoundingClientRect();
                 const inside = t.left >= 0 && t.top >= 0 && t.right <= innerWidth + 0.5 && t.bottom <= innerHeight + 0.5;
                 const off = t.right <= p.left || t.left >= p.right || t.bottom <= p.top || t.top >= p.bottom;
                 if (tip.hidden || !inside || !off) out.push([circle.dataset.series, circle.dataset.index, tip.hidden, inside, off, [t.left, t.top, t.right, t.bottom, innerWidth, innerHeight]]);
                 circle.dispatchEvent(new MouseEvent('mouseleave'));
               }
               done(out);
             })();",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(
        placed,
        serde_json::json!([]),
        "tips hidden, outside the window or over their point: [series, index, hidden, inside, off, rect]"
    );

    c.execute(&format!("{point}.dispatchEvent(new MouseEvent('click')); return true;"), vec![]).await.unwrap();
    until(&c, &s, "the point applied and marked", "JSON.stringify(window.loupe.state.tradeoffs.current) === '[[2,2],[3,1]]'").await;
    let (status, body) = s.get("/api/controls");
    assert_eq!(status, 200);
    let controls: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(controls["overrides"], serde_json::json!({ "quality.path_spp": 4, "quality.renderer": "path" }));
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_inspector_keeps_its_live_stream_across_control_changes_and_auto_fit() {
    let p = Project::copy_of_repo("browser-stream");
    // Continuous rendering: a streamed capture of the final output every frame.
    let s = Server::start(&p.root, &[]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    let throttle = "window.loupe.state.inspector.throttle";
    until(&c, &s, "the inspector streaming", &format!("{throttle}.streaming && {throttle}.streamedLoads >= 3")).await;

    // Each round changes display controls as a user does and then, in the
    // animation frame that redraws (registered after the change, so it runs
    // after the inspector's), reads the stream's state. A control change
    // must leave it alone: the count of streamed captures shown never goes
    // back, the time of the last one (which decides whether a frame is
    // fetched instead) is kept, and a capture waiting to be shown has a
    // timer to show it (or waits for a fetch in flight).
    let controls = [
        "const e = document.querySelector('#exposure'); e.value = '1.5'; e.dispatchEvent(new Event('input'));",
        "document.querySelector('#auto-fit').click();",
        "const ch = document.querySelector('#channel'); ch.value = 'g'; ch.dispatchEvent(new Event('change'));",
        "const e = document.querySelector('#srgb'); e.checked = !e.checked; e.dispatchEvent(new Event('change'));",
        "window.loupe.autoFit();",
        "const m = document.querySelector('#range-max'); m.value = '2'; m.dispatchEvent(new Event('input'));",
    ];
    for round in 0..3 {
        for change in controls {
            let seen = c
                .execute_async(
                    &format!(
                        "const done = arguments[0];
                         const before = {throttle};
                         {change}
                         requestAnimationFrame(() => {{
                           const after = {throttle};
                           done([before.streamedLoads, after.streamedLoads, after.lastStreamed >= before.lastStreamed,
                                 !after.pending || after.applyTimer || after.loading]);
                         }});"
                    ),
                    vec![],
                )
                .await
                .unwrap();
            let (before, after) = (seen[0].as_u64().unwrap(), seen[1].as_u64().unwrap());
            assert!(after >= before, "round {round}, `{change}`: the streamed captures shown went from {before} back to {after}");
            assert_eq!(seen[2], true, "round {round}, `{change}`: the inspector forgot the stream, so it would fetch");
            assert_eq!(seen[3], true, "round {round}, `{change}`: a streamed capture waits without a timer to show it");
        }
    }
    // The stream goes on after the changes.
    let now = c.execute(&format!("return {throttle}.streamedLoads;"), vec![]).await.unwrap().as_u64().unwrap();
    until(&c, &s, "more streamed captures", &format!("{throttle}.streamedLoads >= {}", now + 3)).await;
    c.close().await.unwrap();
}

/// The docs' picture of the inspector, `docs/images/inspector.png`: the
/// showcase scene, raster, with the inspector on the final output and a
/// pixel's values read out. Regenerate it with
/// `LOUPE_BLESS=1 cargo test -p loupe-tests --test e2e browser::the_docs_screenshot`;
/// without LOUPE_BLESS the test takes the picture all the same and checks it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_docs_screenshot_of_the_inspector_is_regenerable() {
    const WIDTH: u32 = 1600;
    const HEIGHT: u32 = 857;
    let committed = repo().join("docs/images/inspector.png");
    let p = Project::copy_of_repo("browser-screenshot");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/showcase.toml"]);
    let (_driver, c) = browser_with_page(WIDTH, HEIGHT).await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "document.querySelector('#frame').complete && Number(document.querySelector('#frame').dataset.frame || 0)")
        .await;
    // The inspector opens on the final output by itself; asking for it
    // again resolves once its data is shown (fetched anew if the first
    // fetch came before the capture).
    let loaded = c.execute_async("window.loupe.inspect('tonemap', 'color').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(loaded, true, "the inspector shows tonemap/color\n{}", s.log());
    // A pixel of the image read out, as when a user hovers it.
    let value = c.execute("return window.loupe.hover(400, 170);", vec![]).await.unwrap();
    assert!(value.is_array(), "the pixel read out: {value}");
    let png = c.screenshot().await.unwrap();
    c.close().await.unwrap();

    let shot = image::load_from_memory_with_format(&png, image::ImageFormat::Png).expect("the screenshot is a PNG").to_rgb8();
    assert_eq!(shot.dimensions(), (WIDTH, HEIGHT), "the screenshot's size");
    let colours: std::collections::HashSet<[u8; 3]> = shot.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 1000, "the screenshot shows the page, not a blank: {} colours", colours.len());
    if std::env::var_os("LOUPE_BLESS").is_some() {
        std::fs::create_dir_all(committed.parent().unwrap()).unwrap();
        std::fs::write(&committed, &png).unwrap();
    }
    let file = image::open(&committed).unwrap_or_else(|e| panic!("{} (LOUPE_BLESS=1 writes it): {e}", committed.display()));
    assert_eq!((file.width(), file.height()), (WIDTH, HEIGHT), "{} has the screenshot's size", committed.display());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_broken_file_shows_its_diff_against_the_last_good_version_and_reverts_to_it() {
    let p = Project::copy_of_repo("browser-file-diff");
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "the tonemap pass listed ok", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"ok\"]')").await;
    let hidden = c.execute("return document.querySelector('#file-diffs').hidden;", vec![]).await.unwrap();
    assert_eq!(hidden, true, "no diff while every file compiles");

    // Broken as vim saves: the diff shows the last good line removed and
    // the broken one added, marked failing.
    let good = p.read(TONEMAP);
    let broken = good.replace("let c = max(", "let c = mux(");
    let line = broken.lines().position(|l| l.contains("mux(")).unwrap() + 1;
    p.save_by_rename(TONEMAP, &broken);
    let file = format!("#file-diffs .file-diff[data-file=\"{TONEMAP}\"]");
    let added = format!("{file} .diff-line.ins.failing[data-new=\"{line}\"]");
    until(&c, &s, "the failing line in the diff", &format!("document.querySelector('{added}')")).await;
    let text = |sel: String| {
        let c = c.clone();
        async move { c.find(Locator::Css(&sel)).await.unwrap().text().await.unwrap() }
    };
    assert!(text(added.clone()).await.contains("mux("));
    assert!(text(format!("{file} .diff-line.del[data-old=\"{line}\"]")).await.contains("max("));
    let unmarked = c.execute(&format!("return document.querySelectorAll('{file} .diff-line.failing').length;"), vec![]).await.unwrap();
    assert_eq!(unmarked, 1, "only the line the error points at is marked");

    // Declined: nothing is written.
    c.execute("window.confirm = () => false;", vec![]).await.unwrap();
    c.find(Locator::Css(&format!("{file} button.revert"))).await.unwrap().click().await.unwrap();
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert_eq!(p.read(TONEMAP), broken, "a declined revert writes nothing");

    // Confirmed: the last good text is back, the pass runs and the diff goes.
    c.execute("window.confirm = () => true;", vec![]).await.unwrap();
    c.find(Locator::Css(&format!("{file} button.revert"))).await.unwrap().click().await.unwrap();
    until(&c, &s, "the diff gone", "document.querySelector('#file-diffs').hidden").await;
    until(&c, &s, "the pass ok again", "document.querySelector('#passes li[data-pass=\"tonemap\"][data-status=\"ok\"]')").await;
    assert_eq!(p.read(TONEMAP), good);
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn against_reference_shows_the_gates_verdict_live_and_blesses_what_it_shows() {
    let p = Project::copy_of_repo("browser-references");
    p.write("loupe.toml", "[[images]]\nname = \"pattern\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\n");
    let s = Server::start(&p.root, &["--scene", "scenes/pattern.toml", "--render", "on-change"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "connected", "document.querySelector('#connection').textContent === 'connected'").await;

    // On: no reference yet, so the case fails, showing what it rendered.
    c.find(Locator::Css("#reference-on")).await.unwrap().click().await.unwrap();
    let case = "#reference-body .reference-case[data-case=\"pattern\"]";
    until(&c, &s, "the failing case", &format!("document.querySelector('{case}[data-verdict=\"failed\"]')")).await;
    let width = format!("document.querySelector('{case} img[data-kind=\"actual\"]').naturalWidth === 64");
    until(&c, &s, "the rendered image", &width).await;
    let shown = c.execute(&format!("return document.querySelectorAll('{case} img').length;"), vec![]).await.unwrap();
    assert_eq!(shown, 1, "no reference, no FLIP map: only the rendered image");

    // Blessed (confirmed): the reference is written and the case passes,
    // with the three images.
    c.execute("window.confirm = () => true;", vec![]).await.unwrap();
    c.find(Locator::Css(&format!("{case} button.bless"))).await.unwrap().click().await.unwrap();
    until(&c, &s, "the case passing", &format!("document.querySelector('{case}[data-verdict=\"passed\"]')")).await;
    assert!(p.path("tests/images/pattern/tonemap.color.png").is_file());
    let figures = c.find(Locator::Css(&format!("{case} .reference-figures"))).await.unwrap().text().await.unwrap();
    assert!(figures.contains("FLIP mean 0.0000 (≤ 0.01)"), "{figures}");
    until(&c, &s, "the FLIP map", &format!("document.querySelector('{case} img[data-kind=\"flip\"]')?.naturalWidth === 64")).await;

    // A tonemapper change, saved: the page says the gate would fail.
    let tonemap = p.read(TONEMAP);
    p.save_by_rename(TONEMAP, tonemap.replace("let c = max(texel.rgb, vec3(0.0));", "let c = max(texel.rgb * 1.5, vec3(0.0));"));
    until(&c, &s, "the case failing again", &format!("document.querySelector('{case}[data-verdict=\"failed\"]')")).await;
    let problem = c.find(Locator::Css(&format!("{case} .reference-problem"))).await.unwrap().text().await.unwrap();
    assert!(problem.contains("differs from its reference"), "{problem}");
    c.close().await.unwrap();
}
