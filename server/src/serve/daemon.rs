//! The daemon's render thread: the one place that owns the device. It takes
//! events one at a time — file changes, compile results, client messages,
//! frame ticks — and publishes snapshots and events for clients.
//!
//! Composition runs on worker threads (it never blocks rendering); only
//! pipeline creation, which needs the device, runs here.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use super::event::{CompileResult, Event, FileBatch, FileChange};
use super::shared::{self, FramePng, Shared};
use crate::diag::{Diagnostic, Severity};
use crate::gpu::{self, Gpu, pipeline};
use crate::protocol::{self, ClientMessage, PassInfo, PassStatus, PassTiming, ReloadTimings, ServerEvent, Status};
use crate::render::{self, frame, graph::PipelineKey, pipelines::{Installed, PipelineCache}, scene_gpu::SceneGpu};
use crate::scene::{self, Scene};
use crate::shader::{Compose, Library, NagaOil, SourceFile, library};

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
}

struct Reload {
    files: Vec<String>,
    pipelines: Vec<String>,
    pending: BTreeSet<PipelineKey>,
    diagnostics: Vec<Diagnostic>,
    first_event: Instant,
    watch_ms: f64,
    compose_ms: f64,
    pipeline_ms: f64,
}

pub struct Daemon {
    gpu: Gpu,
    config: Config,
    lib: Arc<Library>,
    /// Files that failed to load, by display path: their last good content
    /// stays in `lib` meanwhile.
    file_errors: BTreeMap<String, Diagnostic>,
    scene: Scene,
    /// The scene file and the meshes it references: a change to any
    /// reloads the scene.
    scene_files: Vec<PathBuf>,
    scene_gpu: SceneGpu,
    /// Kept to rebuild `scene_gpu` on a new device.
    meshes: BTreeMap<String, Arc<crate::mesh::MeshData>>,
    scene_error: Option<Diagnostic>,
    cache: PipelineCache,
    pool: frame::TexturePool,
    frame: u64,
    shared: Arc<Shared>,
    events: Sender<Event>,
    workers: Arc<rayon::ThreadPool>,
    next_reload: u64,
    reloads: BTreeMap<u64, Reload>,
    /// Reloads finished since the last frame, to tag that frame with.
    finished_reloads: Vec<(u64, ReloadTimings)>,
    in_flight: VecDeque<(frame::PendingFrame, Vec<(u64, ReloadTimings)>)>,
    dirty: bool,
    subscriptions: BTreeSet<String>,
    device_resets: u32,
    last_frame: Instant,
}

impl Daemon {
    pub fn new(gpu: Gpu, config: Config, shared: Arc<Shared>, events: Sender<Event>) -> Self {
        let files: Vec<SourceFile> = library::discover(std::slice::from_ref(&config.shader_root))
            .unwrap_or_default()
            .iter()
            .filter_map(|p| SourceFile::read(p, library::display_path(p)).ok())
            .collect();
        let (loaded, scene_error) = match scene::load(&config.scene_path) {
            Ok(l) => (l, None),
            Err(d) => {
                let empty = scene::parse("", "").expect("the empty scene is valid");
                (scene::Loaded { scene: empty, meshes: Default::default(), files: vec![config.scene_path.clone()] }, Some(d))
            }
        };
        let scene_gpu = SceneGpu::new(&gpu.device, &gpu.queue, &loaded.scene, &loaded.meshes);
        let workers = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .stack_size(256 << 20)
            .thread_name(|i| format!("loupe-compile-{i}"))
            .build()
            .expect("compile worker threads");
        Daemon {
            gpu,
            config,
            lib: Arc::new(Library::new(files)),
            file_errors: BTreeMap::new(),
            scene: loaded.scene,
            scene_files: loaded.files,
            meshes: loaded.meshes,
            scene_gpu,
            scene_error,
            cache: PipelineCache::default(),
            pool: Default::default(),
            frame: 0,
            shared,
            events,
            workers: Arc::new(workers),
            next_reload: 1,
            reloads: BTreeMap::new(),
            finished_reloads: Vec::new(),
            in_flight: VecDeque::new(),
            dirty: true,
            subscriptions: BTreeSet::new(),
            device_resets: 0,
            last_frame: Instant::now(),
        }
    }

