//! Live overrides: values set from the browser on top of the scene file.
//! They are applied by editing the file's text with toml_edit, so the
//! rendered scene and a saved file are the same document, and saving keeps
//! every comment, blank line and key order the user wrote.

use std::collections::BTreeMap;

use serde::Serialize;
use toml_edit::{DocumentMut, Item, Table, Value as TomlValue};

use super::settings::Value;
use super::settings::{self, Kind, SETTINGS};
use super::{LightKind, Scene};

/// Overrides by path, e.g. `post.exposure_ev`, `lights[1].intensity`.
pub type Overrides = BTreeMap<String, Value>;

#[derive(Debug, Clone, PartialEq, Eq)]
enum Seg {
    Key(String),
    Index(usize),
}

fn parse_path(path: &str) -> Result<Vec<Seg>, String> {
    let bad = || format!("`{path}` is not a scene path (expected e.g. `post.exposure_ev` or `lights[0].intensity`)");
    let mut segs = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(bad());
        }
        segs.push(Seg::Key(key.to_owned()));
        while !rest.is_empty() {
            let (n, after) = rest.split_once(']').ok_or_else(bad)?;
            segs.push(Seg::Index(n.parse().map_err(|_| bad())?));
            rest = after.strip_prefix('[').unwrap_or(after);
            if !after.is_empty() && !after.starts_with('[') {
                return Err(bad());
            }
        }
    }
    Ok(segs)
}

fn toml_value(v: &Value) -> TomlValue {
    match v {
        Value::Bool(b) => (*b).into(),
        Value::Int(i) => (*i).into(),
        Value::Float(f) => (*f).into(),
        Value::Text(s) => s.as_str().into(),
        Value::List(l) => l.iter().copied().collect::<toml_edit::Array>().into(),
    }
}

/// Applies `overrides` to the scene text, keeping its layout. The result is
/// what renders and what "save" writes.
pub fn apply(text: &str, overrides: &Overrides) -> Result<String, String> {
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| e.message().to_owned())?;
    for (path, value) in overrides {
        // A table setting's value is checked as the file's would be; the
        // rest are checked when the scene is read.
        let segs = parse_path(path)?;
        settings::find(path).map_or(Ok(()), |s| s.check(value)).map_err(|e| format!("{path}: {e}"))?;
        set(doc.as_table_mut(), &segs, value, false).map_err(|e| format!("{path}: {e}"))?;
    }
    Ok(doc.to_string())
}

/// Sets `path` below `table`; `in_entry`: `table` is an entry of an array
/// of tables (`[[materials]]`), where a missing table is written inline
/// (`params = { roughness = 0.3 }`), as such entries write them.
fn set(table: &mut Table, path: &[Seg], value: &Value, in_entry: bool) -> Result<(), String> {
    let Some((Seg::Key(key), rest)) = path.split_first() else { return Err("a path starts with a key".into()) };
    if rest.is_empty() {
        let new = toml_value(value);
        match table.get_mut(key) {
            Some(Item::Value(old)) => replace_number(old, new, value),
            Some(_) => return Err(format!("`{key}` is a table, not a value")),
            None => {
                table.insert(key, Item::Value(new));
            }
        }
        return Ok(());
    }
    match (rest.first(), table.get_mut(key)) {
        (Some(Seg::Index(i)), Some(Item::ArrayOfTables(a))) => {
            let t = a.get_mut(*i).ok_or_else(|| format!("`{key}` has no entry {i}"))?;
            set(t, &rest[1..], value, true)
        }
        (Some(Seg::Index(i)), Some(Item::Value(TomlValue::Array(a)))) if rest.len() == 1 => {
            let slot = a.get_mut(*i).ok_or_else(|| format!("`{key}` has no element {i}"))?;
            replace(slot, toml_value(value));
            Ok(())
        }
        (Some(Seg::Key(name)), Some(Item::Value(TomlValue::InlineTable(t)))) if rest.len() == 1 => {
            match t.get_mut(name) {
                Some(old) => replace_number(old, toml_value(value), value),
                None => {
                    t.insert(name, toml_value(value));
                }
            }
            Ok(())
        }
        (Some(Seg::Key(name)), None) if in_entry && rest.len() == 1 => {
            let mut t = toml_edit::InlineTable::new();
            t.insert(name, toml_value(value));
            table.insert(key, Item::Value(t.into()));
            Ok(())
        }
        (Some(Seg::Key(_)), Some(Item::Table(t))) => set(t, rest, value, false),
        (Some(Seg::Key(_)), None) => {
            let mut t = Table::new();
            t.set_implicit(false);
            table.insert(key, Item::Table(t));
            let Some(Item::Table(t)) = table.get_mut(key) else { unreachable!("inserted above") };
            set(t, rest, value, false)
        }
        _ => Err(format!("`{key}` does not have that shape")),
    }
}

