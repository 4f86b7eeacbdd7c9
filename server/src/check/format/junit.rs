//! JUnit XML, which most CI systems show as a test report: one test case
//! per checked file, failing when the file has an error, and one per image
//! case (failed, skipped or passed).

use std::fmt::Write as _;
use std::io;
use std::time::Duration;

use super::super::images::Verdict;
use super::super::report::CheckReport;
use super::Options;
use crate::diag::{Diagnostic, Severity};

pub fn write(report: &CheckReport, opts: &Options, out: &mut dyn io::Write) -> io::Result<()> {
    let mut cases: Vec<(&str, Duration, &[Diagnostic])> =
        report.modules.iter().map(|m| (m.file.as_str(), m.duration, &m.diagnostics[..])).collect();
    // Problems with no file (no device) still have to fail the build visibly.
    if !report.general.is_empty() {
        cases.push(("(general)", Duration::ZERO, &report.general));
    }
    let failures = cases.iter().filter(|(_, _, ds)| ds.iter().any(is_error)).count() + report.cases(Verdict::Failed);
    let time = |d: Duration| {
        if opts.timings { format!("{:.3}", d.as_secs_f64()) } else { "0.000".to_owned() }
    };
    let counts = format!(r#"tests="{}" failures="{failures}" errors="0""#, cases.len() + report.images.len());
    let total = time(report.duration);
    let skipped = report.cases(Verdict::Skipped);

    writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
    writeln!(out, r#"<testsuites name="loupe check" {counts} time="{total}">"#)?;
    writeln!(out, r#"  <testsuite name="loupe check" {counts} skipped="{skipped}" time="{total}">"#)?;
    for (name, duration, diagnostics) in cases {
        let open = format!(r#"    <testcase classname="loupe.check" name="{}" time="{}""#, escape(name, true), time(duration));
        if diagnostics.is_empty() {
            writeln!(out, "{open}/>")?;
            continue;
        }
        writeln!(out, "{open}>")?;
        let text = escape(&plain(diagnostics), false);
        match diagnostics.iter().find(|d| is_error(d)) {
            Some(first) => writeln!(
                out,
                r#"      <failure message="{}" type="{}">{text}</failure>"#,
                escape(&first.message, true),
                first.code.as_str()
            )?,
            None => writeln!(out, "      <system-out>{text}</system-out>")?,
        }
        writeln!(out, "    </testcase>")?;
    }
    // One case per image case: a failure with its diagnostics, a skip with
    // its reason, a pass with its figures.
    for c in &report.images {
        let open = format!(r#"    <testcase classname="loupe.images" name="{}" time="{}">"#, escape(&c.name, true), time(c.duration));
        writeln!(out, "{open}")?;
        match (c.verdict, c.diagnostics.iter().find(|d| is_error(d))) {
            (Verdict::Failed, Some(first)) => writeln!(
                out,
                r#"      <failure message="{}" type="{}">{}</failure>"#,
                escape(&first.message, true),
                first.code.as_str(),
                escape(&plain(&c.diagnostics), false)
            )?,
            (Verdict::Skipped, _) => {
                writeln!(out, r#"      <skipped message="{}"/>"#, escape(c.reason.as_deref().unwrap_or_default(), true))?
            }
            _ => writeln!(out, "      <system-out>{}</system-out>", escape(&c.line(), false))?,
        }
        writeln!(out, "    </testcase>")?;
    }
    writeln!(out, "  </testsuite>")?;
    writeln!(out, "</testsuites>")
}

fn is_error(d: &Diagnostic) -> bool {
    d.severity == Severity::Error
}

/// The diagnostics as one-liners, each followed by its notes.
fn plain(diagnostics: &[Diagnostic]) -> String {
    let mut s = String::new();
    for d in diagnostics {
        let _ = writeln!(s, "{d}");
        for note in &d.notes {
            let _ = writeln!(s, "  = {note}");
        }
    }
    s
}

/// Escapes markup and drops characters XML 1.0 forbids outright (other
/// control characters, U+FFFE, U+FFFF). In attributes, whitespace other than
/// the space becomes a character reference because parsers would otherwise
/// normalise it to a space; `\r` always does, or it would become `\n`.
fn escape(s: &str, attribute: bool) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\r' => out.push_str("&#13;"),
            '\n' if attribute => out.push_str("&#10;"),
            '\t' if attribute => out.push_str("&#9;"),
            '\n' | '\t' => out.push(c),
            '\0'..='\x1f' | '\u{fffe}' | '\u{ffff}' => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::fixture;
    use super::*;
    use crate::diag::Code;

    fn render(report: &CheckReport, timings: bool) -> String {
        let mut out = Vec::new();
        write(report, &Options { color: false, timings }, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    /// Just enough XML checking for what we emit: tags balance, attribute
    /// values are quoted and hold no raw markup, and text has no raw `<`
    /// or stray `&`.
    pub fn assert_well_formed(xml: &str) {
        let body = xml.strip_prefix("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n").expect("declaration");
        let mut stack = Vec::new();
        let mut rest = body;
        while let Some(lt) = rest.find('<') {
            assert_text(&rest[..lt]);
            let gt = rest[lt..].find('>').expect("unclosed tag") + lt;
            let tag = &rest[lt + 1..gt];
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop(), Some(name), "mismatched </{name}>");
            } else {
                let self_closing = tag.ends_with('/');
                let tag = tag.trim_end_matches('/');
                let (name, attributes) = tag.split_once(' ').unwrap_or((tag, ""));
                for attribute in attributes.split("\" ").filter(|a| !a.is_empty()) {
                    let (_, value) = attribute.split_once("=\"").expect("quoted attribute");
                    let value = value.trim_end_matches('"');
                    assert!(!value.contains(['"', '<', '\n']), "raw markup in attribute {value:?}");
                    assert_text(value);
                }
                if !self_closing {
                    stack.push(name);
                }
            }
            rest = &rest[gt + 1..];
        }
        assert_text(rest);
        assert!(stack.is_empty(), "unclosed {stack:?}");
    }

    fn assert_text(text: &str) {
        assert!(!text.contains(['<', '>']), "raw markup in {text:?}");
        for (i, _) in text.match_indices('&') {
            let entity = &text[i..i + text[i..].find(';').expect("unterminated entity") + 1];
            assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&apos;", "&#13;", "&#10;", "&#9;"].contains(&entity), "bad entity {entity}");
        }
        assert!(!text.chars().any(|c| c < ' ' && !"\t\n\r".contains(c)), "control char in {text:?}");
    }

    #[test]
    fn one_case_per_module() {
        let xml = render(&fixture::report(), false);
        assert_well_formed(&xml);
        assert_eq!(xml.matches("<testcase ").count(), 2);
        assert!(xml.contains(r#"<testsuites name="loupe check" tests="2" failures="1" errors="0" time="0.000">"#), "{xml}");
        assert!(xml.contains(r#"<testcase classname="loupe.check" name="shaders/clean.wgsl" time="0.000"/>"#), "{xml}");
        assert!(
            xml.contains(
                r#"<failure message="cannot add &quot;f32&quot; &amp; &quot;vec3&lt;f32&gt;&quot;" type="validation">shaders/lib/util.wgsl:5:7: error[validation]: cannot add &quot;f32&quot; &amp; &quot;vec3&lt;f32&gt;&quot;
  = both operands must have the same type
shaders/main.wgsl:3:1: warning[binding-mismatch]: binding 0 is never used
</failure>"#
            ),
            "{xml}"
        );
        assert_eq!(xml.matches("<failure ").count(), 1);
        assert!(!xml.contains("<system-out>"));
    }

    #[test]
    fn warnings_pass_general_and_timings() {
        let mut report = fixture::report();
        report.modules[1].diagnostics.remove(0);
        report.general.push(Diagnostic::error(Code::DeviceMissing, "no\tGPU\r\n\x07<here>"));
        let xml = render(&report, true);
        assert_well_formed(&xml);
        assert_eq!(xml.matches("<testcase ").count(), 3);
        assert!(xml.contains(r#"time="0.040">"#), "{xml}");
        assert!(xml.contains(r#"name="shaders/main.wgsl" time="0.012">"#), "{xml}");
        assert!(
            xml.contains("<system-out>shaders/main.wgsl:3:1: warning[binding-mismatch]: binding 0 is never used\n</system-out>"),
            "{xml}"
        );
        assert!(xml.contains(r#"name="(general)" time="0.000">"#), "{xml}");
        assert!(xml.contains(r#"<failure message="no&#9;GPU&#13;&#10;&lt;here&gt;" type="device-missing">"#), "{xml}");
        assert!(xml.contains(r#"failures="1""#), "{xml}");
    }
}
