//! `loupe.toml`, the project file at the project root: its `[check]` table
//! sets `loupe check`'s defaults, and command-line flags override them.
//!
//! ```toml
//! [check]
//! paths = ["shaders", "scenes"]        # relative to the project root
//! capabilities = ["float64"]           # or "all"
//! deny_warnings = true
//! deny_debug_printf = true
//! format = "github"
//! references = "tests/images"         # the image gate's references
//!
//! [[images]]                           # an image case (images::config)
//! scene = "scenes/minimal.toml"
//! ```
//!
//! Every unknown key and bad value is a diagnostic at its file:line:col.

use std::ops::Range;
use std::path::{Path, PathBuf};

use naga::valid::Capabilities;

use super::capabilities;
use super::format::Format;
use super::images::config::{self as image_config, Case};
use super::spans::{Source, span_of, strings};
use crate::diag::{Code, Diagnostic, Location};

/// The project file's name; a `.toml` of this name is never a scene.
pub const FILE: &str = "loupe.toml";

const CHECK_KEYS: &[&str] = &["paths", "capabilities", "deny_warnings", "deny_debug_printf", "format", "references"];

/// Where the image gate's references live when `references` is not set.
pub const DEFAULT_REFERENCES: &str = "tests/images";

/// `loupe check`'s defaults from the project file; `None`: not set there.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct CheckDefaults {
    /// Already joined to the project root.
    pub paths: Option<Vec<PathBuf>>,
    pub capabilities: Option<Capabilities>,
    pub deny_warnings: Option<bool>,
    pub deny_debug_printf: Option<bool>,
    pub format: Option<Format>,
    /// The image gate's reference folder, joined to the project root
    /// (`DEFAULT_REFERENCES` when not set).
    pub references: Option<PathBuf>,
    /// The `[[images]]` cases, in file order.
    pub images: Vec<Case>,
}

/// Reads `root/loupe.toml`; no file means no defaults.
pub fn read(root: &Path) -> Result<CheckDefaults, Diagnostic> {
    let path = root.join(FILE);
    let display = crate::diag::display_path(&path);
    match std::fs::read_to_string(&path) {
        Ok(text) => parse(&display, &text, root),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(CheckDefaults::default()),
        Err(e) => Err(Diagnostic::error(Code::Io, format!("cannot read the project file: {e}")).at(Location::file_start(&display))),
    }
}

