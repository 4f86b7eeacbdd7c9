//! The Tensors panel: an image-shaped buffer a pass writes (`[y, x,
//! channel]`, the denoiser's activations) as the browser shows it: every
//! channel as a grey image in a grid, any three channels as RGB, or one
//! channel through viridis, and every channel's exact value at the pixel
//! under the cursor. Activations have no natural range: each channel is
//! mapped from its own, the daemon's min and max; a channel that holds
//! one value everywhere (a dead ReLU's) is labelled so, not left to read
//! as data. The images are made on the CPU from the captured values when
//! a newer frame's capture arrives (at most every [`REFRESH`]) or the
//! choice changes.

use std::collections::BTreeSet;

use crate::link::Tensor;
use crate::model::{Model, image_shape};

/// How the tensor is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Grid,
    Rgb,
    Viridis,
}

/// What the images show: a change makes them again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Choice {
    mode: Mode,
    /// The channels shown as R, G and B.
    rgb: [usize; 3],
    /// The channel shown through viridis.
    mapped: usize,
}

/// The images made from one capture, as egui textures.
struct Shown {
    tensor: Tensor,
    /// `[height, width, channels]`.
    shape: [usize; 3],
    choice: Choice,
    /// When they were made (egui's clock).
    made_at: f64,
    textures: Vec<egui::TextureHandle>,
    /// One per image.
    captions: Vec<String>,
}

/// The least width of a grid cell, in points: below it the grid scrolls.
const MIN_CELL: f32 = 32.0;
/// The most texels of a grid cell's texture on its longer side: a cell
/// is drawn small, and a full-size image per channel of a full-size
/// activation (32 × 640 × 360) would take the UI thread most of a frame to
/// make and upload. The readout reads the values, not the textures.
const CELL_TEXELS: usize = 256;
/// The least time between two captures made into images, in seconds
/// (the browser's `REFRESH_MS`): the denoiser may run every frame.
const REFRESH: f64 = 0.25;
/// Lines of the readout's room: its text wraps and scrolls within it, so
/// the images above never move as it changes.
const READOUT_LINES: f32 = 4.0;

pub struct Tensors {
    selected: Option<String>,
    choice: Choice,
    /// The channel count the choice was made for: a tensor of another
    /// count starts over at channels 0, 1, 2 (as the browser's pickers).
    channels: Option<usize>,
    shown: Option<Shown>,
}

impl Default for Tensors {
    fn default() -> Self {
        Tensors { selected: None, choice: Choice { mode: Mode::Grid, rgb: [0, 1, 2], mapped: 0 }, channels: None, shown: None }
    }
}

impl Tensors {
    /// The tensor chosen (`pass/output`).
    pub fn selected(&self) -> Option<&str> {
        self.selected.as_deref()
    }

