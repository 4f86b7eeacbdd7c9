//! The Inspector's quad statistics overlays: quad overdraw (quads launched
//! over each pixel's 2×2 block) or helper lanes (times each pixel ran as a
//! helper), laid over a raster pass's output in the colours of
//! presets.json's `quad_maps` (the browser's), with a legend and the count
//! under the cursor. The maps are the quad model's, computed on the CPU,
//! so the overlay is an ordinary egui texture, uploaded once per frame of
//! statistics.

use crate::link::QuadMap;
use crate::presets::QuadOverlay;

#[derive(Default)]
pub struct Overlay {
    shown: Option<QuadOverlay>,
    /// The uploaded overlay and what it was made from: (frame, pass, map).
    texture: Option<(egui::TextureHandle, (u64, String, QuadOverlay))>,
}

impl Overlay {
    /// The map shown, if any.
    pub fn shown(&self) -> Option<QuadOverlay> {
        self.shown
    }

    /// The chooser and legend. `available`: whether the inspected pass has
    /// quad statistics this frame (a raster pass, with statistics on).
    pub fn controls(&mut self, ui: &mut egui::Ui, available: bool) {
        ui.horizontal_wrapped(|ui| {
            ui.add_enabled_ui(available, |ui| {
                egui::ComboBox::from_label("quad map")
                    .selected_text(self.shown.map_or("none", QuadOverlay::name))
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut self.shown, None, "none");
                        for o in [QuadOverlay::Overdraw, QuadOverlay::Helpers] {
                            ui.selectable_value(&mut self.shown, Some(o), o.name());
                        }
                    })
                    .response
                    .on_disabled_hover_text("turn on quad statistics in Passes, and inspect a raster pass's output");
            });
            if let Some(o) = self.shown.filter(|_| available) {
                legend(ui, o);
            }
        });
    }

    /// Paints the overlay over the image at `image_rect` when a map is
    /// shown and `map` fits the output's `size`.
    pub fn paint(&mut self, ctx: &egui::Context, painter: &egui::Painter, image_rect: egui::Rect, map: Option<&QuadMap>, size: [u32; 2]) {
        let (Some(shown), Some(map)) = (self.shown, map) else { return };
        if [map.width, map.height] != size {
            return;
        }
        let key = (map.frame, map.pass.clone(), shown);
        if self.texture.as_ref().is_none_or(|(_, k)| *k != key) {
            let image = paint_map(map, shown);
            let options = egui::TextureOptions::NEAREST;
            match &mut self.texture {
                Some((handle, k)) => {
                    handle.set(image, options);
                    *k = key;
                }
                None => self.texture = Some((ctx.load_texture("quad-overlay", image, options), key)),
            }
        }
        if let Some((handle, _)) = &self.texture {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(handle.id(), image_rect, uv, egui::Color32::WHITE);
        }
    }

    /// The readout of the shown map's count at `texel`, in the browser's
    /// words (`quads.js` `countText`).
    pub fn readout(&self, map: Option<&QuadMap>, texel: [u32; 2]) -> Option<String> {
        let shown = self.shown?;
        let n = map?.at(shown, texel[0], texel[1])?;
        Some(match shown {
            QuadOverlay::Overdraw => format!("quad overdraw {n} · quads launched over this pixel's 2×2 block"),
            QuadOverlay::Helpers => format!("helper lanes {n} · times this pixel ran as a helper lane"),
        })
    }
}

/// The map as an RGBA image: each count's colour, 0 transparent.
fn paint_map(map: &QuadMap, shown: QuadOverlay) -> egui::ColorImage {
    let values = map.values(shown);
    let mut rgba = vec![0u8; values.len() * 4];
    for (i, (&n, px)) in values.iter().zip(rgba.chunks_exact_mut(4)).enumerate() {
        let (x, y) = (i as u32 % map.width, i as u32 / map.width);
        if let Some(c) = shown.colour(n, x, y) {
            px.copy_from_slice(&c);
        }
    }
    egui::ColorImage::from_rgba_unmultiplied([map.width as usize, map.height as usize], &rgba)
}

/// A swatch per solid count, then the hatched top count.
fn legend(ui: &mut egui::Ui, shown: QuadOverlay) {
    let legend = shown.legend();
    ui.label(match shown {
        QuadOverlay::Overdraw => "quads per 2×2 block:",
        QuadOverlay::Helpers => "helper-lane runs per pixel:",
    });
    let swatch = |ui: &mut egui::Ui, colours: &[[u8; 3]], label: &str| {
        let (rect, _) = ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
        let stripe = rect.width() / colours.len() as f32;
        for (i, [r, g, b]) in colours.iter().enumerate() {
            let part = egui::Rect::from_min_size(rect.min + egui::vec2(stripe * i as f32, 0.0), egui::vec2(stripe, rect.height()));
            ui.painter().rect_filled(part, 0.0, egui::Color32::from_rgb(*r, *g, *b));
        }
        ui.label(label);
    };
    for (colour, label) in &legend.steps {
        swatch(ui, std::slice::from_ref(colour), label);
    }
    swatch(ui, &legend.hatch, &legend.top);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> QuadMap {
        QuadMap {
            pass: "gbuffer".into(),
            frame: 3,
            width: 2,
            height: 2,
            overdraw: vec![0.0, 1.0, 2.0, 7.0],
            helpers: vec![0.0, 0.0, 1.0, 3.0],
        }
    }

    #[test]
    fn a_map_paints_its_counts_and_leaves_zero_clear() {
        let image = paint_map(&map(), QuadOverlay::Overdraw);
        assert_eq!(image.size, [2, 2]);
        assert_eq!(image.pixels[0], egui::Color32::TRANSPARENT, "no quad over this pixel");
        assert_eq!(image.pixels[1], egui::Color32::from_rgba_unmultiplied(76, 2, 161, 190));
        // Count 7 at (1, 1): the hatch's stripe for x + y = 2.
        assert_eq!(image.pixels[3], egui::Color32::from_rgba_unmultiplied(13, 8, 135, 190));
    }

    #[test]
    fn the_readout_is_the_shown_maps_count_at_the_texel() {
        let mut o = Overlay::default();
        assert_eq!(o.readout(Some(&map()), [1, 1]), None, "nothing shown");
        o.shown = Some(QuadOverlay::Helpers);
        assert_eq!(o.readout(Some(&map()), [0, 1]).as_deref(), Some("helper lanes 1 · times this pixel ran as a helper lane"));
        assert_eq!(o.readout(Some(&map()), [2, 0]), None, "outside the map");
        o.shown = Some(QuadOverlay::Overdraw);
        assert_eq!(o.readout(Some(&map()), [1, 1]).as_deref(), Some("quad overdraw 7 · quads launched over this pixel's 2×2 block"));
    }
}
