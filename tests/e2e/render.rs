//! `loupe render`: the full frame without a server, its pass list, the
//! outputs it writes and the NaN report.

use loupe_tests::{Project, Run};
use serde_json::Value;

/// Renders `scene` (relative to the project) small, into `<project>/out`.
fn render(p: &Project, scene: &str, extra: &[&str]) -> (Run, Option<Value>) {
    render_at(p, scene, "96x54", extra)
}

/// Renders `scene` at `size` (WIDTHxHEIGHT) into `<project>/out`.
fn render_at(p: &Project, scene: &str, size: &str, extra: &[&str]) -> (Run, Option<Value>) {
    let mut args = vec!["render", "--scene", scene, "--out", "out", "--size", size];
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
    assert_eq!(names(&r["passes"]), ["shadows", "depth_prepass", "gbuffer", "classify", "lighting", "lighting_simple", "tonemap"], "{r}");
    assert!(culled_reason(&r, "volumes").contains("no participating media"));
    assert!(culled_reason(&r, "volume_shadows").contains("no participating media"));
    assert!(culled_reason(&r, "volume_march").contains("no participating media"));
    assert!(culled_reason(&r, "ltc_tables").contains("no rectangular area light"));
    assert!(culled_reason(&r, "exposure").contains("0"));
    assert!(culled_reason(&r, "debug_view").contains("none"));
    assert!(culled_reason(&r, "test_pattern").contains("content"));
    // Feature permutations follow the scene: no area light, no media; the
    // shorthand's tiles are simple (and the sky's empty).
    let lighting = &r["passes"].as_array().unwrap()[5];
    assert_eq!(lighting["pipelines"], serde_json::json!(["lighting.deferred[SHADOWS,SIMPLE_CLASS]"]), "{lighting}");
    assert!(r["nan"].is_null(), "{r}");
    // Every texture written both ways, at the requested size (the classify
    // pass's buffers are `.npy`).
    for pass in r["passes"].as_array().unwrap() {
        for o in pass["outputs"].as_array().unwrap().iter().filter(|o| o.get("png").is_some()) {
            for key in ["png", "exr"] {
                let f = p.path(&format!("out/{}", o[key].as_str().unwrap()));
                assert!(f.is_file(), "{} missing", f.display());
            }
        }
    }
    let tonemap = &r["passes"].as_array().unwrap()[6]["outputs"][0];
    assert_eq!((tonemap["width"].as_u64(), tonemap["height"].as_u64()), (Some(96), Some(54)));
    // The lit knot reaches the final image: some pixel is clearly brighter
    // than the sky's darkest blue.
    let img = image::open(p.path("out/tonemap.color.png")).unwrap().to_rgb8();
    assert!(img.pixels().any(|px| px.0[0] > 120), "nothing lit in the final frame");
}