    /// Draws the panel from `current`, the newest capture of the selected
    /// tensor; returns the tensors to capture: the one shown, or none.
    pub fn show(&mut self, ui: &mut egui::Ui, model: &Model, current: Option<Tensor>) -> BTreeSet<String> {
        let listed: Vec<(String, [u32; 3])> = model.image_tensors().collect();
        let current = current.filter(|t| Some(&t.name) == self.selected.as_ref());
        let ready = current.map(|t| drawable(&t).map(|shape| (t, shape)));
        if let Some(Ok((_, [_, _, c]))) = &ready
            && self.channels != Some(*c)
        {
            self.choice.rgb = [0, 1, 2].map(|k: usize| k.min(c - 1));
            self.choice.mapped = 0;
            self.channels = Some(*c);
        }
        ui.horizontal_wrapped(|ui| {
            egui::ComboBox::from_label("tensor").selected_text(self.selected.as_deref().unwrap_or("choose a tensor")).show_ui(ui, |ui| {
                for (name, [h, w, c]) in &listed {
                    let chosen = self.selected.as_ref() == Some(name);
                    if ui.selectable_label(chosen, name).on_hover_text(format!("{h} × {w} × {c}")).clicked() && !chosen {
                        (self.selected, self.shown) = (Some(name.clone()), None);
                    }
                }
            });
            if let Some(Ok(_)) = &ready {
                self.controls(ui);
            }
        });
        let Some(name) = self.selected.clone() else {
            ui.label(if listed.is_empty() {
                "No pass writes an image-shaped tensor: the denoiser of a path-traced scene with a [denoiser] does."
            } else {
                "Choose a tensor."
            });
            return BTreeSet::new();
        };
        if !listed.iter().any(|(n, _)| *n == name) {
            ui.label(format!("{name} is not written now"));
            return BTreeSet::new();
        }
        let wanted = BTreeSet::from([name]);
        let (tensor, shape) = match ready {
            None => {
                ui.label("waiting for a frame that captures it…");
                return wanted;
            }
            Some(Err(e)) => {
                ui.label(e);
                return wanted;
            }
            Some(Ok(ready)) => ready,
        };
        self.sync(ui.ctx(), tensor, shape);
        let shown = self.shown.as_ref().expect("just synced");
        let t = &shown.tensor;
        let dims: Vec<String> = t.dims.iter().map(|(n, s)| format!("{n} {s}")).collect();
        ui.label(format!("[{}] · frame {} · NaN {} · Inf {}", dims.join(" × "), t.frame, t.nan, t.inf));

        let line = ui.text_style_height(&egui::TextStyle::Monospace);
        let room = ui.available_size() - egui::vec2(0.0, line * READOUT_LINES + 8.0);
        let hovered = ui.allocate_ui(room.max(egui::Vec2::ZERO), |ui| images(ui, shown)).inner;
        let text = match hovered {
            Some(at) => readout(t, shown.shape, at),
            None => "hover over an image for every channel's value at that pixel".into(),
        };
        egui::ScrollArea::vertical().id_salt("tensor-readout").max_height(line * READOUT_LINES).show(ui, |ui| {
            ui.add(egui::Label::new(egui::RichText::new(text).monospace()).wrap());
        });
        wanted
    }

    /// The mode, and the channels it shows.
    fn controls(&mut self, ui: &mut egui::Ui) {
        let Some(channels) = self.channels else { return };
        let c = &mut self.choice;
        for (mode, label) in [(Mode::Grid, "grid"), (Mode::Rgb, "RGB"), (Mode::Viridis, "viridis")] {
            ui.selectable_value(&mut c.mode, mode, label);
        }
        let pick = |ui: &mut egui::Ui, label: &str, channel: &mut usize| {
            egui::ComboBox::from_label(label).selected_text(format!("c{channel}")).show_ui(ui, |ui| {
                for ch in 0..channels {
                    ui.selectable_value(channel, ch, format!("c{ch}"));
                }
            });
        };
        match c.mode {
            Mode::Grid => {}
            Mode::Rgb => {
                for (label, channel) in ["R", "G", "B"].into_iter().zip(&mut c.rgb) {
                    pick(ui, label, channel);
                }
            }
            Mode::Viridis => pick(ui, "channel", &mut c.mapped),
        }
    }

    /// Makes the images again when the choice changed, or a newer capture
    /// arrived at least [`REFRESH`] after the last, into the textures
    /// already made.
    fn sync(&mut self, ctx: &egui::Context, tensor: Tensor, shape: [usize; 3]) {
        let now = ctx.input(|i| i.time);
        if let Some(s) = &self.shown
            && (s.tensor.name.as_str(), s.choice) == (tensor.name.as_str(), self.choice)
            && (s.tensor.frame == tensor.frame || now - s.made_at < REFRESH)
        {
            return;
        }
        let made = make(&tensor, shape, self.choice);
        let mut textures = self.shown.take().map(|s| s.textures).unwrap_or_default();
        textures.truncate(made.len());
        let mut captions = Vec::with_capacity(made.len());
        for (i, (image, caption)) in made.into_iter().enumerate() {
            match textures.get_mut(i) {
                Some(t) => t.set(image, egui::TextureOptions::NEAREST),
                None => textures.push(ctx.load_texture(format!("tensor-{i}"), image, egui::TextureOptions::NEAREST)),
            }
            captions.push(caption);
        }
        self.shown = Some(Shown { tensor, shape, choice: self.choice, made_at: now, textures, captions });
    }
}

