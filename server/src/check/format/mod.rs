//! The output formats of `loupe check`. Every format carries the same
//! diagnostics in `CheckReport::diagnostics()` order, so a CI system sees
//! exactly what a person at a terminal sees.

mod github;
pub mod human;
mod json;
mod junit;
mod sarif;

use std::io;

use super::report::CheckReport;
use crate::diag::SourceFiles;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Annotated source excerpts and a summary line, for people.
    Human,
    /// One JSON object per diagnostic per line (JSON Lines).
    Json,
    /// GitHub Actions workflow commands, shown as annotations on the diff.
    Github,
    /// A SARIF 2.1.0 log, for code-scanning upload.
    Sarif,
    /// JUnit XML, one test case per checked file.
    Junit,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// ANSI colours (human only).
    pub color: bool,
    /// Print durations (human, junit). Off, the output is byte-for-byte
    /// reproducible, which golden tests rely on.
    pub timings: bool,
}

pub fn write(format: Format, report: &CheckReport, files: &SourceFiles, opts: &Options, out: &mut dyn io::Write) -> io::Result<()> {
    match format {
        Format::Human => human::write(report, files, opts, out),
        Format::Json => json::write(report, out),
        Format::Github => github::write(report, out),
        Format::Sarif => sarif::write(report, out),
        Format::Junit => junit::write(report, opts, out),
    }
}

/// A shared report for the formats' tests: one clean module, and one whose
/// error points into an imported file, with a secondary label back in the
/// importer, a note, and a warning.
#[cfg(test)]
mod fixture {
    use std::time::Duration;

    use super::super::report::{CheckReport, ModuleKind, ModuleResult};
    use crate::diag::{Code, Diagnostic, Location, SourceFiles};

    pub const MAIN: &str = "shaders/main.wgsl";
    pub const UTIL: &str = "shaders/lib/util.wgsl";
    pub const ERROR_MESSAGE: &str = "cannot add \"f32\" & \"vec3<f32>\"";

    pub fn loc(file: &str, line: u32, column: u32, end_line: u32, end_column: u32) -> Location {
        Location { file: file.to_owned(), line, column, end_line, end_column }
    }

    pub fn files() -> SourceFiles {
        let mut files = SourceFiles::default();
        files.insert(MAIN, "#import lib::util\n\n@group(0) @binding(0) var<uniform> u: f32;\n".into());
        files.insert("shaders/clean.wgsl", "fn ok() {}\n".into());
        files.insert(
            UTIL,
            "#define_import_path lib::util\n\nfn g() -> f32 {\n  let v = vec3(1.0);\n  let bad = 1.0 + v;\n  return bad;\n}\n".into(),
        );
        files
    }

    /// The report with three image cases: a pass, a failure (with `<&>` in
    /// its message, for the escaping) and a skip.
    pub fn with_images() -> CheckReport {
        use super::super::images::config::DEFAULT_THRESHOLD;
        use super::super::images::{CaseResult, OutputResult, Verdict};
        use crate::flip::Summary;
        let case = |name: &str, line: u32, verdict: Verdict| CaseResult {
            name: name.to_owned(),
            scene: "scenes/a.toml".to_owned(),
            at: loc("loupe.toml", line, 1, line, 11),
            verdict,
            reason: None,
            threshold: DEFAULT_THRESHOLD,
            adapter_key: None,
            outputs: vec![OutputResult {
                output: "tonemap/color".to_owned(),
                reference: format!("tests/images/{name}/tonemap.color.png"),
                flip: Some(Summary { mean: 0.25, p99: 0.5, weighted_median: 0.3 }),
                relative_mse: Some(0.125),
                blessed: None,
            }],
            diagnostics: vec![],
            duration: Duration::from_millis(7),
        };
        let mut failed = case("b", 5, Verdict::Failed);
        failed.diagnostics.push(Diagnostic::error(Code::ImageMismatch, "`tonemap/color` <&> differs").at(loc("loupe.toml", 5, 1, 5, 11)));
        let skipped = CaseResult { reason: Some("no device".to_owned()), outputs: vec![], ..case("c", 9, Verdict::Skipped) };
        CheckReport { images: vec![case("a", 1, Verdict::Passed), failed, skipped], ..report() }
    }

