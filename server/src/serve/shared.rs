//! State the render thread publishes for the HTTP side to read. The render
//! thread is the only writer; handlers only read snapshots or send events.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, RwLock};

use tokio::sync::{broadcast, watch};

use super::event::Event;
use crate::diag::Diagnostic;
use crate::protocol::{PassInfo, PipelineInfo, ServerEvent, Status};
use crate::render::capture::CapturedImage;

/// How many events a slow WebSocket client may fall behind before it
/// starts losing (and being told how many it lost).
pub const EVENT_QUEUE: usize = 256;

pub struct Shared {
    pub status: RwLock<Status>,
    pub passes: RwLock<Vec<PassInfo>>,
    pub pipelines: RwLock<Vec<PipelineInfo>>,
    pub diagnostics: RwLock<Vec<Diagnostic>>,
    /// Every captured output of the newest frame, by `pass/output`.
    pub captures: RwLock<Arc<BTreeMap<String, Arc<CapturedImage>>>>,
    /// The previous good version of each output, kept when a reload swaps a
    /// pipeline, for A/B compares: by `pass/output`.
    pub last_good: RwLock<Arc<BTreeMap<String, Arc<CapturedImage>>>>,
    /// JSON events for every client; a lagging receiver drops the oldest.
    pub events: broadcast::Sender<ServerEvent>,
    /// The newest final frame as PNG: clients always get the latest, never a
    /// queue of old ones.
    pub frame_png: watch::Sender<Option<Arc<FramePng>>>,
    /// Back to the render thread.
    pub to_daemon: std::sync::mpsc::Sender<Event>,
    /// Directories whose files may be served as sources (shaders/, scenes/).
    pub source_roots: Vec<PathBuf>,
}

#[derive(Debug)]
pub struct FramePng {
    pub frame: u64,
    pub width: u32,
    pub height: u32,
    pub png: Vec<u8>,
}

impl Shared {
    pub fn new(to_daemon: std::sync::mpsc::Sender<Event>, source_roots: Vec<PathBuf>) -> Arc<Self> {
        Arc::new(Shared {
            status: RwLock::new(Status::default()),
            passes: RwLock::new(Vec::new()),
            pipelines: RwLock::new(Vec::new()),
            diagnostics: RwLock::new(Vec::new()),
            captures: RwLock::new(Arc::new(BTreeMap::new())),
            last_good: RwLock::new(Arc::new(BTreeMap::new())),
            events: broadcast::channel(EVENT_QUEUE).0,
            frame_png: watch::channel(None).0,
            to_daemon,
            source_roots,
        })
    }

    /// Sends an event to every connected client; none connected is fine.
    pub fn publish(&self, event: ServerEvent) {
        let _ = self.events.send(event);
    }
}

/// Reads a lock even if a writer panicked: the data is a snapshot, and a
/// stale snapshot is better than a dead server.
pub fn read<T: Clone>(lock: &RwLock<T>) -> T {
    lock.read().unwrap_or_else(|e| e.into_inner()).clone()
}

pub fn write<T>(lock: &RwLock<T>, value: T) {
    *lock.write().unwrap_or_else(|e| e.into_inner()) = value;
}
