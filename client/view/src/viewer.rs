//! The window's contents, one frame at a time: read what the link
//! received, draw the panels, act on what the user clicked. Nothing here
//! waits on the daemon: the link's calls return at once, and the frame
//! shown is whichever the daemon finished last.

use std::collections::{BTreeSet, HashMap};

use crate::link::{Command, Link, QuadMap};
use crate::model::{Location, Model, Problem};
use crate::panels::inspector::{Asks, Inspector};
use crate::panels::tensors::Tensors;
use crate::panels::{self, frame::FrameTexture};

/// The longest the window goes without repainting while nothing wakes it.
const FALLBACK_REPAINT: std::time::Duration = std::time::Duration::from_millis(250);

/// What the centre of the window shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Centre {
    Frame,
    Inspector,
    Tensors,
}

/// What the right-hand panel shows.
#[derive(Clone, Copy, Default, PartialEq, Eq)]
enum RightTab {
    #[default]
    Passes,
    Scene,
    Timings,
    /// The pixel pinned in the Inspector.
    Pixel,
}

pub struct Viewer {
    link: Box<dyn Link>,
    model: Model,
    frame: FrameTexture,
    centre: Centre,
    inspector: Inspector,
    /// Whether the link wakes the window yet.
    woken: bool,
    tensors: Tensors,
    /// Whether quad statistics are asked for (the Passes toggle), and the
    /// inspected pass's newest maps while they are.
    quads: bool,
    quad_map: Option<QuadMap>,
    tab: RightTab,
    scene: panels::scene::Edits,
    /// Source texts for excerpts and prints, read once per file while the
    /// problems stay the same and no reload finishes.
    sources: HashMap<String, Option<String>>,
    sources_for: (Vec<Problem>, u64),
    editor: Option<String>,
    /// A revert asked for, waiting for its confirmation.
    confirm_revert: Option<String>,
}