/// Parses the project file's text; `display` names it in diagnostics and
/// relative paths are joined to `root`.
pub fn parse(display: &str, text: &str, root: &Path) -> Result<CheckDefaults, Diagnostic> {
    let source = Source::new(display, text);
    let error = |span: Option<Range<usize>>, message: String| source.error(span, message);
    let doc = toml_edit::Document::parse(text).map_err(|e| error(e.span(), e.message().trim().to_owned()))?;
    let mut out = CheckDefaults::default();
    for (key, item) in doc.as_table().iter() {
        let key_span = doc.as_table().key(key).and_then(|k| k.span());
        if key == "images" {
            out.images = image_config::parse(&source, item, key_span, root)?;
            continue;
        }
        if key != "check" {
            return Err(error(key_span, format!("unknown table `{key}`; {FILE} has only [check] and [[images]]")));
        }
        let Some(check) = item.as_table() else {
            return Err(error(span_of(item).or(key_span), "`check` must be a table: [check]".to_owned()));
        };
        for (key, item) in check.iter() {
            let key_span = check.key(key).and_then(|k| k.span());
            let value = item
                .as_value()
                .ok_or_else(|| error(span_of(item).or(key_span.clone()), format!("`{key}` must be a value, not a table")))?;
            let bad = |what: &str| error(value.span(), format!("`{key}` must be {what}"));
            match key {
                "paths" => {
                    let items = strings(value).ok_or_else(|| bad("an array of paths"))?;
                    out.paths = Some(items.iter().map(|(p, _)| root.join(p)).collect());
                }
                "capabilities" => {
                    let items = match value.as_str() {
                        Some(s) => vec![(s.to_owned(), value.span())],
                        None => strings(value).ok_or_else(|| bad("an array of capability names, or \"all\""))?,
                    };
                    let mut caps = capabilities::baseline();
                    for (name, span) in items {
                        caps |= capabilities::parse([name.as_str()]).map_err(|e| error(span, e))?;
                    }
                    out.capabilities = Some(caps);
                }
                "deny_warnings" => out.deny_warnings = Some(value.as_bool().ok_or_else(|| bad("true or false"))?),
                "deny_debug_printf" => out.deny_debug_printf = Some(value.as_bool().ok_or_else(|| bad("true or false"))?),
                "format" => {
                    let name = value.as_str().ok_or_else(|| bad("a string"))?;
                    let format = <Format as clap::ValueEnum>::from_str(name, false)
                        .map_err(|_| bad(&format!("one of \"human\", \"json\", \"github\", \"sarif\", \"junit\", not \"{name}\"")))?;
                    out.format = Some(format);
                }
                "references" => out.references = Some(root.join(value.as_str().ok_or_else(|| bad("a folder's path"))?)),
                _ => return Err(error(key_span, format!("unknown key `{key}` in [check]; known keys: {}", CHECK_KEYS.join(", ")))),
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<CheckDefaults, Diagnostic> {
        parse("loupe.toml", text, Path::new("/proj"))
    }

    /// The diagnostic's code, line and column.
    fn located(text: &str) -> (Code, u32, u32, String) {
        let d = parsed(text).expect_err("must be refused");
        let l = d.location.clone().expect("located");
        assert_eq!(l.file, "loupe.toml");
        (d.code, l.line, l.column, d.message)
    }

    #[test]
    fn every_key_sets_its_default() {
        let d = parsed(
            "# project\n[check]\npaths = [\"src/shaders\", \"/abs\"]\ncapabilities = [\"float64\", \"shader-int64\"]\ndeny_warnings = true\ndeny_debug_printf = true\nformat = \"sarif\"\nreferences = \"refs\"\n",
        )
        .unwrap();
        assert_eq!(d.paths, Some(vec![PathBuf::from("/proj/src/shaders"), PathBuf::from("/abs")]));
        let caps = d.capabilities.unwrap();
        assert!(caps.contains(Capabilities::FLOAT64 | Capabilities::SHADER_INT64) && !caps.contains(Capabilities::SUBGROUP));
        assert_eq!((d.deny_warnings, d.deny_debug_printf), (Some(true), Some(true)));
        assert_eq!(d.format, Some(Format::Sarif));
        assert_eq!(d.references, Some(PathBuf::from("/proj/refs")));
        assert_eq!(parsed("[check]\ncapabilities = \"all\"\n").unwrap().capabilities, Some(Capabilities::all()));
        assert_eq!(parsed("").unwrap(), CheckDefaults::default());
        assert_eq!(parsed("[check]\n").unwrap(), CheckDefaults::default());
    }

    #[test]
    fn unknown_keys_and_bad_values_are_located() {
        let (code, line, col, msg) = located("[check]\ndeny_warnings = false\nfromat = \"json\"\n");
        assert_eq!((code, line, col), (Code::ProjectFile, 3, 1));
        assert!(msg.contains("unknown key `fromat`") && msg.contains("format"), "{msg}");
        let (_, line, col, msg) = located("[serve]\nport = 1\n");
        assert!(msg.contains("[check] and [[images]]"), "{msg}");
        assert_eq!((line, col), (1, 2), "{msg}");
        let (_, line, col, msg) = located("[check]\ndeny_warnings = \"yes\"\n");
        assert_eq!((line, col), (2, 17));
        assert!(msg.contains("true or false"), "{msg}");
        let (_, line, col, msg) = located("[check]\nformat = \"xml\"\n");
        assert_eq!((line, col), (2, 10));
        assert!(msg.contains("\"junit\"") && msg.contains("not \"xml\""), "{msg}");
        let (_, line, col, msg) = located("[check]\ncapabilities = [\"float64\", \"f64\"]\n");
        assert_eq!((line, col), (2, 28), "the bad name itself");
        assert!(msg.contains("unknown capability `f64`") && msg.contains("shader-int64"), "{msg}");
        let (_, line, col, _) = located("[check]\npaths = \"shaders\"\n");
        assert_eq!((line, col), (2, 9));
        let (_, line, col, _) = located("[check]\npaths = [1]\n");
        assert_eq!((line, col), (2, 9));
        let (_, line, _, msg) = located("check = 3\n");
        assert_eq!(line, 1);
        assert!(msg.contains("must be a table"), "{msg}");
        // Not TOML at all.
        let (code, line, _, _) = located("[check\n");
        assert_eq!((code, line), (Code::ProjectFile, 1));
    }
}
