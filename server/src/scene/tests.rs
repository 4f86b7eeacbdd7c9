use super::*;

fn err(text: &str) -> Diagnostic {
    parse("s.toml", text).expect_err("the scene is invalid")
}

fn at(d: &Diagnostic) -> (u32, u32) {
    let l = d.location.as_ref().expect("located");
    (l.line, l.column)
}

const BASE: &str = "[[materials]]\nname = \"m\"\n\n[[objects]]\nshape = \"sphere\"\nmaterial = \"m\"\n";

#[test]
fn defaults_apply() {
    let s = parse("s.toml", "# nothing\n").unwrap();
    assert_eq!((s.width, s.height, s.post.tonemap), (1280, 720, Tonemap::Aces));
    assert!(s.is_empty());
}

#[test]
fn every_bundled_scene_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            load(&p).unwrap_or_else(|d| panic!("{}: {d}", p.display()));
            n += 1;
        }
    }
    assert!(n >= 4, "default, showcase, minimal, volume");
}

#[test]
fn output_size_errors_are_located() {
    let e = err("[output]\nwidth = 0\nheight = 10\n");
    assert_eq!(at(&e), (2, 9));
    let e = err("[output]\nwidth = 16384\nheight = 16384\n");
    assert!(e.message.contains("8192"), "{}", e.message);
    assert_eq!(at(&e), (2, 9));
}

#[test]
fn unknown_fields_are_errors_at_their_line() {
    let e = err("[post]\nexposure = 1\n");
    assert_eq!(at(&e).0, 2);
    let e = err(&format!("{BASE}colour = [1, 0, 0]\n"));
    assert_eq!(at(&e).0, 7);
    assert!(e.message.contains("colour"), "{}", e.message);
}

#[test]
fn nan_and_negative_values_are_located_at_the_value() {
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = nan\n"));
    assert!(e.message.starts_with("lights[0].intensity"), "{}", e.message);
    assert_eq!(at(&e), (11, 13));
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = -2.0\n"));
    assert!(e.message.contains("negative"), "{}", e.message);
    assert_eq!(at(&e), (11, 13));
    let e = err("[[materials]]\nname = \"m\"\nroughness = 1.5\n");
    assert_eq!(at(&e), (3, 13));
    let e = err(
        "[[media]]\nabsorption = [0.1, -0.1, 0.1]\nscattering = [1, 1, 1]\nshapes = [{ type = \"sphere\", center = [0, 0, 0], radius = 1 }]\n",
    );
    assert!(e.message.starts_with("media[0].absorption[1]"), "{}", e.message);
    assert_eq!(at(&e), (2, 20));
    let e = err(
        "[[media]]\nabsorption = [0, 0, 0]\nscattering = [1, 1, 1]\nshapes = [{ type = \"sphere\", center = [0, 0, 0], radius = inf }]\n",
    );
    assert!(e.message.contains("radius"), "{}", e.message);
    assert_eq!(at(&e).0, 4);
}

#[test]
fn references_and_light_fields_are_checked() {
    let e = err("[[objects]]\nshape = \"sphere\"\nmaterial = \"nope\"\n");
    assert!(e.message.contains("no material named `nope`"), "{}", e.message);
    assert_eq!(at(&e), (3, 12));
    let e = err(&BASE.replace("sphere", "teapot"));
    assert!(e.message.contains("unknown shape `teapot`"), "{}", e.message);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nsize = [1, 1]\n"));
    assert!(e.message.contains("does not apply for a point light"), "{}", e.message);
    assert_eq!(at(&e).0, 11);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"rect\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\n"));
    assert!(e.message.contains("lights[0].size: is required for a rect light"), "{}", e.message);
    let e = err(&format!("{BASE}\n[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\n"));
    assert!(e.message.contains("zero vector"), "{}", e.message);
    assert_eq!(at(&e), (10, 13));
}

#[test]
fn missing_and_malformed_meshes_are_diagnosed_at_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"gone.gltf\"\nmaterial = \"m\"\n").unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.message.contains("gone.gltf") && e.message.contains("does not exist"), "{}", e.message);
    assert_eq!(at(&e), (4, 8));
    std::fs::write(dir.path().join("bad.gltf"), "{ \"asset\": { \"version\": \"2.0\" }, \n  \"meshes\": [ oops ] }").unwrap();
    std::fs::write(&scene, "[[materials]]\nname = \"m\"\n[[objects]]\nmesh = \"bad.gltf\"\nmaterial = \"m\"\n").unwrap();
    let e = load(&scene).unwrap_err();
    assert!(e.file().is_some_and(|f| f.ends_with("bad.gltf")), "located in the glTF: {e}");
    assert!(e.labels.iter().any(|l| l.location.file.ends_with("s.toml") && l.location.line == 4), "and at the reference: {e:?}");
}

