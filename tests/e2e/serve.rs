//! `loupe serve`: hot reload with real editor save patterns, keep-last-good,
//! the HTTP API.

use std::time::Duration;

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
    let p = Project::copy_of_repo("serve-deps");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let gens = |s: &Server| -> Vec<(String, u64)> {
        s.get_json("/api/pipelines").as_array().unwrap().iter().map(|p| (p["name"].as_str().unwrap().to_owned(), p["generation"].as_u64().unwrap())).collect()
    };
    let before = gens(&s);
    // color.wgsl is imported by tonemap (tonemap_aces) and the test pattern
    // (srgb_to_linear): change a comment-free detail in tonemap_reinhard
    // only used by tonemap, but both import the module, so both rebuild.
    let color = p.read("shaders/lib/color.wgsl").replace("return c / (1.0 + l);", "return c / (1.0 + l + 0.0);");
    p.write("shaders/lib/color.wgsl", color);
    s.wait_for("both importers to rebuild", LIMIT, || {
        let after = gens(&s);
        after.iter().zip(&before).all(|(a, b)| a.1 > b.1).then_some(())
    });
    // fullscreen.wgsl is imported by both too; a file nobody imports
    // rebuilds nothing.
    let before = gens(&s);
    p.write("shaders/lib/unused.wgsl", "#define_import_path demo::unused\nfn nothing() {}\n");
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(gens(&s), before, "an unrelated file rebuilt nothing");
}

#[test]
fn api_shapes() {
    let p = Project::copy_of_repo("serve-api");
    let s = Server::start(&p.root, &["--render", "on-change"]);
    s.wait_for("a first frame", LIMIT, || (frame_of(&s) > 0).then_some(()));
    let st = s.get_json("/api/status");
    assert_eq!(st["protocol"], 1);
    assert!(st["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    let passes = s.get_json("/api/passes");
    let names: Vec<&str> = passes.as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert!(names.contains(&"tonemap"), "{passes}");
    let tm = passes.as_array().unwrap().iter().find(|p| p["name"] == "tonemap").unwrap();
    assert!(tm["time_ms"].as_f64().is_some(), "{tm}");
    let (code, raw) = s.get("/api/captures/tonemap/color.f32");
    assert_eq!(code, 200);
    let w = st["frame"].as_u64().map(|_| 960usize).unwrap();
    assert_eq!(raw.len(), w * 540 * 4 * 4, "RGBA f32 of the scene's size");
    // Real pixels: the test pattern's colour bars reach the final image
    // opaque (an invalid frame would read back as all zeros).
    let px = |i: usize| f32::from_le_bytes(raw[i * 4..i * 4 + 4].try_into().unwrap());
    let row = 270 * 960 * 4; // middle row: colour bars
    let last_bar = row + 959 * 4; // white bar, 0.75 before tonemapping
    assert_eq!(px(row + 3), 1.0, "alpha of the final image");
    assert!(px(last_bar) > 0.3 && px(last_bar + 1) > 0.3 && px(last_bar + 2) > 0.3, "white bar is lit: {:?}", (px(last_bar), px(last_bar + 1)));
    let (code, _) = s.get("/api/captures/nope/color.png");
    assert_eq!(code, 404);
}
