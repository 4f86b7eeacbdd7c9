//! The viewer's one dependency on a daemon: events in, commands out, and
//! the newest frame as a texture on the device the window renders with.

use std::collections::BTreeSet;
use std::sync::Arc;

/// What the window asks of the daemon: the daemon's own inbox commands.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Rebuild every pipeline from the current sources ("Recompile all").
    Rebuild,
    /// Set a scene value live, as the WebSocket `set_override`: `value`
    /// is a number, a boolean or an option's name.
    SetOverride { path: String, value: serde_json::Value },
    /// Drop every override: back to the scene file's values.
    ClearOverrides,
    /// Write the overrides into the scene file.
    SaveScene,
    /// Forget every history resource (temporal passes, the path tracer's
    /// accumulation): the next frame starts over.
    ResetHistory,
    /// Write a broken file's last good text back over it (`POST
    /// /api/files/revert`).
    RevertFile { file: String },
}

/// The newest finished frame, as an `Rgba8Unorm` texture holding sRGB
/// encoded values (what egui's shader expects), on the window's device.
#[derive(Clone, Debug)]
pub struct DisplayImage {
    pub view: wgpu::TextureView,
    pub size: [u32; 2],
    /// Changes whenever the texture is replaced (the frame's size changed):
    /// the window registers the new one.
    pub generation: u64,
}

/// What the Inspector shows: one texture output (`pass/output`, layer 0
/// of an array) through the daemon's display pass.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspect {
    pub output: String,
    pub options: crate::presets::DisplayOptions,
}

/// The inspected output as the display pass drew it after frame `frame`.
#[derive(Clone, Debug)]
pub struct Inspected {
    pub image: DisplayImage,
    pub inspect: Inspect,
    pub frame: u64,
}

/// A texel of an output (`pass/output`, layer 0) to read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Probe {
    pub output: String,
    pub x: u32,
    pub y: u32,
}

/// A texel read back: its value as a shader reads it (RGBA, missing
/// channels 0, missing alpha 1; sRGB decoded), from frame `frame`.
#[derive(Clone, Debug, PartialEq)]
pub struct Probed {
    pub probe: Probe,
    pub frame: u64,
    pub value: [f32; 4],
}

/// The finite range of an output's values, per shown channel (R, G, B,
/// A, luminance), after depth linearisation when asked for and without a
/// depth target's clear value; `None` per channel without a finite value.
#[derive(Clone, Debug, PartialEq)]
pub struct Range {
    pub output: String,
    pub frame: u64,
    pub channels: [Option<(f32, f32)>; 5],
}

/// A buffer a frame captured, read as the tensor its layout describes
/// (what `GET /api/tensors/{pass}/{output}` and its `.f32` serve).
#[derive(Clone)]
pub struct Tensor {
    /// `pass/output`.
    pub name: String,
    pub frame: u64,
    /// `(name, size)` per dimension, outermost first, channels last.
    pub dims: Vec<(String, u32)>,
    /// Every element in layout order, as f32: shared with the capture,
    /// not copied for each look.
    pub values: Arc<dyn AsRef<[f32]> + Send + Sync>,
    /// The daemon's statistics per channel (the innermost dimension),
    /// over finite values only: 0 for a channel without one.
    pub min: Vec<f32>,
    pub max: Vec<f32>,
    /// How many values are NaN, and how many infinite.
    pub nan: u64,
    pub inf: u64,
}

impl Tensor {
    pub fn values(&self) -> &[f32] {
        (*self.values).as_ref()
    }
}

impl std::fmt::Debug for Tensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tensor").field("name", &self.name).field("frame", &self.frame).field("dims", &self.dims).finish_non_exhaustive()
    }
}

/// A raster pass's quad statistics maps for its first render target
/// (layer 0, what the Inspector shows), from frame `frame`.
#[derive(Clone, Debug)]
pub struct QuadMap {
    pub pass: String,
    pub frame: u64,
    pub width: u32,
    pub height: u32,
    /// Quads launched over each pixel's 2×2 block, rows top first.
    pub overdraw: Vec<f32>,
    /// Times each pixel ran as a helper lane.
    pub helpers: Vec<f32>,
}

