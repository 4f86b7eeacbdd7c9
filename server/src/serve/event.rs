//! The one closed set of things that can happen to the daemon. The render
//! thread handles them one at a time, in arrival order.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use crate::diag::Diagnostic;
use crate::protocol::ClientMessage;
use crate::shader::{Composed, ShaderDefs};

pub enum Event {
    /// Debounced, content-checked changes from the watcher.
    FilesChanged(FileBatch),
    /// A compile worker finished composing one pipeline's shader.
    CompileFinished(CompileResult),
    /// A browser or other client asked for something.
    Client(ClientMessage),
    /// Time to render a frame (continuous mode), or a forced redraw.
    Tick,
    /// The device was lost (driver reset, hang, destroyed).
    DeviceLost(String),
    /// Stop the daemon: the HTTP side is shutting down.
    Shutdown,
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
    pub pipeline: String,
    pub defs: ShaderDefs,
    pub result: Result<Composed, Vec<Diagnostic>>,
    pub compose_ms: f64,
}