/// `[height, width, channels]` of a capture that can be drawn: laid out
/// as an image, not empty, with as many values and statistics as that
/// says (a link's data is checked, not trusted).
fn drawable(t: &Tensor) -> Result<[usize; 3], String> {
    let Some(shape) = image_shape(&t.dims) else {
        return Err(format!("{} is not laid out as an image ([y, x, channel])", t.name));
    };
    let [h, w, c] = shape.map(|n| n as usize);
    if h * w * c == 0 {
        return Err(format!("{} is empty ({h} × {w} × {c})", t.name));
    }
    if t.values().len() != h * w * c || t.min.len() != c || t.max.len() != c {
        let n = t.values().len();
        return Err(format!("the capture of {} holds {n} values and {} ranges, not {h} × {w} × {c} and {c}", t.name, t.min.len()));
    }
    Ok([h, w, c])
}

/// The images `choice` shows of `t` (of `shape`), with their captions.
fn make(t: &Tensor, [h, w, c]: [usize; 3], choice: Choice) -> Vec<(egui::ColorImage, String)> {
    let values = t.values();
    let channel = |ch: usize| values.iter().skip(ch).step_by(c).map(move |&v| to_byte(v, (t.min[ch], t.max[ch])));
    match choice.mode {
        Mode::Grid => {
            let first = &values[..c];
            let mut constant: Vec<bool> = first.iter().map(|v| v.is_finite()).collect();
            for pixel in values.chunks_exact(c) {
                for (same, (v, first)) in constant.iter_mut().zip(pixel.iter().zip(first)) {
                    *same &= v == first;
                }
            }
            // Each pixel's channels at once, in the values' order: a pass
            // per channel would read them all again for each.
            let [gw, gh] = thumbnail([w, h]);
            let mut grey = vec![vec![0u8; gw * gh]; c];
            for gy in 0..gh {
                for gx in 0..gw {
                    // The tensor's pixel under the cell texel's centre.
                    let (x, y) = ((2 * gx + 1) * w / (2 * gw), (2 * gy + 1) * h / (2 * gh));
                    for (ch, &v) in values[(y * w + x) * c..][..c].iter().enumerate() {
                        grey[ch][gy * gw + gx] = to_byte(v, (t.min[ch], t.max[ch]));
                    }
                }
            }
            grey.iter()
                .enumerate()
                .map(|(ch, grey)| {
                    let caption = if constant[ch] { format!("c{ch} constant = {}", first[ch]) } else { format!("c{ch}") };
                    (egui::ColorImage::from_gray([gw, gh], grey), caption)
                })
                .collect()
        }
        Mode::Rgb => {
            let [r, g, b] = choice.rgb.map(|ch| channel(ch).collect::<Vec<u8>>());
            let rgb: Vec<u8> = (0..w * h).flat_map(|i| [r[i], g[i], b[i]]).collect();
            let [r, g, b] = choice.rgb;
            vec![(egui::ColorImage::from_rgb([w, h], &rgb), format!("RGB: c{r}, c{g}, c{b}"))]
        }
        Mode::Viridis => {
            let ch = choice.mapped;
            let rgb: Vec<u8> = channel(ch).flat_map(|v| crate::presets::viridis_rgb(f64::from(v) / 255.0)).collect();
            vec![(egui::ColorImage::from_rgb([w, h], &rgb), format!("c{ch} through viridis"))]
        }
    }
}

/// The size of a grid cell's texture for an image of `[w, h]`: the image's
/// own, or nearest-sampled down to [`CELL_TEXELS`] on its longer side.
fn thumbnail([w, h]: [usize; 2]) -> [usize; 2] {
    let long = w.max(h);
    if long <= CELL_TEXELS {
        return [w, h];
    }
    [w, h].map(|n| (n * CELL_TEXELS).div_ceil(long).max(1))
}