// ---- [denoiser] ------------------------------------------------------------

#[test]
fn the_denoiser_section_reads_its_weights_precision_mode_and_input_scale() {
    use crate::denoise_options::{Mode, Precision};
    assert_eq!(parse("s.toml", BASE).unwrap().denoiser, None, "no section, no denoiser");
    let s = parse("s.toml", "[denoiser]\nweights = \"w/rt_hdr.tza\"\n").unwrap();
    let d = s.denoiser.expect("a denoiser");
    assert_eq!((d.weights.as_deref(), d.precision, d.mode), (Some("w/rt_hdr.tza"), Precision::F32, Mode::Hdr), "the defaults");
    assert_eq!((d.at.line, d.at.column), (2, 11), "where the weights are named");
    let d = parse("s.toml", "[denoiser]\nweights = \"a.tza\"\nprecision = \"f16\"\nmode = \"ldr\"\n").unwrap().denoiser.unwrap();
    assert_eq!((d.precision, d.mode, d.input_scale), (Precision::F16, Mode::Ldr, None));
    let d = parse("s.toml", "[denoiser]\nweights = \"a.tza\"\nmode = \"ldr_srgb\"\ninput_scale = 0.25\n").unwrap().denoiser.unwrap();
    assert_eq!((d.mode, d.input_scale), (Mode::LdrSrgb, Some(0.25)));
    // No weights: the bundled network, chosen when the scene is loaded.
    let d = parse("s.toml", "[denoiser]\nprecision = \"f16\"\n").unwrap().denoiser.unwrap();
    assert_eq!((d.weights, d.precision, d.mode), (None, Precision::F16, Mode::Hdr));
    for (text, line, col) in [
        ("[denoiser]\nweights = \"a.tza\"\ninput_scale = 0\n", 3, 15),
        ("[denoiser]\nweights = \"a.tza\"\ninput_scale = nan\n", 3, 15),
        ("[denoiser]\nweights = \"a.tza\"\nprecision = \"f8\"\n", 3, 13),
        ("[denoiser]\nweights = \"a.tza\"\nmode = \"hdr10\"\n", 3, 8),
        ("[denoiser]\nweights = \"a.tza\"\nstrength = 1\n", 3, 1),
        ("[denoiser]\nweights = \"  \"\n", 2, 11),
    ] {
        assert_eq!(at(&err(text)), (line, col), "{text}");
    }
}

// ---- the settings table: [post] and [quality] ----------------------------

use crate::render::passes::affected;
use crate::testing::line_col;
use overrides::{ControlKind, controls};
use settings::{Kind, SETTINGS, Value};

/// A scene that writes `key = value` in its setting's table, after other
/// tables, so positions are not trivially at the start.
fn with_setting(path: &str, value: &str) -> String {
    let (table, key) = path.split_once('.').unwrap();
    format!("[output]\nwidth = 64\nheight = 32\n\n# the setting under test\n[{table}]\n{key} = {value}   # a comment\n")
}

const MEDIUM: &str =
    "[[media]]\nabsorption = [0, 0, 0]\nscattering = [1, 1, 1]\nshapes = [{ type = \"sphere\", center = [0, 0, 0], radius = 1 }]\n";

#[test]
fn every_setting_round_trips() {
    let defaults = parse("s.toml", "").unwrap();
    for s in SETTINGS {
        let default = (s.get)(&defaults);
        let other = match s.kind {
            Kind::Toggle => Value::Bool(default != Value::Bool(true)),
            Kind::Int { max, .. } => Value::Int(max),
            // Halfway to the max: in range, and a metering range stays ordered.
            Kind::Float { max, .. } => Value::Float((settings::number(&default).unwrap() + max) / 2.0),
            Kind::Choice(options) => Value::Text(options.iter().find(|o| Value::Text((**o).to_owned()) != default).unwrap().to_string()),
        };
        for v in [&default, &other] {
            let scene = parse("s.toml", &with_setting(s.path, &v.to_string())).unwrap_or_else(|d| panic!("{}: {d}", s.path));
            assert_eq!((s.get)(&scene), *v, "{}", s.path);
        }
        assert!(default != other, "{}: the test sets a value other than the default", s.path);
    }
}

