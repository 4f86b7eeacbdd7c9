//! The Problems panel: each diagnostic as `file:line:col: severity[code]:
//! message` with the source lines it points at; clicking one asks for the
//! editor at that place. Under them, each file that broke a pass with its
//! diff against its last good version, and "revert to last good".

use crate::model::{FileDiff, Location, Problem};

/// What the user asked of the panel.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Open the editor at a location.
    Open(Location),
    /// Write this file's last good version back (once confirmed).
    Revert(String),
}

const FAILED: egui::Color32 = egui::Color32::from_rgb(230, 90, 80);
const ADDED: egui::Color32 = egui::Color32::from_rgb(110, 190, 110);

/// Draws the problems and the broken files' diffs; `excerpt` gives the
/// source lines of a location. Returns what the user clicked, if anything.
pub fn show(
    ui: &mut egui::Ui,
    problems: &[Problem],
    files: &[FileDiff],
    mut excerpt: impl FnMut(&Location) -> Option<String>,
) -> Option<Action> {
    ui.heading(format!("Problems ({})", problems.len()));
    let mut clicked = None;
    egui::ScrollArea::both().id_salt("problems").show(ui, |ui| {
        for p in problems {
            let color = if p.severity == "error" { FAILED } else { egui::Color32::from_rgb(220, 170, 60) };
            let text = egui::RichText::new(headline(p)).color(color).monospace();
            match &p.location {
                Some(loc) => {
                    if ui.link(text).on_hover_text("open in $VISUAL / $EDITOR").clicked() {
                        clicked = Some(Action::Open(loc.clone()));
                    }
                    if let Some(lines) = excerpt(loc) {
                        ui.label(egui::RichText::new(lines).monospace());
                    }
                }
                None => {
                    ui.label(text);
                }
            }
            ui.separator();
        }
        for f in files {
            ui.horizontal_wrapped(|ui| {
                let running = if f.pipelines.is_empty() { String::new() } else { format!(" (not running: {})", f.pipelines.join(", ")) };
                ui.label(egui::RichText::new(format!("{} changed since it last compiled{running}", f.file)).monospace());
                if ui.button("revert to last good").on_hover_text("write the version that last compiled back to the file").clicked() {
                    clicked = Some(Action::Revert(f.file.clone()));
                }
            });
            for line in diff_lines(f) {
                let (text, colour, failing) = line;
                let mut rich = egui::RichText::new(text).monospace();
                rich = match colour {
                    Some(c) => rich.color(c),
                    None => rich,
                };
                if failing {
                    rich = rich.background_color(egui::Color32::from_rgba_unmultiplied(230, 90, 80, 48));
                }
                ui.label(rich);
            }
            ui.separator();
        }
    });
    clicked
}

/// The diff as lines to draw: `old new tag text` with the line numbers
/// right-aligned, each with its colour and whether an error points at it;
/// `…` between hunks.
fn diff_lines(f: &FileDiff) -> Vec<(String, Option<egui::Color32>, bool)> {
    let numbers = f.hunks.iter().flat_map(|h| &h.lines).flat_map(|l| [l.old, l.new]).flatten();
    let width = numbers.max().unwrap_or(0).to_string().len();
    let number = |n: Option<usize>| n.map_or(" ".repeat(width), |n| format!("{n:>width$}"));
    let mut out = Vec::new();
    for (i, h) in f.hunks.iter().enumerate() {
        if i > 0 {
            out.push(("…".to_owned(), None, false));
        }
        for l in &h.lines {
            let colour = match l.tag.as_str() {
                "-" => Some(FAILED),
                "+" => Some(ADDED),
                _ => None,
            };
            out.push((format!("{} {} {} {}", number(l.old), number(l.new), l.tag, l.text), colour, l.failing));
        }
    }
    out
}

/// The line compilers and problem matchers print.
pub fn headline(p: &Problem) -> String {
    let place = p.location.as_ref().map(|l| format!("{}:{}:{}: ", l.file, l.line, l.column)).unwrap_or_default();
    format!("{place}{}[{}]: {}", p.severity, p.code, p.message)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DiffLine, Hunk};

    fn line(tag: &str, old: Option<usize>, new: Option<usize>, text: &str, failing: bool) -> DiffLine {
        DiffLine { tag: tag.into(), old, new, text: text.into(), failing }
    }

    #[test]
    fn a_diff_reads_as_numbered_lines_with_the_failing_one_marked() {
        let f = FileDiff {
            file: "a.wgsl".into(),
            pipelines: vec!["p".into()],
            hunks: vec![
                Hunk {
                    old_start: 9,
                    new_start: 9,
                    lines: vec![line(" ", Some(9), Some(9), "x", false), line("-", Some(10), None, "y", false)],
                },
                Hunk { old_start: 20, new_start: 19, lines: vec![line("+", None, Some(19), "Y(", true)] },
            ],
        };
        let lines = diff_lines(&f);
        let text: Vec<&str> = lines.iter().map(|(t, _, _)| t.as_str()).collect();
        assert_eq!(text, [" 9  9   x", "10    - y", "…", "   19 + Y("]);
        assert_eq!(lines.iter().map(|l| l.2).collect::<Vec<_>>(), [false, false, false, true]);
        assert_eq!((lines[1].1, lines[3].1), (Some(FAILED), Some(ADDED)));
    }
}
