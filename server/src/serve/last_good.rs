//! The last good version of each source file, and what changed since.
//!
//! A file's text is *good* once the pipelines built from it compiled from
//! it: no reload in flight, at least one of them ok and none stale or
//! failed, and no error pointing into it. While a file is not
//! good, its text on disk is diffed against the last good one: the lines
//! that turned a running pass stale, with the failing lines marked, and the
//! text "revert to last good" writes back. A file never good since the
//! daemon started (broken from the start) has nothing to diff against.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::sync::Arc;

use similar::{ChangeTag, TextDiff};

use super::shared::{Shared, read};
use crate::diag::{Diagnostic, Severity};
use crate::protocol::{DiffLine, FileDiff, Hunk, PassStatus, PipelineInfo};
use crate::shader::Library;

/// Unchanged lines shown around each change.
const CONTEXT: usize = 3;

/// Each file's last good text and where it was read from, by display path.
#[derive(Default)]
pub struct LastGood {
    texts: BTreeMap<String, (PathBuf, Arc<str>)>,
}

impl LastGood {
    /// Records every good file's current text, and returns the diff of each
    /// file that is not good but has a last good text it differs from.
    /// `settled`: no reload is in flight, so the pipelines were built from
    /// the current texts.
    pub fn update(&mut self, library: &Library, pipelines: &[PipelineInfo], diagnostics: &[Diagnostic], settled: bool) -> Vec<FileDiff> {
        let mut broken: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
        let mut built: BTreeSet<&str> = BTreeSet::new();
        for p in pipelines {
            for f in &p.files {
                if p.status == PassStatus::Ok {
                    built.insert(f);
                } else {
                    broken.entry(f).or_default().insert(&p.name);
                }
            }
        }
        let errors: BTreeMap<&str, BTreeSet<usize>> =
            diagnostics.iter().filter(|d| d.severity == Severity::Error).fold(BTreeMap::new(), |mut m, d| {
                if let Some(loc) = &d.location {
                    m.entry(loc.file.as_str()).or_default().insert(loc.line as usize);
                }
                m
            });
        for f in library.files().filter(|_| settled) {
            let name = f.display.as_str();
            if built.contains(name) && !broken.contains_key(name) && !errors.contains_key(name) {
                self.texts.insert(f.display.clone(), (f.path.clone(), f.text.clone()));
            }
        }
        let not_good: BTreeSet<&str> = broken.keys().chain(errors.keys()).copied().collect();
        not_good
            .into_iter()
            .filter_map(|file| {
                let (_, good) = self.texts.get(file)?;
                let current = library.get(file).map_or("", |f| &f.text);
                let failing = errors.get(file).cloned().unwrap_or_default();
                let hunks = hunks(good, current, &failing);
                let pipelines = broken.get(file).map(|s| s.iter().map(|p| (*p).to_owned()).collect()).unwrap_or_default();
                (!hunks.is_empty()).then(|| FileDiff { file: file.to_owned(), pipelines, hunks })
            })
            .collect()
    }

