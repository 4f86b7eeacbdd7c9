//! The daemon's render thread: the one place that owns the device. It takes
//! events one at a time — file changes, compile results, client messages,
//! frame ticks — and publishes snapshots and events for clients.
//!
//! Composition runs on worker threads (it never blocks rendering); only
//! pipeline creation, which needs the device, runs here.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use super::event::{CompileResult, Event, FileBatch, FileChange, SceneCommand};
use super::inbox::Inbox;
use super::shared::{self, FrameImages, Shared};
use crate::diag::{Code, Diagnostic, Location, Severity};
use crate::gpu::pipeline::PipelineSpec;
use crate::gpu::{self, Gpu};
use crate::protocol::{
    self, ControlsReport, NanCount, NanReport, PassInfo, PassQuadReport, PassStatus, PassTiming, QUAD_STATISTICS, QuadReport,
    ReloadTimings, ServerEvent, Status,
};
use crate::render::FrameOptions;
use crate::render::frame::{FrameResult, PendingFrame};
use crate::render::passes;
use crate::render::passes::nan_watch;
use crate::render::pipelines::Installed;
use crate::render::resource::PipelineKey;
use crate::render::session::{PassState, Session};
use crate::scene::{self, overrides::Overrides};
use crate::shader::{Library, SourceFile, library};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderMode {
    /// Render frames continuously, up to the frame-rate cap.
    Continuous,
    /// Render only when something changed.
    OnChange,
}

pub struct Config {
    pub shader_root: PathBuf,
    pub scene_path: PathBuf,
    pub mode: RenderMode,
    pub max_fps: f64,
    /// Where the scene's files outside the watched roots are named.
    pub watch_files: super::watch::WatchedFiles,
}

struct Reload {
    files: Vec<String>,
    pipelines: Vec<String>,
    pending: BTreeSet<PipelineKey>,
    diagnostics: Vec<Diagnostic>,
    watch_ms: f64,
    compose_ms: f64,
    pipeline_ms: f64,
    /// Some of its pipelines are swapped in, others still compiling: a
    /// frame now would mix old and new.
    swapped_any: bool,
}

/// A reload whose pipelines all swapped in, waiting for the first frame
/// that uses them: `reload_succeeded` is sent once that frame is rendered,
/// with its render time.
struct Succeeded {
    id: u64,
    files: Vec<String>,
    pipelines: Vec<String>,
    timings: ReloadTimings,
}

/// A submitted frame on its way back.
/// Where a submitted frame's results stand.
enum Results {
    /// Rendering, or being copied back.
    Gpu(PendingFrame),
    /// Landed, and being converted and measured on the conversion thread:
    /// the render thread goes on submitting frames meanwhile.
    Converting(mpsc::Receiver<FrameResult>),
}

struct InFlight {
    results: Results,
    /// The reloads this frame is the first to show.
    reloads: Vec<Succeeded>,
    started: Instant,
    /// `pass/output` of the final output.
    final_key: Option<String>,
    /// No uncaptured wgpu error while recording or submitting it: its
    /// images are real and may be published.
    clean: bool,
    /// `pass/output` of every output whose pass uses a pipeline swapped in
    /// since the previous frame.
    replaced: BTreeSet<String>,
    /// Why this frame captured every output, when it did.
    trace: Option<&'static str>,
}

