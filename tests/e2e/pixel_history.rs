//! Pixel history (docs/pixel-history.md) through `loupe render
//! --debug-pixel`: the draws that covered a pixel with their depth
//! verdicts, and the values before and after each pass, checked against
//! the frame's own captures.

use loupe_tests::{Project, exr_rgba};
use serde_json::Value;

/// Renders `scene` at `size` with `pixel` selected: the report's history.
fn history(p: &Project, scene: &str, size: &str, pixel: [u32; 2]) -> Value {
    let at = format!("{},{}", pixel[0], pixel[1]);
    let run = p.run(&["render", "--scene", scene, "--out", "out", "--size", size, "--debug-pixel", &at]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let report: Value = serde_json::from_str(&p.read("out/report.json")).expect("report.json is JSON");
    let h = report["history"].clone();
    assert_eq!(h["pixel"], serde_json::json!(pixel), "{h}");
    h
}

fn pass<'a>(h: &'a Value, name: &str) -> &'a Value {
    h["passes"].as_array().expect("passes").iter().find(|p| p["pass"] == name).unwrap_or_else(|| panic!("no `{name}` in {h}"))
}

/// (draw, primitive, verdict, helper) of every fragment of a raster pass.
fn fragments(pass: &Value) -> Vec<(String, u64, String, bool)> {
    let draws = pass["draws"].as_array().unwrap_or_else(|| panic!("a raster pass lists its draws: {pass}"));
    draws
        .iter()
        .flat_map(|d| {
            d["fragments"].as_array().expect("fragments").iter().map(move |f| {
                (
                    d["name"].as_str().expect("name").to_owned(),
                    f["primitive"].as_u64().expect("primitive"),
                    f["verdict"].as_str().expect("verdict").to_owned(),
                    f["helper"].as_bool().expect("helper"),
                )
            })
        })
        .collect()
}

fn rgba(v: &Value) -> [f32; 4] {
    let a = v.as_array().unwrap_or_else(|| panic!("an RGBA value: {v}"));
    [0, 1, 2, 3].map(|i| a[i].as_f64().expect("a finite number") as f32)
}

/// On the showcase, a pixel of the knot with the floor behind it: the
/// depth prepass and the G-buffer list both draws there, floor first (the
/// scene's order); in the G-buffer, which tests against the prepass's
/// depth, the floor's fragment fails and the knot's nearest passes. The
/// depth the prepass left there (read from the GPU) is the depth the model
/// gives its last passing fragment. The tonemap, a fullscreen pass, shows
/// one fragment.
#[test]
fn a_pixel_of_the_knot_lists_the_floor_failing_depth_and_the_knot_passing() {
    let p = Project::copy_of_repo("history-knot");
    let h = history(&p, "scenes/showcase.toml", "160x90", KNOT_OVER_FLOOR);
    let gbuffer = fragments(pass(&h, "gbuffer"));
    let named = |name: &str| gbuffer.iter().filter(|f| f.0 == name).collect::<Vec<_>>();
    let (floor, knot) = (named("floor"), named("knot"));
    assert!(!floor.is_empty() && !knot.is_empty(), "the premise: the knot covers the floor at {KNOT_OVER_FLOOR:?}: {gbuffer:?}");
    assert!(floor.iter().all(|f| f.2 == "failed_depth"), "the floor is behind the knot: {gbuffer:?}");
    assert!(knot.iter().any(|f| f.2 == "passed"), "the knot's nearest fragment passes: {gbuffer:?}");
    let order: Vec<&str> = gbuffer.iter().map(|f| f.0.as_str()).collect();
    let first_knot = order.iter().position(|n| *n == "knot").expect("knot");
    assert!(order.iter().position(|n| *n == "floor").expect("floor") < first_knot, "in submission order: {order:?}");

    let prepass = pass(&h, "depth_prepass");
    let last_passed = prepass["draws"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|d| d["fragments"].as_array().unwrap())
        .rfind(|f| f["verdict"] == "passed")
        .expect("a fragment passed");
    let model = last_passed["depth"].as_f64().expect("a tested depth");
    let gpu = rgba(&prepass["outputs"][0]["after"])[0] as f64;
    assert_eq!(prepass["outputs"][0]["output"], "depth_prepass/depth");
    assert!((model - gpu).abs() < 1e-6, "the model's depth {model} is the GPU's {gpu}");

    // The G-buffer kept the knot's passing fragment.
    let kept = knot.iter().rfind(|f| f.2 == "passed" && !f.3).expect("passed");
    assert_eq!(pass(&h, "gbuffer")["survivor"], serde_json::json!({ "draw": "knot", "primitive": kept.1 }));

    let tonemap = fragments(pass(&h, "tonemap"));
    assert_eq!(tonemap.len(), 1, "one triangle covers the screen: {tonemap:?}");
    assert_eq!(pass(&h, "tonemap")["survivor"], serde_json::json!({ "draw": "fullscreen triangle", "primitive": 0 }));
    assert_eq!((tonemap[0].1, tonemap[0].2.as_str(), tonemap[0].3), (0, "not_tested", false));
}

