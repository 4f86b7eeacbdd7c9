//! The Timings panel: each pass's time over the last frames as a line of
//! its own (a frame it did not run in breaks it), beside the frame's wall
//! time, with a legend that hides and shows them.

use crate::frame_times::{FRAMES, FrameTimes};

pub fn show(ui: &mut egui::Ui, times: &FrameTimes) {
    if times.is_empty() {
        ui.label("no frames yet");
        return;
    }
    ui.label(format!("ms per frame, the last {} of {FRAMES} frames", times.len()));
    let passes = times.passes();
    let frame_ms = times.frame_ms();
    egui_plot::Plot::new("timings")
        .legend(egui_plot::Legend::default().follow_insertion_order(true))
        .x_axis_label("frame")
        .y_axis_label("ms")
        .include_y(0.0)
        .show(ui, |plot| {
            plot.line(egui_plot::Line::new("frame (wall)", frame_ms).color(egui::Color32::GRAY));
            for (i, series) in passes.into_iter().enumerate() {
                let color = color(i);
                for (j, run) in series.runs.into_iter().enumerate() {
                    // A run of one frame has no segment to draw: a dot.
                    if run.len() == 1 {
                        plot.points(egui_plot::Points::new(series.name.clone(), run).color(color).radius(2.0).id((i, j)));
                    } else {
                        plot.line(egui_plot::Line::new(series.name.clone(), run).color(color).id((i, j)));
                    }
                }
            }
        });
}

/// The `i`th pass's colour: hues a golden angle apart, as egui_plot picks
/// them, but fixed per pass so every run of a pass has the same.
fn color(i: usize) -> egui::Color32 {
    let hue = (i as f32 * (std::f32::consts::GOLDEN_RATIO - 1.0)).fract();
    egui::ecolor::Hsva::new(hue, 0.85, 0.5, 1.0).into()
}
