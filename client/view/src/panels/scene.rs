//! The Scene panel: the scene's live controls as egui controls (a slider
//! with an exact entry beside it, a checkbox, a combo box), the renderer
//! switch and the path tracer's progress at the top, the overridden values
//! marked, and clearing or saving the overrides.
//!
//! A value dragged is sent once the drag ends, as the browser's controls
//! send on `change`: the newest value of each control waits meanwhile, so
//! a drag sends one command, never one a frame into the daemon's bounded
//! queue. A value sent is shown until the next `controls` report says what
//! the daemon made of it.

use std::collections::BTreeMap;

use serde_json::Value;

use crate::link::Command;
use crate::model::{Control, ControlKind, Model};

/// The control that picks the renderer, shown first.
const RENDERER: &str = "quality.renderer";
/// The samples per pixel the path tracer accumulates to.
const SPP: &str = "quality.path_spp";

const OVERRIDDEN: egui::Color32 = egui::Color32::from_rgb(220, 170, 60);

/// What the panel holds between frames.
#[derive(Default)]
pub struct Edits {
    /// Per path, the newest value of a control being dragged.
    dragged: BTreeMap<String, Value>,
    /// Per path, a value sent and not yet answered by a report.
    sent: BTreeMap<String, Value>,
    /// The `controls` report (`Model::controls_seen`) `sent` waits past.
    seen: u64,
}

impl Edits {
    /// What `c` shows: the value being dragged, else the one sent, else
    /// the report's.
    fn shown<'a>(&'a self, c: &'a Control) -> &'a Value {
        self.dragged.get(&c.path).or_else(|| self.sent.get(&c.path)).unwrap_or(&c.value)
    }

    /// One frame of a control: `value` when it changed, `dragging` while a
    /// drag holds it. Returns the command to send once nothing holds it.
    fn edited(&mut self, path: &str, value: Option<Value>, dragging: bool) -> Option<Command> {
        if let Some(v) = value {
            self.dragged.insert(path.to_owned(), v);
        }
        if dragging {
            return None;
        }
        let value = self.dragged.remove(path)?;
        self.sent.insert(path.to_owned(), value.clone());
        Some(Command::SetOverride { path: path.to_owned(), value })
    }

    /// A new report answers everything sent before it.
    fn report(&mut self, seen: u64) {
        if seen != self.seen {
            self.sent.clear();
            self.seen = seen;
        }
    }

    /// The daemon refused `path`'s value before reading it: the report's
    /// value is shown again.
    pub fn refused(&mut self, path: &str) {
        self.sent.remove(path);
    }
}

/// Draws the panel; returns the commands the user asked for.
pub fn show(ui: &mut egui::Ui, model: &Model, edits: &mut Edits) -> Vec<Command> {
    edits.report(model.controls_seen);
    let mut out = Vec::new();
    let controls = &model.controls;
    if controls.controls.is_empty() {
        ui.label("no controls yet");
        return out;
    }
    if let Some(renderer) = controls.get(RENDERER) {
        out.extend(renderer_switch(ui, renderer, controls.overrides.contains_key(RENDERER), edits));
        if edits.shown(renderer) == "path" {
            let spp = controls.get(SPP).and_then(|c| c.value.as_u64());
            progress(ui, model.samples, spp);
        }
        ui.separator();
    }
    let n = controls.overrides.len();
    ui.horizontal(|ui| {
        ui.label(if n == 0 { "as in the file".to_owned() } else { format!("{n} unsaved") });
        if ui.add_enabled(n > 0, egui::Button::new("Clear overrides")).clicked() {
            out.push(Command::ClearOverrides);
        }
        let save =
            ui.add_enabled(n > 0, egui::Button::new("Save to scene file")).on_hover_text(format!("write them into {}", controls.scene));
        if save.clicked() {
            out.push(Command::SaveScene);
        }
    });
    egui::ScrollArea::vertical().id_salt("scene").show(ui, |ui| {
        egui::Grid::new("scene-grid").striped(true).num_columns(2).show(ui, |ui| {
            for c in controls.controls.iter().filter(|c| c.path != RENDERER) {
                out.extend(row(ui, c, controls.overrides.contains_key(&c.path), edits));
                ui.end_row();
            }
        });
    });
    out
}

/// The renderer's options as one row of buttons.
fn renderer_switch(ui: &mut egui::Ui, c: &Control, overridden: bool, edits: &mut Edits) -> Option<Command> {
    let ControlKind::Choice { options } = &c.kind else { return None };
    let current = edits.shown(c).as_str().unwrap_or_default().to_owned();
    let mut picked = None;
    ui.horizontal(|ui| {
        ui.label(mark(&c.label, overridden).strong());
        for o in options {
            let button = egui::Button::selectable(current == *o, egui::RichText::new(o).heading());
            if ui.add(button).clicked() && current != *o {
                picked = Some(Value::from(o.as_str()));
            }
        }
    });
    edits.edited(&c.path, picked, false)
}

