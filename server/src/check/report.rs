//! The result of a `loupe check` run, independent of how it is printed.

use std::time::Duration;

use super::images::{CaseResult, Verdict};
use crate::diag::{Diagnostic, Severity};

/// What one checked file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModuleKind {
    /// Declares `#define_import_path`: checked as part of every shader that
    /// imports it, and on its own.
    Library,
    /// A shader with entry points, composed with its imports.
    Entry,
    /// A scene file, loaded with the meshes it references.
    Scene,
    /// A material file (`*.mat`), lowered with the files it imports.
    Material,
}

#[derive(Debug, Clone)]
pub struct ModuleResult {
    /// Display path of the file, as diagnostics name it.
    pub file: String,
    pub kind: ModuleKind,
    /// Every shader-def permutation the file was checked with, each as a
    /// sorted comma-separated list of defs (empty string: no defs).
    pub permutations: Vec<String>,
    /// Pipelines the renderer builds from this file that were created on the
    /// device (zero with `--no-device`).
    pub pipelines: usize,
    /// Diagnostics whose primary location is in this file, or that came from
    /// checking it.
    pub diagnostics: Vec<Diagnostic>,
    pub duration: Duration,
}

impl ModuleResult {
    pub fn errors(&self) -> usize {
        self.diagnostics.iter().filter(|d| d.severity == Severity::Error).count()
    }

    pub fn warnings(&self) -> usize {
        self.diagnostics.iter().filter(|d| d.severity == Severity::Warning).count()
    }
}

#[derive(Debug, Clone, Default)]
pub struct CheckReport {
    /// One per file, sorted by path.
    pub modules: Vec<ModuleResult>,
    /// Diagnostics that belong to no single file (no device).
    pub general: Vec<Diagnostic>,
    /// The adapter pipelines were created on, if any.
    pub adapter: Option<String>,
    /// The image cases, in loupe.toml's order.
    pub images: Vec<CaseResult>,
    pub duration: Duration,
}

impl CheckReport {
    pub fn diagnostics(&self) -> impl Iterator<Item = &Diagnostic> {
        let cases = self.images.iter().flat_map(|c| c.diagnostics.iter());
        self.modules.iter().flat_map(|m| m.diagnostics.iter()).chain(self.general.iter()).chain(cases)
    }

    /// Image cases with this verdict.
    pub fn cases(&self, verdict: Verdict) -> usize {
        self.images.iter().filter(|c| c.verdict == verdict).count()
    }

    pub fn count(&self, severity: Severity) -> usize {
        self.diagnostics().filter(|d| d.severity == severity).count()
    }

    pub fn pipelines(&self) -> usize {
        self.modules.iter().map(|m| m.pipelines).sum()
    }

    /// `--deny-warnings`: every warning becomes an error, with a note
    /// saying why, so that every format reports the failure the exit code
    /// says (a JUnit failure, a SARIF `error`, a GitHub `::error`).
    pub fn deny_warnings(&mut self) {
        let cases = self.images.iter_mut().flat_map(|c| c.diagnostics.iter_mut());
        for d in self.modules.iter_mut().flat_map(|m| m.diagnostics.iter_mut()).chain(self.general.iter_mut()).chain(cases) {
            if d.severity == Severity::Warning {
                d.severity = Severity::Error;
                d.notes.push("a warning, made an error by --deny-warnings (or `deny_warnings = true` in loupe.toml)".to_owned());
            }
        }
    }

    /// The process exit code: 0 clean, 1 any error (warnings count once
    /// `deny_warnings` has made them errors).
    pub fn exit_code(&self) -> i32 {
        i32::from(self.count(Severity::Error) > 0)
    }
}