#[test]
fn defaults_are_the_documented_ones() {
    let s = parse("s.toml", "").unwrap();
    let (p, q) = (&s.post, &s.quality);
    assert_eq!((p.exposure_ev, p.tonemap, p.two_triangles, p.debug_view), (0.0, Tonemap::Aces, false, DebugView::None));
    assert_eq!((p.auto_exposure, p.auto_exposure_speed, p.auto_exposure_min_ev, p.auto_exposure_max_ev), (false, 3.0, -8.0, 8.0));
    assert_eq!(
        (q.shadows, q.shadow_map_size, q.volume_steps, q.volume_shadow_steps, q.volume_estimator),
        (true, 1024, 48, 6, Estimator::Analytic)
    );
    assert_eq!((q.renderer, q.path_spp, q.path_bounces), (Renderer::Raster, 256, 4));
    assert_eq!((q.shadow_filter, q.rect_lights, q.denoise), (1, crate::scene::settings::RectLights::Ltc, true));
    assert_eq!((q.material_bytes, q.path_simplified_materials), (80, false));
}

#[test]
fn out_of_range_settings_are_located_at_the_value() {
    let mut numeric = 0;
    for s in SETTINGS {
        let (min, max, below, above) = match s.kind {
            Kind::Int { min, max, .. } => (min.to_string(), max.to_string(), (min - 1).to_string(), (max + 1).to_string()),
            Kind::Float { min, max, .. } => (min.to_string(), max.to_string(), format!("{:?}", min - 1.0), format!("{:?}", max + 1.0)),
            _ => continue,
        };
        numeric += 1;
        let (_, key) = s.path.split_once('.').unwrap();
        for bad in [below, above] {
            let text = with_setting(s.path, &bad);
            let e = err(&text);
            let shown = bad.trim_end_matches(".0");
            assert_eq!(e.message, format!("{}: must be between {min} and {max}, not {shown}", s.path));
            assert_eq!(at(&e), line_col(&text, &format!("{key} = "), key.len() + 3), "{}", s.path);
        }
    }
    assert_eq!(numeric, 12, "every numeric setting was tried");
    let e = err("[post]\nexposure_ev = 30.0\n");
    assert_eq!(e.message, "post.exposure_ev: must be between -24 and 24, not 30");
    assert_eq!(at(&e), (2, 15));
    let e = err("[post]\nexposure_ev = nan\n");
    assert_eq!(e.message, "post.exposure_ev: must be a finite number, not NaN");
}

#[test]
fn unknown_settings_are_located_at_the_key() {
    let text = "[post]\nexposure_ev = 1.0\n  exposure = 2\n";
    let e = err(text);
    assert_eq!(at(&e), line_col(text, "exposure =", 0));
    assert!(e.message.starts_with("post.exposure: unknown key; expected one of: exposure_ev, auto_exposure,"), "{}", e.message);
    let text = "# inline\nquality = { shadows = false, shadow_size = 512 }\n\n[output]\nwidth = 8\nheight = 8\n";
    let e = err(text);
    assert_eq!(at(&e), line_col(text, "shadow_size", 0));
    assert!(e.message.starts_with("quality.shadow_size: unknown key"), "{}", e.message);
    let e = err("post = 3\n");
    assert_eq!((e.message.as_str(), at(&e)), ("post: must be a table", (1, 8)));
}

#[test]
fn settings_of_the_wrong_type_are_located_at_the_value() {
    for (path, value, message) in [
        ("quality.shadows", "\"yes\"", "must be true or false, not \"yes\""),
        ("quality.volume_steps", "4.5", "must be a whole number, not 4.5"),
        ("post.exposure_ev", "\"bright\"", "must be a number, not \"bright\""),
        ("post.auto_exposure", "[true]", "must be true or false, not an array"),
        ("post.tonemap", "{ curve = 1 }", "must be one of \"aces\", \"reinhard\", not a table"),
    ] {
        let text = with_setting(path, value);
        let e = err(&text);
        assert_eq!(e.message, format!("{path}: {message}"));
        assert_eq!(at(&e), line_col(&text, value, 0), "{path}");
    }
    // A whole number is a number: `exposure_ev = 1` is 1 EV.
    assert_eq!(parse("s.toml", "[post]\nexposure_ev = 1\n").unwrap().post.exposure_ev, 1.0);
}

#[test]
fn a_bad_choice_lists_the_options() {
    let text = with_setting("post.debug_view", "\"normals\"");
    let e = err(&text);
    assert_eq!(
        e.message,
        "post.debug_view: must be one of \"none\", \"normal\", \"albedo\", \"roughness\", \"metallic\", \"uv\", \"depth\", \"tile_class\", \"closures\", \"bytes\", not \"normals\""
    );
    assert_eq!(at(&e), line_col(&text, "\"normals\"", 0));
    let e = err("[quality]\nvolume_estimator = \"exact\"\n");
    assert!(e.message.contains("\"constant\", \"analytic\""), "{}", e.message);
}