/// The path tracer's samples so far against its target.
fn progress(ui: &mut egui::Ui, samples: Option<u32>, spp: Option<u64>) {
    let text = |v: Option<u64>| v.map_or("—".to_owned(), |v| v.to_string());
    let done = samples.map(u64::from);
    let converged = matches!((done, spp), (Some(d), Some(s)) if d >= s);
    ui.label(format!("{} / {} samples{}", text(done), text(spp), if converged { " · converged" } else { "" }));
    if let (Some(d), Some(s)) = (done, spp.filter(|s| *s > 0)) {
        ui.add(egui::ProgressBar::new((d as f32 / s as f32).min(1.0)));
    }
}

/// One control's row: its label (marked when overridden) and its widget.
fn row(ui: &mut egui::Ui, c: &Control, overridden: bool, edits: &mut Edits) -> Option<Command> {
    let mut hover = vec![c.path.clone()];
    if overridden {
        hover.push("overridden: not saved to the scene file".into());
    }
    if !c.affects.is_empty() {
        hover.push(format!("affects: {}", c.affects.join(", ")));
    }
    let label = ui.label(mark(&c.label, overridden)).on_hover_text(hover.join("\n"));
    let shown = edits.shown(c).clone();
    let (value, dragging) = match &c.kind {
        ControlKind::Slider { min, max, step } => {
            let integer = step.fract() == 0.0 && min.fract() == 0.0;
            let mut v = shown.as_f64().unwrap_or(*min);
            let before = v;
            let (slider, typed) = ui
                .horizontal(|ui| {
                    let slider = ui.add(egui::Slider::new(&mut v, *min..=*max).step_by(*step).show_value(false));
                    // The exact value: typed, applied on Enter or leaving
                    // the field, and held to the control's range.
                    let mut typed = egui::DragValue::new(&mut v).range(*min..=*max).speed(*step).update_while_editing(false);
                    if integer {
                        typed = typed.fixed_decimals(0);
                    }
                    (slider, ui.add(typed))
                })
                .inner;
            let (slider, typed) = (slider.labelled_by(label.id), typed.labelled_by(label.id));
            let value = (v != before).then(|| if integer { Value::from(v.round() as i64) } else { Value::from(v) });
            (value, slider.dragged() || typed.dragged())
        }
        ControlKind::Toggle => {
            let mut on = shown.as_bool().unwrap_or(false);
            let changed = ui.checkbox(&mut on, "").labelled_by(label.id).changed();
            (changed.then_some(Value::from(on)), false)
        }
        ControlKind::Choice { options } => {
            let current = shown.as_str().unwrap_or_default().to_owned();
            let mut picked = current.clone();
            let combo = egui::ComboBox::from_id_salt(&c.path).selected_text(&current).show_ui(ui, |ui| {
                for o in options {
                    ui.selectable_value(&mut picked, o.clone(), o);
                }
            });
            combo.response.labelled_by(label.id);
            ((picked != current).then(|| Value::from(picked)), false)
        }
    };
    edits.edited(&c.path, value, dragging)
}

/// A control's label, marked when the control is overridden.
fn mark(label: &str, overridden: bool) -> egui::RichText {
    if overridden { egui::RichText::new(format!("• {label}")).color(OVERRIDDEN) } else { egui::RichText::new(label) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn set(path: &str, value: Value) -> Option<Command> {
        Some(Command::SetOverride { path: path.into(), value })
    }

    #[test]
    fn a_drag_sends_its_newest_value_once_it_ends() {
        let mut e = Edits::default();
        let c = Control { path: "a".into(), label: "A".into(), kind: ControlKind::Toggle, value: json!(0.0), affects: vec![] };
        for v in [0.1, 0.2, 0.3] {
            assert_eq!(e.edited("a", Some(json!(v)), true), None, "nothing is sent while the drag holds it");
            assert_eq!(e.shown(&c), &json!(v));
        }
        // A frame of the drag without a move, then the release.
        assert_eq!(e.edited("a", None, true), None);
        assert_eq!(e.edited("a", None, false), set("a", json!(0.3)));
        assert_eq!(e.edited("a", None, false), None, "sent once");
        // Shown until a report answers it.
        assert_eq!(e.shown(&c), &json!(0.3));
        e.report(0);
        assert_eq!(e.shown(&c), &json!(0.3));
        e.report(1);
        assert_eq!(e.shown(&c), &json!(0.0));
        // A change without a drag (a click, a typed value) goes at once.
        assert_eq!(e.edited("a", Some(json!(2.0)), false), set("a", json!(2.0)));
        e.refused("a");
        assert_eq!(e.shown(&c), &json!(0.0));
    }
}
