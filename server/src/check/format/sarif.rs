//! A SARIF 2.1.0 log, the format code-scanning services (GitHub's among
//! them) ingest.

use std::io;

use serde_json::{Value, json};

use super::super::report::CheckReport;
use crate::diag::display_uri;
use crate::diag::{Code, Diagnostic, Location, Severity};

pub fn write(report: &CheckReport, out: &mut dyn io::Write) -> io::Result<()> {
    let rules: Vec<Value> =
        Code::ALL.iter().map(|code| json!({ "id": code.as_str(), "shortDescription": { "text": code.description() } })).collect();
    let log = json!({
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [{
            "tool": { "driver": { "name": "loupe", "version": env!("CARGO_PKG_VERSION"), "rules": rules } },
            // Our columns count characters, not UTF-16 code units (the default).
            "columnKind": "unicodeCodePoints",
            "results": report.diagnostics().map(result).collect::<Vec<_>>(),
        }],
    });
    serde_json::to_writer_pretty(&mut *out, &log)?;
    writeln!(out)
}

fn result(d: &Diagnostic) -> Value {
    let mut text = d.message.clone();
    for note in &d.notes {
        text.push('\n');
        text.push_str(note);
    }
    let mut result = json!({
        "ruleId": d.code.as_str(),
        "ruleIndex": Code::ALL.iter().position(|&c| c == d.code),
        "level": match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "note",
        },
        "message": { "text": text },
    });
    let Some(location) = &d.location else {
        return result;
    };
    // The label at the diagnostic's own location lends it its message; every
    // other label is related information.
    let primary = d.labels.iter().position(|l| l.primary && l.location == *location);
    let mut main = physical(location);
    if let Some(label) = primary.map(|i| &d.labels[i]) {
        main["message"] = json!({ "text": label.message });
    }
    result["locations"] = json!([main]);
    let related: Vec<Value> = d
        .labels
        .iter()
        .enumerate()
        .filter(|&(i, _)| Some(i) != primary)
        .map(|(i, label)| {
            let mut related = physical(&label.location);
            related["id"] = json!(i);
            related["message"] = json!({ "text": label.message });
            related
        })
        .collect();
    if !related.is_empty() {
        result["relatedLocations"] = json!(related);
    }
    result
}

fn physical(l: &Location) -> Value {
    json!({
        "physicalLocation": {
            "artifactLocation": { "uri": display_uri(&l.file) },
            "region": {
                "startLine": l.line,
                "startColumn": l.column,
                "endLine": l.end_line,
                "endColumn": l.end_column,
            },
        },
    })
}

#[cfg(test)]
mod tests {
    use super::super::fixture;
    use super::*;

    fn log(report: &CheckReport) -> Value {
        let mut out = Vec::new();
        write(report, &mut out).unwrap();
        serde_json::from_slice(&out).unwrap()
    }

    #[test]
    fn log_shape() {
        let log = log(&fixture::report());
        assert_eq!(log["version"], "2.1.0");
        assert_eq!(log["$schema"], "https://json.schemastore.org/sarif-2.1.0.json");
        let run = &log["runs"][0];
        assert_eq!(run["columnKind"], "unicodeCodePoints");
        assert_eq!(run["tool"]["driver"]["name"], "loupe");
        let rules = run["tool"]["driver"]["rules"].as_array().unwrap();
        assert_eq!(rules.len(), Code::ALL.len());
        for (rule, code) in rules.iter().zip(Code::ALL) {
            assert_eq!(rule["id"], code.as_str());
            assert_eq!(rule["shortDescription"]["text"], code.description());
        }

        let results = run["results"].as_array().unwrap();
        assert_eq!(results.len(), 2);
        let error = &results[0];
        assert_eq!(error["ruleId"], "validation");
        assert_eq!(rules[error["ruleIndex"].as_u64().unwrap() as usize]["id"], "validation");
        assert_eq!(error["level"], "error");
        assert_eq!(error["message"]["text"], format!("{}\nboth operands must have the same type", fixture::ERROR_MESSAGE));
        let location = &error["locations"][0];
        assert_eq!(location["message"]["text"], "this expression");
        let physical = &location["physicalLocation"];
        assert_eq!(physical["artifactLocation"]["uri"], fixture::UTIL);
        assert_eq!(physical["region"], json!({"startLine": 5, "startColumn": 7, "endLine": 5, "endColumn": 10}));
        let related = error["relatedLocations"].as_array().unwrap();
        assert_eq!(related.len(), 1);
        assert_eq!(related[0]["message"]["text"], "imported here");
        assert_eq!(related[0]["physicalLocation"]["artifactLocation"]["uri"], fixture::MAIN);
        assert_eq!(results[1]["level"], "warning");
        assert!(results[1].get("relatedLocations").is_none());
    }

    #[test]
    fn no_location_and_uris() {
        let report = CheckReport { general: vec![Diagnostic::error(Code::DeviceMissing, "no GPU")], ..CheckReport::default() };
        let result = &log(&report)["runs"][0]["results"][0];
        assert_eq!(result["ruleId"], "device-missing");
        assert!(result.get("locations").is_none());
        assert_eq!(display_uri("shaders/my lib:x/é.wgsl"), "shaders/my%20lib%3Ax/%C3%A9.wgsl");
        // A name that is not UTF-8: the URI holds its real byte.
        assert_eq!(display_uri("shaders/caf\\xE9.wgsl"), "shaders/caf%E9.wgsl");
    }
}
