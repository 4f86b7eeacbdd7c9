//! `loupe serve`: hot reload with real editor save patterns, keep-last-good,
//! the HTTP API, the WebSocket stream, uncaptured GPU errors, device loss,
//! and a short soak.

use std::collections::BTreeSet;
use std::time::Duration;

use loupe_tests::reload::{self, Driver};
use loupe_tests::ws::Msg;
use loupe_tests::{Project, Server};

const LIMIT: Duration = Duration::from_secs(60);
const TONEMAP: &str = "shaders/post/tonemap.wgsl";

fn frame_of(s: &Server) -> u64 {
    s.get_json("/api/status")["frame"].as_u64().unwrap_or(0)
}

fn pass_status(s: &Server, pass: &str) -> Option<String> {
    let passes = s.get_json("/api/passes");
    passes.as_array()?.iter().find(|p| p["name"] == pass).map(|p| p["status"].as_str().unwrap_or("").to_owned())
}

#[test]
fn broken_shader_keeps_last_good_frame_and_reports_location_then_clears() {
    let p = Project::copy_of_repo("serve-keep-last-good");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    assert_eq!(pass_status(&s, "tonemap").as_deref(), Some("ok"));
    let (code, good_png) = s.get("/api/captures/tonemap/color.png");
    assert_eq!(code, 200);

    // Break it the way vim saves: write a temp file, rename over.
    let good = p.read(TONEMAP);
    let broken = good.replace("let c = max(", "let c = mux(");
    let line = broken.lines().position(|l| l.contains("mux(")).unwrap() as u64 + 1;
    p.save_by_rename(TONEMAP, &broken);
    let diag = s.wait_for("the error to be reported", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.iter().find(|d| d["location"]["file"] == TONEMAP).cloned()
    });
    assert_eq!(diag["location"]["line"].as_u64(), Some(line), "{diag}");
    assert_eq!(pass_status(&s, "tonemap").as_deref(), Some("stale"));
    // The last good pipeline still renders: the capture still exists and a
    // forced new frame keeps producing the same image.
    let (code, still) = s.get("/api/captures/tonemap/color.png");
    assert_eq!(code, 200);
    assert_eq!(still, good_png, "the frame is unchanged while the shader is broken");

    // Fix it with an in-place write: the error clears.
    p.write(TONEMAP, &good);
    s.wait_for("the error to clear", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.is_empty().then_some(())
    });
    s.wait_for("the pass to be ok", LIMIT, || (pass_status(&s, "tonemap").as_deref() == Some("ok")).then_some(()));
}

#[test]
fn a_change_to_an_imported_module_rebuilds_only_its_dependents() {
    // minimal.toml renders depth, G-buffer, tile classification, lighting
    // and tonemap; of their shaders the G-buffer's, classify.wgsl and
    // lighting.wgsl import lib/brdf.wgsl, through the generated material
    // modules (volume_march.wgsl, which shares other modules with them, is
    // culled here; the empty tiles' lighting_environment.wgsl imports no
    // material).
    const BRDF: &str = "shaders/lib/brdf.wgsl";
    const UNUSED: &str = "shaders/lib/unused.wgsl";
    let p = Project::copy_of_repo("serve-deps");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let all: BTreeSet<String> =
        s.get_json("/api/pipelines").as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_owned()).collect();
    let lighting: BTreeSet<String> = all.iter().filter(|n| n.starts_with("lighting.deferred")).cloned().collect();
    assert!(!lighting.is_empty() && all.contains("post.tonemap") && all.iter().any(|n| n.starts_with("geometry.gbuffer")), "{all:?}");
    let brdf_users: BTreeSet<String> = all
        .iter()
        .filter(|n| ["lighting.deferred", "geometry.gbuffer", "passes.classify"].iter().any(|u| n.starts_with(u)))
        .cloned()
        .collect();

    // Three saves, each followed to its frame: the imported module, a file
    // nobody imports, an unrelated shader. The last one bounds the stream:
    // every rebuild the first two caused was announced before it.
    let mut d = Driver::new(&p, &s);
    let brdf = p.read(BRDF);
    let changed = brdf.replace("fn specular_f0(", "fn unused_helper() -> f32 { return 1.0; }\n\nfn specular_f0(");
    assert_ne!(changed, brdf);
    let tonemap = reload::constant_colour(&p.read(TONEMAP), reload::colour(1));
    let mut events = Vec::new();
    for (rel, content) in [(BRDF, changed.as_str()), (UNUSED, "#define_import_path demo::unused\nfn nothing() {}\n"), (TONEMAP, &tonemap)] {
        let o = d.save(rel, content).unwrap_or_else(|| panic!("no reload for {rel}\n{}", s.log()));
        assert!(o.succeeded, "{rel}: {:?}", d.events);
        events.append(&mut d.events);
    }
    let started: Vec<(Vec<String>, BTreeSet<String>)> = events
        .iter()
        .filter(|e| e["type"] == "reload_started")
        .map(|e| {
            let strings = |k: &str| e[k].as_array().unwrap().iter().map(|v| v.as_str().unwrap().to_owned());
            (strings("files").collect::<Vec<_>>(), strings("pipelines").collect::<BTreeSet<_>>())
        })
        .skip_while(|(files, _)| files.iter().all(|f| f != BRDF))
        .collect();
    let expected = vec![
        (vec![BRDF.to_owned()], brdf_users),
        (vec![UNUSED.to_owned()], BTreeSet::new()),
        (vec![TONEMAP.to_owned()], BTreeSet::from(["post.tonemap".to_owned()])),
    ];
    assert_eq!(started, expected, "reloads in order, from the brdf.wgsl save on");
}

