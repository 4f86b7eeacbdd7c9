//! Tile classification on the device (lavapipe without a GPU), 64 × 36
//! (8 × 5 tiles, the last row half covered): the counts against the
//! classes derived here from the captured depth and material headers; the
//! tiled lighting against every tile through the complex pipeline; and a
//! scene of one-closure materials culling the complex pass.

use std::collections::BTreeSet;
use std::path::Path;

use super::*;
use crate::loaded::Loaded;
use crate::render::frame::FrameResult;
use crate::render::session::Session;
use crate::scene::overrides::Overrides;
use crate::scene::settings::Value;

/// A plane of the shorthand on the left, a two-closure material (a
/// coat over a base) on a small box, a one-closure material with a
/// feature (fuzz) on a sphere, the sky above.
const SCENE: &str = r#"
[output]
width = 64
height = 36
[camera]
position = [0.0, 1.0, 4.0]
target = [0.0, 0.6, 0.0]
fov_deg = 50.0
[[lights]]
type = "directional"
direction = [-0.3, -1.0, -0.4]
intensity = 2.0
[[materials]]
name = "floor"
base_color = [0.6, 0.6, 0.6]
roughness = 0.6
[[materials]]
name = "paint"
file = "coat.mat"
[[materials]]
name = "cloth"
file = "sheen.mat"
[[objects]]
shape = "sphere"
material = "cloth"
position = [-1.1, 0.4, 0.8]
scale = [0.35, 0.35, 0.35]
[[objects]]
shape = "plane"
material = "floor"
position = [-1.5, 0.0, 0.0]
scale = [3.0, 1.0, 6.0]
[[objects]]
shape = "cube"
material = "paint"
position = [0.6, 0.5, 0.5]
scale = [0.5, 0.5, 0.5]
"#;

const SHEEN: &str = "material sheen {\n    slab { base_color: rgb(0.2, 0.3, 0.8), fuzz_weight: 0.8, fuzz_color: rgb(1, 0.9, 0.8) }\n}\n";

const COAT: &str = "material coat {\n    layer(slab { base_color: grey(0), specular_roughness: 0.1 }, slab { base_color: rgb(0.7, 0.1, 0.1) })\n}\n";

fn load(dir: &Path, scene: &str, overrides: &Overrides) -> Loaded {
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    std::fs::write(dir.join("coat.mat"), COAT).unwrap();
    std::fs::write(dir.join("sheen.mat"), SHEEN).unwrap();
    crate::loaded::load_with(&dir.join("scene.toml"), overrides).unwrap_or_else(|d| panic!("{d}"))
}

fn session(loaded: &Loaded) -> Session {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let lib = crate::shader::library::read_tree(&root).unwrap();
    let mut s = Session::new(crate::gpu::testing::device(), &root, lib, loaded);
    assert_eq!(s.install_missing(), vec![], "the frame's shaders build");
    s
}

fn render(s: &mut Session) -> FrameResult {
    let wanted: BTreeSet<String> =
        ["lighting/color", "depth_prepass/depth", "gbuffer/material_words", STATS, BYTES, "classify/classes"].map(str::to_owned).into();
    let pending = s.submit(Some(&wanted), 1.0 / 30.0);
    let r = s.wait(pending);
    assert_eq!(s.take_uncaptured(), Vec::<String>::new());
    r
}

fn tensor<'a>(r: &'a FrameResult, key: &str) -> &'a [f32] {
    &r.tensors.iter().find(|t| t.key() == key).unwrap_or_else(|| panic!("{key} is captured")).data
}

fn image<'a>(r: &'a FrameResult, key: &str) -> &'a [f32] {
    &r.captures.iter().find(|c| c.key() == key).unwrap_or_else(|| panic!("{key} is captured")).data
}