#[test]
fn showcase_renders_every_pass() {
    let p = Project::copy_of_repo("render-showcase");
    // With the debug view on, no raster pass is culled: only the test
    // pattern (the scene has content) and the path tracer (the renderer is
    // the raster).
    let (run, report) = render(&p, "scenes/showcase.toml", &["--set", "post.debug_view=normal"]);
    run.code(0);
    let r = report.expect("report.json written");
    assert_eq!(
        names(&r["passes"]),
        [
            "shadows",
            "depth_prepass",
            "gbuffer",
            "classify",
            "ltc_tables",
            "lighting",
            "lighting_simple",
            "lighting_single",
            "lighting_complex",
            "volume_shadows",
            "volume_march",
            "volumes",
            "exposure_histogram",
            "exposure_adapt",
            "exposure",
            "tonemap",
            "debug_view"
        ],
        "{r}"
    );
    assert_eq!(names(&r["culled"]), ["path_trace", "denoise_autoexposure", "denoise_input", "denoise", "test_pattern"]);
    // Tile classification's counts: every pixel and tile in one class, and
    // the material bytes of the pixels with geometry.
    let tiles = &r["tiles"];
    let sum =
        |counts: &serde_json::Value| ["empty", "simple", "single", "complex"].iter().map(|c| counts[*c].as_u64().unwrap()).sum::<u64>();
    let (w, h) = (r["width"].as_u64().unwrap(), r["height"].as_u64().unwrap());
    assert_eq!(sum(&tiles["pixels"]), w * h, "{tiles}");
    assert_eq!(sum(&tiles["tiles"]), w.div_ceil(8) * h.div_ceil(8), "{tiles}");
    assert!(tiles["tiles"]["complex"].as_u64().unwrap() > 0, "the car paint's tiles: {tiles}");
    let geometry = sum(&tiles["pixels"]) - tiles["pixels"]["empty"].as_u64().unwrap();
    assert!(tiles["material_bytes_written"].as_u64().unwrap() >= geometry * 16, "{tiles}");
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
    let pipelines: Vec<&str> =
        r["passes"].as_array().unwrap().iter().flat_map(|p| p["pipelines"].as_array().unwrap()).map(|v| v.as_str().unwrap()).collect();
    assert!(pipelines.contains(&"lighting.deferred[LIGHT_RECT,MEDIA_SHADOWS,SHADOWS]"), "{pipelines:?}");
    assert!(pipelines.contains(&"volume_march[SHADOWS,VOLUME_ANALYTIC]"), "{pipelines:?}");
    assert!(r["nan"].is_null() && r["gpu_errors"].as_array().unwrap().is_empty(), "{r}");
    // The medium attenuates some pixels: transmittance below 1 somewhere.
    let volumes = r["passes"].as_array().unwrap().iter().find(|p| p["name"] == "volumes").unwrap();
    let t = volumes["outputs"].as_array().unwrap().iter().find(|o| o["name"] == "transmittance").unwrap();
    assert!(t["stats"]["min"][0].as_f64().unwrap() < 0.9, "{t}");
    // Every march ran every step: alpha counts them (1 unless the driver
    // cut a loop short), in the pixels and in the volume grid.
    assert_eq!(t["stats"]["min"][3].as_f64(), Some(1.0), "{t}");
    let grid = &pass("volume_shadows")["outputs"][0];
    assert_eq!(grid["layout"]["dims"][0], serde_json::json!(["light", 4]), "{grid}");
    assert_eq!(grid["stats"]["min"][3].as_f64(), Some(1.0), "{grid}");
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
    // `view.environment_top.w` is always 0 (unused): a division by it is a runtime divide by
    // zero naga cannot fold away.
    let lighting = p.read("shaders/passes/lighting.wgsl");
    let broken = lighting.replace("    return color;\n}", "    return color / view.environment_top.w;\n}");
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
    let run = loupe_tests::loupe(
        &elsewhere.root,
        &["render", "--root", root, "--scene", "scenes/pattern.toml", "--size", "32x18", "--out", out.to_str().unwrap()],
    );
    run.code(0);
    assert!(out.join("report.json").is_file());
    let run = loupe_tests::loupe(&elsewhere.root, &["bench", "--root", root, "--size", "32x18", "--frames", "1", "scenes/pattern.toml"]);
    run.code(0).stdout_has("scenes/pattern.toml");
}

fn pass<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["passes"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap_or_else(|| panic!("no pass {name}: {report}"))
}

