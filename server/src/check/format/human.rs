//! Source excerpts with underlined labels, rendered by codespan-reporting,
//! then a one-line summary.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io;

use codespan_reporting::diagnostic::{self as cs, LabelStyle};
use codespan_reporting::files::{self, SimpleFiles};
use codespan_reporting::term::termcolor::{Ansi, NoColor};
use codespan_reporting::term::{self, Config, WriteStyle};

use super::super::images::{Verdict, verdict_word};
use super::super::report::CheckReport;
use super::Options;
use crate::diag::{Diagnostic, Location, Severity, SourceFiles};

pub fn write(report: &CheckReport, files: &SourceFiles, opts: &Options, out: &mut dyn io::Write) -> io::Result<()> {
    if opts.color { render(report, files, opts, &mut Ansi::new(out)) } else { render(report, files, opts, &mut NoColor::new(out)) }
}

/// Diagnostics outside a check report (from `loupe render`), with excerpts
/// read from the files they name.
pub fn write_diagnostics(diags: &[Diagnostic], color: bool, out: &mut dyn io::Write) -> io::Result<()> {
    let mut files = SourceFiles::default();
    read_sources(diags, &mut files);
    if color { emit(diags, &files, &mut Ansi::new(out)) } else { emit(diags, &files, &mut NoColor::new(out)) }
}

/// Adds the text of every file the diagnostics point into that `files`
/// lacks, read by its display path; a file that is not text (a binary glTF)
/// is left out, and its diagnostics print without an excerpt.
pub fn read_sources(diags: &[Diagnostic], files: &mut SourceFiles) {
    for d in diags {
        for l in d.location.iter().chain(d.labels.iter().map(|l| &l.location)) {
            if files.get(&l.file).is_none()
                && let Ok(text) = std::fs::read_to_string(&l.file)
            {
                files.insert(l.file.clone(), text.into());
            }
        }
    }
}

fn emit<W: WriteStyle>(diags: &[Diagnostic], files: &SourceFiles, w: &mut W) -> io::Result<()> {
    let mut db = Database { files, db: SimpleFiles::new(), ids: HashMap::new() };
    for d in diags {
        match to_codespan(d, &mut db) {
            Some(diagnostic) => term::emit_to_write_style(w, &Config::default(), &db.db, &diagnostic).map_err(io_error)?,
            None => one_liner(d, w)?,
        }
    }
    Ok(())
}

fn render<W: WriteStyle>(report: &CheckReport, files: &SourceFiles, opts: &Options, w: &mut W) -> io::Result<()> {
    let diags: Vec<Diagnostic> = report.diagnostics().cloned().collect();
    emit(&diags, files, w)?;
    for case in &report.images {
        writeln!(w, "{}", case.line())?;
    }
    writeln!(w, "{}", summary(report, opts.timings))
}

/// The codespan file database, filled with only the files diagnostics name.
struct Database<'a> {
    files: &'a SourceFiles,
    db: SimpleFiles<&'a str, &'a str>,
    ids: HashMap<&'a str, usize>,
}

impl<'a> Database<'a> {
    /// `None` when the file has no text to excerpt.
    fn label(&mut self, style: LabelStyle, location: &'a Location) -> Option<cs::Label<usize>> {
        let text = self.files.get(&location.file)?;
        let id = *self.ids.entry(&location.file).or_insert_with(|| self.db.add(&location.file, text));
        Some(cs::Label::new(style, id, byte_range(text, location)))
    }
}

/// `None` when the diagnostic's own file has no text to excerpt.
fn to_codespan<'a>(d: &'a Diagnostic, db: &mut Database<'a>) -> Option<cs::Diagnostic<usize>> {
    let location = d.location.as_ref()?;
    let primary = db.label(LabelStyle::Primary, location)?;
    let mut labels = Vec::new();
    // A label in a file we have no text for still carries information, so it
    // becomes a note rather than vanishing.
    let mut notes = Vec::new();
    for label in &d.labels {
        let style = if label.primary { LabelStyle::Primary } else { LabelStyle::Secondary };
        match db.label(style, &label.location) {
            Some(l) => labels.push(l.with_message(&label.message)),
            None => notes.push(format!("{}: {}", label.location, label.message)),
        }
    }
    // codespan's header names the first primary label; without one it would
    // print no location at all.
    if !labels.iter().any(|l| l.style == LabelStyle::Primary) {
        labels.insert(0, primary);
    }
    notes.extend(d.notes.iter().cloned());
    Some(
        cs::Diagnostic::new(severity(d.severity)).with_code(d.code.as_str()).with_message(&d.message).with_labels(labels).with_notes(notes),
    )
}