#[test]
fn tiles_are_classified_by_their_dearest_pixel_and_the_tiled_lighting_matches_the_untiled() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = load(dir.path(), SCENE, &Overrides::new());
    let mut s = session(&loaded);
    let r = render(&mut s);
    let (w, h) = (64usize, 36usize);
    let depth = image(&r, "depth_prepass/depth");
    let words = tensor(&r, "gbuffer/material_words");
    // Derived here: a pixel's class from its depth and header, a tile's
    // the dearest; bytes from the header's class and closure count.
    let pixel_class = |x: usize, y: usize| -> usize {
        let i = y * w + x;
        if depth[i * depth.len() / (w * h)] >= 1.0 { EMPTY } else { (words[i] as u32 & 3) as usize + 1 }
    };
    let (across, down) = tiles(64, 36);
    let mut want_pixels = [0u64; 4];
    let mut want_tiles = [0u64; 4];
    let mut want_classes = vec![];
    for ty in 0..down as usize {
        for tx in 0..across as usize {
            let mut dearest = EMPTY;
            for y in ty * 8..(ty * 8 + 8).min(h) {
                for x in tx * 8..(tx * 8 + 8).min(w) {
                    let c = pixel_class(x, y);
                    want_pixels[c] += 1;
                    dearest = dearest.max(c);
                }
            }
            want_tiles[dearest] += 1;
            want_classes.push(dearest as f32);
        }
    }
    let stats = Statistics::from_tensors(tensor(&r, STATS), tensor(&r, BYTES));
    let per = |p: &PerClass| [p.empty, p.simple, p.single, p.complex];
    assert_eq!(per(&stats.pixels), want_pixels);
    assert_eq!(per(&stats.tiles), want_tiles);
    assert_eq!(tensor(&r, "classify/classes"), want_classes.as_slice());
    // The scene has every class: sky, floor, sphere, box.
    assert!(want_tiles.iter().all(|&t| t > 0), "{want_tiles:?}");
    let simple_pixels = want_pixels[SIMPLE];
    assert!(stats.material_bytes_written >= simple_pixels * 16 + want_pixels[COMPLEX] * 4 * 10, "{stats:?}");
    let tiled = image(&r, "lighting/color").to_vec();

    // Each class's own pipeline lit its tiles: the simple and single
    // ones compiled against their modules.
    let keys: Vec<String> = s.graph().pipelines().iter().map(|k| k.label()).collect();
    for def in [crate::render::passes::lighting::SIMPLE_CLASS, crate::render::passes::lighting::SINGLE_CLASS] {
        assert!(keys.iter().any(|k| k.contains(def)), "{def} in {keys:?}");
    }

    // Every tile through the complex pipeline: the same image.
    let off = load(dir.path(), SCENE, &Overrides::from([("quality.tile_classification".to_owned(), Value::Bool(false))]));
    assert_eq!(s.set_scene_now(&off), vec![]);
    let r = render(&mut s);
    let untiled = image(&r, "lighting/color");
    let worst = tiled.iter().zip(untiled).map(|(a, b)| (a - b).abs() / b.abs().max(1.0)).fold(0.0f32, f32::max);
    assert!(worst <= 1e-6, "tiled against untiled: {worst}");

    // The debug views: each tile's class, each pixel's closures, as the
    // colours `post/debug_tiles.wgsl` gives them (empty grey, then green,
    // yellow, red), at a pixel inside each tile.
    let hue = |rgb: &[f32]| match (rgb[0] > 0.5, rgb[1] > 0.5) {
        (false, false) => EMPTY,
        (false, true) => SIMPLE,
        (true, true) => SINGLE,
        (true, false) => COMPLEX,
    };
    for (view, per_pixel) in [("tile_class", false), ("closures", true)] {
        let o = Overrides::from([("post.debug_view".to_owned(), Value::Text(view.to_owned()))]);
        assert_eq!(s.set_scene_now(&load(dir.path(), SCENE, &o)), vec![]);
        let wanted: BTreeSet<String> = ["debug_view/color".to_owned()].into();
        let pending = s.submit(Some(&wanted), 1.0 / 30.0);
        let r = s.wait(pending);
        let shown = image(&r, "debug_view/color");
        for ty in 0..down as usize {
            for tx in 0..across as usize {
                let (x, y) = (tx * 8 + 3, ty * 8 + 3);
                // Per pixel, one closure (simple, single) shows green and
                // the coat's two yellow.
                let want = if per_pixel { [EMPTY, SIMPLE, SIMPLE, SINGLE][pixel_class(x, y)] } else { want_classes[ty * across as usize + tx] as usize };
                let i = (y * w + x) * 4;
                assert_eq!(hue(&shown[i..i + 3]), want, "{view} at ({x}, {y}): {:?}", &shown[i..i + 3]);
            }
        }
    }
}

#[test]
fn a_scene_without_two_closure_materials_culls_the_complex_pass_and_builds_no_pipeline_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = SCENE
        .replace("name = \"paint\"\nfile = \"coat.mat\"", "name = \"paint\"\nbase_color = [0.7, 0.1, 0.1]")
        .replace("name = \"cloth\"\nfile = \"sheen.mat\"", "name = \"cloth\"\nbase_color = [0.2, 0.3, 0.8]");
    let loaded = load(dir.path(), &text, &Overrides::new());
    let s = session(&loaded);
    let graph = s.graph();
    let culled: Vec<(&str, &str)> = graph.culled.iter().map(|c| (c.name.as_str(), c.reason.as_str())).collect();
    assert!(culled.contains(&("lighting_complex", "no material of the scene has two or more closures")), "{culled:?}");
    assert!(culled.iter().any(|(n, _)| *n == "lighting_single"), "{culled:?}");
    let live: Vec<&str> = graph.passes.iter().map(|p| p.name.as_str()).collect();
    assert!(live.contains(&"classify") && live.contains(&"lighting_simple"), "{live:?}");
    // Only the simple specialisation and the environment are built.
    let keys: Vec<String> = graph.pipelines().iter().filter(|k| k.spec.name.starts_with("lighting")).map(|k| k.label()).collect();
    assert_eq!(keys.len(), 2, "{keys:?}");
    assert!(keys.iter().all(|k| k == "lighting.environment" || k.contains(crate::render::passes::lighting::SIMPLE_CLASS)), "{keys:?}");
}