/// Every value the history states is the frame's: each output's `after`
/// equals its capture at the texel when no later pass writes it, and
/// equals the next writer's `before` when one does.
#[test]
fn the_values_before_and_after_each_pass_are_the_captures() {
    let p = Project::copy_of_repo("history-values");
    let h = history(&p, "scenes/showcase.toml", "160x90", KNOT_OVER_FLOOR);
    let passes = h["passes"].as_array().expect("passes");
    let mut compared = 0;
    for (i, pass) in passes.iter().enumerate() {
        for o in pass["outputs"].as_array().expect("outputs") {
            let name = o["output"].as_str().expect("output");
            let after = rgba(&o["after"]);
            let next = passes[i + 1..].iter().flat_map(|p| p["outputs"].as_array().expect("outputs")).find(|n| n["output"] == name);
            match next {
                Some(n) => {
                    assert_eq!(n["origin"], "read", "{name} was written before: {n}");
                    assert_eq!(rgba(&n["before"]), after, "{name}: what the next writer read");
                }
                None => {
                    let (owner, output) = name.split_once('/').expect("pass/output");
                    let image = exr_rgba(&p.path(&format!("out/{owner}.{output}.exr")));
                    let [x, y, _] = [0, 1, 2].map(|k| o["texel"][k].as_u64().expect("texel") as usize);
                    let width = pass_width(&p, owner, output);
                    assert_eq!(after, image[y * width + x], "{name} at ({x}, {y})");
                }
            }
            compared += 1;
        }
    }
    assert!(compared >= 8, "the showcase writes many images at a pixel: {h}");
    let gbuffer = pass(&h, "gbuffer");
    let normal = gbuffer["outputs"].as_array().unwrap().iter().find(|o| o["output"] == "gbuffer/normal").expect("the G-buffer's normal");
    assert_eq!((normal["origin"].as_str(), &normal["before"]), (Some("cleared"), &Value::Null), "a colour target is cleared");
}

/// The width of `pass/output` as report.json states it.
fn pass_width(p: &Project, pass: &str, output: &str) -> usize {
    let report: Value = serde_json::from_str(&p.read("out/report.json")).expect("JSON");
    let passes = report["passes"].as_array().expect("passes");
    let outputs = passes.iter().find(|q| q["name"] == pass).and_then(|q| q["outputs"].as_array()).expect("outputs");
    outputs.iter().find(|o| o["name"] == output).and_then(|o| o["width"].as_u64()).expect("width") as usize
}

/// A pixel of the showcase at 160×90 where the knot is in front of the floor.
const KNOT_OVER_FLOOR: [u32; 2] = [80, 44];

/// The path tracer's accumulation and each of the denoiser's tensors at
/// the pixel: every channel at the element under the pixel (a U-Net level
/// halves the image) is the captured tensor's, and the path tracer and the
/// denoiser's ends name the invocation that wrote the pixel.
#[test]
fn the_tensors_at_the_pixel_are_the_captured_tensors() {
    let p = Project::copy_of_repo("history-tensors");
    let pixel = [33, 18];
    let at = format!("{},{}", pixel[0], pixel[1]);
    let run = p.run(&[
        "render",
        "--scene",
        "scenes/showcase.toml",
        "--out",
        "out",
        "--size",
        "64x36",
        "--renderer",
        "path",
        "--spp",
        "1",
        "--debug-pixel",
        &at,
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let report: Value = serde_json::from_str(&p.read("out/report.json")).expect("JSON");
    let h = &report["history"];
    let mut levels = std::collections::BTreeSet::new();
    for pass in h["passes"].as_array().expect("passes") {
        for t in pass["tensors"].as_array().expect("tensors") {
            let name = t["output"].as_str().expect("output");
            let (owner, output) = name.split_once('/').expect("pass/output");
            let (shape, data) = npy_f32(&p.path(&format!("out/{owner}.{output}.npy")));
            let channels: Vec<f32> =
                t["channels"].as_array().expect("channels").iter().map(|v| v.as_f64().expect("finite") as f32).collect();
            let c = *shape.last().expect("channels last");
            assert_eq!(channels.len(), c, "{name}: every channel");
            let element = match shape.as_slice() {
                [_, w, _] => {
                    let (x, y) = (t["at"][0].as_u64().unwrap() as usize, t["at"][1].as_u64().unwrap() as usize);
                    levels.insert(pixel[0] as usize / x.max(1));
                    y * w + x
                }
                [_, _] => pixel[1] as usize * 64 + pixel[0] as usize,
                other => panic!("{name}: an unexpected shape {other:?}"),
            };
            assert_eq!(channels, data[element * c..(element + 1) * c], "{name} at {}", t["at"]);
        }
    }
    assert!(levels.len() >= 4, "the U-Net's levels each have their element: {levels:?}");
    for name in ["path_trace", "denoise_input", "denoise"] {
        assert_eq!(pass(h, name)["invocation"], serde_json::json!([pixel[0], pixel[1], 0]), "{name}");
    }
    assert!(pass(h, "path_trace")["tensors"].as_array().unwrap().iter().any(|t| t["output"] == "path_trace/accumulated"));
}

/// A `.npy` of little-endian f32 (as `loupe render` writes them): its shape
/// and data.
fn npy_f32(path: &std::path::Path) -> (Vec<usize>, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..6], b"\x93NUMPY", "{}", path.display());
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).expect("an ASCII header");
    assert!(header.contains("'<f4'"), "{header}");
    let shape = header.split("'shape': (").nth(1).and_then(|s| s.split(')').next()).expect("a shape");
    let shape: Vec<usize> = shape.split(',').filter_map(|d| d.trim().parse().ok()).collect();
    let data = bytes[10 + header_len..].chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    (shape, data)
}
