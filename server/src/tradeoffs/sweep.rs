//! Which quality settings a scene's sweep measures, at which values, and
//! against which reference. The settings themselves (their ranges, what
//! they affect, when they apply) are the settings table's
//! (`scene::settings`); this only says how to sweep them.

use crate::material::Program;
use crate::scene::Scene;
use crate::scene::overrides::Overrides;
use crate::scene::settings;
use crate::scene::settings::Value;

/// What a series' images are compared with.
#[derive(Debug, Clone, PartialEq)]
pub enum Reference {
    /// The same passes at their most accurate settings (these overrides):
    /// the setting only refines how they approximate what they compute.
    Highest(Overrides),
    /// The path tracer at this many samples per pixel, with the full
    /// materials: the setting changes the estimate of the light transport
    /// itself, or the materials (`quality.material_bytes`).
    PathTraced(u32),
}

/// One line of the plot: a setting swept, the others at the scene's values
/// except `with`.
#[derive(Debug, Clone)]
pub struct Series {
    /// A name for the plot's legend: the setting, and `with` when set.
    pub name: String,
    pub setting: &'static str,
    /// Cheapest first.
    pub values: Vec<Value>,
    /// Overrides every point of the series shares.
    pub with: Overrides,
    pub reference: Reference,
}

impl Series {
    /// The overrides of the point at `value`.
    pub fn point(&self, value: &Value) -> Overrides {
        let mut o = self.with.clone();
        o.insert(self.setting.to_owned(), value.clone());
        o
    }

    /// The overrides of the reference image.
    pub fn reference_overrides(&self) -> Overrides {
        match &self.reference {
            Reference::Highest(o) => o.clone(),
            // Undenoised: the reference is the converged estimate itself.
            Reference::PathTraced(spp) => Overrides::from([
                ("quality.renderer".to_owned(), Value::Text("path".into())),
                ("quality.path_spp".to_owned(), Value::Int(i64::from(*spp))),
                ("quality.denoise".to_owned(), Value::Bool(false)),
                ("quality.path_simplified_materials".to_owned(), Value::Bool(false)),
            ]),
        }
    }

    /// Whether a point's image accumulates one path-traced sample a frame,
    /// so that reaching it takes as many frames as its samples.
    pub fn accumulates(&self) -> bool {
        self.setting == "quality.path_spp"
    }
}

/// Powers of two from `from` to `to` inclusive.
fn doublings(from: i64, to: i64) -> Vec<Value> {
    std::iter::successors(Some(from), |v| Some(v * 2)).take_while(|v| *v <= to).map(Value::Int).collect()
}

/// The budgets (`quality.material_bytes`, its range by its step, cheapest
/// first) at which `materials`' instances compile to different simplified
/// definitions, each the cheapest budget of its result, up to the first at
/// which no instance is simplified (the raster's full materials); empty
/// when no budget of the range simplifies any.
fn budgets(materials: &Program) -> Vec<Value> {
    let Some(settings::Kind::Int { min, max, step }) = settings::find("quality.material_bytes").map(|s| s.kind) else {
        return Vec::new();
    };
    let used: std::collections::BTreeSet<usize> = materials.instances.iter().map(|i| i.definition as usize).collect();
    let definitions: Vec<_> = used.iter().filter_map(|&k| materials.definitions.get(k)).collect();
    let mut out = Vec::new();
    let mut last = None;
    for budget in (min..=max).step_by(step.max(1) as usize) {
        let simplified: Vec<_> = definitions.iter().map(|d| crate::material::simplify::simplify(d, budget as u32)).collect();
        let any = simplified.iter().any(|s| s.simplified());
        if !any && out.is_empty() {
            return out;
        }
        let compiled: Vec<_> = simplified.into_iter().map(|s| s.def).collect();
        if last.as_ref() != Some(&compiled) {
            out.push(Value::Int(budget));
            last = Some(compiled);
        }
        if !any {
            break;
        }
    }
    out
}

fn text(t: &str) -> Value {
    Value::Text(t.to_owned())
}