/// Quad statistics of fullscreen passes, against counts derived by hand.
/// One triangle covers every pixel of a W×H target: ⌈W/2⌉·⌈H/2⌉ quads,
/// and the lanes past an odd edge are the only helpers. Two triangles
/// sharing the diagonal of a 512×512 target both touch each of the 256
/// 2×2 blocks the diagonal crosses: 256 more quads, each launched twice
/// for its four pixels, so 4 helper lanes apiece (1,024).
#[test]
fn fullscreen_passes_report_quads_in_either_mode_and_the_other_as_what_if() {
    let p = Project::copy_of_repo("render-quads-fullscreen");
    let cases = [
        // size, two triangles, (quads, helpers), what_if (quads, helpers)
        ("512x512", false, (65_536, 0), (65_792, 1_024)),
        ("512x512", true, (65_792, 1_024), (65_536, 0)),
        // 333×211: 167·106 quads; 4·17,702 − 333·211 = 545 helper lanes.
        ("333x211", false, (17_702, 545), two_triangles(333, 211)),
    ];
    for (size, two, (quads, helpers), (what_quads, what_helpers)) in cases {
        let set = format!("post.two_triangles={two}");
        let (run, report) = render_at(&p, "scenes/pattern.toml", size, &["--set", &set]);
        run.code(0);
        let r = report.expect("report.json written");
        let (w, h): (u64, u64) = size.split_once('x').map(|(w, h)| (w.parse().unwrap(), h.parse().unwrap())).unwrap();
        for name in ["test_pattern", "tonemap"] {
            let pass = pass(&r, name);
            let what = format!("{name} at {size}, two triangles {two}: {pass}");
            let total = &pass["quads"];
            assert_eq!((total["quads"].as_u64(), total["helper_lanes"].as_u64()), (Some(quads), Some(helpers)), "{what}");
            assert_eq!(total["pixels"].as_u64(), Some(w * h), "{what}");
            assert_eq!(total["triangles"].as_u64(), Some(if two { 2 } else { 1 }), "{what}");
            let draws = pass["draws"].as_array().unwrap();
            assert_eq!(draws.len(), 1, "{what}");
            assert_eq!(draws[0]["quads"], total["quads"], "{what}");
            let what_if = &pass["what_if"];
            assert_eq!(what_if["mode"], if two { "one_triangle" } else { "two_triangles" }, "{what}");
            assert_eq!((what_if["quads"].as_u64(), what_if["helper_lanes"].as_u64()), (Some(what_quads), Some(what_helpers)), "{what}");
            // The adapter's own count beside the model's, where it can count
            // (lavapipe can): at least every covered pixel once.
            if let Some(n) = pass["fragment_invocations"].as_u64() {
                assert!(n >= w * h, "{what}");
            }
        }
    }
}

/// Quads and helper lanes of two triangles splitting a `w`×`h` target
/// along its diagonal from the top-left corner to the bottom-right, by
/// brute force: a 2×2 block launches one quad per triangle holding one of
/// its pixel centres. A centre exactly on the diagonal (the centre of the
/// 333×211 target is one) goes by the top-left rule to the triangle whose
/// left edge the diagonal is: at any row the upper-right triangle lies to
/// the diagonal's right, so it takes the centre.
fn two_triangles(w: u64, h: u64) -> (u64, u64) {
    let mut quads = 0;
    for by in 0..h.div_ceil(2) {
        for bx in 0..w.div_ceil(2) {
            // Centre (x + ½, y + ½) below the line y = x·h/w, in integers.
            let below: Vec<bool> = (0..4)
                .map(|i| (2 * bx + i % 2, 2 * by + i / 2))
                .filter(|&(x, y)| x < w && y < h)
                .map(|(x, y)| (2 * y + 1) * w > (2 * x + 1) * h)
                .collect();
            quads += u64::from(below.contains(&true)) + u64::from(below.contains(&false));
        }
    }
    (quads, 4 * quads - w * h)
}

/// The G-buffer pass tests against the prepass's depth (less-equal, no
/// write): it rasterizes exactly what the prepass rasterized, and shades
/// each visible pixel once. Visible pixels are counted from the G-buffer
/// the GPU wrote (normal.w is 1 where geometry was drawn), not from loupe's
/// model; the two agree to within a few silhouette pixels, where the GPU's
/// f32 depth and the model's differ (docs/quads.md, "Depth precision").
#[test]
fn the_gbuffer_pass_rasterizes_what_the_prepass_did_and_shades_each_visible_pixel_once() {
    let p = Project::copy_of_repo("render-quads-gbuffer");
    let (run, report) = render_at(&p, "scenes/minimal.toml", "640x360", &[]);
    run.code(0);
    let r = report.expect("report.json written");
    let (prepass, gbuffer) = (&pass(&r, "depth_prepass")["quads"], &pass(&r, "gbuffer")["quads"]);
    assert_eq!(gbuffer["rasterized"], prepass["rasterized"], "same draws, same positions\n{gbuffer}\n{prepass}");
    let normal = image::open(p.path("out/gbuffer.normal.png")).unwrap().to_rgba8();
    let visible = normal.pixels().filter(|px| px.0[3] == 255).count() as i64;
    let shaded = gbuffer["pixels"].as_i64().unwrap();
    let rasterized = gbuffer["rasterized"]["pixels"].as_i64().unwrap();
    assert!(visible > 10_000, "the knot covers a good part of the frame: {visible}");
    assert!((shaded - visible).abs() * 1000 <= visible, "shaded {shaded} vs {visible} visible pixels (more than 0.1 % apart)");
    assert!(rasterized > shaded + visible / 2, "the knot overlaps itself: {rasterized} rasterized, {shaded} shaded");
    // The prepass writes depth in primitive order: it shades every pixel
    // that was nearest so far, at least each visible one.
    assert!(prepass["pixels"].as_i64().unwrap() >= visible, "{prepass}");
}

