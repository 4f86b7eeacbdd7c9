//! The Passes panel: every pass of the frame with its status, why it is
//! culled or failed, and its time by the clock that measured it. A pass
//! with a texture output is a link to it in the Inspector. With quad
//! statistics on, each raster pass's quad totals, as the browser's pass
//! list states them.

use crate::model::{Pass, QuadTotals};

/// Draws the passes; returns the one the user clicked. `quads`: whether
/// quad statistics are asked for (the toggle above the list).
pub fn show(ui: &mut egui::Ui, passes: &[Pass], inspected: Option<&str>, quads: &mut bool) -> Option<String> {
    ui.checkbox(quads, "quad statistics").on_hover_text(
        "model every raster draw's 2×2 quads and helper lanes each frame: totals here, maps in the Inspector (costs frame time)",
    );
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
                match &p.quads {
                    Some(q) => {
                        ui.vertical(|ui| {
                            ui.label(detail(p));
                            ui.small(quad_text(q));
                        });
                    }
                    None => {
                        ui.label(detail(p));
                    }
                }
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

/// A pass's quad totals, in the browser's words.
fn quad_text(q: &QuadTotals) -> String {
    // Ties round up, as JavaScript's `toFixed` does (Rust's `{:.1}` rounds
    // them to even).
    let efficiency = q.quad_efficiency.map_or("—".to_owned(), |e| format!("{:.1} %", (e * 1000.0).round() / 10.0));
    format!("{} quads · {} helper lanes · {efficiency} efficient", grouped(q.quads), grouped(q.helper_lanes))
}

/// `n` with its thousands separated by commas (`toLocaleString('en-US')`).
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(d);
    }
    out
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

    #[test]
    fn quad_totals_read_as_in_the_browser() {
        let q = QuadTotals { pixels: 3, quads: 1234567, helper_lanes: 999, quad_efficiency: Some(0.8125) };
        assert_eq!(quad_text(&q), "1,234,567 quads · 999 helper lanes · 81.3 % efficient");
        assert_eq!(quad_text(&QuadTotals { quad_efficiency: None, ..q }), "1,234,567 quads · 999 helper lanes · — efficient");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(0), "0");
    }
}
