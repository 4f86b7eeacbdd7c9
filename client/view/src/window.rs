//! The native window: eframe with its wgpu renderer on a device the caller
//! already opened (the daemon's), so the frame texture needs no copy
//! between devices.

use crate::link::Link;
use crate::viewer::Viewer;

#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    #[error(
        "no display: neither DISPLAY nor WAYLAND_DISPLAY is set; `loupe serve` runs the same daemon headless, with the browser inspector"
    )]
    NoDisplay,
    #[error("cannot open the window: {0}")]
    Open(String),
}

/// Whether a window could open at all: an X11 or Wayland display is named.
pub fn check_display() -> Result<(), WindowError> {
    let set = |v: &str| std::env::var_os(v).is_some_and(|d| !d.is_empty());
    if set("DISPLAY") || set("WAYLAND_DISPLAY") { Ok(()) } else { Err(WindowError::NoDisplay) }
}

/// Opens the window and runs it until it is closed (or the link says the
/// daemon stopped). Must run on the main thread (winit's rule).
/// `device`: the one the window renders with.
pub fn run(title: &str, device: egui_wgpu::WgpuSetupExisting, link: Box<dyn Link>) -> Result<(), WindowError> {
    check_display()?;
    let mut viewer = Viewer::new(link, crate::editor::from_env());
    // A window opened again in this process (after its device was lost)
    // can be handed the old window's last events, and eframe ends a run
    // that gets a window event before its window exists: such a run has
    // shown nothing, and is tried again.
    for _ in 0..REOPEN_TRIES {
        let options = eframe::NativeOptions {
            viewport: egui::ViewportBuilder::default().with_title(title).with_inner_size([1280.0, 800.0]),
            wgpu_options: egui_wgpu::WgpuConfiguration { wgpu_setup: egui_wgpu::WgpuSetup::Existing(device.clone()), ..Default::default() },
            ..Default::default()
        };
        let mut shown = false;
        let app = App { viewer: &mut viewer, shown: &mut shown };
        eframe::run_native(title, options, Box::new(|_cc| Ok(Box::new(app)))).map_err(|e| WindowError::Open(e.to_string()))?;
        if shown || viewer.closed() {
            break;
        }
    }
    Ok(())
}

/// How many runs of eframe may end before the window showed.
const REOPEN_TRIES: usize = 10;

struct App<'a> {
    viewer: &'a mut Viewer,
    /// Set once a frame of the window ran.
    shown: &'a mut bool,
}

impl eframe::App for App<'_> {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        if self.viewer.closed() {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        *self.shown = true;
        // eframe paints nothing while minimised: the daemon stops its
        // display work, and renders continuously only for a browser,
        // until the window shows again.
        if ui.ctx().input(|i| i.viewport().minimized == Some(true)) {
            self.viewer.hidden();
            return;
        }
        self.viewer.ui(ui, frame.wgpu_render_state());
    }
}
