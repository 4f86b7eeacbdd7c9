//! The Passes panel: every pass of the frame with its status, why it is
//! culled or failed, and its time by the clock that measured it. A pass
//! with a texture output is a link to it in the Inspector.

use crate::model::Pass;

/// Draws the passes; returns the one the user clicked.
pub fn show(ui: &mut egui::Ui, passes: &[Pass], inspected: Option<&str>) -> Option<String> {
    if passes.is_empty() {
        ui.label("no passes yet");
        return None;
    }
    let mut clicked = None;
    egui::ScrollArea::both().id_salt("passes").show(ui, |ui| {
        egui::Grid::new("passes-grid").striped(true).num_columns(3).show(ui, |ui| {
            for p in passes {
                if p.writes.iter().any(|w| w.kind == "texture") {
                    let open = inspected.is_some_and(|o| o.split_once('/').is_some_and(|(pass, _)| pass == p.name));
                    if ui.selectable_label(open, &p.name).on_hover_text("show its output in the Inspector").clicked() {
                        clicked = Some(p.name.clone());
                    }
                } else {
                    ui.label(&p.name);
                }
                ui.colored_label(status_color(&p.status), &p.status);
                ui.label(detail(p));
                ui.end_row();
            }
        });
    });
    clicked
}

/// The reason a pass does not run, else its time and clock, else why it
/// has no time.
fn detail(p: &Pass) -> String {
    if let Some(reason) = &p.reason {
        return reason.clone();
    }
    match (p.time_ms, &p.timing) {
        (Some(ms), Some(clock)) => format!("{ms:.3} ms ({clock})"),
        (Some(ms), None) => format!("{ms:.3} ms"),
        _ => p.timing_reason.clone().unwrap_or_default(),
    }
}

fn status_color(status: &str) -> egui::Color32 {
    match status {
        "ok" => egui::Color32::from_rgb(110, 190, 110),
        "stale" => egui::Color32::from_rgb(220, 170, 60),
        "failed" => egui::Color32::from_rgb(230, 90, 80),
        _ => egui::Color32::GRAY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_culled_pass_shows_its_reason_and_a_timed_one_its_clock() {
        let culled = Pass { name: "p".into(), status: "culled".into(), reason: Some("rastering".into()), ..Pass::default() };
        assert_eq!(detail(&culled), "rastering");
        let timed = Pass { time_ms: Some(0.5), timing: Some("gpu".into()), ..Pass::default() };
        assert_eq!(detail(&timed), "0.500 ms (gpu)");
    }
}
