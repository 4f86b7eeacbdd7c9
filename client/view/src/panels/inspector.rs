//! The Inspector panel: any texture output of any pass, drawn by the
//! daemon's display pass (channel, exposure, range, sRGB, linear depth,
//! false colour, the NaN/Inf overlay) and shown zero-copy, with zoom and
//! pan and the exact value of the texel under the cursor (the one texel
//! read back). An output opens with its preset (`presets`), as in the
//! browser. Over a raster pass's output, a quad statistics map
//! (`quad_overlay`). A click pins the frame's pixel under the texel for
//! the Pixel panel, and marks it.

use crate::link::{Inspect, Inspected, Probe, Probed, QuadMap, Range};
use crate::model::{Model, Output};
use crate::panels::frame::FrameTexture;
use crate::panels::quad_overlay::Overlay;
use crate::panels::zoom::View;
use crate::pixel;
use crate::presets::{self, Channel, DisplayOptions, Planes};

/// What the panel asks of the daemon this frame.
#[derive(Default)]
pub struct Asks {
    pub inspect: Option<Inspect>,
    pub probe: Option<Probe>,
    /// Measure this output's range (fit to the values).
    pub measure: Option<Inspect>,
    /// Pin this pixel of the frame (`Some(None)`: unpin).
    pub pin: Option<Option<[u32; 2]>>,
}

pub struct Inspector {
    selected: Option<String>,
    options: Option<DisplayOptions>,
    /// Waiting for a measured range of the selected output to fit to.
    fitting: bool,
    texture: FrameTexture,
    /// `None` until the first image: then fitted to the viewport.
    view: Option<View>,
    /// The texel under the cursor.
    hovered: Option<[u32; 2]>,
    /// The newest value read back for the selected output.
    readout: Option<Probed>,
    quads: Overlay,
}

impl Default for Inspector {
    fn default() -> Self {
        Inspector {
            selected: None,
            options: None,
            fitting: false,
            texture: FrameTexture::new(wgpu::FilterMode::Nearest),
            view: None,
            hovered: None,
            readout: None,
            quads: Overlay::default(),
        }
    }
}

impl Inspector {
    pub fn selected(&self) -> Option<&str> {
        self.selected.as_deref()
    }

    pub fn options(&self) -> Option<DisplayOptions> {
        self.options
    }

    /// The pass of the selected output.
    pub fn selected_pass(&self) -> Option<&str> {
        Some(self.selected.as_deref()?.split_once('/')?.0)
    }

    /// The quad statistics map laid over the image, if any.
    pub fn quad_overlay(&self) -> Option<crate::presets::QuadOverlay> {
        self.quads.shown()
    }

    /// Shows `output` (`pass/output`) with its preset.
    pub fn select(&mut self, model: &Model, output: &str) -> Asks {
        let Some((_, o)) = model.textures().find(|(name, _)| name == output) else { return Asks::default() };
        let preset = presets::choose(&o.format, o.meaning.as_deref(), o.planes());
        self.selected = Some(output.to_owned());
        self.options = Some(preset.options);
        self.fitting = preset.fit;
        self.readout = None;
        self.view = None;
        let inspect = self.request();
        Asks { measure: if preset.fit { inspect.clone() } else { None }, inspect, ..Asks::default() }
    }

    /// Shows the first texture output of `pass`; false when it has none.
    pub fn select_pass(&mut self, model: &Model, pass: &str) -> Option<Asks> {
        let output = model.textures().find(|(name, _)| name.split_once('/').is_some_and(|(p, _)| p == pass))?.0;
        Some(self.select(model, &output))
    }

    fn request(&self) -> Option<Inspect> {
        Some(Inspect { output: self.selected.clone()?, options: self.options? })
    }

