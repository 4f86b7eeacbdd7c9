//! The image cases as `loupe serve` shows them live ("against reference"):
//! a case rendered and compared as the gate compares it, keeping the images
//! a page shows (the actual output, its reference, FLIP's map) instead of
//! writing artifacts, and a case's outputs written as its references when a
//! developer blesses what they see.

use std::path::Path;
use std::sync::Arc;

use super::compare::{self, Image, Range};
use super::config::{Case, Threshold};
use super::report::{Verdict, at_case};
use super::run::Renderer;
use crate::diag::{Code, Diagnostic, display_path};
use crate::flip::{ErrorMap, Summary};
use crate::render::capture::CapturedImage;

/// One output of a live case.
pub struct Output {
    /// `pass/output`.
    pub output: String,
    /// The reference file, as diagnostics name paths.
    pub reference: String,
    pub flip: Option<Summary>,
    pub relative_mse: Option<f64>,
    /// What was rendered: what a bless writes.
    pub actual: Arc<CapturedImage>,
    /// The reference as read, and FLIP's map, when they compared.
    pub reference_image: Option<Image>,
    pub map: Option<ErrorMap>,
}

/// One case, compared.
pub struct Compared {
    pub name: String,
    pub verdict: Verdict,
    pub threshold: Threshold,
    /// The adapter key whose threshold applied.
    pub adapter_key: Option<String>,
    pub outputs: Vec<Output>,
    /// Why it failed, at the case's line in loupe.toml.
    pub diagnostics: Vec<Diagnostic>,
}

/// Renders `case` and compares each output with its reference in
/// `references`, as `loupe check` does, writing nothing.
pub fn compare_case(renderer: &mut Renderer, case: &Case, references: &Path, adapter: &str) -> Compared {
    let (threshold, key) = case.threshold_on(adapter);
    let mut out = Compared {
        name: case.name.clone(),
        verdict: Verdict::Passed,
        threshold,
        adapter_key: key.map(str::to_owned),
        outputs: Vec::new(),
        diagnostics: Vec::new(),
    };
    let captures = match crate::shader::guard::guarded(&case.at.file, "the renderer", || renderer.render(case)) {
        Ok(captures) => captures,
        Err(ds) => {
            if ds.iter().any(|d| d.code == Code::CompilerPanic) {
                renderer.reset();
            }
            out.diagnostics.extend(ds.into_iter().map(|d| at_case(&case.at, d)));
            out.verdict = Verdict::Failed;
            return out;
        }
    };
    for c in captures {
        let (output, range) = (c.key(), Range::of(&c.format));
        let path = compare::reference_path(references, &case.name, &output, range);
        let judged = compare::judge(&Image::of(&c), range, &output, &path, threshold, key);
        let (reference_image, compared) = judged.compared.unzip();
        if let Some((_, d)) = judged.failure {
            out.diagnostics.push(at_case(&case.at, d));
            out.verdict = Verdict::Failed;
        }
        out.outputs.push(Output {
            output,
            reference: display_path(&path),
            flip: compared.as_ref().map(|c| c.flip),
            relative_mse: compared.as_ref().map(|c| c.relative_mse),
            actual: Arc::new(c),
            reference_image,
            map: compared.map(|c| c.map),
        });
    }
    out
}

/// Writes `capture` as case `case`'s reference for its output, in the
/// file and format the gate reads.
pub fn bless(capture: &CapturedImage, case: &str, references: &Path) -> Result<(), String> {
    let range = Range::of(&capture.format);
    let path = compare::reference_path(references, case, &capture.key(), range);
    let bytes = compare::encode(capture, range)?;
    let dir = path.parent().expect("a case folder");
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", display_path(dir)))?;
    std::fs::write(&path, bytes).map_err(|e| format!("cannot write {}: {e}", display_path(&path)))
}
