//! Every pass of every bundled scene (`scenes/*.toml`) at the extremes of
//! every setting of the settings table, one at a time: each number at its
//! minimum and maximum, each choice at every option, each toggle both
//! ways, on top of the scene as written. A setting the scene hides (its
//! control's `shown_when`: the path tracer's with the raster, the meter's
//! without auto exposure) is set in the context that shows it: with
//! auto exposure on, or path traced. One that no context shows (the
//! volume settings without media, the denoiser's without `[denoiser]`)
//! changes no pass and is left out. Pairs the file may not hold
//! (`settings::ORDERED`) are left out too, and so is a variant equal to
//! one already tried (an extreme the scene already holds).
//!
//! Two frames each (auto exposure and the path tracer's accumulation move
//! on), every output but depth textures captured (`scanned`), at 64 × 36;
//! the bound is the capture system's NaN scan: no NaN or Inf in any
//! capture, and no NaN origin.

use std::collections::BTreeSet;
use std::path::Path;

use loupe::loaded::Loaded;
use loupe::render::session::Session;
use loupe::scene::Scene;
use loupe::scene::settings::Value;
use loupe::scene::settings::{self, Kind, SETTINGS, Setting};

/// A setting's extremes.
fn extremes(s: &Setting) -> Vec<Value> {
    match s.kind {
        Kind::Toggle => vec![Value::Bool(false), Value::Bool(true)],
        Kind::Int { min, max, .. } => vec![Value::Int(min), Value::Int(max)],
        Kind::Float { min, max, .. } => vec![Value::Float(min), Value::Float(max)],
        Kind::Choice(options) => options.iter().map(|o| Value::Text((*o).to_owned())).collect(),
    }
}

/// The contexts a setting is tried in, in order: the scene as written,
/// with auto exposure, path traced.
fn contexts(base: &Scene) -> Vec<Scene> {
    let with = |path: &str, v: Value| {
        let mut s = base.clone();
        settings::find(path).expect("a table setting").set(&mut s, &v).expect("a valid value");
        s
    };
    vec![base.clone(), with("post.auto_exposure", Value::Bool(true)), with("quality.renderer", Value::Text("path".into()))]
}

fn ordered(scene: &Scene) -> bool {
    settings::ORDERED.iter().all(|(a, b)| {
        let get = |p: &str| settings::number(&(settings::find(p).expect("a table setting").get)(scene));
        get(a) < get(b)
    })
}

/// Every variant of `base`: a label and the scene.
pub fn variants(base: &Scene) -> Vec<(String, Scene)> {
    let mut out = vec![("as written".to_owned(), base.clone())];
    let contexts = contexts(base);
    for setting in SETTINGS {
        for value in extremes(setting) {
            let shown = contexts.iter().find_map(|c| {
                let mut s = c.clone();
                setting.set(&mut s, &value).ok()?;
                ((setting.shown_when)(&s) && ordered(&s)).then_some(s)
            });
            // A value the scene already holds renders a variant tried
            // before (the scene as written, or this setting's other
            // context): rendering it again finds nothing new.
            if let Some(s) = shown.filter(|s| out.iter().all(|(_, tried)| tried != s)) {
                out.push((format!("{} = {value}", setting.path), s));
            }
        }
    }
    out
}

/// The bundled scenes, each at 64 × 36.
pub fn bundled() -> Vec<(String, Loaded)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut paths: Vec<_> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "toml")).collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let mut loaded = loupe::loaded::load(&p).unwrap_or_else(|d| panic!("{d}"));
            (loaded.scene.width, loaded.scene.height) = (64, 36);
            (p.file_name().unwrap().to_string_lossy().into_owned(), loaded)
        })
        .collect()
}

/// The outputs scanned: every output of every live pass but depth
/// textures, which the rasterizer fills with depths clamped to the
/// viewport's [0, 1] and which cannot hold a NaN or Inf (a 4096² shadow
/// map captured and scanned on the CPU takes half a minute per frame in a
/// debug build).
fn scanned(s: &Session) -> BTreeSet<String> {
    s.passes()
        .into_iter()
        .filter(|p| p.kind.is_some())
        .flat_map(|p| p.writes.into_iter().filter(|o| !o.format.starts_with("Depth")).map(move |o| format!("{}/{}", p.name, o.name)))
        .collect()
}