    /// The newest image and range from the daemon.
    pub fn sync(
        &mut self,
        inspected: Option<&Inspected>,
        measured: Option<Range>,
        probed: Option<Probed>,
        render: Option<&egui_wgpu::RenderState>,
    ) {
        if let (Some(i), Some(render)) = (inspected, render) {
            self.texture.sync(&i.image, render);
        }
        if let (Some(range), true) = (measured, self.fitting)
            && Some(&range.output) == self.selected.as_ref()
            && let Some(o) = self.options.as_mut()
        {
            if let Some((min, max)) = fitted(&range, o.channel) {
                (o.min, o.max) = (min, max);
            }
            self.fitting = false;
        }
        if let Some(p) = probed
            && Some(&p.probe.output) == self.selected.as_ref()
        {
            self.readout = Some(p);
        }
    }

    /// Draws the panel; returns what to ask of the daemon. `quads`: the
    /// selected pass's quad maps, while quad statistics are on; `frame`:
    /// the frame's size, which a pinned pixel is of (without it, the
    /// output is taken to be at the frame's size).
    pub fn show(
        &mut self,
        ui: &mut egui::Ui,
        model: &Model,
        inspected: Option<&Inspected>,
        quads: Option<&QuadMap>,
        frame: Option<[u32; 2]>,
    ) -> Asks {
        let mut asks = Asks::default();
        ui.horizontal_wrapped(|ui| {
            // The output chosen, and where to look in it.
            let mut chosen: Option<(String, Option<View>)> = None;
            egui::ComboBox::from_label("output").selected_text(self.selected.as_deref().unwrap_or("choose an output")).show_ui(ui, |ui| {
                for (name, _) in model.textures() {
                    if ui.selectable_label(self.selected.as_deref() == Some(&name), &name).clicked() {
                        chosen = Some((name, None));
                    }
                }
            });
            if let Some(nan) = &model.nan {
                let origin = format!("{}/{}", nan.pass, nan.output);
                let text = format!("NaN/Inf first written by {origin} at ({}, {})", nan.pixel[0], nan.pixel[1]);
                if ui.link(egui::RichText::new(text).color(egui::Color32::from_rgb(255, 0, 255))).clicked() {
                    chosen = Some((origin, Some(View::centred_on(nan.pixel, 16.0))));
                }
            }
            if let Some((name, view)) = chosen {
                asks = self.select(model, &name);
                self.view = view;
            }
        });
        let Some(output) = self.selected.clone() else {
            ui.label("Choose an output, or click a pass in Passes.");
            return asks;
        };
        let Some((_, info)) = model.textures().find(|(n, _)| *n == output) else {
            ui.label(format!("{output} is no longer written"));
            return asks;
        };
        let info = info.clone();
        if self.controls(ui, &info) {
            asks.measure = self.request();
        }
        let quads = quads.filter(|m| self.selected_pass() == Some(m.pass.as_str()));
        let has_quads = model.passes.iter().any(|p| Some(p.name.as_str()) == self.selected_pass() && p.quads.is_some());
        let overlaid = has_quads && quads.is_some();
        self.quads.controls(ui, overlaid);
        // The count's line is kept while a map is shown, so the image does
        // not move as the pointer enters and leaves it.
        let count_line = overlaid && self.quads.shown().is_some();
        let line = ui.text_style_height(&egui::TextStyle::Monospace) + 8.0;
        let readout_height = if count_line { 2.0 * line } else { line };
        let room = ui.available_size() - egui::vec2(0.0, readout_height);
        let current = inspected.filter(|i| i.inspect.output == output);
        // An image with no room (a window resized to nothing) is not
        // drawn, so the display pass is not asked to draw it either.
        let visible = room.x >= 1.0 && room.y >= 1.0;
        let size = [info.width, info.height];
        let frame = frame.unwrap_or(size);
        let pinned = model.pixel.map(|p| pixel::texel_of(p, frame, size));
        let (probe, clicked) = self.image(ui, room, current, &info, quads, pinned);
        if let Some(t) = clicked {
            // The pinned texel clicked again unpins, as Escape does.
            asks.pin = Some((Some(t) != pinned).then(|| pixel::frame_pixel(t, size, frame)));
        } else if pinned.is_some() && ui.input(|i| i.key_pressed(egui::Key::Escape)) {
            asks.pin = Some(None);
        }
        ui.label(egui::RichText::new(self.readout_text(&info)).monospace());
        if count_line {
            let count = self.hovered.and_then(|t| self.quads.readout(quads, t));
            ui.label(egui::RichText::new(count.unwrap_or_default()).monospace());
        }
        if visible {
            asks.inspect = asks.inspect.or_else(|| self.request());
            asks.probe = probe;
        } else {
            asks.inspect = None;
        }
        asks
    }

