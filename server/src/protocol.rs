//! Protocol data: what the daemon tells clients, as plain types. The http
//! module turns them into JSON; nothing else encodes them. PROTOCOL.md at
//! the repository root documents every shape; bump `VERSION` on any
//! incompatible change.

use serde::{Deserialize, Serialize};

use crate::diag::Diagnostic;
use crate::render::frame::NanOrigin;
use crate::render::pipelines::{PipelineSummary, Status as PipelineStatus};
use crate::render::quads::PassQuads;
use crate::render::session::{DepthProjection, PassState, PassSummary};
use crate::scene::overrides::{Control, Overrides};
use crate::scene::settings::Value as OverrideValue;

pub const VERSION: u32 = 3;

/// `GET /api/status`
#[derive(Debug, Clone, Serialize, Default)]
pub struct Status {
    pub protocol: u32,
    pub version: String,
    pub adapter: String,
    /// True on a CPU adapter (lavapipe): timings are only comparable as ratios.
    pub cpu_adapter: bool,
    pub features: Vec<String>,
    /// What degrades because the adapter lacks a feature.
    pub degraded: Vec<String>,
    pub scene: String,
    pub frame: u64,
    pub pipelines_ok: usize,
    pub pipelines_stale: usize,
    pub pipelines_failed: usize,
    /// How many times the device was lost and recreated.
    pub device_resets: u32,
    pub errors: usize,
    pub warnings: usize,
    /// `continuous` or `on-change`.
    pub render_mode: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PassStatus {
    /// Rendering with its current pipelines.
    Ok,
    /// Its newest source failed; the last good pipeline still renders.
    Stale,
    /// It has never built (no last good pipeline): it does not render.
    Failed,
    /// Not needed by this frame.
    Culled,
}

/// One output of a pass: a texture, or a buffer read as a tensor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputInfo {
    pub name: String,
    /// `texture` or `buffer`.
    pub kind: String,
    /// A texture's format (`Rgba16Float`), a buffer's element type (`u32`).
    pub format: String,
    /// A texture's size; for a buffer, its element count and 1.
    pub width: u32,
    pub height: u32,
    /// A buffer's dimensions, outermost first: `[["bin", 256]]`; `null`
    /// for a texture.
    pub shape: Option<Vec<(String, u32)>>,
    /// What its values mean: `color`, `normal`, `depth`, `data` or `id`.
    pub meaning: String,
    /// A depth output's projection (near, far, reversed); `null` otherwise.
    pub depth: Option<DepthProjection>,
    /// Kept across frames (a history resource).
    pub history: bool,
}

/// One node of the render graph, `GET /api/passes`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassInfo {
    pub name: String,
    /// `raster`, `compute` or `copy`; `null` when culled.
    pub kind: Option<String>,
    pub status: PassStatus,
    /// Why it is culled or failed.
    pub reason: Option<String>,
    pub pipelines: Vec<String>,
    pub reads: Vec<String>,
    pub writes: Vec<OutputInfo>,
    /// The last frame's time for this pass, or why there is none.
    #[serde(flatten)]
    pub time: PassTime,
    pub diagnostics: usize,
}

impl PassInfo {
    pub fn new(p: PassSummary, time: PassTime) -> Self {
        PassInfo {
            name: p.name,
            kind: p.kind.map(|k| format!("{k:?}").to_lowercase()),
            status: match p.status {
                PassState::Ok => PassStatus::Ok,
                PassState::Stale => PassStatus::Stale,
                PassState::Failed => PassStatus::Failed,
                PassState::Culled => PassStatus::Culled,
            },
            reason: p.reason,
            pipelines: p.pipelines,
            reads: p.reads,
            writes: p
                .writes
                .into_iter()
                .map(|o| OutputInfo {
                    name: o.name,
                    kind: o.kind.to_owned(),
                    format: o.format,
                    width: o.width,
                    height: o.height,
                    shape: o.tensor.map(|t| t.dims.iter().map(|(n, s)| ((*n).to_owned(), *s)).collect()),
                    meaning: o.meaning.to_owned(),
                    depth: o.depth,
                    history: o.history,
                })
                .collect(),
            time,
            diagnostics: p.diagnostics,
        }
    }