impl QuadMap {
    pub fn values(&self, overlay: crate::presets::QuadOverlay) -> &[f32] {
        match overlay {
            crate::presets::QuadOverlay::Overdraw => &self.overdraw,
            crate::presets::QuadOverlay::Helpers => &self.helpers,
        }
    }

    /// The count at pixel (x, y), or `None` outside the map.
    pub fn at(&self, overlay: crate::presets::QuadOverlay, x: u32, y: u32) -> Option<f32> {
        (x < self.width && y < self.height).then(|| self.values(overlay)[(y * self.width + x) as usize])
    }
}

pub trait Link {
    /// Protocol events (PROTOCOL.md, "WebSocket text messages") received
    /// since the last call, oldest first. Never blocks.
    fn poll(&mut self) -> Vec<serde_json::Value>;
    /// Sends a command; the error says why the daemon refused it.
    fn send(&self, command: Command) -> Result<(), String>;
    /// The text of a diagnostic's file (as the diagnostic names it), for
    /// the excerpt under a problem.
    fn source(&self, file: &str) -> Option<String>;
    /// The newest displayable frame, when there is one.
    fn display(&self) -> Option<DisplayImage>;
    /// Whether the frame is on screen: the daemon skips its display copy
    /// while it is not (a minimised or zero-sized window).
    fn set_shown(&self, shown: bool);
    /// Whether the window is minimised: the daemon then renders
    /// continuously only while a browser is connected.
    fn set_minimised(&self, minimised: bool);
    /// Shows `inspect` from the next frame on (`None`: nothing is
    /// inspected, and the display pass does not run). The newest wins.
    fn inspect(&self, inspect: Option<Inspect>);
    /// The inspected output as the display pass drew it, once it has.
    fn inspected(&self) -> Option<Inspected>;
    /// Reads back one texel after the next frame (the newest wins;
    /// `None`: none).
    fn probe(&self, probe: Option<Probe>);
    /// The newest texel read back.
    fn probed(&self) -> Option<Probed>;
    /// Measures the range of an output once, after the next frame, with
    /// the display options that matter to it (linearisation, the clear
    /// value left out).
    fn measure(&self, inspect: Inspect);
    /// The newest range measured.
    fn measured(&self) -> Option<Range>;
    /// Captures these buffers (`pass/output`) from the next frame on, and
    /// no others for the window: the newest set wins, an empty one asks
    /// for none. The error says why the daemon refused.
    fn tensors(&self, wanted: BTreeSet<String>) -> Result<(), String>;
    /// The newest capture of a buffer as a tensor, once a frame captured it.
    fn tensor(&self, name: &str) -> Option<Tensor>;
    /// Asks for quad statistics with every frame (a `quads` event) while
    /// `on`, as the WebSocket `quad_statistics` does. The error says why the
    /// daemon refused.
    fn quad_statistics(&self, on: bool) -> Result<(), String>;
    /// The newest quad maps of a raster pass, while quad statistics are on.
    fn quad_map(&self, pass: &str) -> Option<QuadMap>;
    /// Selects the frame's pixel (from the top left) whose history and
    /// `debugPrintf` lines every frame reports (`pixel_history` and
    /// `prints` events), as the WebSocket `debug_pixel` does; `None`
    /// clears it. The selection is the daemon's, shared with its
    /// browsers. The error says why it was refused (a pixel outside the
    /// frame, a busy daemon).
    fn debug_pixel(&self, pixel: Option<[u32; 2]>) -> Result<(), String>;
    /// The daemon stopped (Ctrl-C, or it died): the window closes.
    fn closed(&self) -> bool;
    /// Calls `wake` from any thread whenever something new arrives (an
    /// event; each finished frame sends one), so the window repaints when
    /// there is something to show rather than at a fixed rate.
    fn wake_with(&mut self, wake: Box<dyn Fn() + Send + Sync>);
}
