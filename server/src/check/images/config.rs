//! The image cases of `loupe.toml`, each an `[[images]]` table:
//!
//! ```toml
//! [[images]]
//! scene = "scenes/showcase.toml"
//! name = "showcase"                    # default: scene stem, renderer, size
//! size = "320x180"                     # default: DEFAULT_SIZE
//! outputs = ["tonemap/color"]          # default: the frame's final output
//! set = { "quality.volume_steps" = 32 }
//! renderer = "path"                    # or "raster"; default: the scene's
//! spp = 4                              # the path tracer's samples
//! threshold = { flip_mean = 0.01, flip_p99 = 0.1 }
//! [images.adapter."llvmpipe"]          # on adapters whose name holds this
//! flip_mean = 0.02
//! ```
//!
//! Every unknown key and bad value is a `project-file` diagnostic at its
//! line, as in `[check]`. What only rendering can tell (an output the frame
//! lacks, a scene that fails to load) is the case's failure, at its line.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Serialize;
use toml_edit::{Item, TableLike, Value};

use super::super::spans::{Source, span_of, strings};
use crate::diag::{Diagnostic, Location};
use crate::scene::overrides::Overrides;
use crate::scene::settings::Value as Setting;

const KEYS: &[&str] = &["name", "scene", "size", "outputs", "set", "renderer", "spp", "threshold", "adapter"];

/// A case's size when it names none: small enough that the bundled cases
/// render in seconds on lavapipe.
pub const DEFAULT_SIZE: (u32, u32) = (320, 180);

/// What a case allows when it sets no `threshold`. A mean of 0.01 is a
/// difference FLIP's authors call hard to see; the 99th percentile lets 1%
/// of pixels differ more (edges rasterised differently by another adapter).
pub const DEFAULT_THRESHOLD: Threshold = Threshold { flip_mean: 0.01, flip_p99: 0.1 };

/// The most a case's FLIP mean and 99th percentile may be.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Threshold {
    pub flip_mean: f64,
    pub flip_p99: f64,
}

/// `[images.adapter."KEY"]`: the threshold on adapters that match `key`.
#[derive(Debug, Clone, PartialEq)]
pub struct AdapterThreshold {
    pub key: String,
    pub flip_mean: Option<f64>,
    pub flip_p99: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Stable and unique: names the references' folder and the result.
    pub name: String,
    /// Joined to the project root.
    pub scene: PathBuf,
    pub size: (u32, u32),
    /// `pass/output` names with where each is written; empty: the final
    /// output.
    pub outputs: Vec<(String, Location)>,
    /// `set`, `renderer` and `spp`, as `loupe render --set` takes them.
    pub overrides: Overrides,
    pub threshold: Threshold,
    pub adapters: Vec<AdapterThreshold>,
    /// The case's `[[images]]` line.
    pub at: Location,
}

impl Case {
    /// The threshold on `adapter` (as `Gpu::adapter_name` writes it, which
    /// ends in the device type: `llvmpipe (…) (Vulkan, Cpu)`): the first
    /// adapter table whose key the name holds, ignoring case, over the
    /// case's own; with that key.
    pub fn threshold_on(&self, adapter: &str) -> (Threshold, Option<&str>) {
        let name = adapter.to_lowercase();
        match self.adapters.iter().find(|a| name.contains(&a.key.to_lowercase())) {
            Some(a) => (
                Threshold {
                    flip_mean: a.flip_mean.unwrap_or(self.threshold.flip_mean),
                    flip_p99: a.flip_p99.unwrap_or(self.threshold.flip_p99),
                },
                Some(&a.key),
            ),
            None => (self.threshold, None),
        }
    }
}

/// Parses the top-level `images` item; `key_span` is its key's.
pub fn parse(source: &Source, item: &Item, key_span: Option<Range<usize>>, root: &Path) -> Result<Vec<Case>, Diagnostic> {
    let Some(tables) = item.as_array_of_tables() else {
        return Err(source.error(span_of(item).or(key_span), "`images` must be an array of tables: [[images]]".to_owned()));
    };
    let mut cases: Vec<Case> = Vec::new();
    for table in tables.iter() {
        let case = parse_case(source, table, root)?;
        if cases.iter().any(|c| c.name == case.name) {
            return Err(source.error(table.span(), format!("a second image case named `{}`; give one of them a `name`", case.name)));
        }
        cases.push(case);
    }
    Ok(cases)
}

