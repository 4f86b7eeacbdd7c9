//! `GET /api/materials` on the library scene: one entry per scene
//! material with its parameters and override paths, beside the compile
//! report of each definition, and each instance's preview; a `.mat` edit
//! changes the report and the preview, and a broken `.mat` keeps the last
//! good ones while the diagnostics carry the error.

use std::time::Duration;

use loupe_tests::{Project, Server};
use serde_json::Value;

pub const LIMIT: Duration = Duration::from_secs(180);
pub const SCENE: &str = "scenes/small_materials.toml";
const PLASTIC: &str = "scenes/materials/plastic.mat";

/// `scenes/materials.toml` at 64×36: quick on lavapipe.
pub fn small_materials(name: &str) -> Project {
    let p = Project::copy_of_repo(name);
    let small = p.read("scenes/materials.toml").replacen("width = 640", "width = 64", 1).replacen("height = 360", "height = 36", 1);
    assert!(small.contains("width = 64\n") && small.contains("height = 36\n"), "materials.toml's size moved: update this test");
    p.write(SCENE, small);
    p
}

fn entry<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["materials"].as_array().unwrap().iter().find(|m| m["name"] == name).unwrap_or_else(|| panic!("no `{name}`: {report}"))
}

fn definition<'a>(report: &'a Value, name: &str) -> &'a Value {
    &report["definitions"][entry(report, name)["definition"].as_u64().unwrap() as usize]
}