/// `replace`, but a whole number set where the file has a float stays a
/// float (`1.0`, not `1`): JSON has one number type.
fn replace_number(old: &mut TomlValue, mut new: TomlValue, value: &Value) {
    if let (TomlValue::Float(_), Value::Int(i)) = (&*old, value) {
        new = (*i as f64).into();
    }
    replace(old, new);
}

/// Puts `new` in `old`'s place with `old`'s comment and spacing. A
/// trailing comment keeps its column: the spaces before it shrink or grow
/// by what the value's width changed (one stays, however long the value).
fn replace(old: &mut TomlValue, mut new: TomlValue) {
    let width = |v: &TomlValue| {
        let mut bare = v.clone();
        bare.decor_mut().clear();
        bare.to_string().chars().count() as isize
    };
    let grown = width(&new) - width(old);
    let mut decor = old.decor().clone();
    if let Some(suffix) = decor.suffix().and_then(|s| s.as_str()) {
        let rest = suffix.trim_start_matches(' ');
        if rest.starts_with('#') {
            let spaces = (suffix.len() - rest.len()) as isize;
            decor.set_suffix(format!("{}{rest}", " ".repeat((spaces - grown).max(1) as usize)));
        }
    }
    *new.decor_mut() = decor;
    *old = new;
}

/// `overrides` less those equal to the file's own value (`file`: the
/// controls of the scene the file alone gives): a control set back to what
/// the file says leaves nothing unsaved. Numbers are compared as the scene
/// holds them (f32), so `1` equals `1.0` and a slider's `0.30000000000000004`
/// equals `0.3`.
pub fn without_file_values(mut overrides: Overrides, file: &[Control]) -> Overrides {
    let same = |a: &Value, b: &Value| match (settings::number(a), settings::number(b)) {
        (Some(x), Some(y)) => x as f32 == y as f32,
        _ => a == b,
    };
    overrides.retain(|path, v| !file.iter().any(|c| c.path == *path && same(&c.value, v)));
    overrides
}

/// One live control the browser shows for the current scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Control {
    pub path: String,
    pub label: String,
    pub kind: ControlKind,
    pub value: Value,
    /// The render passes whose output it changes.
    pub affects: Vec<&'static str>,
}