/// The path tracer's hierarchy holds the triangles the raster draws: one
/// camera ray through each pixel centre of the minimal scene hits the knot
/// where the G-buffer the GPU wrote covers it. On lavapipe at 320×180 they
/// agree on every pixel; a pixel centre grazing an edge may go either way
/// on another rasterizer, hence the 0.2 % allowed.
#[test]
fn camera_rays_through_the_hierarchy_hit_the_pixels_the_raster_covers() {
    use glam::{Mat4, Vec3};
    let p = Project::copy_of_repo("render-bvh-vs-raster");
    let (w, h) = (320u32, 180u32);
    let (run, _) = render_at(&p, "scenes/minimal.toml", &format!("{w}x{h}"), &[]);
    run.code(0);
    let normal = image::open(p.path("out/gbuffer.normal.png")).unwrap().to_rgba8();
    let loaded = loupe::scene::load(&p.path("scenes/minimal.toml")).unwrap();
    let bvh = loupe::bvh::Bvh::build(&loupe::render::scene_gpu::world_triangles(&loaded.scene, &loaded.meshes));
    let cam = &loaded.scene.camera;
    let view = Mat4::look_at_rh(Vec3::from(cam.position), Vec3::from(cam.target), Vec3::from(cam.up));
    let inv = (Mat4::perspective_rh(cam.fov_deg.to_radians(), w as f32 / h as f32, cam.near, cam.far) * view).inverse();
    let (mut covered, mut differ) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let ndc =
                |z: f32| inv.project_point3(Vec3::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0, z));
            let (near, far) = (ndc(0.0), ndc(1.0));
            let hit = bvh.intersect(near, (far - near).normalize(), 0.0, (far - near).length()).is_some();
            let drawn = normal.get_pixel(x, y).0[3] == 255;
            covered += usize::from(drawn);
            differ += usize::from(hit != drawn);
        }
    }
    assert!(covered > 1000, "the knot is in view: {covered} pixels");
    assert!(differ * 500 <= covered, "{differ} of {covered} pixels differ between the rays and the raster");
}

/// The lighting pass's colour output's statistics, per channel.
fn lighting_stats(r: &Value) -> (Vec<f64>, Vec<f64>) {
    let color = &pass(r, "lighting")["outputs"][0];
    let channel = |k: &str| color["stats"][k].as_array().unwrap().iter().take(3).map(|v| v.as_f64().unwrap()).collect();
    (channel("min"), channel("max"))
}

const SPHERE: &str = "[[materials]]\nname = \"white\"\nbase_color = [1, 1, 1]\nmetallic = 0\nroughness = 1\n\
                      [[objects]]\nshape = \"sphere\"\nmaterial = \"white\"\nposition = [0, 0.5, 0]\n";

