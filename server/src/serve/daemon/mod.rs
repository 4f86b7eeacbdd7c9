//! The daemon's render thread: the one place that owns the device. It takes
//! events one at a time — file changes, compile results, client messages,
//! frame ticks — and publishes snapshots and events for clients.
//!
//! Composition runs on worker threads (it never blocks rendering); only
//! pipeline creation, which needs the device, runs here.
//!
//! Here: the loop, file and scene changes, starting reloads and installing
//! their pipelines, submitting and collecting frames. `reload` is the
//! reload state machine (which compile installs, when a reload is done and
//! which frame shows it); `publish` writes snapshots and sends events;
//! `device` handles a lost device; `gpu_errors` locates a frame's
//! uncaptured wgpu errors; `nan` decides when to trace a NaN/Inf;
//! `timing` decides which pass times are shown, and by which clock.

mod device;
mod gpu_errors;
mod nan;
mod publish;
mod reload;
mod timing;

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use super::display::Source;
use super::event::{CompileResult, Event, FileBatch, FileChange, SceneCommand};
use super::inbox::Inbox;
use super::reference_jobs;
use super::shared::{self, Shared};
use crate::diag::{Diagnostic, display_path};
use crate::gpu::Gpu;
use crate::protocol::{NanReport, PassInfo, QUAD_STATISTICS, REFERENCES, ServerEvent};
use crate::render::FrameOptions;
use crate::render::frame::{FrameResult, PendingFrame};
use crate::render::passes::{classify, nan_watch};
use crate::render::pipelines::Installed;
use crate::render::resource::PipelineKey;
use crate::render::session::Session;
use crate::scene::{self, overrides::Overrides};
use crate::shader::{Library, SourceFile, library};
use reload::{ForFrame, Reloads, Succeeded, Verdict};

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
    /// `loupe view`'s window, which each clean frame is copied for.
    pub display: Option<Arc<super::display::Display>>,
}

/// Where a submitted frame's results stand.
enum Results {
    /// Rendering, or being copied back.
    Gpu(Box<PendingFrame>),
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
    /// Samples per pixel the path tracer holds after this frame, when the
    /// graph path traces.
    samples: Option<u32>,
}

pub struct Daemon {
    /// The device, sources, scene, graph, pipelines and resources.
    session: Session,
    config: Config,
    /// Files that failed to load, by display path: their last good content
    /// stays in the session's library meanwhile.
    file_errors: BTreeMap<String, Diagnostic>,
    /// Each source file's last good text, for the diff of a broken one.
    last_good: crate::serve::last_good::LastGood,
    /// The scene file and the meshes it references: a change to any
    /// reloads the scene.
    scene_files: Vec<PathBuf>,
    scene_error: Option<Diagnostic>,
    /// What the installed scene loaded with but could not represent (glTF
    /// materials), shown beside the errors.
    scene_warnings: Vec<Diagnostic>,
    /// Live values from the browser on top of the scene file.
    overrides: Overrides,
    shared: Arc<Shared>,
    events: Sender<Event>,
    workers: Arc<rayon::ThreadPool>,
    reloads: Reloads,
    in_flight: VecDeque<InFlight>,
    /// The one thread captures are converted on, so results come back in
    /// frame order and never more than the frames in flight.
    converter: rayon::ThreadPool,
    dirty: bool,
    /// What each WebSocket client wants captured, by client id.
    subscriptions: BTreeMap<u64, BTreeSet<String>>,
    /// Uncaptured wgpu errors of the newest frame, as diagnostics.
    gpu_errors: Vec<Diagnostic>,
    /// Where each uncaptured error (by message) was first attributed, so a
    /// persisting error keeps its file.
    gpu_error_files: BTreeMap<String, Vec<String>>,
    /// The pass list last announced in a `passes` event, without times.
    announced_passes: Option<Vec<PassInfo>>,
    /// The newest frame's pass times, as shown.
    last_times: timing::FrameTimes,
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
    /// The scene as installed, for material previews and for what its
    /// reloads keep.
    loaded: Arc<crate::loaded::Loaded>,
    /// The scene's files changed since `loaded` was read: what a reload
    /// must read again (kept across failed reloads).
    stale_inputs: BTreeSet<PathBuf>,
    previews: super::preview::Previews,
}

