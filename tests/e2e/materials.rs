//! Materials from `*.mat` files in `loupe serve`: an edit reaches the frame,
//! rebuilding only the pipelines that import the generated material module
//! (none when only a value changed); a broken file keeps the last good
//! material rendering and is reported at its line; the fix recovers.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use loupe_tests::{Project, Server};

const LIMIT: Duration = Duration::from_secs(120);
const SCENE: &str = "scenes/paint.toml";
const MATERIAL: &str = "scenes/paint.mat";

/// `minimal.toml` with its material taken from `paint.mat`.
fn project(name: &str) -> Project {
    let p = Project::copy_of_repo(name);
    let minimal = p.read("scenes/minimal.toml");
    let shorthand = "base_color = [0.2, 0.45, 0.8]\nmetallic = 0.0\nroughness = 0.35\n";
    assert!(minimal.contains(shorthand), "minimal.toml still has its shorthand material");
    p.write(SCENE, minimal.replace(shorthand, "file = \"paint.mat\"\n"));
    p.write(MATERIAL, paint("rgb(0.2, 0.45, 0.8)", ""));
    p
}

fn paint(colour: &str, extra: &str) -> String {
    format!(
        "// A test paint.\nparam colour: color = {colour}\n\nmaterial paint = slab {{\n    base_color: colour,\n    specular_roughness: 0.35,{extra}\n}}\n"
    )
}

fn frame_png(s: &Server) -> Vec<u8> {
    let (code, png) = s.get("/api/captures/tonemap/color.png");
    assert_eq!(code, 200);
    png
}

/// Each pipeline's generation: a rebuild raises it.
pub fn generations(s: &Server) -> BTreeMap<String, u64> {
    s.get_json("/api/pipelines")
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["name"].as_str().unwrap().to_owned(), p["generation"].as_u64().unwrap()))
        .collect()
}

/// Saves `content` as an editor does and waits for a frame other than
/// `before`; returns it.
fn save_and_see(p: &Project, s: &Server, content: &str, before: &[u8]) -> Vec<u8> {
    p.save_by_rename(MATERIAL, content);
    s.wait_for("a frame showing the edit", LIMIT, || {
        let png = frame_png(s);
        (png != before).then_some(png)
    })
}