#[test]
fn the_environment_lights_the_scene_and_is_its_background() {
    let p = Project::copy_of_repo("render-environment");
    // No light and no environment: the object and the background are black.
    p.write("scenes/dark.toml", format!("{SPHERE}[environment]\nintensity = 0\n"));
    let (run, report) = render(&p, "scenes/dark.toml", &[]);
    run.code(0);
    let (_, max) = lighting_stats(&report.expect("report.json written"));
    assert_eq!(max, [0.0; 3], "black without light");
    // A furnace: a uniform environment of radiance 1 around a Lambertian
    // sphere (roughness 1, metallic 0) that fills the frame. The specular is
    // the same for any base colour (F0 = 0.04), so a white sphere minus a
    // black one is the diffuse alone, which must be albedo·L = 1 at every
    // pixel (to 2e-3: the irradiance is exact, the HDR target is half float,
    // a step of 1e-3 at 1); the black one shows the
    // specular F0·scale + bias of the GGX table (0.012 to 0.014 here).
    let furnace = |base: &str| {
        let scene = format!(
            "[camera]\nposition = [0, 0.5, 3]\ntarget = [0, 0.5, 0]\nfov_deg = 20\n\
             [[materials]]\nname = \"m\"\nbase_color = {base}\nmetallic = 0\nroughness = 1\n\
             [[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\nposition = [0, 0.5, 0]\nscale = 2\n\
             [environment]\ntop = [1, 1, 1]\nbottom = [1, 1, 1]\n"
        );
        p.write("scenes/furnace.toml", scene);
        let (run, report) = render(&p, "scenes/furnace.toml", &[]);
        run.code(0);
        lighting_stats(&report.expect("report.json written"))
    };
    let (white_min, white_max) = furnace("[1, 1, 1]");
    let (black_min, black_max) = furnace("[0, 0, 0]");
    for c in 0..3 {
        assert!(
            (white_min[c] - black_min[c] - 1.0).abs() < 2e-3 && (white_max[c] - black_max[c] - 1.0).abs() < 2e-3,
            "diffuse is albedo·L: white {white_min:?}..{white_max:?}, black {black_min:?}..{black_max:?}"
        );
        assert!(black_min[c] > 0.005 && black_max[c] < 0.3, "the specular is F0·DFG: {black_min:?}..{black_max:?}");
    }
}

/// `--renderer path --spp N` accumulates N samples per pixel and writes the
/// path tracer's colour with its albedo and normal; the raster passes are
/// culled with the reason, and the raster frame culls the path tracer.
#[test]
fn the_path_tracer_renders_offline_with_albedo_and_normal() {
    let p = Project::copy_of_repo("render-path");
    let (run, report) = render_at(&p, "scenes/minimal.toml", "48x27", &["--renderer", "path", "--spp", "5"]);
    run.code(0);
    let r = report.expect("report.json written");
    assert_eq!(names(&r["passes"]), ["path_trace", "tonemap"], "{r}");
    for raster in ["shadows", "depth_prepass", "gbuffer", "lighting"] {
        assert_eq!(culled_reason(&r, raster), "quality.renderer is path");
    }
    let traced = pass(&r, "path_trace");
    for output in ["color", "albedo", "normal", "samples"] {
        assert!(p.path(&format!("out/path_trace.{output}.exr")).is_file(), "path_trace.{output}.exr missing");
    }
    let samples = traced["outputs"].as_array().unwrap().iter().find(|o| o["name"] == "samples").unwrap();
    assert_eq!(
        (samples["stats"]["min"][0].as_f64(), samples["stats"]["max"][0].as_f64()),
        (Some(5.0), Some(5.0)),
        "every pixel holds 5 samples"
    );
    let color = traced["outputs"].as_array().unwrap().iter().find(|o| o["name"] == "color").unwrap();
    assert_eq!(color["format"], "Rgba32Float");
    assert_eq!(color["stats"]["nan"], 0);
    // The knot's paint reaches the albedo: its blue over red.
    let albedo = traced["outputs"].as_array().unwrap().iter().find(|o| o["name"] == "albedo").unwrap();
    assert!((albedo["stats"]["max"][2].as_f64().unwrap() - 0.8).abs() < 0.01, "{albedo}");
    assert!(r["nan"].is_null(), "{r}");

    let (run, report) = render_at(&p, "scenes/minimal.toml", "48x27", &[]);
    run.code(0);
    assert_eq!(culled_reason(&report.unwrap(), "path_trace"), "quality.renderer is raster");
}

