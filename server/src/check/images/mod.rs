//! The image gate of `loupe check`: each `[[images]]` case of loupe.toml
//! (`config`) is rendered headless (`run`), each output compared with its
//! reviewed reference by FLIP (`compare`), and a case fails when the mean or
//! the 99th percentile exceeds its threshold, or when its reference is
//! missing or unreadable. A failure leaves its images and a report page
//! (`artifacts`); results go out in every format (`report`). `--bless`
//! writes the references instead; a plain check never does.

pub mod artifacts;
pub mod compare;
pub mod config;
pub mod live;
mod report;
mod run;

pub use report::{CaseResult, OutputResult, Verdict, verdict_word};
pub use run::Renderer;

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant};

use compare::{Failure, Image, Range};
use config::{Case, Threshold};
use report::at_case;

use crate::diag::{Code, Diagnostic, display_path};
use crate::gpu::Gpu;
use crate::render::capture::CapturedImage;
use crate::shader::Library;

pub struct Options {
    pub cases: Vec<Case>,
    /// The references' folder (loupe.toml's `references`).
    pub references: PathBuf,
    /// Where a failure's images and report.html go.
    pub artifacts: PathBuf,
    /// `--bless`: write references for these cases (empty: every case).
    pub bless: Option<Vec<String>>,
    /// Sessions rendering at once (`--jobs`).
    pub jobs: usize,
    pub shard: Shard,
}

