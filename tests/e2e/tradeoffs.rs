//! `loupe bench tradeoffs`: a real sweep of a small scene through the
//! binary, its three files, and the reference cache.

use loupe_tests::{Project, Server};

fn cached(p: &Project) -> Vec<(String, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(p.path("cache"))
        .map(|d| {
            d.map(|e| e.unwrap())
                .map(|e| (e.file_name().to_string_lossy().into_owned(), e.metadata().unwrap().modified().unwrap()))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn sweeps_settings_into_a_table_a_plot_and_json_with_cached_references() {
    let p = Project::copy_of_repo("tradeoffs");
    let args = [
        "bench",
        "tradeoffs",
        "--scene",
        "scenes/minimal.toml",
        "--size",
        "32x18",
        "--repeats",
        "1",
        "--reference-spp",
        "256",
        "--out",
        "out",
        "--cache",
        "cache",
    ];
    p.run(&args).code(0).stdout_has("## path_spp").stdout_has("Reference: the path tracer at 256 samples per pixel");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(p.path("out/tradeoffs.json")).unwrap()).unwrap();
    let series = json["series"].as_array().unwrap();
    let names: Vec<&str> = series.iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["shadow_map_size", "shadow_filter", "path_spp", "two_triangles"], "minimal.toml has no media: no volume series");

    let path = &series[2]["points"];
    let errors: Vec<f64> = path.as_array().unwrap().iter().map(|p| p["relative_mse"].as_f64().unwrap()).collect();
    assert_eq!(errors.len(), 7, "1 to 64 samples");
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "more samples, less error: {errors:?}");
    // Monte Carlo: the error's variance falls as 1/spp, so 64× the samples
    // cut the relative MSE by about 64 (less: the reference has noise too).
    assert!(errors[6] < errors[0] / 16.0, "{errors:?}");
    let last = &path[6];
    assert_eq!(last["time_ratio"].as_f64(), Some(1.0));
    assert!(path[0]["time_ms"].as_f64().unwrap() < last["time_ms"].as_f64().unwrap(), "64 samples take longer than 1");

    let triangles = &series[3]["points"];
    let lanes = |i: usize| triangles[i]["helper_lanes"].as_u64().unwrap();
    assert!(lanes(0) > lanes(1), "two triangles leave helper lanes along their diagonal: {} against {}", lanes(0), lanes(1));
    assert_eq!(triangles[0]["relative_mse"].as_f64(), Some(0.0), "the same image");

    let points: usize = series.iter().map(|s| s["points"].as_array().unwrap().len()).sum();
    assert_eq!(std::fs::read_dir(p.path("out/points")).unwrap().count(), points, "an image per point");
    let svg = std::fs::read_to_string(p.path("out/tradeoffs.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.matches("<polyline").count() >= 2, "the plot has the series with errors");
    assert!(std::fs::read_to_string(p.path("out/tradeoffs.md")).unwrap().contains("| value | time (ms) |"));

    // A server started on them says they are this scene's from its first
    // answer: a page that connects at once plots them.
    std::fs::create_dir_all(p.path("tradeoffs")).unwrap();
    std::fs::copy(p.path("out/tradeoffs.json"), p.path("tradeoffs/tradeoffs.json")).unwrap();
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change"]);
    assert_eq!(s.get_state("/api/tradeoffs"), (200, Some("current".to_owned())), "{}", s.log());
    drop(s);

    // A second run renders no reference: each is read from the cache.
    let before = cached(&p);
    assert_eq!(before.len(), 4, "a reference per series: {before:?}");
    p.run(&args).code(0);
    assert_eq!(cached(&p), before, "the cached references are reused, untouched");
    // An edited shader is another reference.
    let brdf = p.path("shaders/lib/brdf.wgsl");
    let text = std::fs::read_to_string(&brdf).unwrap();
    std::fs::write(&brdf, text + "\n// edited\n").unwrap();
    p.run(&args).code(0);
    assert_eq!(cached(&p).len(), 8, "the sources' hashes key the cache");
}