/// A small lit scene whose path-traced colour stays within [0, 1], what
/// the LDR weights expect; `denoiser` is its `[denoiser]` section, if any.
fn denoised_scene(denoiser: &str) -> String {
    format!(
        "[camera]\nposition = [0.0, 1.2, 3.5]\ntarget = [0.0, 0.4, 0.0]\n\
         [environment]\ntop = [0.5, 0.6, 0.8]\nbottom = [0.2, 0.2, 0.2]\n\
         [[materials]]\nname = \"red\"\nbase_color = [0.8, 0.2, 0.15]\nroughness = 0.4\n\
         [[materials]]\nname = \"floor\"\nbase_color = [0.6, 0.6, 0.6]\nroughness = 0.8\n\
         [[objects]]\nshape = \"sphere\"\nmaterial = \"red\"\nposition = [0.0, 0.5, 0.0]\nscale = 0.5\n\
         [[objects]]\nshape = \"plane\"\nmaterial = \"floor\"\nscale = 4.0\n\
         [[lights]]\ntype = \"point\"\nposition = [1.0, 2.0, 1.5]\nintensity = 6.0\n{denoiser}"
    )
}

/// RGB of an EXR `loupe render` wrote, clamped to [0, 1]: the range the
/// LDR weights denoise.
fn exr_rgb(path: &std::path::Path) -> Vec<[f32; 3]> {
    loupe_tests::exr_rgba(path).into_iter().map(|[r, g, b, _]| [r, g, b].map(|v| v.clamp(0.0, 1.0))).collect()
}

fn mse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>() / (3 * a.len()) as f64
}

/// A path-traced scene with `[denoiser]`: OIDN's U-Net runs after the path
/// tracer, every layer a pass whose tensor is written as `.npy`, the
/// upsamples and concatenations fused unless `quality.denoiser_fused` is
/// off; the 2-spp image denoised is closer to a 256-spp render than the
/// noisy one is.
#[test]
fn the_denoiser_runs_after_the_path_tracer_and_writes_every_tensor() {
    let p = Project::copy_of_repo("render-denoise");
    // No weights named: the bundled LDR network for colour, albedo and normal.
    p.write("scenes/denoised.toml", denoised_scene("[denoiser]\nmode = \"ldr\"\n"));
    p.write("scenes/reference.toml", denoised_scene(""));
    let (run, report) = render_at(&p, "scenes/denoised.toml", "64x48", &["--renderer", "path", "--spp", "2"]);
    run.code(0);
    let r = report.expect("report.json written");
    let layers = [
        "enc_conv0",
        "enc_conv1",
        "pool1",
        "enc_conv2",
        "pool2",
        "enc_conv3",
        "pool3",
        "enc_conv4",
        "pool4",
        "enc_conv5a",
        "enc_conv5b",
        "dec_conv4a",
        "dec_conv4b",
        "dec_conv3a",
        "dec_conv3b",
        "dec_conv2a",
        "dec_conv2b",
        "dec_conv1a",
        "dec_conv1b",
        "dec_conv0",
    ];
    let mut expected = vec!["path_trace".to_owned(), "denoise_input".to_owned()];
    expected.extend(layers.iter().map(|l| format!("denoise.{l}")));
    expected.extend(["denoise".to_owned(), "tonemap".to_owned()]);
    assert_eq!(names(&r["passes"]), expected, "{r}");
    assert_eq!(culled_reason(&r, "denoise_autoexposure"), "denoiser.mode is ldr: the input scale is 1");
    assert_eq!(culled_reason(&r, "denoise.concat1"), "fused into denoise.dec_conv1a (quality.denoiser_fused)");
    assert!(p.path("out/denoise.color.exr").is_file() && p.path("out/denoise.color.png").is_file());
    // Every tensor: [y, x, channel] of the padded image (64×48 is a
    // multiple of 16 already), channels padded to blocks of 4.
    let input = pass(&r, "denoise_input");
    assert_eq!(input["outputs"][0]["layout"]["dims"], serde_json::json!([["y", 48], ["x", 64], ["channel", 12]]), "{input}");
    for t in expected.iter().filter(|n| n.starts_with("denoise.") || *n == "denoise_input") {
        let out = &pass(&r, t)["outputs"][0];
        assert_eq!(out["name"], "tensor", "{t}: {out}");
        let file = p.path(&format!("out/{t}.tensor.npy"));
        let len: u64 = out["layout"]["dims"].as_array().unwrap().iter().map(|d| d[1].as_u64().unwrap()).product();
        assert_eq!(npy_f32(&file).len() as u64, len, "{t}");
        assert_eq!(out["stats"]["nan"], 0, "{t}");
    }
    let denoised = pass(&r, "denoise")["outputs"][0].clone();
    assert_eq!((denoised["name"].as_str(), denoised["width"].as_u64(), denoised["height"].as_u64()), (Some("color"), Some(64), Some(48)));
    assert!(r["nan"].is_null(), "{r}");
    let noisy = exr_rgb(&p.path("out/path_trace.color.exr"));
    let clean = exr_rgb(&p.path("out/denoise.color.exr"));

    // Upsample and concatenation as passes of their own: their tensors too.
    let (run, report) =
        render_at(&p, "scenes/denoised.toml", "64x48", &["--renderer", "path", "--spp", "2", "--set", "quality.denoiser_fused=false"]);
    run.code(0);
    let r = report.unwrap();
    let names = names(&r["passes"]);
    for t in ["upsample4", "concat4", "upsample1", "concat1"] {
        assert!(names.contains(&format!("denoise.{t}").as_str()), "{t}: {names:?}");
        assert!(p.path(&format!("out/denoise.{t}.tensor.npy")).is_file(), "{t}");
    }
    let concat1 = &pass(&r, "denoise.concat1")["outputs"][0]["layout"]["dims"];
    assert_eq!(concat1[2], serde_json::json!(["channel", 76]), "64 + 9 channels, padded");
    let separate = exr_rgb(&p.path("out/denoise.color.exr"));
    assert!(mse(&separate, &clean) < 1e-10, "fused or not, the same image: {}", mse(&separate, &clean));

    let (run, _) = render_at(&p, "scenes/reference.toml", "64x48", &["--renderer", "path", "--spp", "256"]);
    run.code(0);
    let reference = exr_rgb(&p.path("out/path_trace.color.exr"));
    let (before, after) = (mse(&noisy, &reference), mse(&clean, &reference));
    eprintln!("MSE against 256 spp: 2 spp {before:.5}, denoised {after:.5}");
    assert!(after < before * 0.5, "denoising the 2-spp image brings it closer to the 256-spp one: MSE {before} before, {after} after");
}

