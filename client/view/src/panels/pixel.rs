//! The Pixel panel: for the pixel pinned in the Inspector, its
//! `debugPrintf` lines grouped by pass and call with the call's source
//! line (client/prints.js), and its history through the frame: per pass in
//! frame order, its kind, the invocation of a per-pixel compute pass and
//! the images it read there, each output's value before and after, each
//! draw's fragments with their depth verdicts, and the tensors there
//! (client/pixel_history.js). Values
//! are exact, as the Inspector's readout gives them.

use crate::model::Model;
use crate::pixel::{self, Fragment, PassHistory, Prints, Rgba, TexelChange};

/// Lines shown per call; a loop that prints more says how many it left out.
const MAX_PER_CALL: usize = 64;
/// Channels shown per tensor before "… N more".
const MAX_CHANNELS: usize = 16;

const PASSED: egui::Color32 = egui::Color32::from_rgb(110, 190, 110);
const FAILED: egui::Color32 = egui::Color32::from_rgb(230, 90, 80);
const CULLED: egui::Color32 = egui::Color32::from_rgb(220, 170, 60);

/// Draws the panel; `source_line(file, line)` gives a line of a source
/// file. Returns true when the user asked to unpin.
pub fn show(ui: &mut egui::Ui, model: &Model, mut source_line: impl FnMut(&str, u32) -> Option<String>) -> bool {
    let Some([x, y]) = model.pixel else {
        ui.label("Click a texel in the Inspector to pin its pixel: its debugPrintf lines and its history through the frame show here.");
        return false;
    };
    let mut unpin = false;
    ui.horizontal_wrapped(|ui| {
        ui.label(match &model.history {
            Some(h) => format!("({x}, {y}) through frame {}", h.frame),
            None => format!("({x}, {y}): waiting for a frame"),
        });
        unpin = ui.button("Unpin").on_hover_text("stop recording this pixel (Escape or a click on it in the Inspector)").clicked();
    });
    ui.separator();
    egui::ScrollArea::both().id_salt("pixel").show(ui, |ui| {
        ui.strong("Prints");
        prints(ui, model.prints.as_ref(), &mut source_line);
        ui.separator();
        ui.strong("History");
        for (i, p) in model.history.iter().flat_map(|h| &h.passes).enumerate() {
            pass(ui, i, p);
        }
    });
    unpin
}

fn prints(ui: &mut egui::Ui, prints: Option<&Prints>, source_line: &mut impl FnMut(&str, u32) -> Option<String>) {
    let Some(p) = prints else {
        ui.label("waiting for a frame");
        return;
    };
    if p.lines.is_empty() {
        ui.label(format!("none in frame {}", p.frame));
    }
    for (pass, calls) in pixel::group(&p.lines) {
        ui.label(egui::RichText::new(pass).strong());
        for call in calls {
            ui.horizontal_wrapped(|ui| {
                ui.label(egui::RichText::new(format!("{}:{}:{}", call.file, call.line, call.column)).monospace().weak());
                if let Some(source) = source_line(call.file, call.line) {
                    ui.label(egui::RichText::new(source.trim()).monospace());
                }
            });
            ui.label(egui::RichText::new(shown_lines(&call.texts)).monospace());
        }
    }
    if p.dropped > 0 {
        ui.colored_label(CULLED, format!("{} more did not fit the buffer", p.dropped));
    }
}

/// A call's lines, the first [`MAX_PER_CALL`] and how many more.
fn shown_lines(texts: &[&str]) -> String {
    let shown = texts[..texts.len().min(MAX_PER_CALL)].join("\n");
    match texts.len().saturating_sub(MAX_PER_CALL) {
        0 => shown,
        more => format!("{shown}\n… {more} more"),
    }
}

fn pass(ui: &mut egui::Ui, i: usize, p: &PassHistory) {
    ui.add_space(4.0);
    ui.horizontal_wrapped(|ui| {
        ui.label(egui::RichText::new(&p.pass).strong());
        ui.label(egui::RichText::new(&p.kind).weak());
        if let Some(id) = p.invocation {
            ui.label(format!("invocation ({}, {}, {})", id[0], id[1], id[2]));
        }
        if !p.inputs.is_empty() {
            ui.label(format!("reads {}", p.inputs.join(", ")));
        }
    });
    if !p.outputs.is_empty() {
        egui::Grid::new(("pixel-outputs", i)).striped(true).num_columns(3).show(ui, |ui| {
            for head in ["output", "before", "after"] {
                ui.label(egui::RichText::new(head).weak());
            }
            ui.end_row();
            for o in &p.outputs {
                ui.label(format!("{} [{}, {}]", o.output, o.texel[0], o.texel[1]));
                ui.monospace(before(o));
                ui.monospace(o.after.as_ref().map_or("not read".to_owned(), value));
                ui.end_row();
            }
        });
    }
    match &p.draws {
        None => {}
        Some(draws) if draws.iter().all(|d| d.fragments.is_empty()) => {
            ui.label("no draw launched a fragment here");
        }
        Some(draws) => {
            egui::Grid::new(("pixel-fragments", i)).striped(true).num_columns(4).show(ui, |ui| {
                for head in ["draw", "primitive", "depth", "verdict"] {
                    ui.label(egui::RichText::new(head).weak());
                }
                ui.end_row();
                for d in draws {
                    for f in &d.fragments {
                        ui.label(&d.name);
                        ui.monospace(f.primitive.to_string());
                        ui.monospace(f.depth.map_or("—".to_owned(), |d| d.to_string()));
                        let kept = p.survivor.as_ref().is_some_and(|s| s.is(&d.name, f));
                        let text = if kept { format!("{}, wrote the pixel", verdict(f)) } else { verdict(f) };
                        ui.colored_label(verdict_colour(&f.verdict), text);
                        ui.end_row();
                    }
                }
            });
        }
    }
    if !p.tensors.is_empty() {
        egui::Grid::new(("pixel-tensors", i)).striped(true).num_columns(2).show(ui, |ui| {
            for head in ["tensor", "channel → value"] {
                ui.label(egui::RichText::new(head).weak());
            }
            ui.end_row();
            for t in &p.tensors {
                ui.label(format!("{} [{}, {}]", t.output, t.at[0], t.at[1]));
                ui.monospace(channels(&t.channels));
                ui.end_row();
            }
        });
    }
}