/// `file:line:col: severity[code]: message` and the notes, for diagnostics
/// without an excerpt; styled like codespan's header so both kinds read alike.
fn one_liner<W: WriteStyle>(d: &Diagnostic, w: &mut W) -> io::Result<()> {
    if let Some(location) = &d.location {
        write!(w, "{location}: ")?;
    }
    w.set_header(severity(d.severity))?;
    write!(w, "{}[{}]", d.severity.as_str(), d.code.as_str())?;
    w.set_header_message()?;
    write!(w, ": {}", d.message)?;
    w.reset()?;
    writeln!(w)?;
    for note in &d.notes {
        writeln!(w, "  = {note}")?;
    }
    writeln!(w)
}

fn severity(severity: Severity) -> cs::Severity {
    match severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
        Severity::Note => cs::Severity::Note,
    }
}

fn summary(report: &CheckReport, timings: bool) -> String {
    let mut s = format!("checked {} ({}", count(report.modules.len(), "file"), count(report.pipelines(), "pipeline"));
    if let Some(adapter) = &report.adapter {
        let _ = write!(s, " on {adapter}");
    }
    s.push(')');
    if timings {
        let _ = write!(s, " in {} ms", report.duration.as_millis());
    }
    let _ = write!(s, ": {}, {}", count(report.count(Severity::Error), "error"), count(report.count(Severity::Warning), "warning"));
    if !report.images.is_empty() {
        let _ = write!(s, "; {}:", count(report.images.len(), "image case"));
        let verdicts = [Verdict::Passed, Verdict::Failed, Verdict::Skipped, Verdict::Blessed];
        let counted: Vec<String> = verdicts
            .iter()
            .map(|&v| (report.cases(v), v))
            .filter(|(n, _)| *n > 0)
            .map(|(n, v)| format!("{n} {}", verdict_word(v)))
            .collect();
        let _ = write!(s, " {}", counted.join(", "));
    }
    s
}

fn count(n: usize, noun: &str) -> String {
    if n == 1 { format!("1 {noun}") } else { format!("{n} {noun}s") }
}

/// The byte range a location covers in `text`; see `offset`.
fn byte_range(text: &str, location: &Location) -> std::ops::Range<usize> {
    let start = offset(text, location.line, location.column);
    let end = offset(text, location.end_line, location.end_column).max(start);
    start..end
}

/// Byte offset of a 1-based line and character column, the inverse of
/// `LineIndex::line_col`. A column past the line's end clamps to the end of
/// the line and a line past the last to the end of the text, so a location
/// from a since-edited file still renders instead of failing.
fn offset(text: &str, line: u32, column: u32) -> usize {
    let start = match line {
        0 | 1 => 0,
        n => match text.match_indices('\n').nth(n as usize - 2) {
            Some((i, _)) => i + 1,
            None => return text.len(),
        },
    };
    let rest = &text[start..];
    let line_text = &rest[..rest.find('\n').unwrap_or(rest.len())];
    let in_line = line_text.char_indices().nth(column.saturating_sub(1) as usize).map_or(line_text.len(), |(i, _)| i);
    start + in_line
}