impl Daemon {
    pub fn new(gpu: Gpu, config: Config, shared: Arc<Shared>, events: Sender<Event>) -> Self {
        let (lib, unnamed) = library::load_tree(&config.shader_root).unwrap_or_else(|_| (Library::new([]), Vec::new()));
        let (loaded, scene_error) = match crate::loaded::load(&config.scene_path) {
            Ok(l) => (l, None),
            Err(d) => {
                let empty = scene::parse("", "").expect("the empty scene is valid");
                (
                    crate::loaded::Loaded {
                        scene: empty,
                        meshes: Default::default(),
                        materials: Default::default(),
                        reports: Default::default(),
                        denoiser: None,
                        files: vec![config.scene_path.clone()],
                        warnings: Vec::new(),
                    },
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
        let wall_clock = timing::wall_clock_needed(gpu.is_cpu(), gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY));
        config.watch_files.set(&loaded.files);
        shared::write(&shared.materials, publish::materials_report(&config.scene_path, &loaded));
        let mut session =
            Session::new(gpu, &config.shader_root, lib, &loaded).with_options(FrameOptions { nan_watch: true, ..FrameOptions::default() });
        session.set_serial(wall_clock);
        let previews = super::preview::Previews::start(&config.shader_root);
        let mut daemon = Daemon {
            loaded: Arc::new(loaded.clone()),
            stale_inputs: BTreeSet::new(),
            previews,
            session,
            config,
            // Files whose names are not UTF-8 are left out, each with its warning.
            last_good: Default::default(),
            file_errors: unnamed.into_iter().filter_map(|d| Some((d.file()?.to_owned(), d))).collect(),
            scene_warnings: loaded.warnings,
            scene_files: loaded.files,
            scene_error,
            overrides: Overrides::new(),
            shared,
            events,
            workers: Arc::new(workers),
            reloads: Reloads::default(),
            in_flight: VecDeque::new(),
            converter: rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .thread_name(|_| "loupe-convert".into())
                .build()
                .expect("the capture conversion thread"),
            dirty: true,
            subscriptions: BTreeMap::new(),
            gpu_errors: Vec::new(),
            gpu_error_files: BTreeMap::new(),
            announced_passes: None,
            last_times: timing::FrameTimes::default(),
            device_resets: 0,
            destroy_requested: false,
            last_frame: None,
            trace_next: None,
            trace_stale: false,
            nan_report: None,
        };
        // Before the server listens (it waits for `new`): a client's first
        // `/api/tradeoffs` is judged against this scene, not an empty one,
        // and its first status (`loupe view`'s window reads it at once)
        // names the scene and the adapter.
        daemon.publish_measured();
        daemon.publish_state();
        daemon
    }

    fn gpu(&self) -> &Gpu {
        self.session.gpu()
    }

    /// Whether any client asks for quad statistics.
    fn wants_quads(&self) -> bool {
        self.subscriptions.values().any(|s| s.contains(QUAD_STATISTICS))
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
        self.shared.reference_jobs.stop();
    }

    /// Asks the comparison thread to compare the scene's image cases with
    /// their references using the sources now, while a client wants it.
    fn compare_references(&self) {
        if self.subscriptions.values().any(|s| s.contains(REFERENCES)) {
            let gpu = self.session.gpu().clone();
            self.shared.reference_jobs.submit(reference_jobs::Job { gpu, lib: self.session.library().clone() });
        }
    }

    fn wants_frame(&self) -> bool {
        let continuous = self.config.mode == RenderMode::Continuous && !self.unseen();
        continuous || self.dirty || self.reloads.waiting() || self.session.converging()
    }

    /// Nobody would see a frame: `loupe view`'s window is minimised and no
    /// browser is connected. Frames then render only for changes.
    fn unseen(&self) -> bool {
        self.config.display.as_ref().is_some_and(|d| d.minimised()) && self.shared.clients.connected() == 0
    }

    /// How long until the next frame is due: at once when a reload is
    /// waiting to be shown (the frame-rate cap does not delay a swap).
    fn until_due(&self, interval: Duration) -> Duration {
        match self.last_frame {
            Some(at) if !self.reloads.waiting() => interval.saturating_sub(at.elapsed()),
            _ => Duration::ZERO,
        }
    }

    /// Frames render while shaders compile, except when that would show a
    /// half-applied reload (some of its pipelines swapped, others not yet)
    /// or a pass whose first pipeline is still compiling.
    fn can_render(&self) -> bool {
        let entries = &self.session.pipelines().entries;
        let half_applied = self.reloads.half_applied(|k| entries.get(k).is_some_and(|e| e.current.is_some()));
        self.in_flight.len() < 2 && !half_applied && !self.destroy_requested
    }

    fn handle(&mut self, ev: Event) {
        match ev {
            Event::FilesChanged(batch) => self.files_changed(batch),
            Event::CompileFinished(r) => self.compile_finished(*r),
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
                // A client starting to want the comparison gets one now.
                let wanted = |s: &BTreeSet<String>| s.contains(REFERENCES);
                if self.subscriptions.get(&client).is_some_and(wanted) && !wanted(&before) {
                    self.compare_references();
                }
                let quads = self.wants_quads();
                self.session.set_quads(quads);
                if !quads {
                    shared::write(&self.shared.quads, None);
                }
            }
            Event::Tick => self.dirty = true,
            Event::ResetHistory => {
                self.session.reset_history();
                self.dirty = true;
            }
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
            Event::DebugPixel(pixel) => self.debug_pixel(pixel),
            Event::Preview(request) => {
                let current = super::preview::Current {
                    gpu: self.gpu().clone(),
                    device: self.device_resets,
                    lib: self.session.library().clone(),
                    loaded: self.loaded.clone(),
                };
                self.previews.submit(request, current);
            }
            Event::Shutdown => {}
        }
    }

    /// Selects the pixel whose prints frames report, or clears it; a pixel
    /// outside the frame is refused with an `error` event.
    fn debug_pixel(&mut self, pixel: Option<[u32; 2]>) {
        let (width, height) = (self.session.scene().width, self.session.scene().height);
        if let Some([x, y]) = pixel
            && (x >= width || y >= height)
        {
            let message = format!("`debug_pixel` refused: ({x}, {y}) is outside the {width}x{height} frame");
            self.shared.publish(ServerEvent::Error { message });
            return;
        }
        self.session.set_debug_pixel(pixel);
        self.dirty = true;
    }

    fn files_changed(&mut self, batch: FileBatch) {
        let watch_ms = batch.ready.duration_since(batch.first_event).as_secs_f64() * 1e3;
        let mut lib = (**self.session.library()).clone();
        let mut touched = BTreeSet::new();
        let mut scene_changed = false;
        for change in &batch.changes {
            let path = change.path();
            let display = display_path(path);
            if self.scene_files.iter().any(|f| same_file(path, f)) {
                scene_changed = true;
                self.stale_inputs.insert(path.to_owned());
                touched.insert(display);
                continue;
            }
            if path.extension().is_none_or(|e| e != "wgsl") {
                continue;
            }
            touched.insert(display.clone());
            if path.to_str().is_none() {
                // Left out as at start-up, with its warning until it goes.
                match change {
                    FileChange::Removed { .. } => self.file_errors.remove(&display),
                    FileChange::Written { .. } => self.file_errors.insert(display.clone(), library::name_not_utf8(path)),
                };
                continue;
            }
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
            // A material edit changes the generated material module: the
            // pipelines built from it rebuild like those of an edited shader.
            touched.extend(self.reload_scene());
        }
        self.publish_measured();
        // Exactly the pipelines whose sources depend on a touched file, plus
        // any the (new) graph needs that were never built.
        let mut keys = self.session.built_from(&touched);
        keys.extend(self.session.missing());
        self.start_reload(keys, touched.into_iter().collect(), watch_ms);
    }

    /// Reloads the scene; returns the library files its reload changed.
    fn reload_scene(&mut self) -> BTreeSet<String> {
        let changed = match self.load_scene(&self.overrides) {
            Ok(l) => self.install_scene(l),
            // The last good scene keeps rendering.
            Err(d) => {
                self.scene_error = Some(d);
                BTreeSet::new()
            }
        };
        self.dirty = true;
        self.publish_controls();
        changed
    }

    /// Reads the scene with `overrides`, keeping the installed scene's
    /// meshes, textures and network whose files have not changed since.
    fn load_scene(&self, overrides: &Overrides) -> Result<crate::loaded::Loaded, Diagnostic> {
        let stale = |p: &Path| self.stale_inputs.iter().any(|c| same_file(c, p));
        let keep = crate::loaded::Keep { previous: &self.loaded, changed: &stale };
        crate::loaded::load_keeping(&self.config.scene_path, overrides, Some(&keep))
    }

    /// Swaps the scene in; returns the library files it changed (the
    /// generated material module).
    fn install_scene(&mut self, l: crate::loaded::Loaded) -> BTreeSet<String> {
        self.trace_stale = true;
        self.publish_materials(&l);
        let changed = self.session.set_scene(&l);
        self.loaded = Arc::new(l.clone());
        self.stale_inputs.clear();
        self.scene_files = l.files;
        self.scene_warnings = l.warnings;
        self.config.watch_files.set(&self.scene_files);
        self.scene_error = None;
        changed
    }

    /// Live overrides: a value that makes the scene invalid is refused with
    /// the scene's diagnostic and the previous overrides stay.
    fn scene_command(&mut self, cmd: SceneCommand) {
        let display = display_path(&self.config.scene_path);
        let overrides = match cmd {
            SceneCommand::Set { path, value } => {
                let mut o = self.overrides.clone();
                o.insert(path, value);
                self.without_file_values(o)
            }
            SceneCommand::Clear => Overrides::new(),
            SceneCommand::Save => {
                let saved = std::fs::read_to_string(&self.config.scene_path)
                    .map_err(|e| e.to_string())
                    .and_then(|text| scene::overrides::apply(&text, &self.overrides))
                    .and_then(|text| write_atomically(&self.config.scene_path, &text).map_err(|e| e.to_string()));
                // The file now holds the values: the watcher's reload of it
                // renders the same scene.
                if saved.is_ok() {
                    self.overrides.clear();
                }
                self.shared.publish(ServerEvent::SceneSaved { file: display, error: saved.err() });
                self.publish_controls();
                return;
            }
        };
        match self.load_scene(&overrides) {
            Ok(l) => {
                self.overrides = overrides;
                let changed = self.install_scene(l);
                self.dirty = true;
                let mut keys = self.session.built_from(&changed);
                keys.extend(self.session.missing());
                self.start_reload(keys, vec![display], 0.0);
            }
            Err(d) => self.shared.publish(ServerEvent::Error { message: format!("override refused: {d}") }),
        }
        self.publish_controls();
    }

    /// `overrides` less those equal to the scene file's own value (the
    /// file as it is on disk; unreadable or invalid, all are kept).
    fn without_file_values(&self, overrides: Overrides) -> Overrides {
        let display = display_path(&self.config.scene_path);
        let file = std::fs::read_to_string(&self.config.scene_path).ok().and_then(|text| scene::parse(&display, &text).ok());
        match file {
            Some(scene) => {
                scene::overrides::without_file_values(overrides, &scene::overrides::controls(&scene, crate::render::passes::affected))
            }
            None => overrides,
        }
    }

    fn start_reload(&mut self, keys: BTreeSet<PipelineKey>, files: Vec<String>, watch_ms: f64) {
        let id = self.reloads.start(&keys, files, watch_ms);
        if let Some((files, pipelines)) = self.reloads.describe(id) {
            self.shared.publish(ServerEvent::ReloadStarted { id, files: files.to_vec(), pipelines: pipelines.to_vec() });
        }
        let lib = self.session.library().clone();
        for key in keys {
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
                let _ = tx.send(Event::CompileFinished(Box::new(CompileResult { reload: id, key, result, compose_ms })));
            });
        }
        self.finish_reload(id);
    }

    fn compile_finished(&mut self, r: CompileResult) {
        if self.reloads.compiled(r.reload, &r.key) == Verdict::Install {
            let start = Instant::now();
            // Creation under an error scope; wgpu errors keep the old pipeline.
            let installed = self.session.install(&r.key, r.result);
            let pipeline_ms = start.elapsed().as_secs_f64() * 1e3;
            let diagnostics = match installed {
                Installed::Swapped => Vec::new(),
                _ => self.session.pipelines().entries[&r.key].diagnostics.clone(),
            };
            self.reloads.installed(r.reload, &r.key, installed, r.compose_ms, pipeline_ms, diagnostics);
        }
        self.finish_reload(r.reload);
    }

    /// Publishes reload `id`'s failure once it waits for nothing; a success
    /// waits for the first frame that shows it (`publish_frame`).
    fn finish_reload(&mut self, id: u64) {
        let file_errors = &self.file_errors;
        let scene_error = &self.scene_error;
        let finished = self.reloads.finish(id, |files| {
            let named = file_errors.values().filter(|d| d.file().is_some_and(|f| files.iter().any(|x| x == f)));
            named.chain(scene_error.iter()).cloned().collect()
        });
        match finished {
            None => return,
            Some(Ok(())) => self.trace_stale = true,
            Some(Err(f)) => self.shared.publish(ServerEvent::ReloadFailed {
                id: f.id,
                files: f.files,
                pipelines: f.pipelines,
                diagnostics: f.diagnostics,
            }),
        }
        self.dirty = true;
        self.publish_state();
        self.compare_references();
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
        let mut capture: BTreeSet<String> =
            self.subscriptions.values().flatten().filter(|k| *k != QUAD_STATISTICS && *k != REFERENCES).cloned().collect();
        capture.extend(final_key.clone());
        capture.insert(nan_watch::OUTPUT.to_owned());
        // The frame event's tile statistics.
        capture.extend([classify::STATS, classify::BYTES].map(str::to_owned));
        // A traced frame captures every output.
        let trace = self.trace_next.take();
        let pending = self.session.submit(if trace.is_some() { None } else { Some(&capture) }, dt);
        // wgpu reports invalid frame commands on this thread, while the
        // frame is recorded and submitted: they belong to this frame.
        let mut errors = self.session.take_uncaptured();
        if let (true, Some(display)) = (errors.is_empty(), &self.config.display) {
            let (session, gpu) = (&self.session, self.session.gpu());
            display.after_frame(gpu, session.frame(), session.final_texture(), |name| {
                session.output_texture(name).map(|(texture, meaning)| Source::new(texture, meaning))
            });
            // The display work's own errors, if any, are this frame's too.
            errors = self.session.take_uncaptured();
        }
        let clean = errors.is_empty();
        let ForFrame { reloads, swapped } = self.reloads.for_frame();
        self.set_gpu_errors(&errors, &swapped);
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
        self.in_flight.push_back(InFlight {
            results: Results::Gpu(Box::new(pending)),
            reloads,
            started,
            final_key,
            clean,
            replaced,
            trace,
            samples: self.session.path_samples(),
        });
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
