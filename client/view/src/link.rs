//! The viewer's one dependency on a daemon: events in, commands out, and
//! the newest frame as a texture on the device the window renders with.

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
    /// The daemon stopped (Ctrl-C, or it died): the window closes.
    fn closed(&self) -> bool;
}