    /// The display options; true when the range should be fitted again.
    fn controls(&mut self, ui: &mut egui::Ui, info: &Output) -> bool {
        let Some(o) = self.options.as_mut() else { return false };
        let mut fit = false;
        ui.horizontal_wrapped(|ui| {
            let channels = presets::channels(&presets::format_info(&info.format));
            let label = channels.iter().find(|(c, _)| *c == o.channel).map_or(o.channel.name().to_owned(), |(_, l)| l.clone());
            egui::ComboBox::from_label("channel").selected_text(label).show_ui(ui, |ui| {
                for (c, l) in &channels {
                    ui.selectable_value(&mut o.channel, *c, l);
                }
            });
            ui.label("EV");
            ui.add(egui::DragValue::new(&mut o.exposure).speed(0.05).range(-24.0..=24.0));
            ui.label("min");
            ui.add(egui::DragValue::new(&mut o.min).speed(0.01));
            ui.label("max");
            ui.add(egui::DragValue::new(&mut o.max).speed(0.01));
            fit = ui.button("Fit").on_hover_text("fit min and max to the output's finite values").clicked();
            ui.checkbox(&mut o.srgb, "sRGB");
            if let Some(planes) = info.planes() {
                let mut on = o.linearize.is_some();
                if ui.checkbox(&mut on, "linear depth").changed() {
                    o.linearize = on.then_some(planes);
                    fit = true;
                }
            }
            ui.checkbox(&mut o.false_colour, "false colour");
            ui.checkbox(&mut o.overlay, "NaN/Inf");
            if ui.button("1:1").clicked() {
                self.view = self.view.map(|v| View { zoom: 1.0 / ui.ctx().pixels_per_point(), ..v });
            }
            if ui.button("Fit view").clicked() {
                self.view = None;
            }
        });
        if fit {
            self.fitting = true;
        }
        fit
    }

    /// The image with zoom (scroll) and pan (drag), and `pinned`'s marker;
    /// returns the texel to read back and the texel clicked.
    fn image(
        &mut self,
        ui: &mut egui::Ui,
        room: egui::Vec2,
        current: Option<&Inspected>,
        info: &Output,
        quads: Option<&QuadMap>,
        pinned: Option<[u32; 2]>,
    ) -> (Option<Probe>, Option<[u32; 2]>) {
        let (rect, response) = ui.allocate_exact_size(room.max(egui::Vec2::ZERO), egui::Sense::click_and_drag());
        let size = [info.width, info.height];
        let view = self.view.get_or_insert_with(|| View::fit(rect.size(), size));
        if response.double_clicked() {
            *view = View::fit(rect.size(), size);
        }
        if response.dragged() {
            view.pan(response.drag_delta());
        }
        if let Some(at) = response.hover_pos() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            let factor = ui.input(|i| i.zoom_delta()) * (scroll / 200.0).exp();
            if factor != 1.0 {
                view.zoom_about(rect, at, factor);
            }
        }
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, egui::Color32::from_gray(24));
        match (self.texture.id(), current) {
            (Some(id), Some(_)) => {
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                painter.image(id, view.image_rect(rect, size), uv, egui::Color32::WHITE);
                self.quads.paint(ui.ctx(), &painter, view.image_rect(rect, size), quads, size);
                if let Some(t) = pinned {
                    marker(&painter, view.image_rect(rect, size), view.zoom, t);
                }
            }
            _ => {
                painter.text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "waiting for the display pass",
                    egui::FontId::proportional(14.0),
                    egui::Color32::GRAY,
                );
            }
        }
        self.hovered = response.hover_pos().and_then(|at| view.texel_at(rect, size, at));
        // A double click fits the view; its first click already pinned.
        let clicked = (response.clicked() && !response.double_clicked())
            .then(|| response.interact_pointer_pos().and_then(|at| view.texel_at(rect, size, at)))
            .flatten();
        let probe = self.hovered.zip(self.selected.clone()).map(|([x, y], output)| Probe { output, x, y });
        (probe, clicked)
    }

    fn readout_text(&self, info: &Output) -> String {
        let Some([x, y]) = self.hovered else { return "hover over the image for the value of a texel".into() };
        match self.readout.as_ref().filter(|r| [r.probe.x, r.probe.y] == [x, y]) {
            Some(r) => readout(r, info),
            None => format!("({x}, {y}) reading…"),
        }
    }
}