fn io_error(e: files::Error) -> io::Error {
    match e {
        files::Error::Io(e) => e,
        e => io::Error::other(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixture::{self, loc};
    use super::*;
    use crate::diag::{Code, LineIndex};

    fn render(report: &CheckReport, files: &SourceFiles, opts: Options) -> String {
        let mut out = Vec::new();
        write(report, files, &opts, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn excerpts_imported_file_and_summarises() {
        let out = render(&fixture::report(), &fixture::files(), Options::default());
        assert!(out.contains("error[validation]: cannot add \"f32\" & \"vec3<f32>\""), "{out}");
        assert!(out.contains("┌─ shaders/lib/util.wgsl:5:7"), "{out}");
        assert!(out.contains("  let bad = 1.0 + v;"), "{out}");
        assert!(out.contains("#import lib::util"), "{out}");
        assert!(out.contains("= both operands must have the same type"), "{out}");
        assert!(out.contains("┌─ shaders/main.wgsl:3:1"), "{out}");
        assert!(!out.contains('\x1b'), "no colour unless asked");
        assert!(out.ends_with("\nchecked 2 files (2 pipelines on llvmpipe): 1 error, 1 warning\n"), "{out}");
    }

    #[test]
    fn timings_and_colour_only_when_asked() {
        let out = render(&fixture::report(), &fixture::files(), Options { color: true, timings: true });
        assert!(out.contains('\x1b'));
        assert!(out.ends_with("checked 2 files (2 pipelines on llvmpipe) in 40 ms: 1 error, 1 warning\n"), "{out}");
    }

    #[test]
    fn summary_singular_and_no_adapter() {
        let mut report = fixture::report();
        report.modules.truncate(1);
        report.adapter = None;
        report.general.push(Diagnostic::error(Code::DeviceMissing, "no adapter"));
        assert_eq!(summary(&report, false), "checked 1 file (1 pipeline): 1 error, 0 warnings");
    }

    #[test]
    fn missing_text_falls_back_to_one_liner() {
        let mut report = fixture::report();
        report.general.push(Diagnostic::error(Code::DeviceMissing, "no GPU adapter").with_note("use --no-device"));
        let out = render(&report, &SourceFiles::default(), Options::default());
        assert!(
            out.contains("shaders/lib/util.wgsl:5:7: error[validation]: cannot add \"f32\" & \"vec3<f32>\"\n  = both operands"),
            "{out}"
        );
        assert!(out.contains("\nerror[device-missing]: no GPU adapter\n  = use --no-device\n"), "{out}");
    }

    #[test]
    fn secondary_label_without_text_becomes_note() {
        let mut files = SourceFiles::default();
        files.insert(fixture::UTIL, fixture::files().get(fixture::UTIL).unwrap().into());
        let out = render(&fixture::report(), &files, Options::default());
        assert!(out.contains("┌─ shaders/lib/util.wgsl:5:7"), "{out}");
        assert!(out.contains("= shaders/main.wgsl:1:1: imported here"), "{out}");
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        let text = "x\nlet é = fooo;\n";
        let start = text.find("fooo").unwrap();
        let location = LineIndex::new(text).location("m.wgsl", text, start..start + 4);
        assert_eq!((location.line, location.column, location.end_column), (2, 9, 13));
        assert_eq!(byte_range(text, &location), start..start + 4);

        let mut files = SourceFiles::default();
        files.insert("m.wgsl", text.into());
        let report = CheckReport {
            general: vec![Diagnostic::error(Code::Parse, "unknown").with_label(location, "here", true)],
            ..CheckReport::default()
        };
        let out = render(&report, &files, Options::default());
        assert!(out.contains("┌─ m.wgsl:2:9"), "{out}");
        // The underline sits under `fooo`, whose display column is 8 (0-based).
        let source = out.lines().find(|l| l.ends_with("let é = fooo;")).unwrap();
        let carets = out.lines().find(|l| l.contains("^^^^")).unwrap();
        let column = |line: &str, pat: &str| line[..line.find(pat).unwrap()].chars().count();
        assert_eq!(column(source, "fooo"), column(carets, "^^^^"), "{out}");
    }

    #[test]
    fn offsets_clamp() {
        let text = "ab\ncd";
        assert_eq!(offset(text, 1, 99), 2);
        assert_eq!(offset(text, 2, 3), 5);
        assert_eq!(offset(text, 9, 1), 5);
        assert_eq!(byte_range(text, &loc("f", 2, 2, 1, 1)), 4..4);
    }
}
