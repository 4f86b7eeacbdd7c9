//! `loupe render`: the full frame without a server, its pass list, the
//! outputs it writes and the NaN report.

use loupe_tests::{Project, Run};
use serde_json::Value;

/// Renders `scene` (relative to the project) small, into `<project>/out`.
fn render(p: &Project, scene: &str, extra: &[&str]) -> (Run, Option<Value>) {
    let mut args = vec!["render", "--scene", scene, "--out", "out", "--size", "96x54"];
    args.extend_from_slice(extra);
    let run = p.run(&args);
    let report = std::fs::read_to_string(p.path("out/report.json")).ok().map(|t| serde_json::from_str(&t).expect("report.json is JSON"));
    (run, report)
}

fn names(list: &Value) -> Vec<&str> {
    list.as_array().expect("array").iter().map(|p| p["name"].as_str().expect("name")).collect()
}

fn culled_reason<'a>(report: &'a Value, pass: &str) -> &'a str {
    report["culled"].as_array().unwrap().iter().find(|c| c["name"] == pass).unwrap_or_else(|| panic!("{pass} is not culled: {report}"))["reason"]
        .as_str()
        .unwrap()
}

#[test]
fn minimal_scene_builds_only_what_it_needs() {
    let p = Project::copy_of_repo("render-minimal");
    let (run, report) = render(&p, "scenes/minimal.toml", &[]);
    run.code(0);
    let r = report.expect("report.json written");
    assert_eq!(names(&r["passes"]), ["shadows", "depth_prepass", "gbuffer", "lighting", "tonemap"], "{r}");
    assert!(culled_reason(&r, "volumes").contains("no participating media"));
    assert!(culled_reason(&r, "ltc_tables").contains("no rectangular area light"));
    assert!(culled_reason(&r, "exposure").contains("0"));
    assert!(culled_reason(&r, "debug_view").contains("none"));
    assert!(culled_reason(&r, "test_pattern").contains("content"));
    // Feature permutations follow the scene: no area light, no media.
    let lighting = &r["passes"].as_array().unwrap()[3];
    assert_eq!(lighting["pipelines"], serde_json::json!(["lighting.deferred[SHADOWS]"]), "{lighting}");
    assert!(r["nan"].is_null(), "{r}");
    // Every output written both ways, at the requested size.
    for pass in r["passes"].as_array().unwrap() {
        for o in pass["outputs"].as_array().unwrap() {
            for key in ["png", "exr"] {
                let f = p.path(&format!("out/{}", o[key].as_str().unwrap()));
                assert!(f.is_file(), "{} missing", f.display());
            }
        }
    }
    let tonemap = &r["passes"].as_array().unwrap()[4]["outputs"][0];
    assert_eq!((tonemap["width"].as_u64(), tonemap["height"].as_u64()), (Some(96), Some(54)));
    // The lit knot reaches the final image: some pixel is clearly brighter
    // than the sky's darkest blue.
    let img = image::open(p.path("out/tonemap.color.png")).unwrap().to_rgb8();
    assert!(img.pixels().any(|px| px.0[0] > 120), "nothing lit in the final frame");
}