pub struct Daemon {
    /// The device, sources, scene, graph, pipelines and resources.
    session: Session,
    config: Config,
    /// Files that failed to load, by display path: their last good content
    /// stays in the session's library meanwhile.
    file_errors: BTreeMap<String, Diagnostic>,
    /// The scene file and the meshes it references: a change to any
    /// reloads the scene.
    scene_files: Vec<PathBuf>,
    scene_error: Option<Diagnostic>,
    /// Live values from the browser on top of the scene file.
    overrides: Overrides,
    shared: Arc<Shared>,
    events: Sender<Event>,
    workers: Arc<rayon::ThreadPool>,
    next_reload: u64,
    reloads: BTreeMap<u64, Reload>,
    /// Per pipeline, the newest reload that compiled it: results of older
    /// ones are dropped, also after the newest one's has arrived (bounded by
    /// the pipelines the specs can make).
    newest_compile: BTreeMap<PipelineKey, u64>,
    /// Reloads finished since the last frame, to tag that frame with.
    finished_reloads: Vec<Succeeded>,
    in_flight: VecDeque<InFlight>,
    /// The one thread captures are converted on, so results come back in
    /// frame order and never more than the frames in flight.
    converter: rayon::ThreadPool,
    dirty: bool,
    /// What each WebSocket client wants captured, by client id.
    subscriptions: BTreeMap<u64, BTreeSet<String>>,
    /// Pipelines swapped in since the last frame was submitted.
    swapped_since_frame: BTreeSet<PipelineKey>,
    /// Uncaptured wgpu errors of the newest frame, as diagnostics.
    gpu_errors: Vec<Diagnostic>,
    /// Where each uncaptured error (by message) was first attributed, so a
    /// persisting error keeps its file.
    gpu_error_files: BTreeMap<String, Vec<String>>,
    /// The pass list last announced in a `passes` event, without times.
    announced_passes: Option<Vec<PassInfo>>,
    /// The newest frame's per-pass times and how they were measured.
    last_timings: Vec<(String, f64)>,
    last_timing: String,
    device_resets: u32,
    /// The debug API asked for the device to be destroyed; its loss is on
    /// its way.
    destroy_requested: bool,
    /// When the newest frame was submitted: the next one's time step.
    last_frame: Option<Instant>,
    /// The next frame captures every output, for this reason (`auto`,
    /// `request`), to find where a NaN/Inf started.
    trace_next: Option<&'static str>,
    /// Sources or the scene changed since the last trace: a NaN now may
    /// start elsewhere.
    trace_stale: bool,
    nan_report: Option<NanReport>,
}