/// A square around texel `t` of an image drawn over `image_rect` at `zoom`
/// points per texel, never smaller than a few points, dark under light so
/// it shows over any value.
fn marker(painter: &egui::Painter, image_rect: egui::Rect, zoom: f32, [x, y]: [u32; 2]) {
    let texel = egui::Rect::from_min_size(image_rect.min + egui::vec2(x as f32, y as f32) * zoom, egui::Vec2::splat(zoom));
    let square = texel.expand(((MARKER - zoom) / 2.0).max(0.0));
    painter.rect_stroke(square, 0.0, (3.0, egui::Color32::BLACK), egui::StrokeKind::Outside);
    painter.rect_stroke(square, 0.0, (1.5, egui::Color32::from_rgb(255, 220, 0)), egui::StrokeKind::Outside);
}

/// The least side of the pinned texel's marker, in points.
const MARKER: f32 = 7.0;

/// `(x, y)` and each of the format's channels by name, exactly (Rust's
/// shortest round-trip form), and the view distance of a depth.
pub fn readout(r: &Probed, info: &Output) -> String {
    let names = presets::format_info(&info.format).names;
    let values: Vec<String> = names.iter().zip(r.value).map(|(n, v)| format!("{n} {v}")).collect();
    let mut text = format!("({}, {}) {}", r.probe.x, r.probe.y, values.join("  "));
    if let Some(p) = info.planes().filter(|p| r.value[0] != p.clear()) {
        text += &format!("  (distance {})", Planes::distance(p, r.value[0]));
    }
    text + &format!("  · frame {}", r.frame)
}

/// The range to show `channel` by: the composite's over R, G and B.
fn fitted(range: &Range, channel: Channel) -> Option<(f32, f32)> {
    let c = &range.channels;
    match channel {
        Channel::Rgb => c[..3].iter().flatten().copied().reduce(|a, b| (a.0.min(b.0), a.1.max(b.1))),
        Channel::Luminance => c[4],
        single => c[single.single().expect("a single channel")],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_composite_fits_to_the_colour_channels_only() {
        let range = Range {
            output: "a/b".into(),
            frame: 1,
            channels: [Some((0.5, 2.0)), None, Some((-1.0, 1.0)), Some((1.0, 1.0)), Some((0.2, 0.3))],
        };
        assert_eq!(fitted(&range, Channel::Rgb), Some((-1.0, 2.0)));
        assert_eq!(fitted(&range, Channel::G), None);
        assert_eq!(fitted(&range, Channel::Luminance), Some((0.2, 0.3)));
        assert_eq!(fitted(&range, Channel::A), Some((1.0, 1.0)));
    }

    #[test]
    fn a_readout_names_the_formats_channels_and_a_depths_distance() {
        let probe = Probe { output: "depth_prepass/depth".into(), x: 3, y: 4 };
        let depth = Output {
            format: "Depth32Float".into(),
            depth: Some(crate::model::DepthPlanes { near: Some(1.0), far: Some(3.0), reversed: false }),
            ..Output::default()
        };
        let r = Probed { probe: probe.clone(), frame: 9, value: [0.75, 0.0, 0.0, 1.0] };
        assert_eq!(readout(&r, &depth), "(3, 4) depth 0.75  (distance 2)  · frame 9");
        let colour = Output { format: "Rg16Float".into(), ..Output::default() };
        let r = Probed { probe, frame: 2, value: [0.1, -2.5, 0.0, 1.0] };
        assert_eq!(readout(&r, &colour), "(3, 4) R 0.1  G -2.5  · frame 2");
    }
}