fn parse_case(source: &Source, table: &toml_edit::Table, root: &Path) -> Result<Case, Diagnostic> {
    let at = source.location(table.span());
    let error = |span: Option<Range<usize>>, message: String| source.error(span.or(table.span()), message);
    let (mut name, mut scene, mut size, mut outputs) = (None, None, None, Vec::new());
    let (mut overrides, mut renderer, mut spp) = (Overrides::new(), None, None);
    let (mut threshold, mut adapters) = (DEFAULT_THRESHOLD, Vec::new());
    for (key, item) in table.iter() {
        let key_span = table.key(key).and_then(|k| k.span());
        if key == "threshold" || key == "adapter" {
            let Some(t) = item.as_table_like() else {
                return Err(error(span_of(item).or(key_span), format!("`{key}` must be a table")));
            };
            if key == "threshold" {
                let (mean, p99) = thresholds(source, t)?;
                threshold = Threshold { flip_mean: mean.unwrap_or(threshold.flip_mean), flip_p99: p99.unwrap_or(threshold.flip_p99) };
            } else {
                for (adapter, item) in t.iter() {
                    let span = t.get_key_value(adapter).and_then(|(k, _)| k.span());
                    let Some(inner) = item.as_table_like() else {
                        return Err(error(span, format!("`adapter.\"{adapter}\"` must be a table of thresholds")));
                    };
                    let (flip_mean, flip_p99) = thresholds(source, inner)?;
                    adapters.push(AdapterThreshold { key: adapter.to_owned(), flip_mean, flip_p99 });
                }
            }
            continue;
        }
        if key == "set" {
            let Some(t) = item.as_table_like() else {
                return Err(error(span_of(item).or(key_span), "`set` must be a table of scene values".to_owned()));
            };
            for (path, item) in t.iter() {
                let value = item.as_value().and_then(setting);
                let span = span_of(item).or_else(|| t.get_key_value(path).and_then(|(k, _)| k.span()));
                let value = value.ok_or_else(|| error(span, format!("`{path}` must be a boolean, number, string or array of numbers")))?;
                overrides.insert(path.to_owned(), value);
            }
            continue;
        }
        let Some(value) = item.as_value() else {
            return Err(error(span_of(item).or(key_span), format!("`{key}` must be a value, not a table")));
        };
        let bad = |what: &str| error(value.span(), format!("`{key}` must be {what}"));
        match key {
            "name" => {
                let n = value.as_str().filter(|n| valid_name(n));
                name = Some(n.ok_or_else(|| bad("a name of letters, digits, `-`, `_` and `.`, not starting with `.`"))?.to_owned());
            }
            "scene" => scene = Some(value.as_str().ok_or_else(|| bad("a scene file's path"))?.to_owned()),
            "size" => {
                let s = value.as_str().ok_or_else(|| bad("\"WIDTHxHEIGHT\""))?;
                size = Some(crate::scene::parse_size(s).map_err(|e| error(value.span(), format!("`size`: {e}")))?);
            }
            "outputs" => {
                let items = strings(value).ok_or_else(|| bad("an array of `pass/output` names"))?;
                for (output, span) in items {
                    if !output.contains('/') {
                        return Err(error(span, format!("`{output}` is not a `pass/output` name, such as \"tonemap/color\"")));
                    }
                    outputs.push((output, source.location(span)));
                }
            }
            "renderer" => {
                let r = value.as_str().filter(|r| ["raster", "path"].contains(r));
                renderer = Some(r.ok_or_else(|| bad("\"raster\" or \"path\""))?.to_owned());
            }
            "spp" => {
                let n = value.as_integer().filter(|n| (1..=4096).contains(n));
                spp = Some((n.ok_or_else(|| bad("a whole number of samples from 1 to 4096"))?, value.span()));
            }
            _ => return Err(error(key_span, format!("unknown key `{key}` in [[images]]; known keys: {}", KEYS.join(", ")))),
        }
    }
    let scene = scene.ok_or_else(|| error(None, "an image case needs a `scene`".to_owned()))?;
    if let Some((n, span)) = spp {
        if renderer.as_deref() != Some("path") {
            return Err(error(span, "`spp` counts the path tracer's samples: set `renderer = \"path\"` with it".to_owned()));
        }
        overrides.insert("quality.path_spp".into(), Setting::Int(n));
    }
    if let Some(r) = &renderer {
        overrides.insert("quality.renderer".into(), Setting::Text(r.clone()));
    }
    let size = size.unwrap_or(DEFAULT_SIZE);
    let name = name.unwrap_or_else(|| {
        let stem = Path::new(&scene).file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
        let renderer = renderer.as_ref().map(|r| format!("-{r}")).unwrap_or_default();
        format!("{stem}{renderer}-{}x{}", size.0, size.1)
    });
    Ok(Case { name, scene: root.join(scene), size, outputs, overrides, threshold, adapters, at })
}

/// `flip_mean` and `flip_p99` of a threshold table, each in [0, 1].
fn thresholds(source: &Source, t: &dyn TableLike) -> Result<(Option<f64>, Option<f64>), Diagnostic> {
    let (mut mean, mut p99) = (None, None);
    for (key, item) in t.iter() {
        let key_span = t.get_key_value(key).and_then(|(k, _)| k.span());
        let slot = match key {
            "flip_mean" => &mut mean,
            "flip_p99" => &mut p99,
            _ => return Err(source.error(key_span, format!("unknown threshold `{key}`; known: flip_mean, flip_p99"))),
        };
        let value = item.as_value();
        let number = value.and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)));
        match number {
            Some(n) if (0.0..=1.0).contains(&n) => *slot = Some(n),
            _ => {
                let span = value.and_then(Value::span).or(key_span);
                return Err(source.error(span, format!("`{key}` must be a number from 0 to 1 (FLIP's range)")));
            }
        }
    }
    Ok((mean, p99))
}

/// A `set` value as the scene's overrides type it.
fn setting(value: &Value) -> Option<Setting> {
    match value {
        Value::Boolean(b) => Some(Setting::Bool(*b.value())),
        Value::Integer(i) => Some(Setting::Int(*i.value())),
        Value::Float(f) => Some(Setting::Float(*f.value())),
        Value::String(s) => Some(Setting::Text(s.value().clone())),
        Value::Array(a) => {
            a.iter().map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))).collect::<Option<_>>().map(Setting::List)
        }
        _ => None,
    }
}

/// A case name is a folder's name under the references.
fn valid_name(name: &str) -> bool {
    !name.is_empty() && !name.starts_with('.') && name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
}

#[cfg(test)]
mod tests;
