//! `loupe view`'s window: egui panels over a [`Model`] of what the daemon
//! publishes, independent of how it arrives.
//!
//! The panels read the model and the newest displayable frame from a
//! [`Link`]; commands go back through it. `loupe` implements the link in
//! process (`serve::viewer`, the daemon's own device and events); a remote
//! link over the WebSocket protocol would implement the same trait. This
//! crate never depends on `loupe`: the model is fed the protocol's JSON
//! events (PROTOCOL.md), the shapes the browser reads.

pub mod editor;
pub mod excerpt;
pub mod frame_times;
pub mod link;
pub mod model;
mod panels;
pub mod pixel;
pub mod presets;
pub mod viewer;
pub mod window;

// The versions the panels are drawn with, for hosts and tests.
pub use {egui, egui_wgpu};

pub use link::{Command, DisplayImage, Inspect, Inspected, Link, Probe, Probed, QuadMap, Range, Tensor};
pub use model::Model;
pub use viewer::Viewer;