#[test]
fn the_metering_range_must_be_ordered() {
    let text = "[post]\nauto_exposure_min_ev = 2.0\nauto_exposure_max_ev = 2.0\n";
    let e = err(text);
    assert_eq!(e.message, "post.auto_exposure_max_ev: must be greater than post.auto_exposure_min_ev (2)");
    assert_eq!(at(&e), (3, 24));
    // Without a max in the file, the min written there is at fault.
    let e = err("[post]\nauto_exposure_min_ev = 10.0\n");
    assert_eq!(e.message, "post.auto_exposure_min_ev: must be less than post.auto_exposure_max_ev (8)");
    assert_eq!(at(&e), (2, 24));
    let s = parse("s.toml", "[post]\nauto_exposure_min_ev = -2.5\nauto_exposure_max_ev = -2.0\n").unwrap();
    assert_eq!((s.post.auto_exposure_min_ev, s.post.auto_exposure_max_ev), (-2.5, -2.0));
}

#[test]
fn controls_are_the_table_entries_the_scene_shows() {
    for text in ["", "[post]\nauto_exposure = true\n", MEDIUM, &format!("[post]\nauto_exposure = true\n{MEDIUM}")] {
        let scene = parse("s.toml", text).unwrap();
        let shown = controls(&scene, affected);
        let settings: Vec<_> = shown.iter().filter(|c| !c.path.starts_with("lights[") && !c.path.starts_with("environment.")).collect();
        let expected: Vec<_> = SETTINGS.iter().filter(|s| (s.shown_when)(&scene)).collect();
        assert_eq!(settings.len(), expected.len(), "{text}");
        for (c, s) in settings.iter().zip(expected) {
            assert_eq!(
                (c.path.as_str(), c.label.as_str(), &c.affects, &c.value),
                (s.path, s.label, &affected(s.affects), &(s.get)(&scene))
            );
            match (&c.kind, s.kind) {
                (ControlKind::Toggle, Kind::Toggle) => {}
                (ControlKind::Slider { min, max, step }, Kind::Int { min: lo, max: hi, step: st }) => {
                    assert_eq!((*min, *max, *step), (lo as f64, hi as f64, st as f64), "{}", s.path)
                }
                (ControlKind::Slider { min, max, step }, Kind::Float { min: lo, max: hi, step: st }) => {
                    assert_eq!((*min, *max, *step), (lo, hi, st), "{}", s.path)
                }
                (ControlKind::Choice { options }, Kind::Choice(o)) => assert_eq!(options, o, "{}", s.path),
                (c, k) => panic!("{}: control {c:?} for {k:?}", s.path),
            }
        }
        let has = |p: &str| shown.iter().any(|c| c.path == p);
        assert_eq!(has("quality.volume_steps"), !scene.media.is_empty(), "volume controls only with media: {text}");
        assert_eq!(has("post.auto_exposure_speed"), scene.post.auto_exposure, "metering controls only with auto exposure: {text}");
        assert!(has("post.exposure_ev") && has("quality.shadows"), "{text}");
    }
}

#[test]
fn every_affected_pass_is_a_pass_of_the_frame() {
    // The showcase declares every pass: live, or culled with a reason.
    let showcase = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/showcase.toml");
    let graph = crate::render::build_graph(&load(&showcase).unwrap().scene, None, Default::default());
    let passes: Vec<&str> = graph.passes.iter().map(|p| p.name.as_str()).chain(graph.culled.iter().map(|c| c.name.as_str())).collect();
    for s in SETTINGS {
        for pass in affected(s.affects) {
            assert!(passes.contains(&pass), "{} affects `{pass}`, which is not one of {passes:?}", s.path);
        }
    }
}

#[test]
fn control_values_read_as_written() {
    let scene =
        parse("s.toml", "[post]\nexposure_ev = 0.3\n\n[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 1.2\n").unwrap();
    let value = |p: &str| controls(&scene, affected).into_iter().find(|c| c.path == p).unwrap().value;
    assert_eq!((value("post.exposure_ev"), value("lights[0].intensity")), (Value::Float(0.3), Value::Float(1.2)));
}

