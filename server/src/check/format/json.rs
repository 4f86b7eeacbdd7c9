//! JSON Lines: one self-contained object per diagnostic, so tools can stream
//! and `grep` the output. No summary object: every line has the same shape.

use std::io;

use serde::Serialize;

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

pub fn write(report: &CheckReport, out: &mut dyn io::Write) -> io::Result<()> {
    for d in report.diagnostics() {
        serde_json::to_writer(&mut *out, &Record::from(d))?;
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