/// The series `scene` calls for: only settings that change its image (a
/// scene without media sweeps no volume setting, one whose `materials` ask
/// for no energy compensation no compensation). `reference_spp`: the path
/// tracer's samples for path-traced references.
pub fn series(scene: &Scene, materials: &Program, reference_spp: u32) -> Vec<Series> {
    let mut out = Vec::new();
    let overrides = |pairs: &[(&str, Value)]| -> Overrides { pairs.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect() };
    let mut add = |setting: &'static str, values: Vec<Value>, with: &[(&str, Value)], reference: Reference| {
        let with = overrides(with);
        let short = setting.trim_start_matches("quality.").trim_start_matches("post.");
        let mut name = short.to_owned();
        // The renderer is implied by the setting.
        for (k, v) in with.iter().filter(|(k, _)| *k != "quality.renderer") {
            name += &format!(", {}={v}", k.rsplit('.').next().unwrap_or(k));
        }
        // A second series of the same points is told apart by its
        // reference: the setting's value there.
        if out.iter().any(|s: &Series| s.name == name)
            && let Reference::Highest(o) = &reference
            && let Some(v) = o.get(setting)
        {
            name += &format!(", against {short}={v}");
        }
        out.push(Series { name, setting, values, with, reference });
    };
    let raster = ("quality.renderer", text("raster"));
    // The most accurate raster image: the setting at its best, the others
    // at the scene's values.
    let best = |setting: &str, v: Value| Reference::Highest(overrides(&[raster.clone(), (setting, v)]));
    if !scene.media.is_empty() {
        // Both estimators against one reference, so their errors compare.
        let reference = Reference::Highest(overrides(&[
            raster.clone(),
            ("quality.volume_steps", Value::Int(1024)),
            ("quality.volume_estimator", text("analytic")),
        ]));
        for estimator in settings::Estimator::NAMES {
            let with = [raster.clone(), ("quality.volume_estimator", text(estimator))];
            add("quality.volume_steps", doublings(4, 512), &with, reference.clone());
        }
        add(
            "quality.volume_shadow_steps",
            doublings(1, 32),
            std::slice::from_ref(&raster),
            best("quality.volume_shadow_steps", Value::Int(64)),
        );
        add("quality.volume_grid", doublings(8, 128), std::slice::from_ref(&raster), best("quality.volume_grid", Value::Int(256)));
        let resolutions = settings::VolumeResolution::NAMES.iter().rev().map(|r| text(r)).collect();
        add("quality.volume_resolution", resolutions, std::slice::from_ref(&raster), best("quality.volume_resolution", text("full")));
    }
    if !scene.objects.is_empty() {
        if !scene.lights.is_empty() {
            add(
                "quality.shadow_map_size",
                doublings(128, 2048),
                std::slice::from_ref(&raster),
                best("quality.shadow_map_size", Value::Int(4096)),
            );
            let radii = (0..=3).map(Value::Int).collect();
            add("quality.shadow_filter", radii, std::slice::from_ref(&raster), best("quality.shadow_filter", Value::Int(4)));
        }
        if scene.has_rect_lights() {
            // LTC's closed form against the area sampled through the BRDF.
            add(
                "quality.rect_lights",
                vec![text("ltc"), text("sampled")],
                std::slice::from_ref(&raster),
                best("quality.rect_lights", text("sampled")),
            );
        }
        // Only materials whose definition asks for compensation change with
        // it (`.mat` files and glTF materials, never the shorthand): what it
        // costs the lighting pass, and how far the image moves without it.
        let compensates =
            materials.instances.iter().any(|i| materials.definitions.get(i.definition as usize).is_some_and(|d| d.energy_compensation));
        if compensates {
            add(
                "quality.energy_compensation",
                vec![Value::Bool(false), Value::Bool(true)],
                std::slice::from_ref(&raster),
                best("quality.energy_compensation", Value::Bool(true)),
            );
        }
        // What the budget costs the raster (its G-buffer and lighting)
        // against the truth, the path tracer with the full materials; and
        // against the raster at the first budget that simplifies nothing,
        // where the raster's own approximations (shadow maps, the
        // environment's split sum) cancel and the simplification's error
        // is left. Only where some budget simplifies a material of the
        // scene.
        let budgets = budgets(materials);
        if let Some(full) = budgets.last().cloned() {
            add("quality.material_bytes", budgets.clone(), std::slice::from_ref(&raster), Reference::PathTraced(reference_spp));
            add("quality.material_bytes", budgets, std::slice::from_ref(&raster), best("quality.material_bytes", full));
        }
        let path = [("quality.renderer", text("path"))];
        if scene.denoiser.is_none() {
            add("quality.path_spp", doublings(1, 64), &path, Reference::PathTraced(reference_spp));
        } else {
            // The samples without the denoiser, then with it in each
            // precision (an override of the scene's [denoiser] like any other).
            let without = [path[0].clone(), ("quality.denoise", Value::Bool(false))];
            add("quality.path_spp", doublings(1, 64), &without, Reference::PathTraced(reference_spp));
            for precision in ["f32", "f16"] {
                let with = [path[0].clone(), ("quality.denoise", Value::Bool(true)), ("denoiser.precision", text(precision))];
                add("quality.path_spp", doublings(1, 64), &with, Reference::PathTraced(reference_spp));
            }
        }
    }
    // The same image either way: its cost, beside its quads.
    add(
        "post.two_triangles",
        vec![Value::Bool(true), Value::Bool(false)],
        &[],
        Reference::Highest(overrides(&[("post.two_triangles", Value::Bool(false))])),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loaded(name: &str) -> crate::loaded::Loaded {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
        crate::loaded::load_with(&path, &Overrides::new()).unwrap_or_else(|d| panic!("{d}"))
    }

    /// The series of a bundled scene.
    fn swept(name: &str) -> Vec<Series> {
        let l = loaded(name);
        series(&l.scene, &l.materials, 256)
    }

    /// Only what the scene calls for is swept: no volume series without
    /// media, no shadow-map series without lights; both estimators against
    /// one reference; every series' values cheapest first.
    #[test]
    fn a_scene_sweeps_only_the_settings_that_change_its_image() {
        let names = |s: &[Series]| s.iter().map(|s| s.name.clone()).collect::<Vec<_>>();
        let minimal = swept("minimal.toml");
        assert_eq!(names(&minimal), ["shadow_map_size", "shadow_filter", "path_spp", "two_triangles"]);
        let volume = swept("volume.toml");
        let steps: Vec<_> = volume.iter().filter(|s| s.setting == "quality.volume_steps").collect();
        assert_eq!(steps.len(), 2);
        assert_eq!(steps[0].reference, steps[1].reference, "one reference for both estimators");
        assert_eq!(steps[0].name, "volume_steps, volume_estimator=\"constant\"");
        let pattern = swept("pattern.toml");
        assert_eq!(names(&pattern), ["two_triangles"], "no geometry: nothing to path trace");
        for s in minimal.iter().chain(&volume) {
            let ints: Vec<i64> = s.values.iter().filter_map(|v| if let Value::Int(i) = v { Some(*i) } else { None }).collect();
            assert!(ints.windows(2).all(|w| w[0] < w[1]), "{}: cheapest first", s.name);
        }
        // With a [denoiser]: the samples without it, then with it in each precision.
        let mut denoised = loaded("minimal.toml");
        denoised.scene.denoiser = crate::scene::parse("d.toml", "[denoiser]\nweights = \"w.tza\"\n").unwrap().denoiser;
        let paths: Vec<_> = series(&denoised.scene, &denoised.materials, 256)
            .into_iter()
            .filter(|s| s.setting == "quality.path_spp")
            .map(|s| s.name)
            .collect();
        assert_eq!(
            paths,
            ["path_spp, denoise=false", "path_spp, precision=\"f32\", denoise=true", "path_spp, precision=\"f16\", denoise=true"]
        );
        let path = minimal.iter().find(|s| s.setting == "quality.path_spp").unwrap();
        assert!(path.accumulates());
        assert_eq!(path.reference_overrides()["quality.path_spp"], Value::Int(256));
    }

    /// Energy compensation is swept where a material asks for it: the
    /// showcase's library materials, off against on (the reference, so the
    /// "off" point's error is what compensation changes). The shorthand
    /// materials of `minimal.toml` never compensate: no series there (the
    /// test above).
    #[test]
    fn energy_compensation_is_swept_where_a_material_asks_for_it() {
        let showcase = swept("showcase.toml");
        let s = showcase.iter().find(|s| s.setting == "quality.energy_compensation").expect("a series for energy compensation");
        assert_eq!(s.values, [Value::Bool(false), Value::Bool(true)], "off first: the cheaper");
        assert_eq!(s.with["quality.renderer"], text("raster"));
        assert_eq!(s.reference_overrides()["quality.energy_compensation"], Value::Bool(true));
        assert!(settings::find(s.setting).is_some_and(|d| d.affects.contains(&"lighting")), "its time is the lighting pass's");
    }

    /// The budget is swept where some budget of its range simplifies a
    /// material of the scene (the showcase's car paint, 56 B, and rust,
    /// 48 B), cheapest first, each budget a different simplified program,
    /// the last the first at which nothing is simplified; against the path
    /// tracer with the full materials, even when the scene renders the
    /// simplified ones in its path tracer. The shorthand materials of
    /// `minimal.toml` fit every budget: no series there (the first test).
    #[test]
    fn the_budget_is_swept_where_a_budget_simplifies_a_material() {
        let mut showcase = loaded("showcase.toml");
        showcase.scene.quality.path_simplified_materials = true;
        let all = series(&showcase.scene, &showcase.materials, 256);
        let s = all.iter().find(|s| s.setting == "quality.material_bytes").expect("a series for the budget");
        let ints: Vec<i64> = s.values.iter().map(|v| if let Value::Int(i) = v { *i } else { panic!("{v}") }).collect();
        assert!(ints.len() >= 3 && ints[0] == 24 && ints.windows(2).all(|w| w[0] < w[1]), "{ints:?}");
        assert_eq!(ints.last(), Some(&56), "up to the car paint's full size: {ints:?}");
        assert_eq!(s.with["quality.renderer"], text("raster"));
        assert_eq!(s.reference, Reference::PathTraced(256));
        let reference = s.reference_overrides();
        assert_eq!(reference["quality.renderer"], text("path"));
        assert_eq!(reference["quality.path_simplified_materials"], Value::Bool(false), "the full materials: the truth");
        assert_eq!(s.name, "material_bytes");
        // The budget's own error: the same points against the raster at
        // the first budget that simplifies nothing.
        let own: Vec<&Series> = all.iter().filter(|s| s.setting == "quality.material_bytes").collect();
        assert_eq!(own.len(), 2);
        assert_eq!((own[1].values.clone(), own[1].with.clone()), (s.values.clone(), s.with.clone()));
        let reference = own[1].reference_overrides();
        assert_eq!((reference["quality.renderer"].clone(), reference["quality.material_bytes"].clone()), (text("raster"), Value::Int(56)));
        assert_eq!(own[1].name, "material_bytes, against material_bytes=56");
    }
}