    /// The same pass without its per-frame time: what a `passes` event
    /// announces a change of (times travel in `frame` events).
    pub fn shape(&self) -> PassInfo {
        PassInfo { time: PassTime::default(), ..self.clone() }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct PipelineInfo {
    pub name: String,
    pub shader: String,
    pub defs: String,
    pub status: PassStatus,
    /// Increases each time a new version is swapped in.
    pub generation: u64,
    pub files: Vec<String>,
}

impl From<PipelineSummary> for PipelineInfo {
    fn from(p: PipelineSummary) -> Self {
        let status = match p.status {
            PipelineStatus::Ok => PassStatus::Ok,
            PipelineStatus::Stale => PassStatus::Stale,
            PipelineStatus::Failed => PassStatus::Failed,
        };
        PipelineInfo { name: p.name, shader: p.shader, defs: p.defs, status, generation: p.generation, files: p.files }
    }
}

/// `GET /api/diagnostics`
#[derive(Debug, Clone, Serialize, Default)]
pub struct DiagnosticsReport {
    pub diagnostics: Vec<Diagnostic>,
}

/// Time spent between a save and the frame that shows it.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct ReloadTimings {
    /// From the first file event to the debounced, content-checked change.
    pub watch_ms: f64,
    /// The slowest pipeline's compose + validate, on a worker thread.
    pub compose_ms: f64,
    /// Pipeline creation on the render thread, summed over the reload.
    pub pipeline_ms: f64,
    /// The first frame that used the reload's pipelines: recording,
    /// execution and readback.
    pub render_ms: f64,
}

/// One file's change since its last good version (the `files` event).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FileDiff {
    pub file: String,
    /// The pipelines built from it that are not ok (stale: the last good
    /// one still renders; failed: none does).
    pub pipelines: Vec<String>,
    pub hunks: Vec<Hunk>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Hunk {
    /// First line of the hunk in the last good text and in the current
    /// one, from 1.
    pub old_start: usize,
    pub new_start: usize,
    pub lines: Vec<DiffLine>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiffLine {
    /// `" "` unchanged, `"-"` only in the last good text, `"+"` only in
    /// the current one.
    pub tag: &'static str,
    /// Its line number in the last good text and in the current one.
    pub old: Option<usize>,
    pub new: Option<usize>,
    /// Without its line ending.
    pub text: String,
    /// An error points at this line of the current text.
    pub failing: bool,
}

/// `GET /api/references`: loupe.toml's image cases of the daemon's scene
/// and how each compared with its references ("against reference").
#[derive(Debug, Clone, Default, Serialize)]
pub struct ReferenceReport {
    /// Increases with each comparison published.
    pub generation: u64,
    /// `true` while a comparison of newer sources runs.
    pub comparing: bool,
    /// loupe.toml's error, when it has one (then there are no cases).
    pub config_error: Option<Diagnostic>,
    pub cases: Vec<CaseReport>,
}

#[derive(Debug, Clone, Serialize)]
pub struct CaseReport {
    pub name: String,
    /// `passed` or `failed`.
    pub verdict: crate::check::images::Verdict,
    pub flip_mean: f64,
    pub flip_p99: f64,
    /// The adapter key whose threshold applied, if one did.
    pub adapter_key: Option<String>,
    pub outputs: Vec<OutputReport>,
    pub diagnostics: Vec<Diagnostic>,
}

#[derive(Debug, Clone, Serialize)]
pub struct OutputReport {
    pub output: String,
    pub reference: String,
    pub flip: Option<crate::flip::Summary>,
    pub relative_mse: Option<f64>,
}

/// WebSocket text messages, server → client.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerEvent {
    Hello {
        protocol: u32,
        status: Status,
    },
    ReloadStarted {
        id: u64,
        files: Vec<String>,
        pipelines: Vec<String>,
    },
    ReloadSucceeded {
        id: u64,
        files: Vec<String>,
        pipelines: Vec<String>,
        timings: ReloadTimings,
    },
    ReloadFailed {
        id: u64,
        files: Vec<String>,
        pipelines: Vec<String>,
        diagnostics: Vec<Diagnostic>,
    },
    /// `reload`: the newest reload this frame is the first to show;
    /// `reloads`: every one of them (several can finish between frames).
    /// `frame_ms` = `passes_ms` + `unattributed_ms` (see `FrameTimes`).
    Frame {
        frame: u64,
        passes: Vec<PassTiming>,
        frame_ms: f64,
        passes_ms: f64,
        unattributed_ms: f64,
        reload: Option<u64>,
        reloads: Vec<u64>,
        /// Tile classification's counts (`null`: nothing classified).
        tiles: Option<crate::render::passes::classify::Statistics>,
        /// Samples per pixel the path tracer holds after this frame
        /// (`null`: it did not run).
        samples: Option<u32>,
    },
    Passes {
        passes: Vec<PassInfo>,
    },
    Diagnostics {
        diagnostics: Vec<Diagnostic>,
    },
    DeviceLost {
        message: String,
        recovered: bool,
    },
    /// What this client missed because it read too slowly, since the
    /// previous `dropped`: `frames` rendered that it got no images of, and
    /// `events` it lost.
    Dropped {
        frames: u64,
        events: u64,
    },
    /// The server could not use a message this client sent (bad JSON, an
    /// unknown `type`, a binary message); the connection stays open.
    Error {
        message: String,
    },
    /// The scene's live controls and the overrides set on top of the file
    /// (also `GET /api/controls`), after any change to either.
    Controls(ControlsReport),
    /// A `save_scene` (or `POST /api/scene/save`) was carried out: the
    /// overrides were written into `file`, or `error` says why not.
    SceneSaved {
        file: String,
        error: Option<String>,
    },
    /// A traced frame's NaN report (also `GET /api/nan`); `null` once a
    /// later frame is clean again.
    Nan {
        report: Option<NanReport>,
    },
    /// A frame's quad statistics (also `GET /api/quads`), for every frame
    /// while some client asks for them (`quad_statistics`).
    Quads(QuadReport),
    /// The scene's materials and their compile reports (also `GET
    /// /api/materials`), whenever the scene is (re)installed: a material
    /// file or scene edit, or an override.
    Materials(MaterialsReport),
    /// Each source file that broke a pass since its last good version, with
    /// the diff (also `GET /api/files`), whenever that list changes.
    Files {
        files: Vec<FileDiff>,
    },
    /// The image cases of the daemon's scene compared with their
    /// references (also `GET /api/references`), when a comparison starts
    /// and when it is done.
    References(ReferenceReport),
    /// What a frame's `debugPrintf`s printed at the selected pixel
    /// (`debug_pixel`), for every frame while one is selected.
    Prints {
        frame: u64,
        pixel: [u32; 2],
        lines: Vec<crate::render::debug_print::PrintLine>,
        dropped: u32,
    },
    /// The selected pixel's history through a frame (`debug_pixel`), for
    /// every frame while one is selected.
    PixelHistory(crate::render::pixel_history::PixelHistory),
}

/// `GET /api/materials`: the scene's material instances, one per
/// `[[materials]]` entry in order (the G-buffer's material index), and the
/// compile report of each definition they use.
#[derive(Debug, Clone, Serialize, Default)]
pub struct MaterialsReport {
    pub scene: String,
    pub materials: Vec<MaterialEntry>,
    /// By definition id (`MaterialEntry::definition`).
    pub definitions: Vec<crate::material::report::Report>,
}

#[derive(Debug, Clone, Serialize)]
pub struct MaterialEntry {
    /// The entry's index in the scene, as the G-buffer stores it.
    pub index: u32,
    /// The entry's `name` (a glTF's own material: `FILE::MATERIAL`).
    pub name: String,
    /// The material file as the scene writes it (the glTF file for a
    /// glTF's own material); `null` for the shorthand.
    pub file: Option<String>,
    /// The definition's name (`shorthand` for the scene file's own).
    pub material: String,
    pub definition: u32,
    pub params: Vec<MaterialParam>,
}

/// One parameter of an instance: its value and how a control edits it.
#[derive(Debug, Clone, Serialize)]
pub struct MaterialParam {
    pub name: String,
    /// The scene override path that sets it (`materials[2].params.NAME`;
    /// the shorthand's `materials[0].roughness`); `None` for a glTF's own
    /// materials, which no override sets.
    pub path: Option<String>,
    /// `float`, `color` or `vec3`.
    #[serde(rename = "type")]
    pub ty: &'static str,
    /// A number, or `[r, g, b]` for a colour or vector.
    pub value: serde_json::Value,
    /// The definition's default, in the same form.
    pub default: serde_json::Value,
    /// Inclusive bounds of each component; `null`: any finite value.
    pub min: Option<f32>,
    pub max: Option<f32>,
    pub unit: Option<String>,
    pub doc: Option<String>,
}

/// The subscription member that stands for quad statistics in a client's
/// set of `pass/output` keys (it has no `/`, so no output is named so).
pub const QUAD_STATISTICS: &str = "quads";

/// Likewise for the image cases' comparison with their references.
pub const REFERENCES: &str = "references";

/// One frame's quad statistics: the model's figures per raster pass and
/// draw, beside what the adapter counted.
#[derive(Debug, Clone, Serialize)]
pub struct QuadReport {
    pub frame: u64,
    /// The adapter whose fragment-shader invocations are shown.
    pub adapter: String,
    pub passes: Vec<PassQuadReport>,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassQuadReport {
    #[serde(flatten)]
    pub quads: PassQuads,
    /// Fragment-shader invocations the adapter counted over the pass
    /// (pipeline statistics); `null` where it cannot count them.
    pub fragment_invocations: Option<u64>,
}

/// Where a NaN or Inf started, from a frame that captured every output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NanReport {
    /// The traced frame.
    pub frame: u64,
    /// `auto` (the HDR frame held NaN/Inf) or `request` (`POST /api/frame/trace`).
    pub trigger: String,
    /// The first pass whose output holds a NaN/Inf none of its inputs held;
    /// `null` for a clean frame.
    pub origin: Option<NanOrigin>,
    /// Every output of the frame holding NaN or Inf, in pass order.
    pub outputs: Vec<NanCount>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NanCount {
    pub pass: String,
    pub output: String,
    pub nan: u64,
    pub inf: u64,
}

/// `GET /api/controls`: what the browser's scene panel shows.
#[derive(Debug, Clone, Serialize, Default)]
pub struct ControlsReport {
    pub scene: String,
    pub controls: Vec<Control>,
    /// Values set from the browser, not yet saved to the file.
    pub overrides: Overrides,
}

#[derive(Debug, Clone, Serialize)]
pub struct PassTiming {
    pub name: String,
    #[serde(flatten)]
    pub time: PassTime,
}

/// The clock a pass's time was measured by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Clock {
    /// The adapter's timestamp queries around the pass.
    Gpu,
    /// The pass submitted alone and waited for: recording, execution and
    /// the copies of its captured outputs.
    Wall,
}

/// A pass's time as shown: a figure with its clock, or none with the
/// reason. Never a figure known to be wrong.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct PassTime {
    pub time_ms: Option<f64>,
    /// `null` exactly when `time_ms` is.
    pub timing: Option<Clock>,
    /// Why there is no figure; `null` when there is one.
    pub timing_reason: Option<String>,
}