    pub fn report() -> CheckReport {
        let error = Diagnostic::error(Code::Validation, ERROR_MESSAGE)
            .with_label(loc(UTIL, 5, 7, 5, 10), "this expression", true)
            .with_label(loc(MAIN, 1, 1, 1, 18), "imported here", false)
            .with_note("both operands must have the same type");
        let warning =
            Diagnostic::warning(Code::BindingMismatch, "binding 0 is never used").with_label(loc(MAIN, 3, 1, 3, 22), "declared here", true);
        let module = |file: &str, diagnostics| ModuleResult {
            file: file.to_owned(),
            kind: ModuleKind::Entry,
            permutations: vec![String::new()],
            pipelines: 1,
            diagnostics,
            duration: Duration::from_millis(12),
        };
        CheckReport {
            modules: vec![module("shaders/clean.wgsl", vec![]), module(MAIN, vec![error, warning])],
            general: vec![],
            adapter: Some("llvmpipe".to_owned()),
            images: vec![],
            duration: Duration::from_millis(40),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Severity;

    /// Each format's output for a report whose only problem is a warning.
    fn outputs(deny: bool) -> Vec<(Format, String)> {
        let mut report = fixture::report();
        report.modules[1].diagnostics.retain(|d| d.severity == Severity::Warning);
        if deny {
            report.deny_warnings();
        }
        assert_eq!(report.exit_code(), i32::from(deny), "the exit code");
        [Format::Human, Format::Json, Format::Github, Format::Sarif, Format::Junit]
            .into_iter()
            .map(|f| {
                let mut out = Vec::new();
                write(f, &report, &fixture::files(), &Options::default(), &mut out).unwrap();
                (f, String::from_utf8(out).unwrap())
            })
            .collect()
    }

    /// With `--deny-warnings` the exit code is 1, and every format must say
    /// the run failed where it has a notion of failure; without it, none.
    #[test]
    fn denied_warnings_read_as_failures_in_every_format() {
        for deny in [false, true] {
            for (format, out) in outputs(deny) {
                let failed = match format {
                    Format::Human => out.contains(": 1 error, 0 warnings") && out.contains("error[binding-mismatch]"),
                    Format::Json => out.contains(r#""severity":"error""#),
                    Format::Github => out.starts_with("::error "),
                    Format::Sarif => out.contains(r#""level": "error""#),
                    Format::Junit => out.contains(r#"failures="1""#) && out.contains("<failure "),
                };
                assert_eq!(failed, deny, "{format:?} with deny {deny}:\n{out}");
            }
        }
        let (_, human) = &outputs(true)[0];
        assert!(human.contains("made an error by --deny-warnings"), "{human}");
    }

    fn render(format: Format, report: &CheckReport) -> String {
        let mut out = Vec::new();
        write(format, report, &fixture::files(), &Options::default(), &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    /// Every format carries the image cases: their verdicts, and the
    /// failure at its case's line.
    #[test]
    fn image_cases_in_every_format() {
        let report = fixture::with_images();
        let human = render(Format::Human, &report);
        assert!(
            human.contains("image a: passed; tonemap/color FLIP mean 0.2500 (max 0.01), p99 0.5000 (max 0.1), relMSE 1.25e-1\n"),
            "{human}"
        );
        assert!(human.contains("image b: failed;") && human.contains("image c: skipped (no device)\n"), "{human}");
        assert!(human.contains("loupe.toml:5:1: error[image-mismatch]"), "{human}");
        assert!(human.ends_with("; 3 image cases: 1 passed, 1 failed, 1 skipped\n"), "{human}");

        let json = render(Format::Json, &report);
        let cases: Vec<serde_json::Value> =
            json.lines().map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()).filter(|v| v.get("image").is_some()).collect();
        assert_eq!(cases.len(), 3);
        assert_eq!((&cases[1]["verdict"], &cases[1]["line"]), (&serde_json::json!("failed"), &serde_json::json!(5)));
        assert_eq!(cases[0]["outputs"][0]["flip"]["p99"], 0.5);
        assert_eq!(cases[2]["reason"], "no device");
        assert!(json.contains(r#""code":"image-mismatch""#), "the failure is a diagnostic line too: {json}");

        let junit = render(Format::Junit, &report);
        junit::tests::assert_well_formed(&junit);
        assert!(junit.contains(r#"tests="5" failures="2" errors="0" skipped="1""#), "{junit}");
        assert!(junit.contains(r#"<testcase classname="loupe.images" name="c" time="0.000">"#), "{junit}");
        assert!(junit.contains(r#"<skipped message="no device"/>"#), "{junit}");
        assert!(junit.contains(r#"<failure message="`tonemap/color` &lt;&amp;&gt; differs" type="image-mismatch">"#), "{junit}");

        let sarif: serde_json::Value = serde_json::from_str(&render(Format::Sarif, &report)).unwrap();
        let result = sarif["runs"][0]["results"].as_array().unwrap().iter().find(|r| r["ruleId"] == "image-mismatch").cloned().unwrap();
        assert_eq!(result["locations"][0]["physicalLocation"]["artifactLocation"]["uri"], "loupe.toml");
        let github = render(Format::Github, &report);
        assert!(github.contains("::error file=loupe.toml,line=5,col=1,endLine=5,endColumn=11,title=image-mismatch::"), "{github}");
    }
}