    /// Runs until `Shutdown` or until every sender is gone.
    pub fn run(mut self, rx: Receiver<Event>) {
        self.install_lost_callback();
        let keys = self.graph_pipelines();
        self.start_reload(keys, Vec::new(), Instant::now(), 0.0);
        self.publish_state();
        let interval = Duration::from_secs_f64(1.0 / self.config.max_fps.max(0.1));
        loop {
            let wait = if !self.in_flight.is_empty() {
                Duration::from_millis(2)
            } else if self.config.mode == RenderMode::Continuous || self.dirty {
                interval.saturating_sub(self.last_frame.elapsed())
            } else {
                Duration::from_millis(250)
            };
            match rx.recv_timeout(wait) {
                Ok(Event::Shutdown) => break,
                Ok(ev) => self.handle(ev),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            let _ = self.gpu.device.poll(wgpu::PollType::Poll);
            self.collect_frames();
            let due = self.last_frame.elapsed() >= interval;
            let wanted = self.config.mode == RenderMode::Continuous || self.dirty;
            if due && wanted && self.in_flight.len() < 2 && self.reloads.is_empty() {
                self.render();
            }
        }
    }

    fn handle(&mut self, ev: Event) {
        match ev {
            Event::FilesChanged(batch) => self.files_changed(batch),
            Event::CompileFinished(r) => self.compile_finished(r),
            Event::Client(msg) => self.client(msg),
            Event::Tick => self.dirty = true,
            Event::DeviceLost(reason) => self.recover_device(reason),
            Event::Shutdown => {}
        }
    }

    fn client(&mut self, msg: ClientMessage) {
        match msg {
            ClientMessage::Subscribe { pass, output } => {
                self.subscriptions.insert(format!("{pass}/{output}"));
                self.dirty = true;
            }
            ClientMessage::Rebuild {} => {
                let keys = self.cache.entries.keys().cloned().chain(self.graph_pipelines()).collect();
                self.start_reload(keys, Vec::new(), Instant::now(), 0.0);
            }
        }
    }

    fn shader_display(&self, spec: &pipeline::PipelineSpec) -> String {
        library::display_path(&self.config.shader_root.join(spec.shader))
    }

    fn graph_pipelines(&self) -> BTreeSet<PipelineKey> {
        render::build_graph(&self.scene, self.frame).pipelines()
    }

    fn files_changed(&mut self, batch: FileBatch) {
        let watch_ms = batch.ready.duration_since(batch.first_event).as_secs_f64() * 1e3;
        let mut lib = (*self.lib).clone();
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
                FileChange::Written { content, .. } => {
                    match SourceFile::from_bytes(path, display.clone(), content.to_vec()) {
                        Ok(f) => {
                            self.file_errors.remove(&display);
                            lib.upsert(f);
                        }
                        Err(d) => {
                            self.file_errors.insert(display.clone(), d);
                        }
                    }
                }
            }
        }
        self.lib = Arc::new(lib);
        if scene_changed {
            self.reload_scene();
        }
        // Exactly the pipelines whose sources depend on a touched file, plus
        // any the (new) graph needs that were never built.
        let affected: BTreeSet<String> = touched.iter().flat_map(|d| self.lib.dependents(d)).collect();
        let mut keys: BTreeSet<PipelineKey> = self
            .cache
            .entries
            .iter()
            .filter(|(k, e)| {
                let own = pipeline::spec(k.spec).map(|s| self.shader_display(s));
                e.files.iter().any(|f| affected.contains(f)) || own.is_some_and(|o| affected.contains(&o))
            })
            .map(|(k, _)| k.clone())
            .collect();
        keys.extend(self.graph_pipelines().into_iter().filter(|k| !self.cache.entries.contains_key(k)));
        self.start_reload(keys, touched.into_iter().collect(), batch.first_event, watch_ms);
    }

    fn reload_scene(&mut self) {
        match scene::load(&self.config.scene_path) {
            Ok(l) => {
                self.scene_gpu = SceneGpu::new(&self.gpu.device, &self.gpu.queue, &l.scene, &l.meshes);
                self.scene = l.scene;
                self.scene_files = l.files;
                self.meshes = l.meshes;
                self.scene_error = None;
            }
            // The last good scene keeps rendering.
            Err(d) => self.scene_error = Some(d),
        }
        self.dirty = true;
    }

    fn start_reload(&mut self, keys: BTreeSet<PipelineKey>, files: Vec<String>, first_event: Instant, watch_ms: f64) {
        let id = self.next_reload;
        self.next_reload += 1;
        let pipelines: Vec<String> = keys.iter().map(PipelineKey::label).collect();
        self.shared.publish(ServerEvent::ReloadStarted { id, files: files.clone(), pipelines: pipelines.clone() });
        let reload = Reload {
            files,
            pipelines,
            pending: keys.clone(),
            diagnostics: Vec::new(),
            first_event,
            watch_ms,
            compose_ms: 0.0,
            pipeline_ms: 0.0,
        };
        self.reloads.insert(id, reload);
        for key in keys {
            let spec = pipeline::spec(key.spec).expect("keys come from specs");
            let display = self.shader_display(spec);
            let lib = self.lib.clone();
            let tx = self.events.clone();
            let file_error = self.file_errors.values().find(|d| {
                d.file().is_some_and(|f| f == display || lib.get(&display).is_some_and(|s| lib.dependencies(s).is_ok_and(|deps| deps.iter().any(|x| x.display == f))))
            }).cloned();
            self.workers.spawn(move || {
                let start = Instant::now();
                let result = match (file_error, lib.get(&display)) {
                    (Some(d), _) => Err(vec![d]),
                    (None, Some(file)) => {
                        let caps = gpu::capabilities_without_device();
                        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| NagaOil.compose(&lib, file, &key.defs, caps)))
                            .unwrap_or_else(|_| Err(vec![Diagnostic::error(crate::diag::Code::CompilerPanic, "the WGSL compiler crashed on this file").at(crate::diag::Location::file_start(&display))]))
                    }
                    (None, None) => Err(vec![Diagnostic::error(crate::diag::Code::Io, format!("pipeline `{}` needs `{display}`, which does not exist", key.spec))]),
                };
                let compose_ms = start.elapsed().as_secs_f64() * 1e3;
                let _ = tx.send(Event::CompileFinished(CompileResult { reload: id, pipeline: key.spec.to_owned(), defs: key.defs, result, compose_ms }));
            });
        }
        self.maybe_finish_reload(id);
    }

    fn compile_finished(&mut self, r: CompileResult) {
        let key = PipelineKey { spec: pipeline::spec(&r.pipeline).expect("sent from a spec").name, defs: r.defs };
        let display = self.shader_display(pipeline::spec(key.spec).expect("spec"));
        let start = Instant::now();
        // Creation under an error scope; wgpu errors keep the old pipeline.
        let installed = self.cache.install(&self.gpu.device, &key, r.result, &self.lib, &display);
        let pipeline_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(reload) = self.reloads.get_mut(&r.reload) {
            reload.pending.remove(&key);
            reload.compose_ms = reload.compose_ms.max(r.compose_ms);
            reload.pipeline_ms += pipeline_ms;
            if installed != Installed::Swapped {
                reload.diagnostics.extend(self.cache.entries[&key].diagnostics.iter().cloned());
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
            let timings = ReloadTimings { watch_ms: r.watch_ms, compose_ms: r.compose_ms, pipeline_ms: r.pipeline_ms, render_ms: 0.0 };
            self.finished_reloads.push((id, timings));
            self.shared.publish(ServerEvent::ReloadSucceeded { id, files: r.files, pipelines: r.pipelines, timings });
        } else {
            self.shared.publish(ServerEvent::ReloadFailed { id, files: r.files, pipelines: r.pipelines, diagnostics: r.diagnostics });
        }
        let _ = r.first_event;
        self.dirty = true;
        self.publish_state();
    }

    fn render(&mut self) {
        self.frame += 1;
        self.last_frame = Instant::now();
        self.dirty = false;
        self.pool_for_graph();
        let graph = render::build_graph(&self.scene, self.frame);
        let mut capture: BTreeSet<String> = self.subscriptions.clone();
        if let Some(h) = graph.final_output() {
            capture.insert(frame::capture_name(&graph, h));
        }
        let live = self.cache.live();
        let pending = frame::submit(&self.gpu.device, &self.gpu.queue, self.gpu.features, &self.scene_gpu, &graph, &mut self.pool, &live, Some(&capture), self.frame);
        self.in_flight.push_back((pending, std::mem::take(&mut self.finished_reloads)));
        // Errors no scope caught (invalid frame commands) must not vanish:
        // such a frame renders nothing.
        let errors: Vec<String> = std::mem::take(&mut *self.gpu.uncaptured.lock().unwrap_or_else(|e| e.into_inner()));
        for e in errors {
            log::error!("frame {}: {e}", self.frame);
        }
    }

    fn pool_for_graph(&mut self) {
        let graph = render::build_graph(&self.scene, self.frame);
        self.pool.retain(&graph);
    }

    fn collect_frames(&mut self) {
        while self.in_flight.front().is_some_and(|(p, _)| p.ready()) {
            let (pending, reloads) = self.in_flight.pop_front().expect("checked");
            let result = pending.finish();
            self.publish_frame(result, reloads);
        }
    }

    fn publish_frame(&mut self, result: frame::FrameResult, reloads: Vec<(u64, ReloadTimings)>) {
        let total: f64 = result.timings.iter().map(|(_, t)| t).sum();
        let graph = render::build_graph(&self.scene, self.frame);
        let final_name = graph.final_output().map(|h| frame::capture_name(&graph, h));
        let mut captures = (*shared::read(&self.shared.captures)).clone();
        if !reloads.is_empty() {
            // The frame before a swap is what A/B compares against.
            shared::write(&self.shared.last_good, Arc::new(captures.clone()));
        }
        for c in result.captures {
            let c = Arc::new(c);
            if Some(c.key()) == final_name {
                let png = c.to_png();
                let _ = self.shared.frame_png.send(Some(Arc::new(FramePng { frame: result.frame, width: c.width, height: c.height, png })));
            }
            captures.insert(c.key(), c);
        }
        shared::write(&self.shared.captures, Arc::new(captures));
        let passes: Vec<PassTiming> = result.timings.iter().map(|(n, t)| PassTiming { name: n.clone(), time_ms: *t }).collect();
        self.publish_passes(&result.timings, result.timing);
        let reload = reloads.last().map(|(id, _)| *id);
        self.shared.publish(ServerEvent::Frame { frame: result.frame, passes, total_ms: total, timing: result.timing.to_owned(), reload });
        let mut status = shared::read(&self.shared.status);
        status.frame = result.frame;
        shared::write(&self.shared.status, status);
    }

    fn publish_passes(&self, timings: &[(String, f64)], timing: &str) {
        let graph = render::build_graph(&self.scene, self.frame);
        let mut passes: Vec<PassInfo> = graph
            .passes
            .iter()
            .map(|p| {
                let entries: Vec<_> = p.pipelines.iter().filter_map(|k| self.cache.entries.get(k)).collect();
                let status = entries.iter().map(|e| e.status()).max_by_key(|s| match s {
                    PassStatus::Ok => 0,
                    PassStatus::Stale => 1,
                    PassStatus::Failed => 2,
                    PassStatus::Culled => 3,
                }).unwrap_or(if p.pipelines.is_empty() { PassStatus::Ok } else { PassStatus::Failed });
                PassInfo {
                    name: p.name.clone(),
                    status,
                    reason: (status == PassStatus::Failed).then(|| "its pipeline has never built".to_owned()),
                    pipelines: p.pipelines.iter().map(PipelineKey::label).collect(),
                    reads: p.reads.iter().map(|h| graph.texture(*h).name.clone()).collect(),
                    writes: p.writes.iter().map(|h| {
                        let t = graph.texture(*h);
                        protocol::OutputInfo { name: t.name.rsplit('/').next().unwrap_or("").to_owned(), format: format!("{:?}", t.format), width: t.width, height: t.height }
                    }).collect(),
                    time_ms: timings.iter().find(|(n, _)| *n == p.name).map(|(_, t)| *t),
                    timing: timing.to_owned(),
                    diagnostics: entries.iter().map(|e| e.diagnostics.len()).sum(),
                }
            })
            .collect();
        passes.extend(graph.culled.iter().map(|c| PassInfo {
            name: c.name.clone(),
            status: PassStatus::Culled,
            reason: Some(c.reason.clone()),
            pipelines: Vec::new(),
            reads: Vec::new(),
            writes: Vec::new(),
            time_ms: None,
            timing: timing.to_owned(),
            diagnostics: 0,
        }));
        shared::write(&self.shared.passes, passes.clone());
        self.shared.publish(ServerEvent::Passes { passes });
    }

    fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut all = self.cache.diagnostics();
        for d in self.file_errors.values().chain(self.scene_error.iter()) {
            if !all.iter().any(|x| x.to_string() == d.to_string()) {
                all.push(d.clone());
            }
        }
        all
    }

    fn publish_state(&self) {
        let diagnostics = self.diagnostics();
        let infos = self.cache.info();
        let count = |s: PassStatus| infos.iter().filter(|i| i.status == s).count();
        let status = Status {
            protocol: protocol::VERSION,
            version: env!("CARGO_PKG_VERSION").to_owned(),
            adapter: self.gpu.adapter_name(),
            cpu_adapter: self.gpu.is_cpu(),
            features: format!("{:?}", self.gpu.features).split(" | ").map(str::to_owned).collect(),
            degraded: self.gpu.degraded.clone(),
            scene: library::display_path(&self.config.scene_path),
            frame: self.frame,
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
        self.publish_passes(&[], "gpu");
    }

    fn install_lost_callback(&self) {
        let tx = self.events.clone();
        self.gpu.device.set_device_lost_callback(move |reason, message| {
            if reason != wgpu::DeviceLostReason::Destroyed || !message.is_empty() {
                let _ = tx.send(Event::DeviceLost(format!("{reason:?}: {message}")));
            }
        });
    }

    /// A lost device is replaced and every pipeline rebuilt from its last
    /// good module; the process keeps running.
    fn recover_device(&mut self, reason: String) {
        log::warn!("device lost: {reason}");
        match gpu::open() {
            Ok(g) => {
                self.gpu = g;
                self.device_resets += 1;
                self.pool = Default::default();
                self.scene_gpu = SceneGpu::new(&self.gpu.device, &self.gpu.queue, &self.scene, &self.meshes);
                self.in_flight.clear();
                let problems = self.cache.recreate_all(&self.gpu.device, &self.lib);
                self.install_lost_callback();
                self.shared.publish(ServerEvent::DeviceLost { message: reason, recovered: problems.is_empty() });
                self.dirty = true;
                self.publish_state();
            }
            Err(e) => self.shared.publish(ServerEvent::DeviceLost { message: format!("{reason}; reopening failed: {e}"), recovered: false }),
        }
    }
}

fn same_file(a: &Path, b: &Path) -> bool {
    let c = |p: &Path| p.canonicalize().unwrap_or_else(|_| std::path::absolute(p).unwrap_or_else(|_| p.to_owned()));
    c(a) == c(b)
}