impl PassTime {
    pub fn measured(ms: f64, clock: Clock) -> Self {
        PassTime { time_ms: Some(ms), timing: Some(clock), timing_reason: None }
    }

    pub fn none(reason: impl Into<String>) -> Self {
        PassTime { time_ms: None, timing: None, timing_reason: Some(reason.into()) }
    }
}

/// How a subscribed output is streamed as binary messages.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// 8-bit sRGB PNG for display, as `/api/captures/…png`.
    #[default]
    Png,
    /// Raw little-endian RGBA `f32`, as `/api/captures/…f32`.
    F32,
    /// Raw little-endian RGBA IEEE half floats, as `/api/captures/…f16`.
    F16,
}

impl Encoding {
    pub fn mime(self) -> &'static str {
        match self {
            Encoding::Png => "image/png",
            Encoding::F32 | Encoding::F16 => "application/octet-stream",
        }
    }
}

/// WebSocket text messages, client → server.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ClientMessage {
    /// Capture `pass/output` every frame and stream it to this client as
    /// binary `capture` messages, newest only.
    Subscribe {
        pass: String,
        output: String,
        #[serde(default)]
        encoding: Encoding,
    },
    /// Stop streaming `pass/output` to this client.
    Unsubscribe { pass: String, output: String },
    /// Rebuild every pipeline from the current sources (`POST /api/reload`
    /// sends this too).
    Rebuild {},
    /// Set a scene value live (`post.exposure_ev`, `lights[0].intensity`):
    /// the scene re-renders with it; the file is untouched until saved.
    SetOverride { path: String, value: OverrideValue },
    /// Drop every override: back to the file's values.
    ClearOverrides {},
    /// Write the overrides into the scene file, keeping its comments and
    /// layout, and clear them.
    SaveScene {},
    /// Forget every history resource (temporal passes, the path tracer's
    /// accumulation) and render a frame that starts over.
    ResetHistory {},
    /// Start (`on: true`) or stop receiving `quads` events: the daemon
    /// computes quad statistics while any client wants them.
    QuadStatistics { on: bool },
    /// Start or stop comparing the scene's image cases with their
    /// references after every reload (`references` events): the daemon
    /// renders them while any client wants them.
    ReferenceComparison { on: bool },
    /// Select the pixel whose `debugPrintf`s every frame reports in a
    /// `prints` event; `x` and `y` `null` (or left out) clear it.
    DebugPixel {
        #[serde(default)]
        x: Option<u32>,
        #[serde(default)]
        y: Option<u32>,
    },
}