#[test]
fn materials_are_served_with_their_reports_and_previews_and_a_broken_file_keeps_the_last_good_one() {
    let p = small_materials("materials-api");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    s.wait_for("a first frame", LIMIT, || (s.get_json("/api/status")["frame"].as_u64() > Some(0)).then_some(()));
    let first = s.get_json("/api/materials");
    assert_eq!(first["scene"], SCENE);
    let names: Vec<&str> = first["materials"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "floor",
            "car paint",
            "polished metal",
            "rough metal",
            "hazy metal",
            "fabric",
            "skin",
            "plastic",
            "rust",
            "thin glass",
            "solid glass",
            "anodized metal",
            "brushed metal"
        ]
    );
    for (i, m) in first["materials"].as_array().unwrap().iter().enumerate() {
        assert_eq!(m["index"], i, "{m}");
    }

    // The shorthand: its parameters are the entry's own keys.
    let floor = entry(&first, "floor");
    assert!(floor["file"].is_null() && floor["material"] == "shorthand", "{floor}");
    assert_eq!(floor["params"][2]["path"], "materials[0].roughness");
    assert_eq!(floor["params"][2]["value"].as_f64().unwrap() as f32, 0.9);

    // A file's: the scene's values over the defaults, with range and doc.
    let plastic = entry(&first, "plastic");
    assert_eq!(plastic["file"], "materials/plastic.mat");
    let colour = &plastic["params"][0];
    assert_eq!(colour["path"], "materials[7].params.base_color");
    assert_eq!(colour["type"], "color");
    let floats = |v: &Value| v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>();
    assert_eq!(floats(&colour["value"]), [0.05, 0.35, 0.1], "the scene's value");
    assert_eq!(floats(&colour["default"]), [0.7, 0.08, 0.06], "the file's");
    assert_eq!((colour["min"].as_f64(), colour["max"].as_f64()), (Some(0.0), Some(1.0)));
    assert_eq!(colour["doc"], "The diffuse colour (linear RGB).");
    assert_eq!(plastic["params"][2]["max"].as_f64(), Some(2.5));

    // Reports: car paint is a layer over a mix, with three closures.
    let paint = definition(&first, "car paint");
    let root = &paint["nodes"][paint["root"].as_u64().unwrap() as usize];
    assert_eq!((root["kind"].as_str(), root["depth"].as_u64()), (Some("layer"), Some(0)), "{paint}");
    assert!(paint["closures"].as_array().unwrap().len() >= 2, "{paint}");
    assert_eq!(paint["gbuffer_bytes_per_pixel"], 56 + 32, "its words (it fits the default 80 B) and the inspection targets");
    assert!(paint["wgsl_bytes"].as_u64() > Some(1000) && paint["compile_ms"].as_f64() > Some(0.0), "{paint}");
    assert_eq!(definition(&first, "plastic")["features"], serde_json::json!(["diffuse", "specular"]));

    // Previews: plastic is the scene's green, raster and path traced; the
    // corner is the sky, whichever the material.
    let preview = |query: &str| {
        let (status, body) = s.get(&format!("/api/materials/{query}"));
        assert_eq!(status, 200, "{query}: {}\n{}", String::from_utf8_lossy(&body), s.log());
        body
    };
    let green = preview("7/preview");
    let [r, g, b] = preview_pixel(&green, 64, 64);
    assert!(g > r + 20 && g > b + 20, "a green sphere in the middle: {:?}", [r, g, b]);
    let metal = preview("2/preview?renderer=raster");
    assert_eq!(preview_pixel(&metal, 2, 2), preview_pixel(&green, 2, 2), "the same sky behind both");
    assert_ne!(preview_pixel(&metal, 64, 64), [r, g, b]);
    let [r, g, b] = preview_pixel(&preview("7/preview?renderer=path"), 64, 64);
    assert!(g > r + 20 && g > b + 20, "path traced, green too: {:?}", [r, g, b]);
    let (status, body) = s.get("/api/materials/99/preview");
    assert_eq!(status, 404, "{}", String::from_utf8_lossy(&body));
    assert!(String::from_utf8_lossy(&body).contains("no material 99: the scene has 13"));
    assert_eq!(s.get("/api/materials/7/preview?renderer=photon").0, 400);
    assert_eq!(s.get("/api/materials/seven/preview").0, 404);

    // An edit that adds fuzz, and a tint: the report says so, and the
    // tint is new generated code the preview's pipelines are rebuilt from.
    let good = p.read(PLASTIC);
    let fuzzy = good
        .replace("    specular_ior: specular_ior,\n", "    specular_ior: specular_ior,\n    fuzz_weight: 0.5,\n")
        .replace("    base_color: base_color,\n", "    base_color: base_color * rgb(0.1, 0.2, 8.0),\n");
    assert!(fuzzy.contains("fuzz_weight") && fuzzy.contains("8.0)"), "plastic.mat's slab moved: update this test");
    p.save_by_rename(PLASTIC, &fuzzy);
    let edited = s.wait_for("the report of the edit", LIMIT, || {
        let r = s.get_json("/api/materials");
        (definition(&r, "plastic")["features"] == serde_json::json!(["diffuse", "specular", "fuzz"])).then_some(r)
    });
    let node = &definition(&edited, "plastic")["nodes"][0];
    assert!(node["fields"].as_array().unwrap().iter().any(|f| f["field"] == "fuzz_weight" && f["value_text"] == "0.5"), "{node}");
    let is_blue = |png: &[u8]| {
        let [r, g, b] = preview_pixel(png, 64, 64);
        b > r + 20 && b > g + 20
    };
    assert!(is_blue(&preview("7/preview")), "the preview shows the edit");

    // Broken: the diagnostics name the file and line; the report stays.
    p.save_by_rename(PLASTIC, fuzzy.replace("fuzz_weight: 0.5,", "fuzz_weight: 0.5 +,"));
    let diagnostic = s.wait_for("the error", LIMIT, || {
        let d = s.get_json("/api/diagnostics")["diagnostics"].as_array().unwrap().first().cloned();
        d.filter(|d| d["location"]["file"].as_str().is_some_and(|f| f.ends_with("plastic.mat")))
    });
    assert_eq!(diagnostic["location"]["line"], 16, "{diagnostic}");
    assert_eq!(s.get_json("/api/materials"), edited, "the last good report stays");
    assert!(is_blue(&preview("7/preview")), "the last good preview stays");
}

/// A preview's pixel at (x, y), as 8-bit sRGB.
fn preview_pixel(png: &[u8], x: u32, y: u32) -> [u8; 3] {
    let img = image::load_from_memory(png).expect("a PNG").to_rgb8();
    assert_eq!(img.dimensions(), (128, 128));
    img.get_pixel(x, y).0
}