    /// The last good text of `file` and its path.
    pub fn text(&self, file: &str) -> Option<(PathBuf, Arc<str>)> {
        self.texts.get(file).cloned()
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RevertError {
    #[error("`{0}` has no last good version to revert to: it is good, or never was")]
    NoLastGood(String),
    #[error("`{0}` is not a source file under the project's source roots")]
    NotASource(String),
    #[error("cannot write `{0}`: {1}")]
    Write(String, std::io::Error),
}

/// Writes `file`'s last good text over it (`POST /api/files/revert`, the
/// window's "revert to last good"), as an editor saves: a sibling
/// temporary file renamed over it, so it is never seen half written. The
/// watcher then reloads it like any save. Only a project source under a
/// source root is written (not a generated module).
pub fn revert(shared: &Shared, file: &str) -> Result<(), RevertError> {
    let state = read(&shared.files);
    let (path, text) = state.last_good.get(file).ok_or_else(|| RevertError::NoLastGood(file.to_owned()))?;
    let inside = |root: &PathBuf| Some(path.canonicalize().ok()?.starts_with(root.canonicalize().ok()?));
    if !shared.source_roots.iter().any(|r| inside(r) == Some(true)) {
        return Err(RevertError::NotASource(file.to_owned()));
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let temporary = path.with_file_name(format!(".{name}.loupe-revert"));
    let written = std::fs::write(&temporary, text.as_bytes()).and_then(|()| std::fs::rename(&temporary, path));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        RevertError::Write(file.to_owned(), e)
    })
}

/// The line diff of `old` → `new` in hunks with [`CONTEXT`] lines around
/// each change; `failing`: lines of `new` to mark.
fn hunks(old: &str, new: &str, failing: &BTreeSet<usize>) -> Vec<Hunk> {
    let diff = TextDiff::from_lines(old, new);
    diff.grouped_ops(CONTEXT)
        .iter()
        .map(|group| {
            let lines: Vec<DiffLine> = group
                .iter()
                .flat_map(|op| diff.iter_changes(op))
                .map(|c| {
                    let (old, new) = (c.old_index().map(|i| i + 1), c.new_index().map(|i| i + 1));
                    DiffLine {
                        tag: match c.tag() {
                            ChangeTag::Equal => " ",
                            ChangeTag::Delete => "-",
                            ChangeTag::Insert => "+",
                        },
                        old,
                        new,
                        text: c.value().trim_end_matches(['\n', '\r']).to_owned(),
                        failing: new.is_some_and(|n| failing.contains(&n)),
                    }
                })
                .collect();
            let first = group.first().expect("a group holds an op");
            Hunk { old_start: first.old_range().start + 1, new_start: first.new_range().start + 1, lines }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::{Code, Location};
    use crate::shader::SourceFile;

    fn library(files: &[(&str, &str)]) -> Library {
        Library::new(files.iter().map(|(name, text)| SourceFile::from_text((*name).into(), name.into(), Arc::from(*text))))
    }

    fn pipeline(name: &str, status: PassStatus, files: &[&str]) -> PipelineInfo {
        PipelineInfo {
            name: name.into(),
            shader: String::new(),
            defs: String::new(),
            status,
            generation: 1,
            files: files.iter().map(|f| (*f).into()).collect(),
        }
    }

    fn error_at(file: &str, line: u32) -> Diagnostic {
        Diagnostic::error(Code::Parse, "broken").at(Location { file: file.into(), line, column: 1, end_line: line, end_column: 2 })
    }

    #[test]
    fn a_file_is_diffed_against_its_text_when_last_every_pipeline_built_from_it_compiled() {
        let mut last = LastGood::default();
        let good = library(&[("a.wgsl", "x\ny\n"), ("b.wgsl", "b\n")]);
        let ok = [pipeline("p", PassStatus::Ok, &["a.wgsl", "b.wgsl"])];
        assert!(last.update(&good, &ok, &[], true).is_empty(), "all good: nothing to diff");

        // a.wgsl broken: p is stale, its error at line 2.
        let broken = library(&[("a.wgsl", "x\nY(\n"), ("b.wgsl", "b\n")]);
        let stale = [pipeline("p", PassStatus::Stale, &["a.wgsl", "b.wgsl"])];
        let diffs = last.update(&broken, &stale, &[error_at("a.wgsl", 2)], true);
        assert_eq!(diffs.len(), 1, "b.wgsl is unchanged: no diff, {diffs:?}");
        assert_eq!((diffs[0].file.as_str(), diffs[0].pipelines.as_slice()), ("a.wgsl", ["p".to_owned()].as_slice()));
        let marked: Vec<&str> = diffs[0].hunks[0].lines.iter().filter(|l| l.failing).map(|l| l.text.as_str()).collect();
        assert_eq!(marked, ["Y("]);
        assert_eq!(last.text("a.wgsl").map(|(_, t)| t).as_deref(), Some("x\ny\n"), "the broken text is not recorded as good");

        // A second broken edit still diffs against the last good one.
        let worse = library(&[("a.wgsl", "x\nZ(\n"), ("b.wgsl", "b\n")]);
        let diffs = last.update(&worse, &stale, &[error_at("a.wgsl", 2)], true);
        assert!(diffs[0].hunks[0].lines.iter().any(|l| l.tag == "-" && l.text == "y"));

        // Fixed: good again, and the fix is the new last good text.
        let fixed = library(&[("a.wgsl", "x\nz\n"), ("b.wgsl", "b\n")]);
        assert!(last.update(&fixed, &ok, &[], true).is_empty());
        assert_eq!(last.text("a.wgsl").map(|(_, t)| t).as_deref(), Some("x\nz\n"));
    }

    #[test]
    fn a_text_no_pipeline_compiled_yet_is_not_good() {
        let mut last = LastGood::default();
        let lib = library(&[("a.wgsl", "x\n")]);
        // Not built yet, or built while a reload of a newer text compiles.
        assert!(last.update(&lib, &[], &[], true).is_empty());
        last.update(&lib, &[pipeline("p", PassStatus::Ok, &["a.wgsl"])], &[], false);
        assert!(last.text("a.wgsl").is_none());
        last.update(&lib, &[pipeline("p", PassStatus::Ok, &["a.wgsl"])], &[], true);
        assert!(last.text("a.wgsl").is_some());
    }

    #[test]
    fn a_file_broken_from_the_start_has_nothing_to_diff_against() {
        let mut last = LastGood::default();
        let broken = library(&[("a.wgsl", "(\n")]);
        let failed = [pipeline("p", PassStatus::Failed, &["a.wgsl"])];
        assert!(last.update(&broken, &failed, &[error_at("a.wgsl", 1)], true).is_empty());
        assert!(last.text("a.wgsl").is_none());
    }

    #[test]
    fn a_changed_line_is_removed_and_added_with_context_and_its_failure_marked() {
        let old = "a\nb\nc\nd\ne\nf\ng\nh\n";
        let new = "a\nb\nc\nd\nE\nf\ng\nh\n";
        let h = hunks(old, new, &BTreeSet::from([5]));
        assert_eq!(h.len(), 1);
        assert_eq!((h[0].old_start, h[0].new_start), (2, 2), "three lines of context before");
        let tags: Vec<_> = h[0].lines.iter().map(|l| (l.tag, l.old, l.new, l.text.as_str(), l.failing)).collect();
        assert_eq!(
            tags,
            [
                (" ", Some(2), Some(2), "b", false),
                (" ", Some(3), Some(3), "c", false),
                (" ", Some(4), Some(4), "d", false),
                ("-", Some(5), None, "e", false),
                ("+", None, Some(5), "E", true),
                (" ", Some(6), Some(6), "f", false),
                (" ", Some(7), Some(7), "g", false),
                (" ", Some(8), Some(8), "h", false),
            ]
        );
    }

    #[test]
    fn distant_changes_are_separate_hunks_and_equal_texts_none() {
        let old: String = (1..=30).map(|i| format!("{i}\n")).collect();
        let new: String = (1..=30).filter(|i| *i != 27).map(|i| if i == 3 { "three\n".to_owned() } else { format!("{i}\n") }).collect();
        let h = hunks(&old, &new, &BTreeSet::new());
        assert_eq!(h.len(), 2);
        assert_eq!((h[1].old_start, h[1].new_start), (24, 24));
        assert!(h[1].lines.iter().any(|l| l.tag == "-" && l.text == "27"));
        assert!(hunks(&old, &old, &BTreeSet::new()).is_empty());
    }
}
