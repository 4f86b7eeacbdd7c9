//! State the render thread publishes for the HTTP side to read. The render
//! thread is the only writer; handlers only read snapshots or send events.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock, RwLock};

use tokio::sync::{broadcast, watch};

use super::inbox::Clients;
use crate::diag::Diagnostic;
use crate::protocol::{
    ControlsReport, Encoding, FileDiff, MaterialsReport, NanReport, PassInfo, PipelineInfo, QuadReport, ServerEvent, Status,
};
use crate::render::capture::{CapturedImage, CapturedTensor};

/// How many events a slow WebSocket client may fall behind before it
/// starts losing (and being told how many it lost).
pub const EVENT_QUEUE: usize = 256;

pub struct Shared {
    pub status: RwLock<Status>,
    pub passes: RwLock<Vec<PassInfo>>,
    pub pipelines: RwLock<Vec<PipelineInfo>>,
    pub diagnostics: RwLock<Vec<Diagnostic>>,
    /// The newest capture of every output captured so far, by
    /// `pass/output`: bounded by the outputs passes declare.
    pub captures: RwLock<Arc<BTreeMap<String, Arc<CapturedImage>>>>,
    /// The newest traced frame's NaN report, while frames are not clean.
    pub nan: RwLock<Option<NanReport>>,
    /// The newest frame's quad statistics, while some client asks for them.
    pub quads: RwLock<Option<Arc<QuadReport>>>,
    /// Every captured buffer (as a tensor) of the newest frames, by
    /// `pass/output`.
    pub tensors: RwLock<Arc<BTreeMap<String, Arc<CapturedTensor>>>>,
    /// The previous good version of each output, kept when a reload swaps a
    /// pipeline, for A/B compares: by `pass/output`.
    pub last_good: RwLock<Arc<BTreeMap<String, Arc<CapturedImage>>>>,
    /// JSON events for every client; a lagging receiver drops the oldest.
    pub events: broadcast::Sender<ServerEvent>,
    /// The newest frame's images: each client always gets the latest, never
    /// a queue of old ones.
    pub frames: watch::Sender<Option<Arc<FrameImages>>>,
    /// Clients' way back to the render thread (bounded).
    pub clients: Clients,
    /// Directories whose files may be served as sources (shaders/, scenes/).
    pub source_roots: Vec<PathBuf>,
    /// Whether `/api/debug/*` exists (`loupe serve --debug-api`).
    pub debug_api: bool,
    /// Where `loupe bench tradeoffs` wrote its results (`/api/tradeoffs`).
    pub tradeoffs: PathBuf,
    /// The scene and sources being rendered, as `loupe bench tradeoffs`
    /// hashes them: which results are this scene's, and current.
    pub measured: RwLock<crate::tradeoffs::Provenance>,
    pub controls: RwLock<ControlsReport>,
    /// The newest good scene's materials: a broken material file leaves
    /// the last good report here (the diagnostics carry the error).
    pub materials: RwLock<Arc<MaterialsReport>>,
    /// Each source file that broke a pass, diffed against its last good
    /// text (`GET /api/files`), and those texts, which a revert writes back.
    pub files: RwLock<Arc<FilesState>>,
    /// The newest comparison of the scene's image cases with their
    /// references, and the way to ask for one.
    pub references: RwLock<Arc<super::reference_jobs::State>>,
    pub reference_jobs: Arc<super::reference_jobs::Queue>,
}

/// The source files not good now that have a last good version.
#[derive(Debug, Default)]
pub struct FilesState {
    pub diffs: Vec<FileDiff>,
    /// By display path; one for each diff.
    pub last_good: BTreeMap<String, (PathBuf, Arc<str>)>,
}

/// One encoding of one image, made once by whichever client asks first.
type Encoded = Arc<OnceLock<Arc<[u8]>>>;

/// One frame's captured images: the final output and every output some
/// client subscribed to. Each encoding of each image is made once, by the
/// first client that sends it, and shared by the others.
#[derive(Debug)]
pub struct FrameImages {
    pub frame: u64,
    /// `pass/output` of the frame's final output, when it was captured.
    pub final_key: Option<String>,
    /// This frame's captures by `pass/output`.
    pub captures: BTreeMap<String, Arc<CapturedImage>>,
    encoded: Mutex<BTreeMap<(String, Encoding), Encoded>>,
}

impl FrameImages {
    pub fn new(frame: u64, final_key: Option<String>, captures: BTreeMap<String, Arc<CapturedImage>>) -> Self {
        FrameImages { frame, final_key, captures, encoded: Mutex::new(BTreeMap::new()) }
    }

    /// `key` encoded as `encoding`, made at most once per frame (this may
    /// take milliseconds: call it off the async reactor).
    pub fn encoded(&self, key: &str, encoding: Encoding) -> Option<Arc<[u8]>> {
        let image = self.captures.get(key)?;
        let cell = self.encoded.lock().unwrap_or_else(|e| e.into_inner()).entry((key.to_owned(), encoding)).or_default().clone();
        Some(
            cell.get_or_init(|| match encoding {
                Encoding::Png => image.to_png().into(),
                Encoding::F32 => image.raw_f32().into(),
                Encoding::F16 => image.raw_f16().into(),
            })
            .clone(),
        )
    }
}

impl Shared {
    pub fn new(clients: Clients, source_roots: Vec<PathBuf>, debug_api: bool, tradeoffs: PathBuf) -> Arc<Self> {
        Arc::new(Shared {
            status: RwLock::new(Status::default()),
            passes: RwLock::new(Vec::new()),
            pipelines: RwLock::new(Vec::new()),
            diagnostics: RwLock::new(Vec::new()),
            captures: RwLock::new(Arc::new(BTreeMap::new())),
            last_good: RwLock::new(Arc::new(BTreeMap::new())),
            tensors: RwLock::new(Arc::new(BTreeMap::new())),
            nan: RwLock::new(None),
            quads: RwLock::new(None),
            events: broadcast::channel(EVENT_QUEUE).0,
            frames: watch::channel(None).0,
            clients,
            source_roots,
            debug_api,
            tradeoffs,
            measured: RwLock::new(Default::default()),
            controls: RwLock::new(ControlsReport::default()),
            files: RwLock::new(Arc::default()),
            references: RwLock::new(Arc::default()),
            reference_jobs: Arc::default(),
            materials: RwLock::new(Arc::default()),
        })
    }

    /// The first event a client gets: the protocol version and the status.
    pub fn hello(&self) -> ServerEvent {
        ServerEvent::Hello { protocol: crate::protocol::VERSION, status: read(&self.status) }
    }

    /// The state a client that keeps no HTTP snapshots starts from, or
    /// rebuilds after it lost events: the pass list, the diagnostics, the
    /// files' diffs, the scene's controls and the NaN report, as events.
    pub fn state_events(&self) -> [ServerEvent; 5] {
        [
            ServerEvent::Passes { passes: read(&self.passes) },
            ServerEvent::Diagnostics { diagnostics: read(&self.diagnostics) },
            ServerEvent::Files { files: read(&self.files).diffs.clone() },
            ServerEvent::Controls(read(&self.controls)),
            ServerEvent::Nan { report: read(&self.nan) },
        ]
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
