//! The shader capabilities `loupe check` validates with: their names on the
//! command line and in `loupe.toml`, and what a missing one means in the
//! user's words instead of naga's.
//!
//! Names are naga's `Capabilities` flags in kebab case (`FLOAT64` is
//! `float64`, `SHADER_INT64` is `shader-int64`). A list replaces the default
//! set; what every WebGPU device has is always allowed on top of it.

use std::sync::Arc;

use naga::valid::Capabilities;

use crate::diag::{Code, Diagnostic};
use crate::gpu;
use crate::shader::SourceFile;

/// What the shader uses, for the capabilities a shader author meets most.
const USES: &[(Capabilities, &str)] = &[
    (Capabilities::FLOAT64, "`f64` (64-bit floats)"),
    (Capabilities::SHADER_INT64, "`i64`/`u64` (64-bit integers)"),
    (Capabilities::SHADER_FLOAT16, "`f16` (16-bit floats)"),
    (Capabilities::SHADER_INT16, "`i16`/`u16` (16-bit integers)"),
    (Capabilities::SHADER_FLOAT16_IN_FLOAT32, "`pack2x16float`/`unpack2x16float`"),
    (Capabilities::SUBGROUP, "subgroup operations"),
    (Capabilities::SUBGROUP_BARRIER, "`subgroupBarrier`"),
    (Capabilities::PRIMITIVE_INDEX, "`@builtin(primitive_index)`"),
    (Capabilities::IMMEDIATES, "immediate data (`var<immediate>`)"),
    (Capabilities::CLIP_DISTANCES, "`@builtin(clip_distances)`"),
    (Capabilities::DUAL_SOURCE_BLENDING, "`@blend_src`"),
    (Capabilities::MULTIVIEW, "`@builtin(view_index)`"),
    (Capabilities::RAY_QUERY, "ray queries"),
    (Capabilities::SHADER_INT64_ATOMIC_MIN_MAX, "64-bit integer atomics"),
    (Capabilities::SHADER_INT64_ATOMIC_ALL_OPS, "64-bit integer atomics"),
    (Capabilities::SHADER_FLOAT32_ATOMIC, "`atomic<f32>`"),
    (Capabilities::SHADER_BARYCENTRICS, "`@builtin(barycentric)`"),
];

/// Type names that need a capability: where naga reports no span (type
/// errors have none), the first one written is where the shader uses it.
const TYPE_NAMES: &[(Capabilities, &[&str])] = &[
    (Capabilities::FLOAT64, &["f64"]),
    (Capabilities::SHADER_INT64, &["i64", "u64"]),
    (Capabilities::SHADER_FLOAT16, &["f16"]),
    (Capabilities::SHADER_INT16, &["i16", "u16"]),
];

/// What every WebGPU-compliant device allows: always part of the set.
pub fn baseline() -> Capabilities {
    gpu::capabilities(wgpu::Features::empty(), wgpu::DownlevelFlags::compliant())
}

/// The name of one flag: `SHADER_INT64` → `shader-int64`.
fn kebab(flag: &str) -> String {
    flag.to_lowercase().replace('_', "-")
}

/// Every capability name, in naga's flag order.
pub fn names() -> Vec<String> {
    Capabilities::all().iter_names().map(|(n, _)| kebab(n)).collect()
}

/// The names of `caps` beyond the baseline, comma-separated.
pub fn describe(caps: Capabilities) -> String {
    let extra = caps.difference(baseline());
    if extra.is_empty() { "none beyond WebGPU's".to_owned() } else { list(extra) }
}

fn list(caps: Capabilities) -> String {
    caps.iter_names().map(|(n, _)| kebab(n)).collect::<Vec<_>>().join(",")
}

/// Parses `all` or capability names (each item may itself be a
/// comma-separated list). The error names every valid one.
pub fn parse<'a>(items: impl IntoIterator<Item = &'a str>) -> Result<Capabilities, String> {
    let mut caps = baseline();
    for name in items.into_iter().flat_map(|i| i.split(',')).map(str::trim).filter(|n| !n.is_empty()) {
        if name == "all" {
            caps |= Capabilities::all();
            continue;
        }
        let flag = Capabilities::all().iter_names().find(|(n, _)| kebab(n) == name).map(|(_, f)| f);
        caps |= flag.ok_or_else(|| format!("unknown capability `{name}`; valid names: all, {}", names().join(", ")))?;
    }
    Ok(caps)
}

/// clap's parser for `--capabilities`.
pub fn parse_arg(s: &str) -> Result<Capabilities, String> {
    parse([s])
}

