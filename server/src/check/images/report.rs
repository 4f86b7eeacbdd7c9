//! What the image gate found, case by case, for the five formats.

use std::time::Duration;

use serde::Serialize;

use super::config::Threshold;
use crate::diag::{Diagnostic, Label, Location, Severity};
use crate::flip::Summary;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Passed,
    Failed,
    /// Not rendered (no device, `--no-device`, shader errors): never a pass.
    Skipped,
    /// `--bless`: rendered and written as the reference.
    Blessed,
}

#[derive(Debug, Clone, Serialize)]
pub struct OutputResult {
    /// `pass/output`.
    pub output: String,
    /// The reference file, as diagnostics name paths.
    pub reference: String,
    /// `null` when there was nothing to compare with.
    pub flip: Option<Summary>,
    pub relative_mse: Option<f64>,
    /// `--bless`: what the new reference replaced, in words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blessed: Option<String>,
}

#[derive(Debug, Clone)]
pub struct CaseResult {
    pub name: String,
    /// The scene file, as diagnostics name it.
    pub scene: String,
    /// The case's line in loupe.toml.
    pub at: Location,
    pub verdict: Verdict,
    /// Why a skipped case was skipped.
    pub reason: Option<String>,
    /// The threshold applied, and the adapter key that chose it.
    pub threshold: Threshold,
    pub adapter_key: Option<String>,
    pub outputs: Vec<OutputResult>,
    /// Why it failed; empty for a pass.
    pub diagnostics: Vec<Diagnostic>,
    pub duration: Duration,
}

impl CaseResult {
    /// The verdict of a rendered case: failed when any diagnostic is an
    /// error.
    pub fn settle(&mut self) {
        if self.diagnostics.iter().any(|d| d.severity == Severity::Error) {
            self.verdict = Verdict::Failed;
        }
    }

    /// One line: the verdict and each output's figures against the
    /// threshold.
    pub fn line(&self) -> String {
        let mut s = format!("image {}: {}", self.name, verdict_word(self.verdict));
        if let Some(r) = &self.reason {
            s.push_str(&format!(" ({r})"));
        }
        let t = self.threshold;
        for o in &self.outputs {
            match (&o.blessed, o.flip) {
                (Some(b), _) => s.push_str(&format!("; {} {b}", o.output)),
                (None, Some(f)) => s.push_str(&format!(
                    "; {} FLIP mean {:.4} (max {}), p99 {:.4} (max {}), relMSE {:.2e}",
                    o.output,
                    f.mean,
                    t.flip_mean,
                    f.p99,
                    t.flip_p99,
                    o.relative_mse.unwrap_or(0.0)
                )),
                (None, None) => {}
            }
        }
        s
    }
}

pub fn verdict_word(v: Verdict) -> &'static str {
    match v {
        Verdict::Passed => "passed",
        Verdict::Failed => "failed",
        Verdict::Skipped => "skipped",
        Verdict::Blessed => "blessed",
    }
}

/// `d`, moved to the case's line in loupe.toml (where the case is fixed or
/// blessed), its own place kept as a secondary label: every case's failure
/// points at its case, whatever file it came from.
pub fn at_case(at: &Location, d: Diagnostic) -> Diagnostic {
    let mut labels = vec![Label { location: at.clone(), message: "in this image case".into(), primary: true }];
    if let Some(own) = d.location.clone().filter(|l| l != at) {
        labels.push(Label { location: own, message: "here".into(), primary: false });
    }
    labels.extend(d.labels.into_iter().filter(|l| l.location != *at).map(|l| Label { primary: false, ..l }));
    Diagnostic { location: Some(at.clone()), labels, ..d }
}
