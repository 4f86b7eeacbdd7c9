//! The one closed set of things that can happen to the daemon. The render
//! thread handles them one at a time, in arrival order.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use crate::diag::Diagnostic;
use crate::render::pipelines::Compiled;
use crate::render::resource::PipelineKey;

pub enum Event {
    /// Debounced, content-checked changes from the watcher.
    FilesChanged(FileBatch),
    /// A compile worker finished composing one pipeline's shader.
    /// Boxed: a compiled module is far larger than every other event.
    CompileFinished(Box<CompileResult>),
    /// Rebuild every pipeline from the current sources (the WebSocket
    /// `rebuild` message, `POST /api/reload`).
    Rebuild,
    /// The outputs (`pass/output`) WebSocket client `client` wants captured
    /// every frame, replacing what it wanted before; empty when it left.
    Subscriptions { client: u64, outputs: BTreeSet<String> },
    /// A live scene override from a client, or saving them to the file.
    Scene(SceneCommand),
    /// Time to render a frame (continuous mode), or a forced redraw.
    Tick,
    /// The device was lost (driver reset, hang, destroyed). `device` is
    /// which device it was (the daemon's count of resets when it was
    /// opened), so a late report about a replaced device is ignored.
    DeviceLost { device: u32, reason: wgpu::DeviceLostReason, message: String },
    /// Forget every history resource (temporal passes, the path tracer's
    /// accumulation) and render: the WebSocket `reset_history` message.
    ResetHistory,
    /// Debug API only (`--debug-api`): destroy the device for real, to
    /// exercise recovery.
    LoseDevice,
    /// Capture every output of the next frame and report where a NaN/Inf
    /// started (`POST /api/frame/trace`).
    Trace,
    /// Render a material's preview (`GET /api/materials/{index}/preview`):
    /// the daemon hands it to the preview thread with its current scene.
    Preview(super::preview::Request),
    /// Select the pixel whose prints each frame reports (`None`: clear):
    /// the WebSocket `debug_pixel` message.
    DebugPixel(Option<[u32; 2]>),
    /// Stop the daemon: the HTTP side is shutting down.
    Shutdown,
}

pub enum SceneCommand {
    Set { path: String, value: crate::scene::settings::Value },
    Clear,
    Save,
}

/// Files whose content changed, as one batch (a `git checkout` of many files
/// arrives as one batch, so dependents rebuild once).
#[derive(Debug, Clone)]
pub struct FileBatch {
    pub changes: Vec<FileChange>,
    /// When the first raw file-system event of this batch was seen.
    pub first_event: Instant,
    /// When the batch was debounced and every file's content read.
    pub ready: Instant,
}

#[derive(Debug, Clone)]
pub enum FileChange {
    /// Created or modified: the new content (already read and hashed).
    Written { path: PathBuf, content: Arc<[u8]> },
    /// Gone, and still gone after the retry window.
    Removed { path: PathBuf },
}

impl FileChange {
    pub fn path(&self) -> &std::path::Path {
        match self {
            FileChange::Written { path, .. } | FileChange::Removed { path } => path,
        }
    }
}

/// The result of composing one pipeline's shader off the render thread.
pub struct CompileResult {
    /// Which reload this belongs to.
    pub reload: u64,
    pub key: PipelineKey,
    pub result: Result<Compiled, Vec<Diagnostic>>,
    pub compose_ms: f64,
}