/// A control as the protocol sends it: every key of every kind, `null`
/// where the kind has none (PROTOCOL.md: no key is ever left out).
impl Serialize for Control {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let (kind, range, options) = match &self.kind {
            ControlKind::Slider { min, max, step } => ("slider", Some((min, max, step)), None),
            ControlKind::Toggle => ("toggle", None, None),
            ControlKind::Choice { options } => ("choice", None, Some(options)),
        };
        let mut out = s.serialize_struct("Control", 9)?;
        out.serialize_field("path", &self.path)?;
        out.serialize_field("label", &self.label)?;
        out.serialize_field("kind", kind)?;
        out.serialize_field("min", &range.map(|r| r.0))?;
        out.serialize_field("max", &range.map(|r| r.1))?;
        out.serialize_field("step", &range.map(|r| r.2))?;
        out.serialize_field("options", &options)?;
        out.serialize_field("value", &self.value)?;
        out.serialize_field("affects", &self.affects)?;
        out.end()
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum ControlKind {
    Slider { min: f64, max: f64, step: f64 },
    Toggle,
    Choice { options: Vec<String> },
}

impl From<Kind> for ControlKind {
    fn from(k: Kind) -> Self {
        match k {
            Kind::Toggle => ControlKind::Toggle,
            Kind::Int { min, max, step } => ControlKind::Slider { min: min as f64, max: max as f64, step: step as f64 },
            Kind::Float { min, max, step } => ControlKind::Slider { min, max, step },
            Kind::Choice(options) => ControlKind::Choice { options: options.iter().map(|o| (*o).to_owned()).collect() },
        }
    }
}

/// The controls for `scene`: each setting of the table its scene shows,
/// then the environment's intensity and each light's. (`[environment]` is
/// a plain scene section, checked in `validate`, not a table of settings.)
/// `affected` turns a setting's `affects` into pass names
/// (`render::passes::affected`, which knows the passes).
pub fn controls(scene: &Scene, affected: fn(&[&'static str]) -> Vec<&'static str>) -> Vec<Control> {
    let mut out: Vec<Control> = SETTINGS
        .iter()
        .filter(|s| (s.shown_when)(scene))
        .map(|s| Control {
            path: s.path.into(),
            label: s.label.into(),
            kind: s.kind.into(),
            value: (s.get)(scene),
            affects: affected(s.affects),
        })
        .collect();
    out.push(Control {
        path: "environment.intensity".into(),
        label: "Environment intensity".into(),
        kind: ControlKind::Slider { min: 0.0, max: 10.0, step: 0.05 },
        value: settings::float(scene.environment.intensity),
        affects: vec!["lighting"],
    });
    for (i, l) in scene.lights.iter().enumerate() {
        let kind = match l.kind {
            LightKind::Directional { .. } => "directional",
            LightKind::Point { .. } => "point",
            LightKind::Spot { .. } => "spot",
            LightKind::Rect { .. } => "rect",
        };
        out.push(Control {
            path: format!("lights[{i}].intensity"),
            label: format!("Light {i} ({kind}) intensity"),
            kind: ControlKind::Slider { min: 0.0, max: 100.0, step: 0.1 },
            value: settings::float(l.intensity),
            affects: vec!["lighting", "volume_march", "volumes"],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "# My scene\n[post]\nexposure_ev = 0.0 # stops\ntonemap = \"aces\"\n\n[[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 5.0\n";

    #[test]
    fn apply_keeps_comments_and_layout() {
        let mut o = Overrides::new();
        o.insert("lights[0].intensity".into(), Value::Float(2.0));
        o.insert("quality.volume_steps".into(), Value::Int(12));
        o.insert("post.exposure_ev".into(), Value::Int(2));
        let out = apply(TEXT, &o).unwrap();
        assert!(out.starts_with("# My scene\n[post]\nexposure_ev = 2.0 # stops\ntonemap = \"aces\"\n\n[[lights]]\n"), "{out}");
        assert!(out.contains("intensity = 2.0\n"), "{out}");
        assert!(out.contains("[quality]\nvolume_steps = 12\n"), "{out}");
        let s = crate::scene::parse("s.toml", &out).unwrap();
        assert_eq!(s.post.exposure_ev, 2.0);
        assert_eq!(s.quality.volume_steps, 12);
    }

    #[test]
    fn trailing_comments_keep_their_column() {
        let text = "[post]\nexposure_ev = 0.0    # stops\nbloom = 0.04 # tight\n[camera]\nposition = [0.0, 1.0,  2.0] # eye\n";
        let mut o = Overrides::new();
        o.insert("post.exposure_ev".into(), Value::Float(-12.5));
        o.insert("post.bloom".into(), Value::Float(1.0));
        let out = apply(text, &o).unwrap();
        let column = |out: &str, key: &str| out.lines().find(|l| l.starts_with(key)).and_then(|l| l.find('#'));
        assert_eq!(column(&out, "exposure_ev"), column(text, "exposure_ev"), "{out}");
        assert!(out.contains("exposure_ev = -12.5  # stops\n"), "{out}");
        assert_eq!(column(&out, "bloom"), column(text, "bloom"), "a shorter value pads: {out}");
        assert!(out.contains("bloom = 1.0  # tight\n"), "{out}");
        o.insert("post.exposure_ev".into(), Value::Float(-12.345678));
        assert!(apply(text, &o).unwrap().contains("exposure_ev = -12.345678 # stops\n"), "one space stays");
    }

    #[test]
    fn an_override_equal_to_the_file_is_dropped() {
        let s = crate::scene::parse("s.toml", TEXT).unwrap();
        let file = controls(&s, crate::render::passes::affected);
        let mut o = Overrides::new();
        o.insert("post.exposure_ev".into(), Value::Int(0));
        o.insert("post.tonemap".into(), Value::Text("aces".into()));
        o.insert("lights[0].intensity".into(), Value::Float(5.000000000000001));
        o.insert("post.two_triangles".into(), Value::Bool(true));
        let kept = without_file_values(o, &file);
        assert_eq!(kept.keys().collect::<Vec<_>>(), ["post.two_triangles"]);
    }

    /// A material parameter's path reaches an inline `params` table (its
    /// layout kept), a `[materials.params]` sub-table, or an entry with
    /// none yet (written inline); a colour is an array.
    #[test]
    fn material_parameters_are_set_in_any_params_table() {
        let entry = |params: &str| {
            format!("# lib\n[[materials]]\nname = \"a\"\n\n[[materials]]\nname = \"b\" # second\nfile = \"m.mat\"\n{params}")
        };
        let mut o = Overrides::new();
        o.insert("materials[1].params.rough".into(), Value::Int(1));
        o.insert("materials[1].params.tint".into(), Value::List(vec![0.5, 0.25, 1.0]));
        let out = apply(&entry("params = { rough = 0.5, other = 2.0 } # p\n"), &o).unwrap();
        assert!(
            out.ends_with("name = \"b\" # second\nfile = \"m.mat\"\nparams = { rough = 1.0, other = 2.0 , tint = [0.5, 0.25, 1.0] } # p\n"),
            "{out}"
        );
        let out = apply(&entry("\n[materials.params]\nrough = 0.5 # r\n"), &o).unwrap();
        assert!(out.ends_with("[materials.params]\nrough = 1.0 # r\ntint = [0.5, 0.25, 1.0]\n"), "{out}");
        let out = apply(&entry(""), &o).unwrap();
        assert!(out.ends_with("file = \"m.mat\"\nparams = { rough = 1, tint = [0.5, 0.25, 1.0] }\n"), "{out}");
        assert!(out.starts_with("# lib\n[[materials]]\nname = \"a\"\n"), "{out}");
        o.insert("materials[2].params.rough".into(), Value::Float(1.0));
        assert_eq!(apply(&entry(""), &o).unwrap_err(), "materials[2].params.rough: `materials` has no entry 2");
    }

    #[test]
    fn bad_paths_and_shapes_are_refused() {
        for path in ["", "post..x", "lights[x].intensity", "lights[5].intensity", "post.exposure_ev[0]", "lights.intensity"] {
            let mut o = Overrides::new();
            o.insert(path.into(), Value::Float(1.0));
            assert!(apply(TEXT, &o).is_err(), "{path}");
        }
    }

    #[test]
    fn controls_follow_the_scene() {
        let s = crate::scene::parse("s.toml", TEXT).unwrap();
        let c = controls(&s, crate::render::passes::affected);
        assert!(c.iter().any(|c| c.path == "lights[0].intensity" && c.value == Value::Float(5.0)));
        assert!(!c.iter().any(|c| c.path == "quality.volume_steps"), "no media, no volume controls");
    }
}