impl Daemon {
    pub fn new(gpu: Gpu, config: Config, shared: Arc<Shared>, events: Sender<Event>) -> Self {
        let (lib, unnamed) = library::load_tree(&config.shader_root).unwrap_or_else(|_| (Library::new([]), Vec::new()));
        let (loaded, scene_error) = match scene::load(&config.scene_path) {
            Ok(l) => (l, None),
            Err(d) => {
                let empty = scene::parse("", "").expect("the empty scene is valid");
                (
                    scene::Loaded { scene: empty, meshes: Default::default(), denoiser: None, files: vec![config.scene_path.clone()] },
                    Some(d),
                )
            }
        };
        let workers = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .stack_size(256 << 20)
            .thread_name(|i| format!("loupe-compile-{i}"))
            .build()
            .expect("compile worker threads");
        let timing = if gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) { "gpu" } else { "cpu" };
        config.watch_files.set(&loaded.files);
        Daemon {
            session: Session::new(gpu, &config.shader_root, lib, &loaded)
                .with_options(FrameOptions { nan_watch: true, ..FrameOptions::default() }),
            config,
            // Files whose names are not UTF-8 are left out, each with its warning.
            file_errors: unnamed.into_iter().filter_map(|d| Some((d.file()?.to_owned(), d))).collect(),
            scene_files: loaded.files,
            scene_error,
            overrides: Overrides::new(),
            shared,
            events,
            workers: Arc::new(workers),
            next_reload: 1,
            reloads: BTreeMap::new(),
            newest_compile: BTreeMap::new(),
            finished_reloads: Vec::new(),
            in_flight: VecDeque::new(),
            converter: rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .thread_name(|_| "loupe-convert".into())
                .build()
                .expect("the capture conversion thread"),
            dirty: true,
            subscriptions: BTreeMap::new(),
            swapped_since_frame: BTreeSet::new(),
            gpu_errors: Vec::new(),
            gpu_error_files: BTreeMap::new(),
            announced_passes: None,
            last_timings: Vec::new(),
            last_timing: timing.to_owned(),
            device_resets: 0,
            destroy_requested: false,
            last_frame: None,
            trace_next: None,
            trace_stale: false,
            nan_report: None,
        }
    }

    fn gpu(&self) -> &Gpu {
        self.session.gpu()
    }

    /// Runs until `Shutdown` or until every sender is gone.
    pub fn run(mut self, rx: Inbox) {
        self.install_lost_callback();
        let keys = self.session.wanted();
        self.start_reload(keys, Vec::new(), 0.0);
        self.publish_state();
        self.publish_controls();
        let interval = Duration::from_secs_f64(1.0 / self.config.max_fps.max(0.1));
        loop {
            // Frames on their way back are polled for; otherwise only an
            // event (or the next frame falling due) changes anything.
            let wait = if !self.in_flight.is_empty() {
                Duration::from_millis(2)
            } else if self.wants_frame() && self.can_render() {
                self.until_due(interval)
            } else {
                Duration::from_millis(250)
            };
            match rx.recv_timeout(wait) {
                Ok(Event::Shutdown) => break,
                Ok(ev) => self.handle(ev),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            self.session.poll();
            self.collect_frames();
            if self.wants_frame() && self.until_due(interval).is_zero() && self.can_render() {
                self.render();
            }
        }
    }

    fn wants_frame(&self) -> bool {
        self.config.mode == RenderMode::Continuous || self.dirty || !self.finished_reloads.is_empty() || self.session.converging()
    }

    /// How long until the next frame is due: at once when a reload is
    /// waiting to be shown (the frame-rate cap does not delay a swap).
    fn until_due(&self, interval: Duration) -> Duration {
        match self.last_frame {
            Some(at) if self.finished_reloads.is_empty() => interval.saturating_sub(at.elapsed()),
            _ => Duration::ZERO,
        }
    }

    /// Frames render while shaders compile, except when that would show a
    /// half-applied reload (some of its pipelines swapped, others not yet)
    /// or a pass whose first pipeline is still compiling.
    fn can_render(&self) -> bool {
        let half_applied = self.reloads.values().any(|r| {
            r.swapped_any || r.pending.iter().any(|k| self.session.pipelines().entries.get(k).is_none_or(|e| e.current.is_none()))
        });
        self.in_flight.len() < 2 && !half_applied && !self.destroy_requested
    }

    fn handle(&mut self, ev: Event) {
        match ev {
            Event::FilesChanged(batch) => self.files_changed(batch),
            Event::CompileFinished(r) => self.compile_finished(r),
            Event::Scene(cmd) => self.scene_command(cmd),
            Event::Rebuild => {
                let keys = self.session.wanted();
                self.start_reload(keys, Vec::new(), 0.0);
            }
            Event::Subscriptions { client, outputs } => {
                let before = self.subscriptions.remove(&client).unwrap_or_default();
                // A new output (or quad statistics) needs a frame that
                // captures it.
                self.dirty |= !outputs.is_subset(&before);
                if !outputs.is_empty() {
                    self.subscriptions.insert(client, outputs);
                }
                let quads = self.subscriptions.values().any(|s| s.contains(QUAD_STATISTICS));
                self.session.set_quads(quads);
                if !quads {
                    shared::write(&self.shared.quads, None);
                }
            }
            Event::Tick => self.dirty = true,
            Event::DeviceLost { device, reason, message } => self.device_lost(device, reason, message),
            Event::LoseDevice => {
                log::warn!("destroying the device on request (debug API)");
                self.destroy_requested = true;
                self.gpu().device.destroy();
                self.session.poll();
            }
            Event::Trace => {
                self.trace_next = Some("request");
                self.dirty = true;
            }
            Event::Shutdown => {}
        }
    }

    fn files_changed(&mut self, batch: FileBatch) {
        let watch_ms = batch.ready.duration_since(batch.first_event).as_secs_f64() * 1e3;
        let mut lib = (**self.session.library()).clone();
        let mut touched = BTreeSet::new();
        let mut scene_changed = false;
        for change in &batch.changes {
            let path = change.path();
            let display = library::display_path(path);
            if self.scene_files.iter().any(|f| same_file(path, f)) {
                scene_changed = true;
                touched.insert(display);
                continue;
            }
            if path.extension().is_none_or(|e| e != "wgsl") {
                continue;
            }
            touched.insert(display.clone());
            match change {
                FileChange::Removed { .. } => {
                    self.file_errors.remove(&display);
                    lib.remove(&display);
                }
                FileChange::Written { content, .. } => match SourceFile::from_bytes(path, display.clone(), content.to_vec()) {
                    Ok(f) => {
                        self.file_errors.remove(&display);
                        lib.upsert(f);
                    }
                    Err(d) => {
                        self.file_errors.insert(display.clone(), d);
                    }
                },
            }
        }
        self.session.apply_sources(lib);
        if scene_changed {
            self.reload_scene();
        }
        // Exactly the pipelines whose sources depend on a touched file, plus
        // any the (new) graph needs that were never built.
        let lib = self.session.library().clone();
        let affected: BTreeSet<String> = touched.iter().flat_map(|d| lib.dependents(d)).collect();
        let mut keys = self.session.built_from(&affected);
        keys.extend(self.session.missing());
        self.start_reload(keys, touched.into_iter().collect(), watch_ms);
    }

    fn reload_scene(&mut self) {
        match scene::load_with(&self.config.scene_path, &self.overrides) {
            Ok(l) => self.install_scene(l),
            // The last good scene keeps rendering.
            Err(d) => self.scene_error = Some(d),
        }
        self.dirty = true;
        self.publish_controls();
    }

    fn install_scene(&mut self, l: scene::Loaded) {
        self.trace_stale = true;
        self.session.set_scene(&l);
        self.scene_files = l.files;
        self.config.watch_files.set(&self.scene_files);
        self.scene_error = None;
    }

    /// Live overrides: a value that makes the scene invalid is refused with
    /// the scene's diagnostic and the previous overrides stay.
    fn scene_command(&mut self, cmd: SceneCommand) {
        let display = library::display_path(&self.config.scene_path);
        let overrides = match cmd {
            SceneCommand::Set { path, value } => {
                let mut o = self.overrides.clone();
                o.insert(path, value);
                o
            }
            SceneCommand::Clear => Overrides::new(),
            SceneCommand::Save => {
                let saved = std::fs::read_to_string(&self.config.scene_path)
                    .map_err(|e| e.to_string())
                    .and_then(|text| scene::overrides::apply(&text, &self.overrides))
                    .and_then(|text| write_atomically(&self.config.scene_path, &text).map_err(|e| e.to_string()));
                match saved {
                    // The file now holds the values: the watcher's reload
                    // of it renders the same scene.
                    Ok(()) => self.overrides.clear(),
                    Err(e) => self.shared.publish(ServerEvent::Error { message: format!("cannot save {display}: {e}") }),
                }
                self.publish_controls();
                return;
            }
        };
        match scene::load_with(&self.config.scene_path, &overrides) {
            Ok(l) => {
                self.overrides = overrides;
                self.install_scene(l);
                self.dirty = true;
                let keys = self.session.missing();
                self.start_reload(keys, vec![display], 0.0);
            }
            Err(d) => self.shared.publish(ServerEvent::Error { message: format!("override refused: {d}") }),
        }
        self.publish_controls();
    }

    fn publish_controls(&self) {
        let report = ControlsReport {
            scene: library::display_path(&self.config.scene_path),
            controls: scene::overrides::controls(self.session.scene()),
            overrides: self.overrides.clone(),
        };
        shared::write(&self.shared.controls, report.clone());
        self.shared.publish(ServerEvent::Controls(report));
    }

    fn start_reload(&mut self, keys: BTreeSet<PipelineKey>, files: Vec<String>, watch_ms: f64) {
        let id = self.next_reload;
        self.next_reload += 1;
        let pipelines: Vec<String> = keys.iter().map(PipelineKey::label).collect();
        self.shared.publish(ServerEvent::ReloadStarted { id, files: files.clone(), pipelines: pipelines.clone() });
        let reload = Reload {
            files,
            pipelines,
            pending: keys.clone(),
            diagnostics: Vec::new(),
            watch_ms,
            compose_ms: 0.0,
            pipeline_ms: 0.0,
            swapped_any: false,
        };
        self.reloads.insert(id, reload);
        let lib = self.session.library().clone();
        for key in keys {
            self.newest_compile.insert(key.clone(), id);
            let display = self.session.shader_display(key.spec);
            let tx = self.events.clone();
            // A file that failed to load fails every pipeline built from it,
            // even while its last good content is still in the library.
            let file_error = self
                .file_errors
                .values()
                .find(|d| {
                    d.file().is_some_and(|f| {
                        f == display
                            || lib.get(&display).is_some_and(|s| lib.dependencies(s).is_ok_and(|deps| deps.iter().any(|x| x.display == f)))
                    })
                })
                .cloned();
            let compose = self.session.compose_job(&key);
            self.workers.spawn(move || {
                let start = Instant::now();
                let result = match file_error {
                    Some(d) => Err(vec![d]),
                    None => compose(),
                };
                let compose_ms = start.elapsed().as_secs_f64() * 1e3;
                let _ = tx.send(Event::CompileFinished(CompileResult { reload: id, key, result, compose_ms }));
            });
        }
        self.maybe_finish_reload(id);
    }

    fn compile_finished(&mut self, r: CompileResult) {
        let key = r.key;
        // A compile that a newer one of the same pipeline supersedes (its
        // sources changed again meanwhile) is never installed, whichever
        // finishes first: it would put back what the user replaced.
        if self.newest_compile.get(&key).is_some_and(|&newest| newest > r.reload) {
            if let Some(reload) = self.reloads.get_mut(&r.reload) {
                reload.pending.remove(&key);
            }
            self.maybe_finish_reload(r.reload);
            return;
        }
        let start = Instant::now();
        // Creation under an error scope; wgpu errors keep the old pipeline.
        let installed = self.session.install(&key, r.result);
        let pipeline_ms = start.elapsed().as_secs_f64() * 1e3;
        if installed == Installed::Swapped {
            self.swapped_since_frame.insert(key.clone());
        }
        if let Some(reload) = self.reloads.get_mut(&r.reload) {
            reload.pending.remove(&key);
            reload.compose_ms = reload.compose_ms.max(r.compose_ms);
            reload.pipeline_ms += pipeline_ms;
            if installed == Installed::Swapped {
                reload.swapped_any = true;
            } else {
                reload.diagnostics.extend(self.session.pipelines().entries[&key].diagnostics.iter().cloned());
            }
        }
        self.maybe_finish_reload(r.reload);
    }

    fn maybe_finish_reload(&mut self, id: u64) {
        if !self.reloads.get(&id).is_some_and(|r| r.pending.is_empty()) {
            return;
        }
        let mut r = self.reloads.remove(&id).expect("checked");
        r.diagnostics.extend(self.file_errors.values().filter(|d| d.file().is_some_and(|f| r.files.iter().any(|x| x == f))).cloned());
        r.diagnostics.extend(self.scene_error.iter().cloned());
        if r.diagnostics.is_empty() {
            // Announced with the first frame that shows it (`publish_frame`).
            let timings = ReloadTimings { watch_ms: r.watch_ms, compose_ms: r.compose_ms, pipeline_ms: r.pipeline_ms, render_ms: 0.0 };
            self.finished_reloads.push(Succeeded { id, files: r.files, pipelines: r.pipelines, timings });
            self.trace_stale = true;
        } else {
            self.shared.publish(ServerEvent::ReloadFailed { id, files: r.files, pipelines: r.pipelines, diagnostics: r.diagnostics });
        }
        self.dirty = true;
        self.publish_state();
    }

    /// The one place a frame is submitted.
    fn render(&mut self) {
        let started = Instant::now();
        // Real time drives temporal passes, capped so a stall (a long
        // compile, a paused on-change session) does not jump them.
        let dt = self.last_frame.map_or(0.0, |t| t.elapsed().as_secs_f32().min(0.25));
        self.last_frame = Some(started);
        self.dirty = false;
        let final_key = self.session.graph().final_name();
        let mut capture: BTreeSet<String> = self.subscriptions.values().flatten().filter(|k| *k != QUAD_STATISTICS).cloned().collect();
        capture.extend(final_key.clone());
        capture.insert(nan_watch::OUTPUT.to_owned());
        // A traced frame captures every output.
        let trace = self.trace_next.take();
        let pending = self.session.submit(if trace.is_some() { None } else { Some(&capture) }, dt);
        // wgpu reports invalid frame commands on this thread, while the
        // frame is recorded and submitted: they belong to this frame.
        let errors = self.session.take_uncaptured();
        let clean = errors.is_empty();
        let swapped = std::mem::take(&mut self.swapped_since_frame);
        self.set_gpu_errors(&errors, &swapped);
        let reloads = std::mem::take(&mut self.finished_reloads);
        // The outputs of passes whose pipelines this frame is the first to
        // use: their previous images become the "last good" ones.
        let replaced = self
            .session
            .graph()
            .passes
            .iter()
            .filter(|p| p.pipelines.iter().any(|k| swapped.contains(k)))
            .flat_map(|p| p.writes().map(|h| self.session.graph().resource(h).name.clone()))
            .collect();
        self.in_flight.push_back(InFlight { results: Results::Gpu(pending), reloads, started, final_key, clean, replaced, trace });
    }

    /// Turns the uncaptured wgpu errors of the newest frame into
    /// diagnostics, located at the shader of the pass or pipeline involved
    /// when that can be known: a resource label naming one, or — for an
    /// error that first appeared in the frame right after some pipelines
    /// were swapped in — the file of the one pipeline swapped. Otherwise
    /// the diagnostic has no file.
    fn set_gpu_errors(&mut self, errors: &[String], swapped: &BTreeSet<PipelineKey>) {
        let mut diagnostics: Vec<Diagnostic> = Vec::new();
        let mut files_by_message = BTreeMap::new();
        for text in errors {
            let message = text.lines().map(str::trim).rfind(|l| !l.is_empty()).unwrap_or("wgpu error").to_owned();
            if files_by_message.contains_key(&message) {
                continue; // the same error, reported again at submit
            }
            let files = self
                .gpu_error_files
                .get(&message)
                .cloned()
                .or_else(|| self.files_named_in(text))
                .or_else(|| {
                    let files: BTreeSet<String> = swapped.iter().map(|k| self.session.shader_display(k.spec)).collect();
                    (self.gpu_errors.is_empty() && !files.is_empty()).then(|| files.into_iter().collect())
                })
                .unwrap_or_default();
            let mut d = Diagnostic::error(Code::Gpu, format!("the GPU rejected frame commands: {message}"))
                .with_note(format!("wgpu reported, with no error scope to catch it:\n{}", text.trim_end()))
                .with_note("the frame's images were not published: the previous image stays");
            match files.as_slice() {
                [one] => d = d.at(Location::file_start(one)),
                [] => {}
                many => d = d.with_note(format!("it began when these were swapped in: {}", many.join(", "))),
            }
            files_by_message.insert(message, files);
            diagnostics.push(d);
        }
        self.gpu_error_files = files_by_message;
        if diagnostics != self.gpu_errors {
            for d in &diagnostics {
                log::error!("frame {}: {d}", self.session.frame());
            }
            self.gpu_errors = diagnostics;
            self.publish_state();
        }
    }

    /// Shader files of the passes and pipelines an error's labels
    /// (`label = 'name'`) name, if any.
    fn files_named_in(&self, text: &str) -> Option<Vec<String>> {
        let mut files = BTreeSet::new();
        for label in text.split("label = '").skip(1).filter_map(|rest| rest.split('\'').next()) {
            let specs: Vec<&PipelineSpec> = match self.session.graph().passes.iter().find(|p| p.name == label) {
                Some(pass) => pass.pipelines.iter().map(|k| k.spec).collect(),
                None => passes::spec(label).into_iter().collect(),
            };
            files.extend(specs.into_iter().map(|s| self.session.shader_display(s)));
        }
        (!files.is_empty()).then(|| files.into_iter().collect())
    }

    /// Traces a frame when the NaN watch sees a NaN/Inf that no current
    /// report explains; publishes a traced frame's report; clears it once
    /// a frame is clean.
    fn follow_nan(&mut self, result: &FrameResult, trace: Option<&'static str>) {
        if let Some(trigger) = trace {
            let outputs = result
                .captures
                .iter()
                .filter(|c| c.stats.has_non_finite())
                .map(|c| NanCount { pass: c.pass.clone(), output: c.output.clone(), nan: c.stats.nan, inf: c.stats.inf })
                .chain(result.tensors.iter().filter(|t| t.stats.has_non_finite()).map(|t| NanCount {
                    pass: t.pass.clone(),
                    output: t.output.clone(),
                    nan: t.stats.nan,
                    inf: t.stats.inf,
                }))
                .collect();
            let report = NanReport { frame: result.frame, trigger: trigger.to_owned(), origin: result.nan.clone(), outputs };
            self.trace_stale = false;
            self.set_nan_report(Some(report));
            return;
        }
        let Some(counts) = result.tensors.iter().find(|t| t.key() == nan_watch::OUTPUT) else { return };
        let bad = counts.data.iter().any(|n| *n > 0.0);
        let explained = self.nan_report.as_ref().is_some_and(|r| r.origin.is_some()) && !self.trace_stale;
        if bad && !explained && self.trace_next.is_none() {
            self.trace_next = Some("auto");
            self.dirty = true;
        } else if !bad && self.nan_report.as_ref().is_some_and(|r| r.frame < result.frame) {
            self.set_nan_report(None);
        }
    }

    fn set_nan_report(&mut self, report: Option<NanReport>) {
        if report != self.nan_report {
            shared::write(&self.shared.nan, report.clone());
            self.shared.publish(ServerEvent::Nan { report: report.clone() });
            self.nan_report = report;
        }
    }

    /// Hands every landed frame to the conversion thread, and publishes
    /// converted frames in order.
    fn collect_frames(&mut self) {
        for f in &mut self.in_flight {
            if matches!(&f.results, Results::Gpu(p) if p.ready()) {
                let (tx, rx) = mpsc::sync_channel(1);
                let Results::Gpu(pending) = std::mem::replace(&mut f.results, Results::Converting(rx)) else {
                    unreachable!("matched above")
                };
                self.converter.spawn(move || {
                    let _ = tx.send(pending.finish());
                });
            }
        }
        while let Some(Results::Converting(rx)) = self.in_flight.front().map(|f| &f.results) {
            let result = match rx.try_recv() {
                Ok(result) => result,
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => {
                    log::error!("a frame's conversion was lost");
                    self.in_flight.pop_front();
                    continue;
                }
            };
            let done = self.in_flight.pop_front().expect("checked");
            self.publish_frame(done, result);
        }
    }

    fn publish_frame(&mut self, done: InFlight, result: FrameResult) {
        let InFlight { results: _, reloads, started, final_key, clean, replaced, trace } = done;
        if clean {
            self.follow_nan(&result, trace);
        }
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let total = result.total_ms;
        let mut images = None;
        if clean {
            let mut captures = (*shared::read(&self.shared.captures)).clone();
            if !replaced.is_empty() {
                // What a pass showed before its pipelines changed is what
                // A/B compares against; other passes keep theirs.
                let mut last_good = (*shared::read(&self.shared.last_good)).clone();
                last_good.extend(replaced.iter().filter_map(|k| captures.get(k).map(|c| (k.clone(), c.clone()))));
                shared::write(&self.shared.last_good, Arc::new(last_good));
            }
            let this_frame: BTreeMap<String, Arc<_>> = result.captures.into_iter().map(|c| (c.key(), Arc::new(c))).collect();
            captures.extend(this_frame.iter().map(|(k, c)| (k.clone(), c.clone())));
            shared::write(&self.shared.captures, Arc::new(captures));
            let mut tensors = (*shared::read(&self.shared.tensors)).clone();
            tensors.extend(result.tensors.into_iter().map(|t| (t.key(), Arc::new(t))));
            shared::write(&self.shared.tensors, Arc::new(tensors));
            images = Some(FrameImages::new(result.frame, final_key, this_frame));
        }
        if clean && !result.quads.is_empty() {
            self.publish_quads(result.frame, result.quads, &result.fragment_invocations);
        }
        self.last_timings = result.timings;
        self.last_timing = result.timing.to_owned();
        for r in &reloads {
            let timings = ReloadTimings { render_ms, ..r.timings };
            self.shared.publish(ServerEvent::ReloadSucceeded { id: r.id, files: r.files.clone(), pipelines: r.pipelines.clone(), timings });
        }
        self.publish_passes();
        let passes: Vec<PassTiming> = self.last_timings.iter().map(|(n, t)| PassTiming { name: n.clone(), time_ms: *t }).collect();
        let ids: Vec<u64> = reloads.iter().map(|r| r.id).collect();
        self.shared.publish(ServerEvent::Frame {
            frame: result.frame,
            passes,
            total_ms: total,
            timing: result.timing.to_owned(),
            reload: ids.last().copied(),
            reloads: ids,
        });
        let mut status = shared::read(&self.shared.status);
        status.frame = result.frame;
        shared::write(&self.shared.status, status);
        // Images last: encoding and sending them takes a client a while,
        // and the events say what they show.
        if let Some(images) = images {
            self.shared.frames.send_replace(Some(Arc::new(images)));
        }
    }

    /// A frame's quad statistics, beside the adapter's own counts.
    fn publish_quads(&mut self, frame: u64, quads: Vec<crate::render::quads::PassQuads>, invocations: &[(String, u64)]) {
        let passes = quads
            .into_iter()
            .map(|q| PassQuadReport { fragment_invocations: invocations.iter().find(|(p, _)| *p == q.pass).map(|(_, n)| *n), quads: q })
            .collect();
        let report = QuadReport { frame, adapter: self.gpu().adapter_name(), passes };
        shared::write(&self.shared.quads, Some(Arc::new(report.clone())));
        self.shared.publish(ServerEvent::Quads(report));
    }

    /// Writes the pass list snapshot (with the newest times) and announces
    /// it in a `passes` event only when something but the times changed.
    fn publish_passes(&mut self) {
        let passes: Vec<PassInfo> = self
            .session
            .passes()
            .into_iter()
            .map(|p| {
                let time_ms = (p.status != PassState::Culled)
                    .then(|| self.last_timings.iter().find(|(n, _)| *n == p.name).map(|(_, t)| *t))
                    .flatten();
                PassInfo::new(p, time_ms, &self.last_timing)
            })
            .collect();
        shared::write(&self.shared.passes, passes.clone());
        let shape: Vec<PassInfo> = passes.iter().map(PassInfo::shape).collect();
        if self.announced_passes.as_ref() != Some(&shape) {
            self.announced_passes = Some(shape);
            self.shared.publish(ServerEvent::Passes { passes });
        }
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut all = self.session.pipeline_diagnostics();
        for d in self.file_errors.values().chain(self.scene_error.iter()).chain(self.gpu_errors.iter()) {
            if !all.iter().any(|x| x.to_string() == d.to_string()) {
                all.push(d.clone());
            }
        }
        all
    }

    fn publish_state(&mut self) {
        let diagnostics = self.diagnostics();
        let infos: Vec<protocol::PipelineInfo> = self.session.pipeline_summaries().into_iter().map(Into::into).collect();
        let count = |s: PassStatus| infos.iter().filter(|i| i.status == s).count();
        let gpu = self.gpu();
        let status = Status {
            protocol: protocol::VERSION,
            version: env!("CARGO_PKG_VERSION").to_owned(),
            adapter: gpu.adapter_name(),
            cpu_adapter: gpu.is_cpu(),
            features: gpu.feature_names(),
            degraded: gpu.degraded.clone(),
            scene: library::display_path(&self.config.scene_path),
            frame: shared::read(&self.shared.status).frame,
            pipelines_ok: count(PassStatus::Ok),
            pipelines_stale: count(PassStatus::Stale),
            pipelines_failed: count(PassStatus::Failed),
            device_resets: self.device_resets,
            errors: diagnostics.iter().filter(|d| d.severity == Severity::Error).count(),
            warnings: diagnostics.iter().filter(|d| d.severity == Severity::Warning).count(),
            render_mode: match self.config.mode {
                RenderMode::Continuous => "continuous".into(),
                RenderMode::OnChange => "on-change".into(),
            },
        };
        shared::write(&self.shared.status, status);
        shared::write(&self.shared.pipelines, infos);
        shared::write(&self.shared.diagnostics, diagnostics.clone());
        self.shared.publish(ServerEvent::Diagnostics { diagnostics });
        self.publish_passes();
    }

    fn install_lost_callback(&self) {
        let tx = self.events.clone();
        let device = self.device_resets;
        self.gpu().device.set_device_lost_callback(move |reason, message| {
            let _ = tx.send(Event::DeviceLost { device, reason, message });
        });
    }

    fn device_lost(&mut self, device: u32, reason: wgpu::DeviceLostReason, message: String) {
        if device != self.device_resets {
            return; // about a device already replaced
        }
        let requested = std::mem::take(&mut self.destroy_requested);
        if reason == wgpu::DeviceLostReason::Destroyed && message.is_empty() && !requested {
            return; // destroyed by loupe itself, not lost
        }
        let reason = if requested && message.is_empty() {
            "device destroyed on request (POST /api/debug/lose-device)".to_owned()
        } else {
            format!("{reason:?}: {message}")
        };
        self.recover_device(reason);
    }

    /// A lost device is replaced and every pipeline rebuilt from its last
    /// good module; the process keeps running.
    fn recover_device(&mut self, reason: String) {
        log::warn!("device lost: {reason}");
        match gpu::open() {
            Ok(g) => {
                let problems = self.session.replace_device(g);
                self.device_resets += 1;
                // Frames of the old device never come back; the reloads
                // they were to announce go with the next frame instead.
                let lost: Vec<Succeeded> = self.in_flight.drain(..).flat_map(|f| f.reloads).collect();
                self.finished_reloads.splice(0..0, lost);
                self.swapped_since_frame.clear();
                self.gpu_errors.clear();
                self.gpu_error_files.clear();
                self.install_lost_callback();
                // The snapshots first: a client reading `/api/status` on the
                // event sees the new device.
                self.dirty = true;
                self.publish_state();
                self.shared.publish(ServerEvent::DeviceLost { message: reason, recovered: problems.is_empty() });
            }
            Err(e) => {
                self.shared.publish(ServerEvent::DeviceLost { message: format!("{reason}; reopening failed: {e}"), recovered: false })
            }
        }
    }
}

fn same_file(a: &Path, b: &Path) -> bool {
    let c = |p: &Path| p.canonicalize().unwrap_or_else(|_| std::path::absolute(p).unwrap_or_else(|_| p.to_owned()));
    c(a) == c(b)
}

/// Writes like an editor that saves safely: a temporary file beside the
/// target, renamed over it, so a reader never sees half a file.
fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let tmp = path.with_extension("toml.loupe-save~");
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}