/// A unit sphere seen from +Z, filling most of a square frame, with the
/// UV debug view on.
const UV_SCENE: &str = "[output]\nwidth = 64\nheight = 64\n[camera]\nposition = [0.0, 0.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = 45.0\n\
[post]\ndebug_view = \"uv\"\n[[materials]]\nname = \"m\"\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n\
[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\n";

/// The sphere's UV where pixel (x, y)'s ray meets it (longitude u = φ/2π
/// with φ from +X towards −Z, latitude v = θ/π from the north pole).
fn sphere_uv(x: u32, y: u32, size: u32) -> [f32; 2] {
    let half = (45f32.to_radians() * 0.5).tan();
    let ndc = |i: u32| (2.0 * (i as f32 + 0.5) / size as f32 - 1.0) * half;
    let dir = glam::Vec3::new(ndc(x), -ndc(y), -1.0).normalize();
    let eye = glam::Vec3::new(0.0, 0.0, 3.0);
    // |eye + t dir| = 1, the nearer root.
    let b = eye.dot(dir);
    let t = -b - (b * b - (eye.length_squared() - 1.0)).sqrt();
    let p = eye + dir * t;
    let phi = (-p.z).atan2(p.x).rem_euclid(std::f32::consts::TAU);
    [phi / std::f32::consts::TAU, p.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI]
}