#[test]
fn showcase_renders_every_pass() {
    let p = Project::copy_of_repo("render-showcase");
    // With the debug view on, no pass of the renderer is culled but the
    // test pattern (the scene has content).
    let (run, report) = render(&p, "scenes/showcase.toml", &["--set", "post.debug_view=normal"]);
    run.code(0);
    let r = report.expect("report.json written");
    assert_eq!(
        names(&r["passes"]),
        ["shadows", "depth_prepass", "gbuffer", "ltc_tables", "lighting", "volumes", "exposure_histogram", "exposure_adapt", "exposure", "tonemap", "debug_view"],
        "{r}"
    );
    assert_eq!(names(&r["culled"]), ["test_pattern"]);
    // Auto exposure: compute passes whose buffers are written as tensors.
    let pass = |name: &str| r["passes"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap().clone();
    assert_eq!(pass("exposure_histogram")["kind"], "compute");
    assert_eq!(pass("exposure")["pipelines"], serde_json::json!(["post.exposure[AUTO_EXPOSURE]"]));
    let histogram = &pass("exposure_histogram")["outputs"][0];
    assert_eq!(histogram["layout"]["dims"], serde_json::json!([["bin", 256]]), "{histogram}");
    let bins = npy_f32(&p.path(&format!("out/{}", histogram["npy"].as_str().unwrap())));
    assert_eq!(bins.len(), 256);
    assert_eq!(bins.iter().sum::<f32>(), 96.0 * 54.0, "every pixel metered once");
    let state = &pass("exposure_adapt")["outputs"][0];
    let ev = npy_f32(&p.path(&format!("out/{}", state["npy"].as_str().unwrap())));
    assert!(ev[0].is_finite() && ev[0] == ev[1] && ev[3] == 1.0, "the first frame starts at its target: {ev:?}");
    let pipelines: Vec<&str> = r["passes"].as_array().unwrap().iter().flat_map(|p| p["pipelines"].as_array().unwrap()).map(|v| v.as_str().unwrap()).collect();
    assert!(pipelines.contains(&"lighting.deferred[LIGHT_RECT,MEDIA_SHADOWS,SHADOWS]"), "{pipelines:?}");
    assert!(pipelines.contains(&"volumes.raymarch[SHADOWS,VOLUME_ANALYTIC]"), "{pipelines:?}");
    assert!(r["nan"].is_null() && r["gpu_errors"].as_array().unwrap().is_empty(), "{r}");
    // The medium attenuates some pixels: transmittance below 1 somewhere.
    let volumes = r["passes"].as_array().unwrap().iter().find(|p| p["name"] == "volumes").unwrap();
    let t = volumes["outputs"].as_array().unwrap().iter().find(|o| o["name"] == "transmittance").unwrap();
    assert!(t["stats"]["min"][0].as_f64().unwrap() < 0.9, "{t}");
    // Four point-light cube faces + directional + spot: 8 shadow layers.
    let shadows = &r["passes"].as_array().unwrap()[0]["outputs"][0];
    assert_eq!(shadows["height"].as_u64(), Some(1024 * 8), "layers stack vertically: {shadows}");
}

/// The values of a little-endian f32 `.npy` file, read by its header.
fn npy_f32(path: &std::path::Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00", "npy magic and version 1.0");
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(header.contains("'descr': '<f4'"), "{header}");
    assert_eq!((10 + header_len) % 64, 0, "data is aligned");
    bytes[10 + header_len..].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect()
}

#[test]
fn nan_report_names_the_pass_that_divides_by_zero() {
    let p = Project::copy_of_repo("render-nan");
    // `view.params.w` is always 0: a division by it is a runtime divide by
    // zero naga cannot fold away.
    let lighting = p.read("shaders/passes/lighting.wgsl");
    let broken = lighting.replace("    return vec4(color, 1.0);\n}", "    return vec4(color / view.params.w, 1.0);\n}");
    assert_ne!(broken, lighting, "the edit applies");
    p.write("shaders/passes/lighting.wgsl", broken);
    let (run, report) = render(&p, "scenes/minimal.toml", &[]);
    run.code(1).stderr_has("NaN/Inf first made by pass `lighting`");
    let nan = &report.expect("report.json written")["nan"];
    assert_eq!(nan["pass"], "lighting", "{nan}");
    assert_eq!(nan["output"], "color");
    assert_eq!(nan["inputs_checked"], true);
    let [x, y] = [nan["pixel"][0].as_u64().unwrap(), nan["pixel"][1].as_u64().unwrap()];
    assert!(x < 96 && y < 54, "{nan}");
    assert!(nan["nan"].as_u64().unwrap() + nan["inf"].as_u64().unwrap() > 0);
}

#[test]
fn bad_scenes_are_diagnosed_at_their_line() {
    let p = Project::copy_of_repo("render-bad-scene");
    p.write("scenes/bad.toml", "[output]\nwidth = 16384\nheight = 16384\n");
    // --size replaces the scene's size only once the file is valid.
    let (run, _) = render(&p, "scenes/bad.toml", &[]);
    run.code(1).stderr_has("scenes/bad.toml:2:9").stderr_has("8192");
    p.write("scenes/bad.toml", "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"meshes/gone.gltf\"\nmaterial = \"m\"\n");
    let (run, _) = render(&p, "scenes/bad.toml", &[]);
    run.code(1).stderr_has("scenes/bad.toml:4:8").stderr_has("does not exist");
    let run = p.run(&["render", "--scene", "scenes/minimal.toml", "--out", "out", "--size", "0x10"]);
    run.code(2).stderr_has("outside");
}

#[test]
fn render_and_bench_read_the_scene_under_root_as_serve_does() {
    let p = Project::copy_of_repo("render-root");
    let elsewhere = Project::empty("render-root-cwd");
    let root = p.root.to_str().unwrap();
    let out = elsewhere.path("out");
    let run = loupe_tests::loupe(&elsewhere.root, &["render", "--root", root, "--scene", "scenes/pattern.toml", "--size", "32x18", "--out", out.to_str().unwrap()]);
    run.code(0);
    assert!(out.join("report.json").is_file());
    let run = loupe_tests::loupe(&elsewhere.root, &["bench", "--root", root, "--size", "32x18", "--frames", "1", "scenes/pattern.toml"]);
    run.code(0).stdout_has("scenes/pattern.toml");
}
