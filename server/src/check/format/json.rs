//! JSON Lines: one self-contained object per diagnostic, so tools can stream
//! and `grep` the output, then one per image case (the lines with an
//! `image` key). No summary object.

use std::io;

use serde::Serialize;

use super::super::images::config::Threshold;
use super::super::images::{OutputResult, Verdict};
use super::super::report::CheckReport;
use crate::diag::{Code, Diagnostic, Label, Severity};

/// The flat shape of a line; the location's fields are `null` for a
/// diagnostic with no file.
#[derive(Serialize)]
struct Record<'a> {
    file: Option<&'a str>,
    line: Option<u32>,
    column: Option<u32>,
    end_line: Option<u32>,
    end_column: Option<u32>,
    severity: Severity,
    code: Code,
    message: &'a str,
    labels: &'a [Label],
    notes: &'a [String],
}

impl<'a> From<&'a Diagnostic> for Record<'a> {
    fn from(d: &'a Diagnostic) -> Self {
        let l = d.location.as_ref();
        Record {
            file: l.map(|l| l.file.as_str()),
            line: l.map(|l| l.line),
            column: l.map(|l| l.column),
            end_line: l.map(|l| l.end_line),
            end_column: l.map(|l| l.end_column),
            severity: d.severity,
            code: d.code,
            message: &d.message,
            labels: &d.labels,
            notes: &d.notes,
        }
    }
}

/// An image case's line: its verdict and each output's figures, at the
/// case's line in loupe.toml. Its failures are diagnostic lines too.
#[derive(Serialize)]
struct Case<'a> {
    image: &'a str,
    verdict: Verdict,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<&'a str>,
    scene: &'a str,
    file: &'a str,
    line: u32,
    threshold: Threshold,
    adapter_key: Option<&'a str>,
    outputs: &'a [OutputResult],
}

pub fn write(report: &CheckReport, out: &mut dyn io::Write) -> io::Result<()> {
    for d in report.diagnostics() {
        serde_json::to_writer(&mut *out, &Record::from(d))?;
        writeln!(out)?;
    }
    for c in &report.images {
        let case = Case {
            image: &c.name,
            verdict: c.verdict,
            reason: c.reason.as_deref(),
            scene: &c.scene,
            file: &c.at.file,
            line: c.at.line,
            threshold: c.threshold,
            adapter_key: c.adapter_key.as_deref(),
            outputs: &c.outputs,
        };
        serde_json::to_writer(&mut *out, &case)?;
        writeln!(out)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use serde_json::{Value, json};

    use super::super::fixture;
    use super::*;

    fn lines(report: &CheckReport) -> Vec<Value> {
        let mut out = Vec::new();
        write(report, &mut out).unwrap();
        String::from_utf8(out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect()
    }

    #[test]
    fn one_object_per_diagnostic() {
        let lines = lines(&fixture::report());
        assert_eq!(lines.len(), 2);
        assert_eq!(
            lines[0],
            json!({
                "file": fixture::UTIL, "line": 5, "column": 7, "end_line": 5, "end_column": 10,
                "severity": "error", "code": "validation", "message": fixture::ERROR_MESSAGE,
                "labels": [
                    {"file": fixture::UTIL, "line": 5, "column": 7, "end_line": 5, "end_column": 10,
                     "message": "this expression", "primary": true},
                    {"file": fixture::MAIN, "line": 1, "column": 1, "end_line": 1, "end_column": 18,
                     "message": "imported here", "primary": false},
                ],
                "notes": ["both operands must have the same type"],
            })
        );
        assert_eq!(lines[1]["severity"], "warning");
        assert_eq!(lines[1]["code"], "binding-mismatch");
        assert_eq!(lines[1]["file"], fixture::MAIN);
    }

    #[test]
    fn no_location_is_null() {
        let report = CheckReport { general: vec![Diagnostic::error(Code::DeviceMissing, "no GPU")], ..CheckReport::default() };
        let line = &lines(&report)[0];
        for field in ["file", "line", "column", "end_line", "end_column"] {
            assert_eq!(line[field], Value::Null, "{field}");
        }
        assert_eq!(line["labels"], json!([]));
        assert_eq!(line["code"], "device-missing");
    }
}