/// Rewrites naga's "requires the `naga::valid::Capabilities::FLOAT64`
/// flag" (or "Capability Capabilities(SHADER_INT64) is required") into
/// what the shader uses and how to allow it; the location and naga's own
/// words (as a note) are kept. naga gives type errors no span: those are
/// located at the first such type name written in `files` (the shader,
/// then what it imports). Other diagnostics pass through unchanged.
pub fn explain(d: Diagnostic, checked: Capabilities, files: &[Arc<SourceFile>]) -> Diagnostic {
    if d.code != Code::Validation || !d.message.contains("apabilit") {
        return d;
    }
    let needed = d
        .message
        .split(|c: char| !(c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_'))
        .filter_map(Capabilities::from_name)
        .fold(Capabilities::empty(), |a, f| a | f)
        .difference(checked);
    if needed.is_empty() {
        return d;
    }
    let mut uses: Vec<String> = needed
        .iter()
        .map(|f| USES.iter().find(|(c, _)| *c == f).map_or_else(|| format!("a feature that needs `{}`", list(f)), |(_, u)| (*u).to_owned()))
        .collect();
    uses.dedup();
    let names = list(needed);
    let plural = if needed.iter().count() > 1 { "capabilities" } else { "capability" };
    let wanted = list(checked.difference(baseline()) | needed);
    let features = providers(needed);
    let mut out = Diagnostic {
        message: format!("this shader uses {}: that needs the `{names}` {plural}, which is not enabled", uses.join(" and ")),
        notes: Vec::new(),
        ..d.clone()
    };
    out = out.with_note(format!(
        "allow it with `--capabilities {wanted}` (or `capabilities = [...]` under [check] in loupe.toml; `all` allows everything)"
    ));
    if !features.is_empty() {
        out = out.with_note(format!("on a device, an adapter with {features} allows it"));
    }
    out = out.with_note(format!("checked with: {}", describe(checked)));
    out.notes.push(format!("naga: {}", d.message));
    out.notes.extend(d.notes);
    if out.labels.is_empty() {
        let names: Vec<&str> = TYPE_NAMES.iter().filter(|(c, _)| needed.contains(*c)).flat_map(|(_, n)| n.iter().copied()).collect();
        if let Some((loc, name)) = files.iter().find_map(|f| first_word(f, &names)) {
            out.location = None;
            out = out.with_label(loc, format!("`{name}` used here"), true);
        }
    }
    out
}

/// The first of `words` written in `file` as a whole word, outside `//`
/// comments.
fn first_word(file: &SourceFile, words: &[&str]) -> Option<(crate::diag::Location, String)> {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut offset = 0;
    for line in file.text.split_inclusive('\n') {
        let code = line.split("//").next().unwrap_or_default();
        for (at, _) in code.char_indices() {
            let before = code[..at].chars().next_back();
            let Some(word) = words.iter().find(|w| code[at..].starts_with(**w)) else { continue };
            let after = code[at + word.len()..].chars().next();
            if !before.is_some_and(ident) && !after.is_some_and(ident) {
                return Some((file.location(offset + at..offset + at + word.len()), (*word).to_owned()));
            }
        }
        offset += line.len();
    }
    None
}

/// The wgpu features (or downlevel flags) that give a device `caps`, by
/// wgpu's own mapping: `the wgpu feature SHADER_F64`.
fn providers(caps: Capabilities) -> String {
    let mut out = Vec::new();
    for cap in caps.iter() {
        let features: Vec<&str> = wgpu::Features::all()
            .iter_names()
            .filter(|(_, f)| gpu::capabilities(*f, wgpu::DownlevelFlags::empty()).contains(cap))
            .map(|(n, _)| n)
            .collect();
        let downlevel: Vec<&str> = wgpu::DownlevelFlags::all()
            .iter_names()
            .filter(|(_, f)| gpu::capabilities(wgpu::Features::empty(), *f).contains(cap))
            .map(|(n, _)| n)
            .collect();
        match (features.as_slice(), downlevel.as_slice()) {
            ([], []) => {}
            ([f], _) => out.push(format!("the wgpu feature {f}")),
            (fs, []) => out.push(format!("one of the wgpu features {}", fs.join(", "))),
            ([], ds) => out.push(format!("the downlevel flag {}", ds.join(", "))),
            (fs, ds) => out.push(format!("the wgpu features {} or downlevel flags {}", fs.join(", "), ds.join(", "))),
        }
    }
    out.dedup();
    out.join(" and ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Location;

    #[test]
    fn names_parse_and_unknown_ones_list_the_valid() {
        let c = parse(["float64,shader-int64", "shader-float16"]).unwrap();
        assert!(c.contains(Capabilities::FLOAT64 | Capabilities::SHADER_INT64 | Capabilities::SHADER_FLOAT16));
        assert!(!c.contains(Capabilities::SUBGROUP));
        assert!(c.contains(baseline()), "WebGPU's own are always allowed");
        assert_eq!(parse(["all"]).unwrap(), Capabilities::all());
        assert_eq!(parse([] as [&str; 0]).unwrap(), baseline());
        let e = parse(["float64,f64"]).unwrap_err();
        assert!(e.contains("unknown capability `f64`") && e.contains("float64") && e.contains("shader-int64"), "{e}");
        assert_eq!(names().len(), Capabilities::all().iter().count());
        assert!(names().contains(&"shader-float16-in-float32".to_owned()));
    }

    #[test]
    fn the_documented_default_is_the_real_one() {
        let default = describe(gpu::capabilities_without_device());
        assert_eq!(default, "primitive-index,subgroup,subgroup-barrier,shader-float16");
        assert!(include_str!("../../../docs/check.md").contains(&format!("without one: `{default}`")), "docs/check.md states {default}");
        assert!(include_str!("../cli/check.rs").contains(&format!("/// `{default}`")), "--help states {default}");
    }

    #[test]
    fn describe_leaves_out_the_baseline() {
        assert_eq!(describe(baseline()), "none beyond WebGPU's");
        assert_eq!(describe(parse(["shader-int64,float64"]).unwrap()), "float64,shader-int64");
    }

    fn naga_error(message: &str) -> Diagnostic {
        let at = Location { file: "x.wgsl".into(), line: 3, column: 9, end_line: 3, end_column: 12 };
        Diagnostic::error(Code::Validation, message).with_label(at, "here", true).with_note("Function [0] 'f' is invalid")
    }

    #[test]
    fn a_missing_capability_is_explained_in_the_users_words() {
        let checked = parse(["shader-float16"]).unwrap();
        let d = explain(naga_error("Using `f64` values requires the `naga::valid::Capabilities::FLOAT64` flag"), checked, &[]);
        assert!(d.message.contains("`f64` (64-bit floats)") && d.message.contains("`float64` capability"), "{}", d.message);
        let notes = d.notes.join("\n");
        assert!(notes.contains("--capabilities float64,shader-float16"), "{notes}");
        assert!(notes.contains("the wgpu feature SHADER_F64"), "{notes}");
        assert!(notes.contains("naga: Using `f64`"), "naga's words stay: {notes}");
        assert!(notes.contains("Function [0]"), "{notes}");
        let loc = d.location.as_ref().unwrap();
        assert_eq!((loc.line, loc.column), (3, 9), "the location is kept");

        let d = explain(naga_error("Capability Capabilities(SHADER_INT64) is required"), checked, &[]);
        assert!(d.message.contains("`i64`/`u64`") && d.message.contains("`shader-int64`"), "{}", d.message);
        assert!(d.notes.join("\n").contains("SHADER_INT64"));
    }

    #[test]
    fn other_diagnostics_pass_through() {
        let d = naga_error("Expression [3] is invalid");
        assert_eq!(explain(d.clone(), baseline(), &[]).message, d.message);
        // A capability the check had is not the problem.
        let d = naga_error("Capability Capabilities(FLOAT64) is required");
        assert_eq!(explain(d.clone(), Capabilities::all(), &[]).message, d.message);
    }

    #[test]
    fn a_type_error_without_a_span_points_at_the_type_written() {
        let file = |name: &str, text: &str| Arc::new(SourceFile::from_text(name.into(), name.into(), text.into()));
        let files = [
            file("main.wgsl", "// no u64 here\nfn f() -> u32 { return 1u; }\n"),
            file("lib.wgsl", "// i64 in a comment\nfn g(x: u32) -> u64x { return x; }\nfn h(x: u64) -> u64 { return x; }\n"),
        ];
        let spanless =
            Diagnostic::error(Code::Validation, "Using `u64` values requires the `naga::valid::Capabilities::SHADER_INT64` flag")
                .at(Location::file_start("main.wgsl"));
        let d = explain(spanless, baseline(), &files);
        let loc = d.location.as_ref().unwrap();
        assert_eq!((loc.file.as_str(), loc.line, loc.column, loc.end_column), ("lib.wgsl", 3, 9, 12), "{d:?}");
        assert_eq!(d.labels[0].message, "`u64` used here");
        // naga's own span wins.
        let d = explain(naga_error("Using `f64` values requires the `naga::valid::Capabilities::FLOAT64` flag"), baseline(), &files);
        assert_eq!(d.location.unwrap().line, 3);
    }
}