/// `--shard K/N`: the K-th of N slices, every N-th case from the K-th.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub const ALL: Shard = Shard { index: 1, count: 1 };
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}` is not K/N with 1 <= K <= N");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if (1..=count).contains(&index) { Ok(Shard { index, count }) } else { Err(bad()) }
    }
}

impl Options {
    /// The cases this run takes: its shard's, of those `--bless` names.
    pub fn selected(&self) -> Vec<&Case> {
        let named = |c: &Case| self.bless.as_ref().is_none_or(|names| names.is_empty() || names.contains(&c.name));
        self.cases
            .iter()
            .enumerate()
            .filter(|(i, _)| i % self.shard.count == self.shard.index - 1)
            .map(|(_, c)| c)
            .filter(|c| named(c))
            .collect()
    }

    /// Names given to `--bless` that no case has.
    pub fn unknown_names(&self) -> Vec<&str> {
        let names = self.bless.iter().flatten();
        names.filter(|n| !self.cases.iter().any(|c| &c.name == *n)).map(String::as_str).collect()
    }
}

/// Every selected case, skipped for `reason`: reported, never passed.
pub fn skipped(opts: &Options, reason: &str) -> Vec<CaseResult> {
    opts.selected()
        .into_iter()
        .map(|case| CaseResult { verdict: Verdict::Skipped, reason: Some(reason.to_owned()), ..result(case, case.threshold, None) })
        .collect()
}

/// Renders and compares (or blesses) the selected cases on `gpu`, `jobs`
/// sessions at once; also returns what went wrong outside any case.
pub fn run(opts: &Options, gpu: &Gpu, shader_root: &Path, lib: &Library) -> (Vec<CaseResult>, Vec<Diagnostic>) {
    let selected = opts.selected();
    let adapter = gpu.adapter_name();
    // Each job has a session of its own; on one device they share its
    // queue, so more jobs help only where the device has room (a GPU), and
    // on lavapipe, which already spreads a draw over every core, they
    // mostly add pipeline builds.
    let jobs = opts.jobs.clamp(1, selected.len().max(1));
    let mut results: Vec<(usize, CaseResult)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..jobs)
            .map(|j| {
                let (selected, adapter) = (&selected, &adapter);
                s.spawn(move || {
                    let mut renderer = run::Renderer::new(gpu.clone(), shader_root.to_owned(), lib.clone());
                    selected
                        .iter()
                        .enumerate()
                        .skip(j)
                        .step_by(jobs)
                        .map(|(i, case)| (i, one(&mut renderer, case, opts, adapter)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers.into_iter().flat_map(|w| w.join().unwrap_or_default()).collect::<Vec<_>>()
    });
    results.sort_by_key(|(i, _)| *i);
    let cases: Vec<CaseResult> = results.into_iter().map(|(_, r)| r).collect();
    let mut general = Vec::new();
    if cases.len() != selected.len() {
        general.push(Diagnostic::error(Code::CompilerPanic, "an image job crashed: some cases have no result"));
    }
    if opts.bless.is_none()
        && let Err(e) = artifacts::write_report(&opts.artifacts, &cases, &adapter)
    {
        general.push(Diagnostic::error(Code::Io, e));
    }
    (cases, general)
}

fn result(case: &Case, threshold: Threshold, adapter_key: Option<&str>) -> CaseResult {
    CaseResult {
        name: case.name.clone(),
        scene: display_path(&case.scene),
        at: case.at.clone(),
        verdict: Verdict::Passed,
        reason: None,
        threshold,
        adapter_key: adapter_key.map(str::to_owned),
        outputs: Vec::new(),
        diagnostics: Vec::new(),
        duration: Duration::ZERO,
    }
}

/// One case: rendered, then each output checked or blessed.
fn one(renderer: &mut run::Renderer, case: &Case, opts: &Options, adapter: &str) -> CaseResult {
    let start = Instant::now();
    let (threshold, key) = case.threshold_on(adapter);
    let mut r = result(case, threshold, key);
    match crate::shader::guard::guarded(&case.at.file, "the renderer", || renderer.render(case)) {
        Ok(captures) => {
            for c in &captures {
                let output = if opts.bless.is_some() { bless(c, case, opts, &mut r) } else { check(c, case, opts, &mut r) };
                r.outputs.push(output);
            }
        }
        Err(ds) => {
            // A panic's diagnostic names the file; the renderer's own are
            // already at the case.
            if ds.iter().any(|d| d.code == Code::CompilerPanic) {
                renderer.reset();
            }
            r.diagnostics.extend(ds.into_iter().map(|d| if d.code == Code::CompilerPanic { at_case(&case.at, d) } else { d }));
        }
    }
    if opts.bless.is_some() && r.diagnostics.is_empty() {
        r.verdict = Verdict::Blessed;
    }
    r.settle();
    r.duration = start.elapsed();
    r
}

/// Compares one output with its reference; a failure's diagnostic goes to
/// `r`, its images to the artifacts.
fn check(c: &CapturedImage, case: &Case, opts: &Options, r: &mut CaseResult) -> OutputResult {
    let (output, range) = (c.key(), Range::of(&c.format));
    let path = compare::reference_path(&opts.references, &case.name, &output, range);
    let shown = display_path(&path);
    let actual = Image::of(c);
    let judged = compare::judge(&actual, range, &output, &path, r.threshold, r.adapter_key.as_deref());
    let figures = judged.compared.as_ref().map(|(_, compared)| (compared.flip, compared.relative_mse));
    let out =
        OutputResult { output, reference: shown.clone(), flip: figures.map(|f| f.0), relative_mse: figures.map(|f| f.1), blessed: None };
    if let Some((failure, d)) = judged.failure {
        let bless_hint = format!("if the new image is intended: `loupe check --bless {}`, then review and commit {shown}", case.name);
        let d = match failure {
            Failure::Missing => d.with_note(format!("render it with `loupe check --bless {}`, look at it, and commit it", case.name)),
            Failure::Unusable => d.with_note(bless_hint),
            Failure::Mismatch => {
                let mse = figures.map_or(0.0, |f| f.1);
                d.with_note(format!("relMSE {mse:.3e} against {shown}")).with_note(bless_hint)
            }
        };
        let compared = judged.compared.as_ref().map(|(reference, compared)| (reference, &compared.map));
        fail(r, case, opts, d, (c, &actual), compared);
    }
    out
}

/// Records a failed output: its diagnostic, at the case, naming where its
/// images were written. `actual`: the capture and its image; `compared`:
/// the reference and FLIP's map, when the two could be compared.
fn fail(
    r: &mut CaseResult,
    case: &Case,
    opts: &Options,
    d: Diagnostic,
    (c, actual): (&CapturedImage, &Image),
    compared: Option<(&Image, &crate::flip::ErrorMap)>,
) {
    let exr = (Range::of(&c.format) == Range::High).then(|| compare::encode(c, Range::High).ok()).flatten();
    let (reference, map) = compared.unzip();
    let written = artifacts::write_output(&opts.artifacts, &case.name, &c.key(), actual, exr.as_deref(), reference, map);
    let d = at_case(&case.at, d);
    r.diagnostics.push(match written {
        Ok(()) => d.with_note(format!(
            "images: {}, report: {}",
            display_path(&opts.artifacts.join(&case.name)),
            display_path(&opts.artifacts.join("report.html"))
        )),
        Err(e) => d.with_note(format!("its images were not written: {e}")),
    });
}

/// Writes one output as its reference, saying what it replaced; an
/// unchanged reference is left as it is, so blessing twice changes no file.
fn bless(c: &CapturedImage, case: &Case, opts: &Options, r: &mut CaseResult) -> OutputResult {
    let (output, range) = (c.key(), Range::of(&c.format));
    let path = compare::reference_path(&opts.references, &case.name, &output, range);
    let shown = display_path(&path);
    let actual = Image::of(c);
    let change = match compare::read(&path, range) {
        Ok(None) => "new".to_owned(),
        Err(_) => "replaces an unreadable reference".to_owned(),
        Ok(Some(old)) if (old.width, old.height) != (actual.width, actual.height) => {
            format!("replaces a {}x{} reference", old.width, old.height)
        }
        Ok(Some(old)) => match compare::compare(&actual, &old, range) {
            Ok(d) if d.relative_mse == 0.0 && d.flip.mean == 0.0 => "unchanged".to_owned(),
            Ok(d) => format!("changed: FLIP mean {:.4}, p99 {:.4}, relMSE {:.2e} against the old", d.flip.mean, d.flip.p99, d.relative_mse),
            Err(e) => format!("replaces a reference that does not compare: {e}"),
        },
    };
    if change != "unchanged" {
        let written = compare::encode(c, range).and_then(|bytes| {
            let dir = path.parent().expect("a case folder");
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
            std::fs::write(&path, bytes).map_err(|e| e.to_string())
        });
        if let Err(e) = written {
            r.diagnostics.push(at_case(&case.at, Diagnostic::error(Code::Io, format!("cannot write {shown}: {e}"))));
        }
    }
    OutputResult { output, reference: shown, flip: None, relative_mse: None, blessed: Some(change) }
}