#[test]
fn a_material_edit_reaches_the_frame_and_a_broken_one_keeps_the_last_good_until_fixed() {
    let p = project("materials-live");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    s.wait_for("a first frame", LIMIT, || (s.get_json("/api/status")["frame"].as_u64() > Some(0)).then_some(()));
    assert!(s.get_json("/api/diagnostics")["diagnostics"].as_array().unwrap().is_empty(), "{}", s.log());
    let blue = frame_png(&s);
    let first = generations(&s);
    // The pipelines the paint's code reaches: the G-buffer and the tile
    // classification (`loupe::material`) and the single tiles' lighting
    // (`loupe::material_single`, which holds the one-closure paint); not
    // the simple tiles' (`loupe::material_simple`, the shorthand alone,
    // though lighting.wgsl names all three modules behind its `#ifdef`s).
    // A one-closure paint makes no complex tiles.
    let material_users: BTreeSet<&String> = first
        .keys()
        .filter(|n| {
            ["lighting.deferred", "geometry.gbuffer", "passes.classify"].iter().any(|u| n.starts_with(u)) && !n.contains("SIMPLE_CLASS")
        })
        .collect();
    assert_eq!(material_users.len(), 3, "{first:?}");
    assert!(first.keys().any(|n| n.contains("SIMPLE_CLASS")) && material_users.iter().any(|n| n.contains("SINGLE_CLASS")), "{first:?}");

    // A new value: the parameter's buffer changes, no pipeline does.
    let orange = save_and_see(&p, &s, &paint("rgb(0.8, 0.3, 0.1)", ""), &blue);
    assert_eq!(generations(&s), first, "a value edit rebuilds nothing");

    // New code (haze): exactly the pipelines that import the material module.
    let hazy = save_and_see(&p, &s, &paint("rgb(0.8, 0.3, 0.1)", "\n    haze_weight: 0.5,"), &orange);
    let now = generations(&s);
    let rebuilt: BTreeSet<&String> = now.iter().filter(|(name, g)| first.get(*name) != Some(*g)).map(|(name, _)| name).collect();
    assert_eq!(rebuilt, material_users, "the material's users rebuild, nothing else");

    // Broken: reported at its line; the last good material keeps rendering.
    let broken = paint("rgb(0.8, 0.3, 0.1)", "\n    haze_weight: 0.5 +,");
    let line = broken.lines().position(|l| l.contains("0.5 +")).unwrap() as u64 + 1;
    p.save_by_rename(MATERIAL, &broken);
    let diagnostic = s.wait_for("the material's error", LIMIT, || {
        s.get_json("/api/diagnostics")["diagnostics"].as_array()?.iter().find(|d| d["location"]["file"] == MATERIAL).cloned()
    });
    assert_eq!(diagnostic["location"]["line"].as_u64(), Some(line), "{diagnostic}");
    assert_eq!(frame_png(&s), hazy, "the last good material still renders");

    // Fixed: the error clears and the frame is the first one again.
    p.save_by_rename(MATERIAL, paint("rgb(0.2, 0.45, 0.8)", ""));
    s.wait_for("the error to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
    s.wait_for("the first frame's image again", LIMIT, || (frame_png(&s) == blue).then_some(()));
}

/// The bundled scenes, whose materials are the scene file's shorthand,
/// render what they rendered before materials were a language: images made
/// by the last build before it (`tests/golden/images/`, 96×54, one sample
/// per pixel). The path tracer reads the same f32 values and runs the same
/// arithmetic: within 1e-4. The raster's G-buffer used to hold the
/// shorthand's values and the normal as f16; the material buffer holds the
/// values as f16 still (the simple storage class) and the normal
/// octahedrally (16 + 16 bits, within 1e-4 rad, where f16 components were
/// off by up to about 2.4e-4), so the lit colour moves by the two normals'
/// difference: at most 2⁻⁸ of the value plus 1e-4 (measured: 0.25 % at
/// the old showcase's metal highlight, 0.2 % on the minimal scene).
#[test]
fn the_bundled_scenes_render_what_they_rendered_before_materials() {
    let p = Project::copy_of_repo("materials-unchanged");
    let golden = loupe_tests::repo().join("tests/golden/images");
    // The showcase as it was when the references were made (the bundled
    // one has since gained library materials), beside the meshes it names.
    p.write("scenes/showcase_shorthand.toml", std::fs::read(golden.join("showcase_shorthand.toml")).expect("the old showcase"));
    for (scene, file) in [("minimal", "minimal"), ("showcase", "showcase_shorthand")] {
        for (renderer, outputs, relative) in
            [("raster", &["lighting.color", "volumes.color"][..], 2f32.powi(-8)), ("path", &["path_trace.color"][..], 0.0)]
        {
            let out = format!("out-{scene}-{renderer}");
            let scene_file = format!("scenes/{file}.toml");
            p.run(&["render", "--scene", &scene_file, "--renderer", renderer, "--size", "96x54", "--out", &out]).code(0);
            for output in outputs {
                let reference = golden.join(format!("{scene}.{output}.exr"));
                if !reference.is_file() {
                    continue;
                }
                let (want, got) = (loupe_tests::exr_rgba(&reference), loupe_tests::exr_rgba(&p.path(&format!("{out}/{output}.exr"))));
                assert_eq!(want.len(), got.len(), "{scene} {output}");
                for (i, (w, g)) in want.iter().zip(&got).enumerate() {
                    for c in 0..3 {
                        let bound = 1e-4 + relative * w[c].abs();
                        assert!(
                            (w[c] - g[c]).abs() <= bound,
                            "{scene} {output}: pixel ({}, {}) channel {c} is {} where it was {} (bound {bound})",
                            i % 96,
                            i / 96,
                            g[c],
                            w[c]
                        );
                    }
                }
            }
        }
    }
}

const TEXTURED_SCENE: &str = "scenes/textured.toml";
const TEXTURE: &str = "scenes/albedo.png";

/// `minimal.toml` at 64×36 with a material that emits its texture's colour
/// and reflects nothing, so a lit pixel of the object is the texel itself.
fn textured_project(name: &str) -> Project {
    let p = project(name);
    let scene = p.read(SCENE).replace("width = 640\nheight = 360", "width = 64\nheight = 36");
    assert!(scene.contains("width = 64\n"), "minimal.toml's [output] is 640×360");
    p.write(TEXTURED_SCENE, scene.replace("file = \"paint.mat\"", "file = \"textured.mat\""));
    p.write(
        "scenes/textured.mat",
        "param albedo: texture = \"albedo.png\"\n\nmaterial textured = slab {\n    base_color: grey(0.0),\n    specular_weight: 0.0,\n    emission_color: sample(albedo),\n    emission_luminance: 1.0,\n}\n",
    );
    p.write(TEXTURE, png([255, 128, 0]));
    p
}

/// A 2×2 PNG of one sRGB colour.
fn png(rgb: [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb(rgb));
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encode a PNG");
    bytes
}

/// An 8-bit sRGB channel, decoded to linear as the texture loader does.
fn linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

fn lit(s: &Server) -> loupe_tests::Capture {
    s.capture_f32("lighting/color").expect("the lighting pass is captured")
}

/// Saves the texture as an editor does and waits for a frame with other
/// pixels; returns it. The object's pixels moved by exactly what the texel
/// did (its emission; the rest of its light is the same), and no other
/// pixel moved.
fn retexture_and_see(
    p: &Project,
    s: &Server,
    ws: &mut loupe_tests::ws::Ws,
    before: &loupe_tests::Capture,
    old: [u8; 3],
    new: [u8; 3],
) -> loupe_tests::Capture {
    p.save_by_rename(TEXTURE, png(new));
    rebuilds_nothing(ws);
    let after = s.wait_for("a frame showing the new texel", LIMIT, || {
        let now = lit(s);
        (now.frame > before.frame && now.data != before.data).then_some(now)
    });
    let step: [f32; 3] = std::array::from_fn(|c| linear(new[c]) - linear(old[c]));
    let mut object = 0;
    for y in 0..before.height {
        for x in 0..before.width {
            let (was, is) = (before.pixel(x, y), after.pixel(x, y));
            if was == is {
                continue;
            }
            object += 1;
            // Half-float texels and target: 2e-3.
            let moved: [f32; 3] = std::array::from_fn(|c| is[c] - was[c]);
            assert!((0..3).all(|c| (moved[c] - step[c]).abs() <= 2e-3), "pixel ({x}, {y}) moved by {moved:?}, the texel by {step:?}");
        }
    }
    assert!(object >= 50, "the object covers {object} pixels of {}×{}", before.width, before.height);
    after
}

/// The reload a texture save starts names the image and no pipeline: the
/// texture array is uploaded again, no shader changed.
fn rebuilds_nothing(ws: &mut loupe_tests::ws::Ws) {
    let started = ws.event("reload_started", LIMIT, |e| e["files"].as_array().is_some_and(|f| f.iter().any(|f| f == TEXTURE)));
    assert_eq!(started["pipelines"], serde_json::json!([]), "{started}");
}

#[test]
fn a_texture_edit_reaches_the_frame_without_a_rebuild_and_a_broken_one_keeps_the_last_good_until_fixed() {
    let p = textured_project("materials-texture");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", TEXTURED_SCENE]);
    // The lit frame is captured while a client subscribes to it.
    let mut ws = s.ws();
    ws.send(serde_json::json!({ "type": "subscribe", "pass": "lighting", "output": "color", "encoding": "f32" }));
    let orange = s.wait_for("a first lit frame", LIMIT, || s.capture_f32("lighting/color"));
    assert!(s.get_json("/api/diagnostics")["diagnostics"].as_array().unwrap().is_empty(), "{}", s.log());
    let first = generations(&s);

    // A new image: the texture array is uploaded again, no pipeline rebuilds.
    let blue = retexture_and_see(&p, &s, &mut ws, &orange, [255, 128, 0], [0, 64, 255]);
    assert_eq!(generations(&s), first, "a texture edit rebuilds nothing");

    // Truncated, as a crashed export leaves it: an error naming the image,
    // and the last good texture keeps rendering.
    let whole = png([0, 255, 0]);
    p.save_by_rename(TEXTURE, &whole[..whole.len() / 2]);
    rebuilds_nothing(&mut ws);
    let diagnostic = s.wait_for("the texture's error", LIMIT, || {
        s.get_json("/api/diagnostics")["diagnostics"]
            .as_array()?
            .iter()
            .find(|d| d["message"].as_str().is_some_and(|m| m.contains(TEXTURE)))
            .cloned()
    });
    assert_eq!(diagnostic["severity"], "error", "{diagnostic}");
    assert_eq!(diagnostic["location"]["file"], "scenes/textured.mat", "at the param naming the image: {diagnostic}");
    // (A failed reload still marks the frame dirty: one more renders.)
    s.wait_for("a frame after the error", LIMIT, || (lit(&s).frame > blue.frame).then_some(()));
    assert_eq!(lit(&s).data, blue.data, "the last good texture still renders");
    assert_eq!(generations(&s), first, "a broken texture rebuilds nothing");

    // Fixed: the error clears and the new texel shows.
    let still = lit(&s);
    retexture_and_see(&p, &s, &mut ws, &still, [0, 64, 255], [0, 255, 0]);
    s.wait_for("the error to clear", LIMIT, || s.get_json("/api/diagnostics")["diagnostics"].as_array()?.is_empty().then_some(()));
    assert_eq!(generations(&s), first, "nothing rebuilt");
}