/// `1e308` is a finite number no `f32` holds: the message says it is out
/// of range, and which range, not that it is infinite.
#[test]
fn numbers_too_large_for_an_f32_are_out_of_range_not_infinite() {
    let light = "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 1.0\n";
    let o = overrides::Overrides::from([("lights[0].intensity".to_owned(), Value::Float(1e308))]);
    let e = err(&overrides::apply(light, &o).unwrap());
    assert_eq!(e.message, "lights[0].intensity: out of range: must be between -3.4028235e38 and 3.4028235e38, not 1e308");
    assert_eq!(at(&e), (4, 13));
    let e = err("[environment]\ntop = [0.1, -1e39, 0.3]\n");
    assert_eq!(e.message, "environment.top[1]: out of range: must be between -3.4028235e38 and 3.4028235e38, not -1e39");
    assert_eq!(at(&e), (2, 13));
    let o = overrides::Overrides::from([("post.exposure_ev".to_owned(), Value::Float(1e308))]);
    assert_eq!(overrides::apply("", &o), Err("post.exposure_ev: must be between -24 and 24, not 1e308".to_owned()));
}

#[test]
fn overrides_of_settings_are_checked_by_the_table() {
    for (path, value, message) in [
        ("post.exposure_ev", Value::Float(30.0), "post.exposure_ev: must be between -24 and 24, not 30"),
        ("quality.shadow_map_size", Value::Int(8), "quality.shadow_map_size: must be between 64 and 4096, not 8"),
        ("quality.shadows", Value::Int(1), "quality.shadows: must be true or false, not 1"),
        ("post.tonemap", Value::Text("filmic".into()), "post.tonemap: must be one of \"aces\", \"reinhard\", not \"filmic\""),
    ] {
        let o = overrides::Overrides::from([(path.to_owned(), value)]);
        assert_eq!(overrides::apply("[post]\nexposure_ev = 0.0\n", &o), Err(message.to_owned()));
    }
    let o = overrides::Overrides::from([("post.auto_exposure".to_owned(), Value::Bool(true))]);
    let s = parse("s.toml", &overrides::apply("", &o).unwrap()).unwrap();
    assert!(s.post.auto_exposure);
}

#[test]
fn the_environment_defaults_to_the_old_sky() {
    let s = parse("s.toml", "").unwrap();
    assert_eq!(s.environment, Environment { top: [0.10, 0.16, 0.28], bottom: [0.02, 0.022, 0.025], intensity: 1.0 });
    let s = parse("s.toml", "[environment]\ntop = [1, 0.5, 0.25]\nbottom = [0, 0.1, 0.2]\nintensity = 2.5\n").unwrap();
    assert_eq!(s.environment, Environment { top: [1.0, 0.5, 0.25], bottom: [0.0, 0.1, 0.2], intensity: 2.5 });
    let s = parse("s.toml", "[environment]\nintensity = 0\n").unwrap();
    assert_eq!((s.environment.intensity, s.environment.top), (0.0, [0.10, 0.16, 0.28]), "the colours keep their defaults");
}

#[test]
fn bad_environment_values_are_located() {
    let e = err("[environment]\nintensity = -1.0\n");
    assert!(e.message.starts_with("environment.intensity") && e.message.contains("negative"), "{}", e.message);
    assert_eq!(at(&e), (2, 13));
    let e = err("[environment]\nintensity = nan\n");
    assert!(e.message.contains("finite"), "{}", e.message);
    assert_eq!(at(&e), (2, 13));
    let e = err("[environment]\ntop = [0.1, inf, 0.3]\n");
    assert!(e.message.starts_with("environment.top[1]") && e.message.contains("finite"), "{}", e.message);
    assert_eq!(at(&e), (2, 13));
    let e = err("# sky\n[environment]\nbottom = [0.1, 0.2, -0.3]\n");
    assert!(e.message.starts_with("environment.bottom[2]") && e.message.contains("negative"), "{}", e.message);
    assert_eq!(at(&e), (3, 21));
    let e = err("[environment]\ncolour = [1, 1, 1]\n");
    assert!(e.message.contains("colour"), "{}", e.message);
    assert_eq!(at(&e).0, 2);
}

#[test]
fn the_environment_intensity_is_a_live_control() {
    let s = parse("s.toml", "[environment]\nintensity = 0.5\n").unwrap();
    let c = overrides::controls(&s, affected);
    let env = c.iter().find(|c| c.path == "environment.intensity").expect("a control");
    assert_eq!(env.value, Value::Float(0.5));
    let mut o = overrides::Overrides::new();
    o.insert("environment.intensity".into(), Value::Float(3.0));
    let text = overrides::apply("# no environment\n", &o).unwrap();
    assert_eq!(parse("s.toml", &text).unwrap().environment.intensity, 3.0);
}
