//! The Problems panel: each diagnostic as `file:line:col: severity[code]:
//! message` with the source lines it points at; clicking one asks for the
//! editor at that place.

use crate::model::{Location, Problem};

/// Draws the problems; `excerpt` gives the source lines of a location.
/// Returns the location the user clicked, if any.
pub fn show(ui: &mut egui::Ui, problems: &[Problem], mut excerpt: impl FnMut(&Location) -> Option<String>) -> Option<Location> {
    ui.heading(format!("Problems ({})", problems.len()));
    let mut clicked = None;
    egui::ScrollArea::both().id_salt("problems").show(ui, |ui| {
        for p in problems {
            let color = if p.severity == "error" { egui::Color32::from_rgb(230, 90, 80) } else { egui::Color32::from_rgb(220, 170, 60) };
            let text = egui::RichText::new(headline(p)).color(color).monospace();
            match &p.location {
                Some(loc) => {
                    if ui.link(text).on_hover_text("open in $VISUAL / $EDITOR").clicked() {
                        clicked = Some(loc.clone());
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
    });
    clicked
}

/// The line compilers and problem matchers print.
pub fn headline(p: &Problem) -> String {
    let place = p.location.as_ref().map(|l| format!("{}:{}:{}: ", l.file, l.line, l.column)).unwrap_or_default();
    format!("{place}{}[{}]: {}", p.severity, p.code, p.message)
}