#[test]
fn api_shapes() {
    let p = Project::copy_of_repo("serve-api");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let st = s.get_json("/api/status");
    assert_eq!(st["protocol"], 3);
    assert!(st["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    let passes = s.get_json("/api/passes");
    let names: Vec<&str> = passes.as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert!(names.contains(&"tonemap"), "{passes}");
    let tm = passes.as_array().unwrap().iter().find(|p| p["name"] == "tonemap").unwrap();
    assert!(tm["time_ms"].as_f64().is_some(), "{tm}");
    let capture = s.capture_f32("tonemap/color").expect("the final output is captured");
    // pattern.toml's [output] is 960×540: what the server says and sends.
    assert_eq!((capture.width, capture.height), (960, 540), "the capture's X-Loupe-Width/Height");
    assert_eq!(capture.data.len(), 960 * 540 * 4, "RGBA f32 of the scene's size");
    let listed = s.get_json("/api/captures");
    let final_entry = listed.as_array().unwrap().iter().find(|c| c["pass"] == "tonemap" && c["output"] == "color").expect("listed");
    assert_eq!((final_entry["width"].as_u64(), final_entry["height"].as_u64()), (Some(960), Some(540)), "{final_entry}");
    // Real pixels: the test pattern's colour bars reach the final image
    // opaque (an invalid frame would read back as all zeros).
    let px = |i: usize| capture.data[i];
    let row = 270 * 960 * 4; // middle row: colour bars
    let last_bar = row + 959 * 4; // white bar, 0.75 before tonemapping
    assert_eq!(px(row + 3), 1.0, "alpha of the final image");
    assert!(
        px(last_bar) > 0.3 && px(last_bar + 1) > 0.3 && px(last_bar + 2) > 0.3,
        "white bar is lit: {:?}",
        (px(last_bar), px(last_bar + 1))
    );
    let (code, _) = s.get("/api/captures/nope/color.png");
    assert_eq!(code, 404);
    let captures = s.get_json("/api/captures");
    let finals: Vec<&str> =
        captures.as_array().unwrap().iter().filter(|c| c["final"] == true).map(|c| c["pass"].as_str().unwrap()).collect();
    assert_eq!(finals, ["tonemap"], "{captures}");
    // Without --debug-api there is no debug API.
    let (code, body) = s.post("/api/debug/lose-device");
    assert_eq!(code, 404, "{}", String::from_utf8_lossy(&body));
    assert_eq!(s.get_json("/api/status")["device_resets"], 0);
}

/// What exists but has nothing yet is a documented state (204 and
/// `X-Loupe-State`), not a 404: an output no frame captured, a last good
/// version no reload made, tradeoff results not written; tradeoff results
/// say whose they are. Unknown names stay 404.
#[test]
fn states_are_answered_as_states_and_unknown_names_as_404() {
    let p = Project::copy_of_repo("serve-states");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let state = |path: &str| s.get_state(path);
    let not_captured = (204, Some("not-captured".to_owned()));
    assert_eq!(state("/api/captures/gbuffer/normal.f32"), not_captured, "written by the graph, not subscribed to");
    assert_eq!(state("/api/captures/tonemap/color.png?version=last_good"), not_captured, "no reload replaced it yet");
    assert_eq!(state("/api/captures/gbuffer/nope.f32"), (404, None));
    assert_eq!(state("/api/captures/nope/normal.f32"), (404, None));
    assert_eq!(state("/api/tensors/gbuffer/nope.f32"), (404, None));
    assert_eq!(state("/api/captures/tonemap/color.f32"), (200, None), "the final output is captured");

    assert_eq!(state("/api/tradeoffs"), (204, Some("not-written".to_owned())));
    std::fs::create_dir_all(p.path("tradeoffs")).unwrap();
    let results = |json: &str| {
        std::fs::write(p.path("tradeoffs/tradeoffs.json"), json).unwrap();
        state("/api/tradeoffs")
    };
    let said = |v: &str| (200, Some(v.to_owned()));
    assert_eq!(results(r#"{"scene":"scenes/minimal.toml","hash":"0","series":[]}"#), said("stale"));
    assert_eq!(results(r#"{"scene":"scenes/showcase.toml","hash":"0","series":[]}"#), said("other-scene"));
}

fn image_kind(m: &Msg) -> Option<(String, serde_json::Value)> {
    match m {
        Msg::Image(h, _) => Some((h["kind"].as_str().unwrap_or("").to_owned(), h.clone())),
        Msg::Event(_) => None,
    }
}

#[test]
fn websocket_streams_subscribed_outputs_per_client_and_announces_passes_only_on_change() {
    let p = Project::copy_of_repo("serve-ws");
    let s = Server::start(&p.root, &["--render", "continuous", "--fps", "10"]);
    let mut ws = s.ws();
    let hello = ws.event("hello", LIMIT, |_| true);
    assert_eq!(hello["protocol"], 3);
    let other = s.ws(); // a second client that subscribes to nothing

    // Every client gets the final output as a `frame` image.
    let (_, h) = ws.until("a frame image", LIMIT, |m| image_kind(m).filter(|(k, _)| k == "frame"));
    assert_eq!((h["pass"].as_str(), h["final"].as_bool(), h["mime"].as_str()), (Some("tonemap"), Some(true), Some("image/png")), "{h}");

    // Subscribed: the HDR test pattern streams as exact floats.
    ws.send(serde_json::json!({ "type": "subscribe", "pass": "test_pattern", "output": "color", "encoding": "f32" }));
    let (h, data) = ws.until("a capture image", LIMIT, |m| match m {
        Msg::Image(h, d) if h["kind"] == "capture" => Some((h.clone(), d.clone())),
        _ => None,
    });
    assert_eq!((h["pass"].as_str(), h["output"].as_str(), h["final"].as_bool()), (Some("test_pattern"), Some("color"), Some(false)), "{h}");
    assert_eq!((h["encoding"].as_str(), h["format"].as_str()), (Some("f32"), Some("Rgba16Float")));
    let (w, ht) = (h["width"].as_u64().unwrap() as usize, h["height"].as_u64().unwrap() as usize);
    assert_eq!(data.len(), w * ht * 16);
    let alpha = f32::from_le_bytes(data[(ht / 2 * w) * 16 + 12..][..4].try_into().unwrap());
    assert_eq!(alpha, 1.0, "real pixels: the pattern is opaque");

    // Frames keep coming; the pass list does not change, so no `passes`.
    let mut frames = 0;
    ws.until("five frames", LIMIT, |m| {
        assert_ne!(m.event_type(), Some("passes"), "a `passes` event without a change");
        frames += usize::from(m.event_type() == Some("frame"));
        (frames == 5).then_some(())
    });

    // A change of status is announced.
    p.save_by_rename(reload::TONEMAP, reload::broken(&p.read(reload::TONEMAP)));
    let passes = ws.event("passes", LIMIT, |_| true);
    let tonemap = passes["passes"].as_array().unwrap().iter().find(|p| p["name"] == "tonemap").unwrap().clone();
    assert_eq!(tonemap["status"], "stale", "{passes}");

    // Unsubscribed (an invalid message after it marks when the server has
    // read it): no more captures.
    ws.send(serde_json::json!({ "type": "unsubscribe", "pass": "test_pattern", "output": "color" }));
    ws.send(serde_json::json!({ "type": "marker" }));
    ws.event("error", LIMIT, |_| true);
    three_frames_and_no_capture(&mut ws, "a capture after unsubscribing");

    // The other client never subscribed: only final frames, never captures.
    let mut other = other;
    other.event("hello", LIMIT, |_| true);
    three_frames_and_no_capture(&mut other, "a capture nobody on this connection asked for");
}

/// Reads until three `frame` images came, failing on any `capture` image.
fn three_frames_and_no_capture(ws: &mut loupe_tests::ws::Ws, why: &str) {
    let mut images = 0;
    ws.until("three frame images", LIMIT, |m| {
        let kind = image_kind(m).map(|k| k.0);
        assert_ne!(kind.as_deref(), Some("capture"), "{why}");
        images += usize::from(kind.as_deref() == Some("frame"));
        (images == 3).then_some(())
    });
}

#[test]
fn a_reload_is_announced_with_its_render_time_and_the_frame_that_shows_it() {
    let p = Project::copy_of_repo("serve-reload-frame");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let mut d = Driver::new(&p, &s);
    let colour = reload::colour(7);
    let o = d.save(reload::TONEMAP, &reload::constant_colour(&p.read(reload::TONEMAP), colour)).expect("the reload finished");
    assert!(o.succeeded);
    let t = o.timings.clone().unwrap();
    for k in ["watch_ms", "compose_ms", "pipeline_ms", "render_ms"] {
        assert!(t[k].as_f64().is_some_and(|v| v > 0.0), "{k} is measured: {t}");
    }
    // The frame that carries the reload shows the new colour.
    let frame = o.frame.unwrap();
    let c = s.capture_f32(reload::FINAL).unwrap();
    assert_eq!(c.frame, frame, "on-change: nothing rendered after the reload's frame");
    let px = c.pixel(c.width / 2, c.height / 2);
    for (want, got) in colour.iter().zip(px) {
        assert!((reload::srgb(*want) - reload::srgb(got)).abs() < 1.5 / 255.0, "{colour:?} vs {px:?}");
    }
}

#[test]
fn a_uniform_of_the_wrong_size_is_refused_before_it_reaches_the_gpu() {
    let p = Project::copy_of_repo("serve-uniform-size");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let before = s.capture_f32(reload::FINAL).unwrap();
    let mut d = Driver::new(&p, &s);

    // The shader asks for a 32-byte uniform where the renderer binds 16.
    // It parses and validates; the layout's declared size refuses it.
    const PATTERN: &str = "shaders/passes/test_pattern.wgsl";
    let good = p.read(PATTERN);
    let bigger = good.replace("    frame: u32,\n}", "    frame: u32,\n    extra: vec4<f32>,\n}");
    assert_ne!(bigger, good);
    let o = d.save(PATTERN, &bigger).expect("the reload finished");
    assert!(!o.succeeded, "refused at pipeline creation");
    let api = s.get_json("/api/diagnostics");
    let line = bigger.lines().position(|l| l.contains("var<uniform> frame")).unwrap() + 1;
    let mismatch = api["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["code"] == "binding-mismatch")
        .unwrap_or_else(|| panic!("no binding-mismatch: {api}"));
    assert_eq!(mismatch["location"]["file"], PATTERN, "{mismatch}");
    assert_eq!(mismatch["location"]["line"].as_u64(), Some(line as u64), "{mismatch}");
    assert!(mismatch.to_string().contains("32 bytes"), "{mismatch}");
    // The last good pipeline keeps rendering: no GPU error, the frame's
    // pixels are the old ones.
    let passes = s.get_json("/api/passes");
    let tp = passes.as_array().unwrap().iter().find(|p| p["name"] == "test_pattern").unwrap();
    assert_eq!(tp["status"], "stale", "{tp}");
    let now = s.capture_f32(reload::FINAL).unwrap();
    assert_eq!(now.pixel(now.width - 1, now.height / 2), before.pixel(before.width - 1, before.height / 2));
    assert!(!api.to_string().contains("\"gpu\""), "{api}");

    // Fixed: the diagnostic goes and the pass is ok again.
    let o = d.save(PATTERN, &good).expect("the reload finished");
    assert!(o.succeeded);
    s.wait_for("the diagnostic to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
}

fn generation(s: &Server, name: &str) -> u64 {
    let pipelines = s.get_json("/api/pipelines");
    pipelines.as_array().unwrap().iter().find(|p| p["name"] == name).and_then(|p| p["generation"].as_u64()).unwrap()
}

#[test]
fn a_lost_device_is_recreated_from_the_last_good_sources() {
    let p = Project::copy_of_repo("serve-device-loss");
    let s = Server::start(&p.root, &["--render", "continuous", "--fps", "10", "--debug-api"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let good_pixels = s.capture_f32(reload::FINAL).unwrap();
    let mut d = Driver::new(&p, &s);
    let generation_before = generation(&s, "post.tonemap");

    // Break the shader: stale, the last good pipeline renders.
    let good = p.read(reload::TONEMAP);
    let o = d.save(reload::TONEMAP, &reload::broken(&good)).expect("the reload finished");
    assert!(!o.succeeded);
    assert_eq!(pass_status(&s, "tonemap").as_deref(), Some("stale"));

    // Lose the device for real.
    let (code, body) = s.post("/api/debug/lose-device");
    assert_eq!(code, 202, "{}", String::from_utf8_lossy(&body));
    let lost = d.ws.event("device_lost", LIMIT, |_| true);
    assert_eq!(lost["recovered"], true, "{lost}");
    let st = s.get_json("/api/status");
    assert_eq!(st["device_resets"], 1);
    let lost_at = st["frame"].as_u64().unwrap();

    // Rebuilt from the last good module, not from the broken file on disk:
    // still stale (not failed), same generation, and frames keep coming
    // with the same real pixels.
    assert_eq!(pass_status(&s, "tonemap").as_deref(), Some("stale"));
    assert_eq!(generation(&s, "post.tonemap"), generation_before);
    let frame = d.ws.event("frame", LIMIT, |v| v["frame"].as_u64() > Some(lost_at + 1));
    let after = s.wait_for("a capture after the loss", LIMIT, || s.capture_f32(reload::FINAL).filter(|c| c.frame > lost_at));
    assert!(frame["frame"].as_u64().unwrap() > lost_at);
    assert_eq!(after.data, good_pixels.data, "the recovered device renders the last good image");
    assert_eq!(after.pixel(after.width / 2, after.height / 2)[3], 1.0);

    // Fixing the file still swaps in.
    let colour = reload::colour(3);
    let o = d.save(reload::TONEMAP, &reload::constant_colour(&good, colour)).expect("the reload finished");
    assert!(o.succeeded);
    assert_eq!(pass_status(&s, "tonemap").as_deref(), Some("ok"));
    assert_eq!(generation(&s, "post.tonemap"), generation_before + 1);
    let shown = s.wait_for("the fixed frame", LIMIT, || s.capture_f32(reload::FINAL).filter(|c| c.frame >= o.frame.unwrap()));
    assert!((reload::srgb(shown.pixel(0, 0)[0]) - reload::srgb(colour[0])).abs() < 1.5 / 255.0);
    assert_eq!(s.get_json("/api/status")["device_resets"], 1);
}

/// A short version of `bench-reload soak`: every save produces its event,
/// memory stays bounded, the final frame matches the final file.
#[test]
fn soak_edit_break_fix_cycles() {
    const CYCLES: usize = 25;
    const RSS_BOUND_MIB: u64 = 256;
    let p = Project::copy_of_repo("serve-soak");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let mut d = Driver::new(&p, &s);
    let r = reload::soak(&s, &mut d, CYCLES, 5, |_| {});
    assert!(r.lost.is_empty(), "lost: {:?}\n{}", r.lost, s.log());
    assert_eq!(r.outcomes, 3 * CYCLES);
    assert_eq!(r.dropped_events, 0);
    assert!(r.final_matches(), "final colour {:?} (sRGB-encoded), pixel {:?}", r.final_colour.map(reload::srgb), r.final_pixel);
    assert!(r.rss_max_kib() <= RSS_BOUND_MIB * 1024, "VmRSS {:?} KiB over {RSS_BOUND_MIB} MiB", r.rss);
}

/// What A/B compares against: the image a pass showed before its own
/// pipelines last really changed.
#[test]
fn last_good_images_are_kept_per_pass_and_replaced_only_by_a_real_change() {
    let p = Project::copy_of_repo("serve-last-good");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let first = s.capture_f32(reload::FINAL).unwrap();
    // Whether there is a last good image, and whether it is the first one
    // (images are compared, not printed: they are large).
    let last_good = |s: &Server| -> Option<bool> {
        let (status, body) = s.get(&format!("/api/captures/{}.f32?version=last_good", reload::FINAL));
        let data: Vec<f32> = body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        (status == 200).then(|| data == first.data)
    };
    assert_eq!(last_good(&s), None, "nothing has changed yet");
    let mut d = Driver::new(&p, &s);

    // A rebuild compiles the same sources again: nothing is replaced.
    let (code, _) = s.post("/api/reload");
    assert_eq!(code, 202);
    let done = d.ws.event("reload_succeeded", LIMIT, |_| true);
    d.ws.event("frame", LIMIT, |v| v["reloads"].as_array().is_some_and(|r| r.contains(&done["id"])));
    assert_eq!(last_good(&s), None, "a rebuild of unchanged sources keeps no last good image");

    // A real change to tonemap: the image before it is tonemap's last good.
    let good = p.read(reload::TONEMAP);
    let o = d.save(reload::TONEMAP, &reload::constant_colour(&good, reload::colour(1))).expect("the reload finished");
    assert!(o.succeeded);
    assert_eq!(last_good(&s), Some(true), "tonemap's image before the change");

    // A change to another pass leaves tonemap's last good image alone.
    let pattern = p.read("shaders/passes/test_pattern.wgsl").replace("rgb * 0.75", "rgb * 0.5");
    let o = d.save("shaders/passes/test_pattern.wgsl", &pattern).expect("the reload finished");
    assert!(o.succeeded);
    assert_eq!(last_good(&s), Some(true), "still tonemap's own last good image");
}

/// A glTF's external `.bin` is a scene input like the glTF itself.
#[test]
fn an_edit_to_a_meshs_external_buffer_reloads_the_scene() {
    let p = Project::copy_of_repo("serve-mesh-bin");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    break_and_mend_buffer(&p, &s, "scenes/meshes/torus_knot.bin");
}

/// A scene outside `scenes/` is watched with everything it loads.
#[test]
fn a_scene_outside_the_scenes_folder_is_watched_with_its_meshes() {
    let p = Project::copy_of_repo("serve-scene-elsewhere");
    for file in ["torus_knot.gltf", "torus_knot.bin"] {
        p.write(&format!("elsewhere/meshes/{file}"), std::fs::read(p.path(&format!("scenes/meshes/{file}"))).unwrap());
    }
    let scene = "elsewhere/scene.toml";
    let good = p.read("scenes/minimal.toml");
    p.write(scene, &good);
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", scene]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));

    p.save_by_rename(scene, good.replace("intensity = 12.0", "intensity = -12.0"));
    let diagnostic = s.wait_for("the scene's error reported", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.iter().find(|d| d["code"] == "scene").cloned()
    });
    assert!(diagnostic["location"]["file"] == scene, "{diagnostic}");
    p.save_by_rename(scene, &good);
    s.wait_for("the scene's error to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
    break_and_mend_buffer(&p, &s, "elsewhere/meshes/torus_knot.bin");
}

/// Truncates a mesh's buffer by a rename save, waits for the located
/// diagnostic, restores it and waits for the diagnostic to clear.
fn break_and_mend_buffer(p: &Project, s: &Server, bin: &str) {
    let good = std::fs::read(p.path(bin)).unwrap();
    p.save_by_rename(bin, &good[..good.len() / 2]);
    let diagnostic = s.wait_for("the truncated buffer reported", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.iter().find(|d| d["message"].as_str().is_some_and(|m| m.contains("byteLength"))).cloned()
    });
    assert!(diagnostic["message"].as_str().unwrap().contains("buffers[0]"), "{diagnostic}");
    p.save_by_rename(bin, &good);
    s.wait_for("the diagnostic to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
}

/// A scene's denoiser weights are one of its files: a broken save is the
/// weights diagnostic in that file while the last good scene, denoiser
/// included, keeps rendering; the mended file clears it. (The weights are
/// copied into the temporary project, outside `scenes/`.)
#[test]
fn broken_denoiser_weights_keep_the_last_good_denoiser_rendering() {
    let p = Project::copy_of_repo("serve-weights");
    let weights = std::fs::read(loupe_tests::oidn_weights("rt_ldr_alb_nrm.tza")).unwrap();
    p.write("weights/rt_ldr_alb_nrm.tza", &weights);
    let scene = p.read("scenes/minimal.toml").replace("width = 640\nheight = 360", "width = 64\nheight = 48")
        + "\n[quality]\nrenderer = \"path\"\npath_spp = 2\n\n[denoiser]\nweights = \"../weights/rt_ldr_alb_nrm.tza\"\nmode = \"ldr\"\n";
    p.write("scenes/denoised.toml", scene);
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/denoised.toml"]);
    s.wait_for("a denoised frame", LIMIT, || (pass_status(&s, "denoise.dec_conv0")? == "ok" && frame_of(&s) > 0).then_some(()));
    assert_eq!(pass_status(&s, "denoise").as_deref(), Some("ok"));

    p.save_by_rename("weights/rt_ldr_alb_nrm.tza", &weights[..weights.len() / 2]);
    let diagnostic = s.wait_for("the truncated weights reported", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.iter().find(|d| d["code"] == "weights").cloned()
    });
    // As the scene names it, relative to the scene's folder.
    assert_eq!(diagnostic["location"]["file"], "scenes/../weights/rt_ldr_alb_nrm.tza", "{diagnostic}");
    assert!(
        diagnostic["labels"].as_array().unwrap().iter().any(|l| l["file"] == "scenes/denoised.toml"),
        "and where the scene names it: {diagnostic}"
    );
    assert_eq!(pass_status(&s, "denoise").as_deref(), Some("ok"), "the last good denoiser still runs");
    // A frame rendered after the break still has every layer.
    let before = frame_of(&s);
    let (status, _) = s.post("/api/reload");
    assert_eq!(status, 202);
    s.wait_for("a frame after the break", LIMIT, || (frame_of(&s) > before).then_some(()));
    assert_eq!(pass_status(&s, "denoise.enc_conv0").as_deref(), Some("ok"));

    p.save_by_rename("weights/rt_ldr_alb_nrm.tza", &weights);
    s.wait_for("the diagnostic to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
    assert_eq!(pass_status(&s, "denoise").as_deref(), Some("ok"));
}

/// Quad statistics while a client asks: a `quads` event per frame, the
/// same report at `GET /api/quads`, and counts that follow an edit to the
/// vertex stage (a fullscreen "triangle" shrunk to the lower-left half of
/// the screen launches fewer quads), gone when the client stops asking.
#[test]
fn quad_statistics_stream_while_asked_and_follow_a_vertex_stage_edit() {
    let p = Project::copy_of_repo("serve-quads");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/pattern.toml"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let not_computed = (204, Some("not-computed".to_owned()));
    assert_eq!(s.get_state("/api/quads"), not_computed, "not computed until asked");
    assert_eq!(s.get_state("/api/quads/tonemap/overdraw.f32"), not_computed);
    let mut ws = s.ws();
    ws.send(serde_json::json!({ "type": "quad_statistics", "on": true }));
    let tonemap_quads =
        |ev: &serde_json::Value| ev["passes"].as_array()?.iter().find(|p| p["pass"] == "tonemap")?["quads"]["quads"].as_u64();
    // pattern.toml is 960×540: one triangle launches 480·270 quads.
    let ev = ws.event("quads", LIMIT, |_| true);
    assert_eq!(tonemap_quads(&ev), Some(480 * 270), "{ev}");
    assert_eq!(tonemap_quads(&s.get_json("/api/quads")), Some(480 * 270));
    let (status, map) = s.get("/api/quads/tonemap/overdraw.f32");
    assert_eq!((status, map.len()), (200, 960 * 540 * 4));
    assert_eq!(s.get_state("/api/quads/nope/overdraw.f32"), (404, None), "not a raster pass of the frame");

    // (-1,-1), (1,-1), (-1,1): the lower-left half of the screen.
    let fullscreen = p.read("shaders/lib/fullscreen.wgsl");
    let half = fullscreen.replace("f32(vertex_index & 2u)) * 2.0 - 1.0", "f32(vertex_index & 2u)) - 1.0");
    assert_ne!(half, fullscreen, "fullscreen.wgsl changed: update this test");
    p.write("shaders/lib/fullscreen.wgsl", half);
    let ev = ws.event("quads", LIMIT, |ev| tonemap_quads(ev).is_some_and(|q| q != 480 * 270));
    let q = tonemap_quads(&ev).unwrap();
    // Half the blocks, plus the ones the diagonal cuts.
    assert!((480 * 270 / 2..480 * 270 / 2 + 480).contains(&q), "{q} quads for half the screen");

    ws.send(serde_json::json!({ "type": "quad_statistics", "on": false }));
    s.wait_for("the statistics to stop", LIMIT, || (s.get_state("/api/quads") == not_computed).then_some(()));
}

/// The per-pixel sample count of each `path_trace/samples` capture that
/// arrives, in order, until `until` returns true. Each is the `samples`
/// of its frame's `frame` event (which arrives before its images).
fn sample_counts(ws: &mut loupe_tests::ws::Ws, mut until: impl FnMut(&[f32]) -> bool) -> Vec<f32> {
    let mut seen = Vec::new();
    let mut announced = std::collections::BTreeMap::new();
    ws.until("path_trace/samples captures", LIMIT, |m| match m {
        Msg::Event(e) if e["type"] == "frame" => {
            announced.insert(e["frame"].as_u64().unwrap(), e["samples"].clone());
            None
        }
        Msg::Image(h, d) if h["kind"] == "capture" && h["pass"] == "path_trace" => {
            let values: Vec<f32> = d.chunks_exact(16).map(|px| f32::from_le_bytes(px[..4].try_into().unwrap())).collect();
            let first = values[0];
            assert!(values.iter().all(|v| *v == first), "every pixel holds the same count: {first}");
            let frame = h["frame"].as_u64().unwrap();
            assert_eq!(announced.get(&frame), Some(&serde_json::json!(first as u32)), "frame {frame}'s event says its samples");
            seen.push(first);
            until(&seen).then_some(())
        }
        _ => None,
    });
    seen
}

/// `serve` accumulates the path tracer one sample a frame up to
/// `quality.path_spp`, on-change mode included, says so in each `frame`
/// event, and starts over on `reset_history` and when a setting or the
/// shader changes.
#[test]
fn the_path_tracer_accumulates_to_its_samples_and_restarts_on_a_change() {
    let p = Project::copy_of_repo("serve-path");
    let scene = p.read("scenes/minimal.toml").replace("width = 640\nheight = 360", "width = 40\nheight = 24");
    p.write("scenes/minimal.toml", format!("{scene}\n[quality]\nrenderer = \"path\"\npath_spp = 6\n"));
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change"]);
    let mut ws = s.ws();
    ws.event("hello", LIMIT, |_| true);
    ws.send(serde_json::json!({ "type": "subscribe", "pass": "path_trace", "output": "samples", "encoding": "f32" }));
    let counts = sample_counts(&mut ws, |c| c.last() == Some(&6.0));
    assert!(counts.windows(2).all(|w| w[1] == w[0] + 1.0), "one sample a frame: {counts:?}");
    // Converged: an on-change server stops rendering.
    let frame = frame_of(&s);
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(frame_of(&s), frame, "no frames once the samples are reached");

    // A history reset: the accumulation starts over from one sample.
    ws.send(serde_json::json!({ "type": "reset_history" }));
    let counts = sample_counts(&mut ws, |c| c.last() == Some(&6.0));
    assert_eq!(counts[0], 1.0, "restarted after the reset: {counts:?}");

    // A setting changes: accumulation starts over.
    ws.send(serde_json::json!({ "type": "set_override", "path": "lights[0].intensity", "value": 20.0 }));
    let counts = sample_counts(&mut ws, |c| c.last() == Some(&6.0));
    assert!(counts[0] < 6.0, "restarted after the override: {counts:?}");

    // The pass's shader changes: its history is forgotten too.
    let shader = p.read("shaders/passes/path_trace.wgsl");
    p.save_by_rename(
        "shaders/passes/path_trace.wgsl",
        shader.replace("const ROULETTE_AFTER: u32 = 3u;", "const ROULETTE_AFTER: u32 = 2u;"),
    );
    let counts = sample_counts(&mut ws, |c| c.len() > 1 && c.last() == Some(&6.0));
    assert!(counts.iter().any(|c| *c < 6.0), "restarted after the edit: {counts:?}");
}

/// A WGSL file whose name is not UTF-8 cannot be watched or named in a
/// URL: the daemon leaves it out, and says so with a warning at the file
/// (it used to leave it out silently).
#[cfg(unix)]
#[test]
fn a_shader_whose_name_is_not_utf8_is_reported_not_ignored() {
    use std::os::unix::ffi::OsStrExt;
    let p = Project::copy_of_repo("serve-latin1-name");
    std::fs::write(p.path("shaders").join(std::ffi::OsStr::from_bytes(b"caf\xe9.wgsl")), "fn f() {}\n").expect("write");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    let d = s.wait_for("the file's warning", LIMIT, || {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array()?.iter().find(|d| d["code"] == "encoding").cloned()
    });
    assert_eq!((d["severity"].as_str(), d["location"]["file"].as_str()), (Some("warning"), Some("shaders/caf\\xE9.wgsl")), "{d}");
    // One saved while serving is reported too, and its warning goes with it.
    let later = p.path("shaders").join(std::ffi::OsStr::from_bytes(b"na\xefve.wgsl"));
    std::fs::write(&later, "fn g() {}\n").expect("write");
    let warned = |file: &str| {
        let d = s.get_json("/api/diagnostics");
        d["diagnostics"].as_array().is_some_and(|all| all.iter().any(|d| d["code"] == "encoding" && d["location"]["file"] == file))
    };
    s.wait_for("the saved file's warning", LIMIT, || warned("shaders/na\\xEFve.wgsl").then_some(()));
    std::fs::remove_file(&later).expect("remove");
    s.wait_for("the warning to go with the file", LIMIT, || (!warned("shaders/na\\xEFve.wgsl")).then_some(()));
}

/// This machine's address on its first network interface (not loopback):
/// where a client on another machine would reach a server bound to
/// 0.0.0.0. Connecting a UDP socket sends nothing; it only picks the
/// interface a route would use.
fn outward_address() -> std::net::IpAddr {
    let socket = std::net::UdpSocket::bind("0.0.0.0:0").expect("a UDP socket");
    socket.connect("10.255.255.255:9").expect("a route off this machine");
    let ip = socket.local_addr().expect("its address").ip();
    assert!(!ip.is_loopback() && !ip.is_unspecified(), "this test needs a network interface besides loopback: {ip}");
    ip
}

#[test]
fn a_broken_edit_shows_its_diff_against_the_last_good_source_and_revert_writes_it_back() {
    let p = Project::copy_of_repo("serve-last-good");
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change", "--bind", "0.0.0.0"]);
    let mut ws = s.ws();
    ws.event("hello", LIMIT, |_| true);
    s.wait_for("every pipeline built", LIMIT, || {
        let pipelines = s.get_json("/api/pipelines");
        let all = pipelines.as_array()?;
        (!all.is_empty() && all.iter().all(|p| p["status"] == "ok")).then_some(())
    });
    assert_eq!(s.get_json("/api/files"), serde_json::json!({ "files": [] }), "every file good");

    // Broken as an editor saves: the diff names the line that changed,
    // marks it failing where the error points, and the stale pass.
    let good = p.read(reload::TONEMAP);
    let bad = reload::broken(&good);
    p.save_by_rename(reload::TONEMAP, &bad);
    let event = ws.event("files", LIMIT, |e| e["files"].as_array().is_some_and(|f| !f.is_empty()));
    let changed_line = good.lines().position(|l| l.contains("let c = max(")).expect("the line broken") + 1;
    let files = event["files"].as_array().expect("files");
    assert_eq!(files.len(), 1, "{event}");
    assert_eq!(files[0]["file"], reload::TONEMAP);
    assert_eq!(files[0]["pipelines"], serde_json::json!(["post.tonemap"]));
    let lines = files[0]["hunks"][0]["lines"].as_array().expect("one hunk");
    let changes: Vec<(&str, &serde_json::Value, &serde_json::Value, &str, bool)> = lines
        .iter()
        .filter(|l| l["tag"] != " ")
        .map(|l| (l["tag"].as_str().unwrap(), &l["old"], &l["new"], l["text"].as_str().unwrap(), l["failing"] == true))
        .collect();
    let text = |t: &str| t.lines().nth(changed_line - 1).expect("the line").to_owned();
    assert_eq!(
        changes,
        [
            ("-", &serde_json::json!(changed_line), &serde_json::Value::Null, text(&good).as_str(), false),
            ("+", &serde_json::Value::Null, &serde_json::json!(changed_line), text(&bad).as_str(), true),
        ]
    );
    assert!(lines.iter().filter(|l| l["tag"] == " ").count() >= 3, "context around the change");
    assert_eq!(s.get_json("/api/files"), serde_json::json!({ "files": files }), "the API holds what the event said");

    // From another machine, refused, whatever its Host says.
    let port: u16 = s.addr.rsplit_once(':').expect("host:port").1.parse().expect("a port");
    let outside = std::net::SocketAddr::new(outward_address(), port);
    let request = serde_json::json!({ "file": reload::TONEMAP });
    let (status, body) = s.post_json("/api/files/revert", &request, Some(outside));
    assert_eq!(status, 403, "{}", String::from_utf8_lossy(&body));
    assert_eq!(p.read(reload::TONEMAP), bad, "nothing written");
    // Bad requests.
    assert_eq!(s.post_json("/api/files/revert", &serde_json::json!({ "path": reload::TONEMAP }), None).0, 400);
    assert_eq!(s.post_json("/api/files/revert", &serde_json::json!({ "file": "shaders/lib/color.wgsl" }), None).0, 404);

    // Reverted: the last good text is back, and so is the pass.
    let (status, body) = s.post_json("/api/files/revert", &request, None);
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    assert_eq!(p.read(reload::TONEMAP), good);
    ws.event("files", LIMIT, |e| e["files"].as_array().is_some_and(|f| f.is_empty()));
    let passes = s.get_json("/api/passes");
    let tonemap = passes.as_array().expect("passes").iter().find(|p| p["name"] == "tonemap").expect("tonemap").clone();
    assert_eq!(tonemap["status"], "ok");
}

/// Waits for a finished comparison whose one case has `verdict`; returns
/// its report. (Comparisons of older sources may come first: one asked
/// for when the client asked, one after the first reload.)
fn compared(ws: &mut loupe_tests::ws::Ws, verdict: &str) -> serde_json::Value {
    ws.event("references", LIMIT, |e| e["comparing"] == false && e["cases"][0]["verdict"] == verdict)
}

/// The inspector's "against reference": while a client asks, the daemon
/// compares the scene's image cases with their references after every
/// reload, as `loupe check` would, and a loopback client may bless them.
#[test]
fn the_image_cases_of_the_scene_are_compared_live_and_blessed_from_the_page() {
    let p = Project::copy_of_repo("serve-references");
    p.write("loupe.toml", "[[images]]\nname = \"pattern\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\n");
    let s = Server::start(&p.root, &["--scene", "scenes/pattern.toml", "--render", "on-change", "--bind", "0.0.0.0"]);
    let mut ws = s.ws();
    ws.event("hello", LIMIT, |_| true);
    let idle = s.get_json("/api/references");
    assert_eq!(
        (idle["generation"].as_u64(), idle["cases"].as_array().map(Vec::len)),
        (Some(0), Some(0)),
        "nothing compared unasked: {idle}"
    );

    // Asked: no reference yet, so the case fails, and its image shows.
    ws.send(serde_json::json!({ "type": "reference_comparison", "on": true }));
    let first = compared(&mut ws, "failed");
    let case = &first["cases"][0];
    assert_eq!((case["name"].as_str(), case["verdict"].as_str()), (Some("pattern"), Some("failed")), "{first}");
    assert_eq!(case["diagnostics"][0]["code"], "reference-missing", "{first}");
    assert_eq!(case["outputs"][0]["output"], "tonemap/color");
    let (status, png) = s.get("/api/references/pattern/0/actual.png");
    assert_eq!((status, &png[1..4]), (200, b"PNG".as_slice()));
    assert_eq!(s.get("/api/references/pattern/0/reference.png").0, 404, "no reference to show");

    // Blessed from another machine: refused. From this one: written, and
    // the comparison that follows passes exactly.
    let port: u16 = s.addr.rsplit_once(':').expect("host:port").1.parse().expect("a port");
    let outside = std::net::SocketAddr::new(outward_address(), port);
    let (status, _) = s.post_json("/api/references/pattern/bless", &serde_json::json!({}), Some(outside));
    assert_eq!(status, 403);
    assert!(!p.path("tests/images/pattern").exists(), "nothing written");
    let (status, body) = s.post("/api/references/pattern/bless");
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    assert!(p.path("tests/images/pattern/tonemap.color.png").is_file());
    let blessed = compared(&mut ws, "passed");
    assert_eq!(blessed["cases"][0]["verdict"], "passed", "{blessed}");
    assert_eq!(blessed["cases"][0]["outputs"][0]["flip"]["mean"], 0.0);

    // A deliberate change to the tonemapper, saved as an editor saves: the
    // next comparison fails the case, with FLIP's map to look at.
    let tonemap = p.read(reload::TONEMAP);
    let input = "let c = max(texel.rgb, vec3(0.0));";
    assert!(tonemap.contains(input));
    p.save_by_rename(reload::TONEMAP, tonemap.replace(input, "let c = max(texel.rgb * 1.5, vec3(0.0));"));
    let changed = compared(&mut ws, "failed");
    let case = &changed["cases"][0];
    assert_eq!((case["verdict"].as_str(), case["diagnostics"][0]["code"].as_str()), (Some("failed"), Some("image-mismatch")), "{changed}");
    assert!(case["outputs"][0]["flip"]["mean"].as_f64().unwrap() > 0.01, "{changed}");
    let (status, png) = s.get("/api/references/pattern/0/flip.png");
    assert_eq!((status, &png[1..4]), (200, b"PNG".as_slice()));
}