/// `post.debug_view = "uv"`: the G-buffer's `uv` target holds each pixel's
/// UV, and the debug view shows it in red and green. Pixels well inside
/// the sphere's outline see the UV of where their ray meets the true
/// sphere, up to its tessellation.
#[test]
fn the_uv_debug_view_shows_where_each_pixel_sits_on_the_sphere() {
    let p = Project::copy_of_repo("render-uv");
    p.write("scenes/uv.toml", UV_SCENE);
    let (run, report) = render_at(&p, "scenes/uv.toml", "64x64", &[]);
    run.code(0);
    let r = report.expect("report.json written");
    let gbuffer = r["passes"].as_array().unwrap().iter().find(|p| p["name"] == "gbuffer").unwrap();
    assert_eq!(names(&gbuffer["outputs"]), ["normal", "albedo", "material", "uv", "material_words"], "{gbuffer}");
    let uv = exr_rgb(&p.path("out/gbuffer.uv.exr"));
    let shown = exr_rgb(&p.path("out/debug_view.color.exr"));
    for (x, y) in [(32, 32), (20, 24), (44, 40), (26, 44), (40, 20)] {
        let want = sphere_uv(x, y, 64);
        let (got, seen) = (uv[(y * 64 + x) as usize], shown[(y * 64 + x) as usize]);
        for c in 0..2 {
            assert!((got[c] - want[c]).abs() < 0.01, "pixel ({x}, {y}): uv {got:?}, the sphere's is {want:?}");
            assert!((seen[c] - want[c]).abs() < 0.015, "pixel ({x}, {y}): the debug view shows {seen:?}, the sphere's uv is {want:?}");
        }
        assert_eq!(seen[2], 0.0, "pixel ({x}, {y}): blue is 0");
    }
}

/// `--debug-pixel`: a print added to the tonemap pass shows its pixel's
/// position and HDR input in report.json, from the instrumented pipeline;
/// without it the report has no prints; a pixel outside is refused.
#[test]
fn debug_pixel_writes_the_prints_of_that_pixel_into_the_report() {
    let p = Project::copy_of_repo("printf");
    let tonemap = p.read("shaders/post/tonemap.wgsl");
    let needle = "    let c = max(texel.rgb, vec3(0.0));\n";
    assert!(tonemap.contains(needle), "the premise: tonemap computes `c` so");
    let line = tonemap[..tonemap.find(needle).unwrap()].lines().count() + 2 + 1;
    let edited = format!(
        "enable wgpu_debug_printf;\n{}",
        tonemap.replacen(needle, &format!("{needle}    debugPrintf(\"at %v2f hdr %v3f\", in.position.xy, c);\n"), 1)
    );
    p.write("shaders/post/tonemap.wgsl", edited);

    let (run, report) = render(&p, "scenes/minimal.toml", &["--debug-pixel", "70,20"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let prints = &report.expect("report.json written")["prints"];
    assert_eq!(prints["pixel"], serde_json::json!([70, 20]));
    assert_eq!(prints["pipelines"], serde_json::json!(["post.tonemap"]), "only the pipeline with a print is instrumented");
    assert_eq!(prints["dropped"], 0);
    let lines = prints["lines"].as_array().expect("lines");
    assert_eq!(lines.len(), 1, "one invocation is the pixel: {prints}");
    let l = &lines[0];
    assert_eq!(
        (l["pass"].as_str(), l["file"].as_str(), l["line"].as_u64(), l["column"].as_u64()),
        (Some("tonemap"), Some("shaders/post/tonemap.wgsl"), Some(line as u64), Some(5))
    );
    assert_eq!(l["values"][0], serde_json::json!([70.5, 20.5]));
    let hdr = l["values"][1].as_array().expect("a vec3");
    assert!(hdr.len() == 3 && hdr.iter().all(|c| c.as_f64().is_some_and(|c| c >= 0.0)), "{l}");
    assert!(l["text"].as_str().unwrap().starts_with("at 70.500000, 20.500000 hdr "), "{l}");

    let (run, report) = render(&p, "scenes/minimal.toml", &[]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(report.expect("report.json written").get("prints").is_none(), "no pixel selected: no prints");

    let (run, _) = render(&p, "scenes/minimal.toml", &["--debug-pixel", "96,0"]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--debug-pixel 96,0 is outside the 96x54 frame"), "{}", run.stderr);
}