/// `v` mapped from `lo … hi` to 0 … 255 (`tensor_image.js` `toByte`): a
/// flat channel is mid-grey, NaN and Inf full intensity, to stand out.
fn to_byte(v: f32, (lo, hi): (f32, f32)) -> u8 {
    if !v.is_finite() {
        return 255;
    }
    if hi <= lo {
        return 128;
    }
    let (v, lo, hi) = (f64::from(v), f64::from(lo), f64::from(hi));
    ((v - lo) / (hi - lo) * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Draws the images, each scaled with its aspect kept; returns the
/// tensor's pixel under the cursor.
fn images(ui: &mut egui::Ui, shown: &Shown) -> Option<[usize; 2]> {
    let [h, w, _] = shown.shape;
    let size = [w as u32, h as u32];
    let mut hovered = None;
    let mut image = |ui: &mut egui::Ui, texture: &egui::TextureHandle, caption: &str, at: egui::Vec2| {
        let response = ui.add(egui::Image::new((texture.id(), at)).fit_to_exact_size(at).alt_text(caption));
        if let Some(pos) = response.hover_pos() {
            hovered = pixel_at(response.rect, [w, h], pos).or(hovered);
        }
        ui.add(egui::Label::new(egui::RichText::new(caption).small()).truncate());
    };
    let room = ui.available_size();
    let gap = ui.spacing().item_spacing;
    let caption = ui.text_style_height(&egui::TextStyle::Small) + 2.0 * gap.y;
    if shown.choice.mode != Mode::Grid {
        image(ui, &shown.textures[0], &shown.captions[0], super::frame::fit(room - egui::vec2(0.0, caption), size));
        return hovered;
    }
    let (columns, cell) = grid_layout(room, size, shown.textures.len(), caption, gap.x);
    egui::ScrollArea::both().id_salt("tensor-grid").show(ui, |ui| {
        egui::Grid::new("tensor-grid-cells").num_columns(columns).show(ui, |ui| {
            for (i, (texture, text)) in shown.textures.iter().zip(&shown.captions).enumerate() {
                ui.vertical(|ui| image(ui, texture, text, cell));
                if (i + 1) % columns == 0 {
                    ui.end_row();
                }
            }
        });
    });
    hovered
}

/// The pixel of an image of `[w, h]` pixels drawn in `rect` under `pos`.
fn pixel_at(rect: egui::Rect, [w, h]: [usize; 2], pos: egui::Pos2) -> Option<[usize; 2]> {
    let t = (pos - rect.min) / rect.size();
    let (x, y) = ((t.x * w as f32).floor(), (t.y * h as f32).floor());
    (x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32).then_some([x as usize, y as usize])
}

/// The columns for `n` cells of images of `[w, h]` texels in `room`, each
/// `caption` points taller and `gap` apart, and the images' size: the
/// largest at which every cell fits, but never under [`MIN_CELL`] wide
/// (the grid scrolls then).
fn grid_layout(room: egui::Vec2, [w, h]: [u32; 2], n: usize, caption: f32, gap: f32) -> (usize, egui::Vec2) {
    let (w, h) = (w.max(1) as f32, h.max(1) as f32);
    let scale = |columns: usize| {
        let (cols, rows) = (columns as f32, n.div_ceil(columns) as f32);
        ((room.x - gap * cols) / (cols * w)).min((room.y - rows * caption) / (rows * h))
    };
    let (columns, s) = (1..=n.max(1)).map(|c| (c, scale(c))).max_by(|a, b| a.1.total_cmp(&b.1)).expect("one column at least");
    if s * w >= MIN_CELL {
        return (columns, egui::vec2(w * s, h * s));
    }
    let columns = ((room.x / (MIN_CELL + gap)).floor() as usize).clamp(1, n.max(1));
    (columns, egui::vec2(MIN_CELL, MIN_CELL * h / w))
}

/// `(x, y)` and every channel's value there, exactly (Rust's shortest
/// round-trip form), and the frame they were captured in. A channel and
/// its value have no space between them: lines wrap between channels.
fn readout(t: &Tensor, [_, w, c]: [usize; 3], [x, y]: [usize; 2]) -> String {
    let at = (y * w + x) * c;
    let values: Vec<String> = t.values()[at..at + c].iter().enumerate().map(|(ch, v)| format!("c{ch}={v}")).collect();
    format!("({x}, {y}) {}  · frame {}", values.join("  "), t.frame)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A 2×3 tensor of 2 channels: c0 counts up from 0, c1 is 7 but one NaN.
    fn tensor() -> Tensor {
        let mut values: Vec<f32> = (0..6).flat_map(|i| [i as f32, 7.0]).collect();
        values[5] = f32::NAN;
        Tensor {
            name: "denoise.enc_conv0/tensor".into(),
            frame: 9,
            dims: vec![("y".into(), 2), ("x".into(), 3), ("channel".into(), 2)],
            values: Arc::new(values),
            min: vec![0.0, 7.0],
            max: vec![5.0, 7.0],
            nan: 1,
            inf: 0,
        }
    }

    #[test]
    fn each_channel_is_grey_over_its_own_range_and_a_constant_one_says_so() {
        let made = make(&tensor(), [2, 3, 2], Choice { mode: Mode::Grid, rgb: [0, 1, 0], mapped: 0 });
        let grey = |i: usize| made[i].0.pixels.iter().map(|p| p.r()).collect::<Vec<u8>>();
        assert_eq!(grey(0), [0, 51, 102, 153, 204, 255]);
        // Flat (min = max) is mid-grey; the NaN stands out.
        assert_eq!(grey(1), [128, 128, 255, 128, 128, 128]);
        assert_eq!((made[0].1.as_str(), made[1].1.as_str()), ("c0", "c1"), "a NaN is not a constant");
        let dead = Tensor { values: Arc::new(vec![0.0f32, 1.0, 0.0, 2.0, 0.0, 3.0, 0.0, 4.0, 0.0, 5.0, 0.0, 6.0]), ..tensor() };
        let made = make(&dead, [2, 3, 2], Choice { mode: Mode::Grid, rgb: [0, 1, 0], mapped: 0 });
        assert_eq!((made[0].1.as_str(), made[1].1.as_str()), ("c0 constant = 0", "c1"), "a dead channel is labelled");
    }

    #[test]
    fn three_channels_make_rgb_and_one_goes_through_viridis() {
        let t = tensor();
        let rgb = make(&t, [2, 3, 2], Choice { mode: Mode::Rgb, rgb: [0, 1, 0], mapped: 0 });
        assert_eq!(rgb.len(), 1);
        assert_eq!(rgb[0].0.pixels[1], egui::Color32::from_rgb(51, 128, 51));
        let mapped = make(&t, [2, 3, 2], Choice { mode: Mode::Viridis, rgb: [0, 1, 0], mapped: 0 });
        let [r, g, b] = crate::presets::viridis_rgb(1.0);
        assert_eq!(mapped[0].0.pixels[5], egui::Color32::from_rgb(r, g, b));
    }

    #[test]
    fn the_readout_has_every_channel_exactly() {
        let t = tensor();
        assert_eq!(readout(&t, [2, 3, 2], [2, 0]), "(2, 0) c0=2  c1=NaN  · frame 9");
        assert_eq!(readout(&t, [2, 3, 2], [0, 1]), "(0, 1) c0=3  c1=7  · frame 9");
    }

    #[test]
    fn a_capture_unlike_its_shape_is_not_drawn() {
        assert_eq!(drawable(&tensor()), Ok([2, 3, 2]));
        let short = Tensor { values: Arc::new(vec![0.0f32; 5]), ..tensor() };
        assert!(drawable(&short).is_err());
        let flat = Tensor { dims: vec![("bin".into(), 12)], ..tensor() };
        assert!(drawable(&flat).is_err());
    }

    #[test]
    fn the_grid_picks_the_columns_that_make_cells_largest() {
        // Four square cells in a wide room: one row.
        assert_eq!(grid_layout(egui::vec2(400.0, 100.0), [10, 10], 4, 0.0, 0.0), (4, egui::vec2(100.0, 100.0)));
        // In a square room: two by two.
        assert_eq!(grid_layout(egui::vec2(200.0, 200.0), [10, 10], 4, 0.0, 0.0), (2, egui::vec2(100.0, 100.0)));
        // Too many to fit: the least size, as many columns as fit.
        assert_eq!(grid_layout(egui::vec2(100.0, 100.0), [10, 10], 64, 0.0, 0.0), (3, egui::vec2(MIN_CELL, MIN_CELL)));
        assert_eq!(thumbnail([64, 48]), [64, 48]);
        assert_eq!(thumbnail([640, 368]), [256, 148]);
        assert_eq!(
            pixel_at(egui::Rect::from_min_size(egui::pos2(10.0, 10.0), egui::vec2(30.0, 20.0)), [3, 2], egui::pos2(35.0, 25.0)),
            Some([2, 1])
        );
    }
}