impl Viewer {
    /// `editor`: the command problems open in (`editor::from_env()`).
    pub fn new(link: Box<dyn Link>, editor: Option<String>) -> Self {
        Viewer {
            link,
            model: Model::default(),
            frame: FrameTexture::new(wgpu::FilterMode::Linear),
            centre: Centre::Frame,
            inspector: Inspector::default(),
            woken: false,
            tensors: Tensors::default(),
            quads: false,
            quad_map: None,
            tab: RightTab::default(),
            scene: panels::scene::Edits::default(),
            sources: HashMap::new(),
            sources_for: (Vec::new(), 0),
            editor,
            confirm_revert: None,
        }
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn centre(&self) -> Centre {
        self.centre
    }

    /// The output the Inspector shows (`pass/output`).
    pub fn inspected(&self) -> Option<&str> {
        self.inspector.selected()
    }

    /// How the Inspector shows it.
    pub fn display_options(&self) -> Option<crate::presets::DisplayOptions> {
        self.inspector.options()
    }

    /// The quad statistics map laid over the Inspector's image, and the
    /// maps it was painted from.
    pub fn quad_overlay(&self) -> Option<(crate::presets::QuadOverlay, Option<&QuadMap>)> {
        Some((self.inspector.quad_overlay()?, self.quad_map.as_ref()))
    }

    /// The daemon stopped: the window should close.
    pub fn closed(&self) -> bool {
        self.link.closed()
    }

    /// The window is minimised: nothing of the frame is on screen.
    pub fn hidden(&mut self) {
        self.link.set_minimised(true);
        self.link.set_shown(false);
        self.ask(Asks::default());
        self.want_tensors(BTreeSet::new());
        self.want_quads(false);
    }

    /// One frame of the window. `render`: the renderer the frame texture is
    /// registered with (none: the frame is not shown).
    pub fn ui(&mut self, ui: &mut egui::Ui, render: Option<&egui_wgpu::RenderState>) {
        if !self.woken {
            let ctx = ui.ctx().clone();
            self.link.wake_with(Box::new(move || ctx.request_repaint()));
            self.woken = true;
        }
        self.link.set_minimised(false);
        for event in self.link.poll() {
            self.model.apply(event);
        }
        if (&self.sources_for.0, self.sources_for.1) != (&self.model.problems, self.model.reloads) {
            self.sources.clear();
            self.sources_for = (self.model.problems.clone(), self.model.reloads);
        }
        let image = self.link.display();
        if let (Some(image), Some(render)) = (&image, render) {
            self.frame.sync(image, render);
        }
        let inspected = self.link.inspected();
        self.inspector.sync(inspected.as_ref(), self.link.measured(), self.link.probed(), render);

        // Sizes are bounded by the window, not by the longest line: text
        // is cut to the panel and scrolls.
        let (width, height) = (ui.available_width(), ui.available_height());
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar(ui));
        let clicked = egui::Panel::bottom("problems")
            .default_size(height * 0.3)
            .max_size(height * 0.6)
            .resizable(true)
            .show(ui, |ui| {
                let (link, sources) = (&self.link, &mut self.sources);
                panels::problems::show(ui, &self.model.problems, &self.model.files, |loc| excerpt(link.as_ref(), sources, loc))
            })
            .inner;
        let (asked, picked, unpin) = egui::Panel::right("passes")
            .default_size(width * 0.35)
            .max_size(width * 0.6)
            .resizable(true)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let tabs = [
                        (RightTab::Passes, "Passes"),
                        (RightTab::Scene, "Scene"),
                        (RightTab::Timings, "Timings"),
                        (RightTab::Pixel, "Pixel"),
                    ];
                    for (tab, name) in tabs {
                        ui.selectable_value(&mut self.tab, tab, name);
                    }
                });
                ui.separator();
                match self.tab {
                    RightTab::Passes => {
                        (Vec::new(), panels::passes::show(ui, &self.model.passes, self.inspector.selected(), &mut self.quads), false)
                    }
                    RightTab::Scene => (panels::scene::show(ui, &self.model, &mut self.scene), None, false),
                    RightTab::Timings => {
                        panels::timings::show(ui, &self.model.times);
                        (Vec::new(), None, false)
                    }
                    RightTab::Pixel => {
                        let (link, sources) = (&self.link, &mut self.sources);
                        let unpin = panels::pixel::show(ui, &self.model, |file, line| source_line(link.as_ref(), sources, file, line));
                        (Vec::new(), None, unpin)
                    }
                }
            })
            .inner;
        for command in asked {
            self.send(command);
        }
        if unpin {
            self.pin(None);
        }
        self.want_quads(self.quads);
        if let Some(pass) = picked
            && let Some(asks) = self.inspector.select_pass(&self.model, &pass)
        {
            self.centre = Centre::Inspector;
            self.ask(asks);
        }
        egui::CentralPanel::default().show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.selectable_value(&mut self.centre, Centre::Frame, "Frame");
                ui.selectable_value(&mut self.centre, Centre::Inspector, "Inspector");
                ui.selectable_value(&mut self.centre, Centre::Tensors, "Tensors");
            });
            // Only what is on screen is drawn, or captured, by the daemon.
            let wanted = match self.centre {
                Centre::Frame => {
                    let shown = self.frame.show(ui, image.as_ref());
                    self.link.set_shown(shown);
                    self.ask(Asks::default());
                    BTreeSet::new()
                }
                Centre::Inspector => {
                    self.link.set_shown(false);
                    self.refresh_quad_map();
                    let frame = image.as_ref().map(|i| i.size);
                    let asks = self.inspector.show(ui, &self.model, inspected.as_ref(), self.quad_map.as_ref(), frame);
                    self.ask(asks);
                    BTreeSet::new()
                }
                Centre::Tensors => {
                    self.link.set_shown(false);
                    self.ask(Asks::default());
                    let current = self.tensors.selected().and_then(|name| self.link.tensor(name));
                    self.tensors.show(ui, &self.model, current)
                }
            };
            self.want_tensors(wanted);
        });
        match clicked {
            Some(panels::problems::Action::Open(loc)) => self.open(&loc),
            Some(panels::problems::Action::Revert(file)) => self.confirm_revert = Some(file),
            None => {}
        }
        self.confirm(ui.ctx());
        // The window repaints when the link wakes it (a frame finished, an
        // event came) and on input; the fallback catches what arrives
        // without an event (a texel read back after the newest frame).
        ui.ctx().request_repaint_after(FALLBACK_REPAINT);
    }

    fn toolbar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if ui.button("Recompile all").clicked() {
                self.send(Command::Rebuild);
            }
            if ui.button("Reset history").on_hover_text("temporal passes and the path tracer's samples start over").clicked() {
                self.send(Command::ResetHistory);
            }
            if let Some((frame, ms)) = self.model.frame {
                ui.label(format!("frame {frame}, {ms:.1} ms"));
            }
            if let Some(notice) = &self.model.notice {
                ui.add(egui::Label::new(egui::RichText::new(notice).color(egui::Color32::from_rgb(220, 170, 60))).truncate());
            }
            let s = &self.model.status;
            ui.add(egui::Label::new(format!("{} on {}", s.scene, s.adapter)).truncate());
        });
    }

    fn ask(&mut self, asks: Asks) {
        self.link.inspect(asks.inspect);
        self.link.probe(asks.probe);
        if let Some(measure) = asks.measure {
            self.link.measure(measure);
        }
        if let Some(pixel) = asks.pin {
            self.pin(pixel);
        }
    }

    /// Selects `pixel` on the daemon (`None`: clears it) and shows it in
    /// the Pixel panel; a refusal leaves the pin as it was and says why.
    fn pin(&mut self, pixel: Option<[u32; 2]>) {
        match self.link.debug_pixel(pixel) {
            Ok(()) => {
                self.model.pin(pixel);
                if pixel.is_some() {
                    self.tab = RightTab::Pixel;
                }
            }
            Err(e) => self.model.notice = Some(e),
        }
    }

    /// Asks for quad statistics, or stops asking; a refusal turns the
    /// toggle off and says why.
    fn want_quads(&mut self, on: bool) {
        if let Err(e) = self.link.quad_statistics(on) {
            self.model.notice = Some(e);
            self.quads = false;
        }
        if !self.quads {
            self.model.forget_quads();
            self.quad_map = None;
        }
    }

    /// Reads the inspected pass's maps again once newer statistics came.
    fn refresh_quad_map(&mut self) {
        let (Some(frame), Some(pass)) = (self.model.quads_frame, self.inspector.selected_pass()) else {
            self.quad_map = None;
            return;
        };
        if self.quad_map.as_ref().is_some_and(|m| m.pass == pass && m.frame >= frame) {
            return;
        }
        self.quad_map = self.link.quad_map(pass);
    }

    fn want_tensors(&mut self, wanted: BTreeSet<String>) {
        if let Err(e) = self.link.tensors(wanted) {
            self.model.notice = Some(e);
        }
    }

    fn send(&mut self, command: Command) {
        let set = match &command {
            Command::SetOverride { path, .. } => Some(path.clone()),
            _ => None,
        };
        if let Err(e) = self.link.send(command) {
            self.model.notice = Some(e);
            if let Some(path) = set {
                self.scene.refused(&path);
            }
        }
    }

    /// The confirmation a revert waits for: it overwrites the file.
    fn confirm(&mut self, ctx: &egui::Context) {
        let Some(file) = self.confirm_revert.clone() else { return };
        let mut answer = None;
        egui::Modal::new(egui::Id::unique("confirm-revert")).show(ctx, |ui| {
            ui.label(format!("Write the last good version of {file} over the file? Its current text is lost."));
            ui.horizontal(|ui| {
                if ui.button("Revert").clicked() {
                    answer = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    answer = Some(false);
                }
            });
        });
        if let Some(revert) = answer {
            self.confirm_revert = None;
            if revert {
                self.send(Command::RevertFile { file });
            }
        }
    }

    fn open(&mut self, loc: &Location) {
        let Some(editor) = &self.editor else {
            self.model.notice = Some("set $VISUAL or $EDITOR to open problems in an editor".into());
            return;
        };
        if let Err(e) = crate::editor::open(editor, &loc.file, loc.line, loc.column) {
            self.model.notice = Some(e);
        }
    }
}

fn excerpt(link: &dyn Link, sources: &mut HashMap<String, Option<String>>, loc: &Location) -> Option<String> {
    crate::excerpt::excerpt(source(link, sources, &loc.file)?, loc.line, loc.column)
}

/// Line `line` (1-based) of `file`, as it is now.
fn source_line(link: &dyn Link, sources: &mut HashMap<String, Option<String>>, file: &str, line: u32) -> Option<String> {
    let index = usize::try_from(line).ok()?.checked_sub(1)?;
    source(link, sources, file)?.lines().nth(index).map(str::to_owned)
}

fn source<'a>(link: &dyn Link, sources: &'a mut HashMap<String, Option<String>>, file: &str) -> Option<&'a str> {
    sources.entry(file.to_owned()).or_insert_with(|| link.source(file)).as_deref()
}