/// Renders two frames of `scene` with `scanned` outputs captured; returns
/// what the NaN scan found, one line per bad output.
pub fn scan(s: &mut Session, loaded: &Loaded, scene: &Scene) -> Vec<String> {
    let diagnostics = s.set_scene_now(&loaded.with_scene(scene.clone()));
    if !diagnostics.is_empty() {
        return diagnostics.iter().map(ToString::to_string).collect();
    }
    s.reset_history();
    let outputs = scanned(s);
    let mut bad = Vec::new();
    for frame in 1..=2 {
        let pending = s.submit(Some(&outputs), 1.0 / 30.0);
        let r = s.wait(pending);
        for c in r.captures.iter().filter(|c| c.stats.has_non_finite()) {
            bad.push(format!(
                "frame {frame}: {} holds {} NaN and {} Inf, the first at {:?}",
                c.key(),
                c.stats.nan,
                c.stats.inf,
                c.stats.first_nan
            ));
        }
        for t in r.tensors.iter().filter(|t| t.stats.has_non_finite()) {
            bad.push(format!("frame {frame}: {} holds {} NaN and {} Inf", t.key(), t.stats.nan, t.stats.inf));
        }
        bad.extend(r.nan.map(|o| format!("frame {frame}: NaN origin {o:?}")));
    }
    bad
}

/// A scene beyond the bundled ones: a mirror floor (roughness 0, white
/// metal) under a point light bright enough that the reflected radiance
/// exceeds f16's largest value, 65504, in the raster's HDR target
/// (Rgba16Float); validation accepts any finite intensity. Whether a
/// render target saturates such a value or stores Inf is the adapter's
/// choice: lavapipe saturates (`lighting/color` peaks at 65504).
/// An adapter that stores Inf fails here.
pub const BRIGHT: &str = "[output]\nwidth = 64\nheight = 36\n\
    [camera]\nposition = [0.0, 1.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n\
    [[materials]]\nname = \"mirror\"\nbase_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 0.0\n\
    [[materials]]\nname = \"white\"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\n\
    [[objects]]\nshape = \"plane\"\nmaterial = \"mirror\"\nscale = 4.0\n\
    [[objects]]\nshape = \"sphere\"\nmaterial = \"white\"\nposition = [0.8, 0.5, 0.0]\nscale = 0.5\n\
    [[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, -1.0]\nintensity = 10000000.0\n";

/// Materials at the edges of their fields' ranges, for the material
/// buffer's quantisers: an `add` whose weights pass 1, a white mirror
/// metal emitting 1e6 (past rgb9e5's 65408), a black fuzz-only slab, a
/// fully anisotropic, transmitting, thin-film slab of thickness 0, and a
/// slab with a normal of its own pointing away. Every feature has words, so
/// every quantiser runs.
pub const EXTREME_MAT: &str = "
param away: vec3 = rgb(0, 0, -1)
material extreme = add(
    slab { base_color: rgb(1, 1, 1), base_metalness: 1, specular_roughness: 0, emission_luminance: 1000000, emission_color: rgb(1, 0, 0) },
    add(
        slab { base_color: rgb(0, 0, 0), specular_roughness: 1, fuzz_weight: 1, fuzz_color: rgb(1, 1, 1), fuzz_roughness: 0, haze_weight: 1, haze_roughness: 0 },
        slab { specular_roughness_anisotropy: 1, specular_rotation: 0.25, specular_roughness: 0, thin_film_weight: 1, thin_film_thickness: 0,
               transmission_weight: 1, specular_edge_color: rgb(0, 0, 0), normal: away }))
";

/// A sphere and a plane wearing `EXTREME_MAT`, lit by a point light.
pub const EXTREME: &str = "[output]\nwidth = 64\nheight = 36\n\
    [camera]\nposition = [0.0, 1.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n\
    [[materials]]\nname = \"extreme\"\nfile = \"extreme.mat\"\n\
    [[objects]]\nshape = \"plane\"\nmaterial = \"extreme\"\nscale = 4.0\n\
    [[objects]]\nshape = \"sphere\"\nmaterial = \"extreme\"\nposition = [0.0, 0.5, 0.0]\nscale = 0.5\n\
    [[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 1.0]\nintensity = 10.0\n";

/// `EXTREME` loaded from a folder of its own (the scene names its `.mat`
/// by path).
pub fn extreme() -> Loaded {
    let dir = std::env::temp_dir().join(format!("loupe-stability-extreme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("extreme.mat"), EXTREME_MAT).unwrap();
    std::fs::write(dir.join("extreme.toml"), EXTREME).unwrap();
    let loaded = loupe::loaded::load(&dir.join("extreme.toml")).unwrap_or_else(|d| panic!("{d}"));
    let _ = std::fs::remove_dir_all(&dir);
    loaded
}