/// A channel exactly (the shortest decimal that reads back as the same
/// 32-bit float); JSON carries no NaN or infinity.
fn number(v: Option<f32>) -> String {
    v.map_or("not finite".to_owned(), |v| v.to_string())
}

/// An RGBA value, channels separated.
fn value(v: &Rgba) -> String {
    v.map(number).join(", ")
}

/// What an output held before the pass, in words or numbers.
fn before(o: &TexelChange) -> String {
    match (o.origin.as_str(), &o.before) {
        ("read", Some(v)) => value(v),
        ("cleared", _) => "cleared".to_owned(),
        ("undefined", _) => "undefined (first write)".to_owned(),
        _ => "not read".to_owned(),
    }
}

fn verdict(f: &Fragment) -> String {
    let words = match f.verdict.as_str() {
        "failed_depth" => "failed depth",
        "not_tested" => "not tested",
        other => other,
    };
    if f.helper { format!("{words} (helper lane)") } else { words.to_owned() }
}

fn verdict_colour(verdict: &str) -> egui::Color32 {
    match verdict {
        "passed" => PASSED,
        "failed_depth" => FAILED,
        "culled" => CULLED,
        _ => egui::Color32::GRAY,
    }
}

/// `c: value` for the first [`MAX_CHANNELS`] channels, and how many more.
fn channels(values: &[Option<f32>]) -> String {
    let shown: Vec<String> = values.iter().take(MAX_CHANNELS).enumerate().map(|(c, v)| format!("{c}: {}", number(*v))).collect();
    match values.len().saturating_sub(MAX_CHANNELS) {
        0 => shown.join("  "),
        more => format!("{}  … {more} more", shown.join("  ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(origin: &str, before: Option<Rgba>) -> TexelChange {
        TexelChange { output: "a/b".into(), texel: [1, 2, 0], origin: origin.into(), before, after: None }
    }

    #[test]
    fn values_read_exactly_and_before_says_where_it_came_from() {
        let v = [Some(0.1), Some(-2.5), None, Some(1.0)];
        assert_eq!(value(&v), "0.1, -2.5, not finite, 1");
        assert_eq!(before(&change("read", Some(v))), "0.1, -2.5, not finite, 1");
        assert_eq!(before(&change("cleared", None)), "cleared");
        assert_eq!(before(&change("undefined", None)), "undefined (first write)");
        assert_eq!(before(&change("unread", None)), "not read");
    }

    #[test]
    fn verdicts_read_in_words_with_the_helper_lane_marked() {
        let f = |verdict: &str, helper| Fragment { primitive: 0, depth: None, verdict: verdict.into(), helper };
        assert_eq!(verdict(&f("failed_depth", false)), "failed depth");
        assert_eq!(verdict(&f("passed", true)), "passed (helper lane)");
        assert_eq!(verdict(&f("not_tested", false)), "not tested");
        assert_eq!((verdict_colour("passed"), verdict_colour("failed_depth")), (PASSED, FAILED));
    }

    #[test]
    fn long_runs_are_cut_and_say_how_many_more() {
        let values: Vec<Option<f32>> = (0..18).map(|c| Some(c as f32 / 4.0)).collect();
        let text = channels(&values);
        assert!(text.starts_with("0: 0  1: 0.25  2: 0.5"), "{text}");
        assert!(text.ends_with("15: 3.75  … 2 more"), "{text}");
        assert_eq!(channels(&values[..2]), "0: 0  1: 0.25");
        let texts: Vec<String> = (0..66).map(|i| i.to_string()).collect();
        let texts: Vec<&str> = texts.iter().map(String::as_str).collect();
        assert!(shown_lines(&texts).ends_with("\n63\n… 2 more"));
        assert_eq!(shown_lines(&texts[..2]), "0\n1");
    }
}
