//! A rendering session: one device, the shader library, the scene and its
//! GPU data, the frame's graph, the pipeline cache and the resource pool.
//! `loupe serve`'s daemon and `loupe render` / `loupe bench` drive the same
//! session; they differ only in where compiles run and what they do with
//! a finished frame.
//!
//! Architecture Invariant: the graph is rebuilt exactly when the scene
//! changes (`set_scene`), or replaced whole by an offline command that
//! renders frames of its own (`use_graph`), and the pipelines to build
//! are derived from it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;

use super::FrameOptions;
use super::context::DEPTH_CLEAR;
use super::frame::{self, FrameInputs, FrameResult, PendingFrame};
use super::graph::{Graph, PassKind};
use super::pipelines::{self, Compiled, Installed, PipelineCache, PipelineSummary, Status};
use super::pool::ResourcePool;
use super::print_selection::PrintSelection;
use super::quads::ReplayCache;
use super::resource::{Lifetime, Meaning, PipelineKey, Projection, ResourceDesc, TensorLayout};
use super::scene_gpu::SceneGpu;
use super::vertex_capture::VertexCapture;
use crate::denoise::network::Network;
use crate::diag::{Diagnostic, display_path};
use crate::gpu::Gpu;
use crate::gpu::pipeline::{MESH_VERTICES, PipelineSpec, Stages};
use crate::loaded::Loaded;
use crate::material::{self, Program};
use crate::mesh::MeshData;
use crate::scene::{Camera, Scene};
use crate::shader::{ComposeCache, Library, SourceFile};

/// How a pass stands this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PassState {
    /// Rendering with its current pipelines.
    Ok,
    /// Its newest source failed; the last good pipeline still renders.
    Stale,
    /// A pipeline has never built: the pass does not render.
    Failed,
    /// Not needed by this frame.
    Culled,
}

/// One resource a pass writes, as reports describe it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputSummary {
    pub name: String,
    /// `texture` or `buffer`.
    pub kind: &'static str,
    /// The texture format (`Rgba16Float`), or the buffer's element type.
    pub format: String,
    /// Texture size; a buffer's element count and 1.
    pub width: u32,
    pub height: u32,
    /// A buffer's tensor layout.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tensor: Option<TensorLayout>,
    /// What its values mean: `color`, `normal`, `depth`, `data` or `id`.
    pub meaning: &'static str,
    /// For depth, how to read it as distance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth: Option<DepthProjection>,
    /// Kept across frames.
    pub history: bool,
}

/// One pass of the frame, live or culled: the renderer's one description
/// of a pass, which the daemon maps to the protocol and `loupe render`
/// writes into its report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassSummary {
    pub name: String,
    /// `None` when culled.
    pub kind: Option<PassKind>,
    pub status: PassState,
    /// Why it is culled or failed.
    pub reason: Option<String>,
    pub pipelines: Vec<String>,
    pub reads: Vec<String>,
    pub writes: Vec<OutputSummary>,
    /// Diagnostics of its pipelines.
    pub diagnostics: usize,
}

/// How a depth output reads as distance: the near and far planes of the
/// projection it went through (`None` for a light's, which varies by
/// light), and whether depth is reversed (near at 1, cleared to 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DepthProjection {
    pub near: Option<f32>,
    pub far: Option<f32>,
    pub reversed: bool,
}

impl DepthProjection {
    fn of(projection: Projection, camera: &Camera) -> Self {
        let planes = (projection == Projection::Camera).then_some((camera.near, camera.far));
        DepthProjection { near: planes.map(|p| p.0), far: planes.map(|p| p.1), reversed: DEPTH_CLEAR == 0.0 }
    }
}

/// Pipelines no longer used by the frame that are kept, in case a setting
/// switches back.
const KEPT_UNUSED: usize = 32;

/// Frames in a row without quad statistics after which their replays
/// (each render target's positions, depth and maps) are let go: long
/// enough for `loupe bench`, which interleaves three frames without them
/// between frames with them, short enough to give the memory back soon
/// after the last page stops asking.
const QUAD_REPLAYS_KEPT_IDLE: u32 = 16;

pub struct Session {
    gpu: Gpu,
    shader_root: PathBuf,
    lib: Arc<Library>,
    scene: Scene,
    /// Kept to rebuild the scene's GPU data on a new device.
    meshes: BTreeMap<String, Arc<MeshData>>,
    /// The network the scene's `[denoiser]` names.
    network: Option<Arc<Network>>,
    /// The scene's materials; their WGSL is the library's
    /// `loupe::material` module.
    materials: Arc<Program>,
    scene_gpu: SceneGpu,
    graph: Graph,
    cache: PipelineCache,
    pool: ResourcePool,
    frame: u64,
    options: FrameOptions,
    /// naga_oil composers kept warm between compiles, shared by the jobs.
    composer: Arc<ComposeCache>,
    /// Whether frames gather quad statistics (costly: only while asked).
    quads: bool,
    /// Whether frames submit and time each pass on its own (`loupe bench
    /// --serial`).
    serial: bool,
    /// The vertex captures of the frame's raster pipelines, with the
    /// generation each was instrumented from; built while `quads` is on.
    vertex_captures: BTreeMap<PipelineKey, VertexCapture>,
    capture_generations: BTreeMap<PipelineKey, u64>,
    /// The quad model's replays, kept while the session lives so that a
    /// render target recorded as the frame before is not replayed again.
    quad_replays: ReplayCache,
    /// Frames submitted without quad statistics since they were last on.
    frames_without_quads: u32,
    /// The selected pixel's prints (`None`: no pixel selected).
    prints: Option<PrintSelection>,
    /// Frames run the plain pipelines though a pixel is selected (`loupe
    /// bench` times both ways, interleaved, without rebuilding).
    prints_paused: bool,
    /// Frames submitted since the history was last forgotten: the samples
    /// per pixel the path tracer holds.
    accumulated: u32,
}

impl Session {
    pub fn new(gpu: Gpu, shader_root: &Path, mut lib: Library, loaded: &Loaded) -> Self {
        let scene_gpu =
            SceneGpu::new(&gpu.device, &gpu.queue, &loaded.scene, &loaded.meshes, &loaded.materials, loaded.denoiser.as_ref(), None);
        material_module(&mut lib, shader_root, &loaded.materials);
        let limits = gpu.device.limits();
        let options = FrameOptions {
            max_buffer: Some(crate::gpu::largest_binding(&limits)),
            material_words: loaded.materials.raster_words(),
            tile_classes: super::passes::classify::Classes::of(&loaded.materials.raster_definitions()),
            ..FrameOptions::default()
        };
        Session {
            graph: super::build_graph(&loaded.scene, loaded.denoiser.as_deref(), options),
            options,
            composer: Arc::default(),
            quads: false,
            serial: false,
            vertex_captures: BTreeMap::new(),
            capture_generations: BTreeMap::new(),
            quad_replays: ReplayCache::default(),
            frames_without_quads: 0,
            prints: None,
            prints_paused: false,
            accumulated: 0,
            scene: loaded.scene.clone(),
            meshes: loaded.meshes.clone(),
            network: loaded.denoiser.clone(),
            materials: loaded.materials.clone(),
            scene_gpu,
            shader_root: shader_root.to_owned(),
            lib: Arc::new(lib),
            cache: PipelineCache::default(),
            pool: ResourcePool::default(),
            frame: 0,
            gpu,
        }
    }

    /// Builds frames with `options` from now on (the device's limits stay
    /// the session's).
    pub fn with_options(mut self, options: FrameOptions) -> Self {
        let o = &self.options;
        self.options = FrameOptions { max_buffer: o.max_buffer, material_words: o.material_words, tile_classes: o.tile_classes, ..options };
        self.graph = super::build_graph(&self.scene, self.network.as_deref(), self.options);
        self
    }

    /// Turns quad statistics on or off for the frames that follow.
    pub fn set_quads(&mut self, on: bool) {
        self.quads = on;
    }

    /// How many render targets the quad model has replayed, not counting
    /// those reused because they were recorded as the frame before.
    pub fn quad_replays(&self) -> u64 {
        self.quad_replays.replayed()
    }

    /// Times each pass of the frames that follow by the wall clock,
    /// submitting it alone and waiting for it.
    pub fn set_serial(&mut self, on: bool) {
        self.serial = on;
    }

    /// Whether frames are timed pass by pass by the wall clock.
    pub fn serial(&self) -> bool {
        self.serial
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's materials, as last installed.
    pub fn materials(&self) -> &Program {
        &self.materials
    }

    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    pub fn library(&self) -> &Arc<Library> {
        &self.lib
    }

    pub fn pipelines(&self) -> &PipelineCache {
        &self.cache
    }

    /// The newest frame submitted (0 before the first).
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Renders `graph` instead of the scene's own: `loupe denoise`'s frames
    /// of images (`render::denoise_graph`), and tests of single passes.
    pub fn use_graph(&mut self, graph: Graph) {
        self.graph = graph;
    }

    /// Replaces the scene: its GPU data and the graph follow. Pipelines
    /// the new frame no longer uses are kept (switching back costs
    /// nothing), at most `KEPT_UNUSED` of them. Returns the library files
    /// the scene changed (the material module, when its code changed):
    /// the pipelines built from them must be rebuilt.
    pub fn set_scene(&mut self, loaded: &Loaded) -> BTreeSet<String> {
        self.scene_gpu = SceneGpu::new(
            &self.gpu.device,
            &self.gpu.queue,
            &loaded.scene,
            &loaded.meshes,
            &loaded.materials,
            loaded.denoiser.as_ref(),
            Some(&self.scene_gpu),
        );
        self.scene = loaded.scene.clone();
        self.meshes = loaded.meshes.clone();
        self.network = loaded.denoiser.clone();
        let mut changed = BTreeSet::new();
        if !self.materials.same_code(&loaded.materials) {
            let mut lib = (*self.lib).clone();
            let regenerated = material_module(&mut lib, &self.shader_root, &loaded.materials);
            if !regenerated.is_empty() {
                changed.extend(regenerated.into_iter().map(str::to_owned));
                self.lib = Arc::new(lib);
            }
        }
        self.materials = loaded.materials.clone();
        self.options.material_words = loaded.materials.raster_words();
        self.options.tile_classes = super::passes::classify::Classes::of(&loaded.materials.raster_definitions());
        self.graph = super::build_graph(&self.scene, self.network.as_deref(), self.options);
        // History describes the old scene: accumulation starts over.
        self.reset_history();
        let wanted = self.wanted();
        let unused: Vec<PipelineKey> = self.cache.entries.keys().filter(|k| !wanted.contains(*k)).cloned().collect();
        for k in unused.iter().take(unused.len().saturating_sub(KEPT_UNUSED)) {
            self.cache.entries.remove(k);
        }
        changed
    }

    /// `set_scene` for a caller that renders at once (the offline
    /// commands, the tests): the pipelines built from what the scene
    /// changed (a regenerated material module) are rebuilt and the missing
    /// ones built, here and now. Returns the diagnostics of those that
    /// failed. The daemon instead rebuilds in the background, the last
    /// good pipelines rendering meanwhile.
    pub fn set_scene_now(&mut self, loaded: &Loaded) -> Vec<Diagnostic> {
        let changed = self.set_scene(loaded);
        let stale = self.built_from(&changed);
        let mut errors = self.install_now(stale);
        errors.extend(self.install_missing());
        errors
    }

    /// A new version of the shader sources; pipelines rebuild only when
    /// installed.
    pub fn apply_sources(&mut self, lib: Library) {
        self.lib = Arc::new(lib);
    }

    /// Where `spec`'s shader is, as diagnostics show it.
    pub fn shader_display(&self, spec: &PipelineSpec) -> String {
        display_path(&self.shader_root.join(spec.shader))
    }

    /// Every pipeline the frame uses.
    pub fn wanted(&self) -> BTreeSet<PipelineKey> {
        self.graph.pipelines()
    }

    /// Pipelines the frame uses that were never installed.
    pub fn missing(&self) -> BTreeSet<PipelineKey> {
        self.wanted().into_iter().filter(|k| !self.cache.entries.contains_key(k)).collect()
    }

    /// The pipelines the frame uses that were built from any of `changed`
    /// (shader displays) or from a file importing one of them: what a
    /// change to them rebuilds. Pipelines kept from earlier frames that
    /// were built from them are dropped instead: they would be stale, and
    /// the frame does not use them.
    pub fn built_from(&mut self, changed: &BTreeSet<String>) -> BTreeSet<PipelineKey> {
        let files: BTreeSet<String> = changed.iter().flat_map(|d| self.lib.dependents(d)).collect();
        let wanted = self.wanted();
        let touched: BTreeSet<PipelineKey> = self
            .cache
            .entries
            .iter()
            .filter(|(k, e)| e.files.iter().any(|f| files.contains(f)) || files.contains(&self.shader_display(k.spec)))
            .map(|(k, _)| k.clone())
            .collect();
        self.cache.entries.retain(|k, _| wanted.contains(k) || !touched.contains(k));
        touched.into_iter().filter(|k| wanted.contains(k)).collect()
    }

    /// The pipelines the frame uses, as reports show them. Pipelines kept
    /// for quick toggling back are not reported.
    pub fn pipeline_summaries(&self) -> Vec<PipelineSummary> {
        let wanted = self.wanted();
        self.cache.summaries_of(|k| wanted.contains(k))
    }

    /// Diagnostics of the pipelines the frame uses.
    pub fn pipeline_diagnostics(&self) -> Vec<Diagnostic> {
        let wanted = self.wanted();
        self.cache.diagnostics_of(|k| wanted.contains(k))
    }

    /// Composing `key` as a job for any thread: it holds this version of
    /// the sources.
    pub fn compose_job(&self, key: &PipelineKey) -> impl FnOnce() -> Result<Compiled, Vec<Diagnostic>> + Send + 'static {
        let (lib, composer) = (self.lib.clone(), self.composer.clone());
        let key = key.clone();
        let display = self.shader_display(key.spec);
        move || pipelines::compose(&*composer, &lib, &key, &display)
    }

    /// Creates the pipeline from a compile result and swaps it in when it
    /// built (on this thread: it owns the device).
    pub fn install(&mut self, key: &PipelineKey, result: Result<Compiled, Vec<Diagnostic>>) -> Installed {
        let display = self.shader_display(key.spec);
        let installed = self.cache.install(&self.gpu.device, key, result, &self.lib, &display);
        if installed == Installed::Swapped {
            // What a pass accumulated came from the old code.
            for pass in self.graph.passes.iter().filter(|p| p.pipelines.contains(key)) {
                self.pool.reset_history_of(&pass.name);
                if pass.name == "path_trace" {
                    self.accumulated = 0;
                }
            }
        }
        installed
    }

    /// Composes and installs every pipeline the frame lacks, here and now;
    /// returns the diagnostics of those that failed.
    pub fn install_missing(&mut self) -> Vec<Diagnostic> {
        let missing = self.missing();
        self.install_now(missing)
    }

    /// Composes and installs `keys` here and now; returns the diagnostics
    /// of those that failed.
    pub fn install_now(&mut self, keys: BTreeSet<PipelineKey>) -> Vec<Diagnostic> {
        let mut errors = Vec::new();
        for key in keys {
            let result = self.compose_job(&key)();
            self.install(&key, result);
            errors.extend(self.cache.entries[&key].diagnostics.iter().cloned());
        }
        errors
    }

    /// Records and submits the next frame. `capture`: the outputs to read
    /// back (`None`: all); `dt`: seconds since the previous frame, which
    /// temporal passes adapt by.
    pub fn submit(&mut self, capture: Option<&BTreeSet<String>>, dt: f32) -> PendingFrame {
        self.frame += 1;
        self.accumulated = self.accumulated.saturating_add(1);
        let pixel = self.prints.as_ref().filter(|_| !self.prints_paused).map(PrintSelection::pixel);
        let record_draws = self.quads || pixel.is_some();
        if record_draws {
            self.refresh_vertex_captures();
        }
        // A pixel's history records draws too, but never replays whole
        // targets: only quad statistics keep the replays alive.
        if self.quads {
            self.frames_without_quads = 0;
        } else {
            self.frames_without_quads = self.frames_without_quads.saturating_add(1);
            if self.frames_without_quads == QUAD_REPLAYS_KEPT_IDLE {
                self.quad_replays.clear();
            }
        }
        let mut live = self.cache.live();
        let prints = self.prints.as_mut().filter(|_| !self.prints_paused);
        if let Some(prints) = prints {
            let keys: Vec<(PipelineKey, String)> =
                self.graph.passes.iter().flat_map(|p| p.pipelines.iter().map(|k| (k.clone(), p.name.clone()))).collect();
            prints.refresh(&self.gpu.device, &self.cache, &self.lib, &keys);
            prints.replace(&mut live);
        }
        let g = &self.gpu;
        let inputs = FrameInputs {
            device: &g.device,
            queue: &g.queue,
            features: g.features,
            scene: &self.scene_gpu,
            graph: &self.graph,
            pipelines: &live,
            capture,
            statistics: self.quads,
            vertex_captures: record_draws.then_some(&self.vertex_captures),
            quad_replays: self.quads.then(|| self.quad_replays.clone()),
            pixel: pixel.map(|p| (p, (self.scene.width, self.scene.height))),
            frame: self.frame,
            samples: self.accumulated,
            dt,
            serial: self.serial,
            prints: self.prints.as_ref().filter(|_| !self.prints_paused).map(PrintSelection::binding),
        };
        frame::submit(inputs, &mut self.pool)
    }

    /// Selects the pixel whose prints and history the next frames collect
    /// (`None`: none, and the plain pipelines run again).
    pub fn set_debug_pixel(&mut self, pixel: Option<[u32; 2]>) {
        if self.prints.as_ref().map(PrintSelection::pixel) != pixel {
            self.prints = pixel.map(|p| PrintSelection::new(&self.gpu.device, p));
        }
    }

    /// Runs the plain pipelines while `paused`, keeping the selection and
    /// its instrumented pipelines for when it is not.
    pub fn pause_prints(&mut self, paused: bool) {
        self.prints_paused = paused;
    }

    /// The selection, when a pixel is selected.
    pub fn debug_prints(&self) -> Option<&PrintSelection> {
        self.prints.as_ref()
    }

    /// Instruments the vertex stage of every raster pipeline the frame uses
    /// whose current module is new since the last time: quad statistics
    /// follow every edit. One that cannot be instrumented is left out
    /// (its pass gets no statistics) with a warning.
    fn refresh_vertex_captures(&mut self) {
        let keys: BTreeSet<PipelineKey> = self.graph.passes.iter().flat_map(|p| p.pipelines.iter().cloned()).collect();
        self.vertex_captures.retain(|k, _| keys.contains(k));
        self.capture_generations.retain(|k, _| keys.contains(k));
        for key in keys {
            let (entry, layout) = match key.spec.stages {
                Stages::Fullscreen { .. } => ("vs_fullscreen", None),
                Stages::Mesh { vertex, .. } => (vertex, Some(&MESH_VERTICES)),
                Stages::Compute { .. } => continue,
            };
            let Some(e) = self.cache.entries.get(&key) else { continue };
            let Some(module) = e.current.as_ref().and(e.last_good.as_ref()) else { continue };
            if self.capture_generations.get(&key) == Some(&e.generation) {
                continue;
            }
            self.capture_generations.insert(key.clone(), e.generation);
            // naga's compactor, writer and parser run here: a bug of theirs
            // costs this pipeline its statistics, not the render thread.
            let device = &self.gpu.device;
            let built =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| VertexCapture::new(device, &module.module, entry, layout)));
            match built {
                Ok(Ok(c)) => {
                    self.vertex_captures.insert(key, c);
                }
                Ok(Err(err)) => {
                    log::warn!("quad statistics: the vertex stage of {} cannot be captured: {err}", key.label());
                    self.vertex_captures.remove(&key);
                }
                Err(_) => {
                    log::error!("quad statistics: instrumenting the vertex stage of {} panicked", key.label());
                    self.vertex_captures.remove(&key);
                }
            }
        }
    }

    /// The texture of the frame's final output as the newest submitted
    /// frame wrote it; `None` when the graph has none or it is not
    /// allocated (its pass culled). Commands submitted after that frame
    /// see what it wrote.
    pub fn final_texture(&self) -> Option<&wgpu::Texture> {
        match self.pool.try_get(&self.graph, self.graph.final_output()?)? {
            super::resource::Physical::Texture { texture, .. } => Some(texture),
            super::resource::Physical::Buffer(_) => None,
        }
    }

    /// Output `name` (`pass/output`) as the newest submitted frame left
    /// it, with what its values mean; `None` when it is a buffer or not
    /// allocated (its pass culled).
    pub fn output_texture(&self, name: &str) -> Option<(&wgpu::Texture, super::resource::Meaning)> {
        let h = self.graph.resources.iter().position(|r| r.name == name).map(super::resource::Handle)?;
        match self.pool.try_get(&self.graph, h)? {
            super::resource::Physical::Texture { texture, .. } => Some((texture, self.graph.resource(h).meaning)),
            super::resource::Physical::Buffer(_) => None,
        }
    }

    /// Polls the device without blocking, so readbacks can land.
    pub fn poll(&self) {
        let _ = self.gpu.device.poll(wgpu::PollType::Poll);
    }

    /// Waits until a submitted frame's readbacks have landed.
    pub fn land(&self, pending: &PendingFrame) {
        while !pending.ready() {
            let _ = self.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        }
    }

    /// Waits for a submitted frame and converts its readbacks.
    pub fn wait(&self, pending: PendingFrame) -> FrameResult {
        self.land(&pending);
        pending.finish()
    }

    /// Forgets every history resource: the next frame starts over.
    pub fn reset_history(&mut self) {
        self.pool.reset_history();
        self.accumulated = 0;
    }

    /// Samples per pixel the path tracer holds after the newest submitted
    /// frame, when the graph path traces: the frames since its history was
    /// last forgotten, up to `quality.path_spp` (where it stops adding).
    pub fn path_samples(&self) -> Option<u32> {
        let traced = self.graph.passes.iter().any(|p| p.name == "path_trace");
        traced.then(|| self.accumulated.min(self.scene.quality.path_spp))
    }

    /// Whether frames still change with nothing else changing: the path
    /// tracer has not reached `quality.path_spp` samples per pixel.
    pub fn converging(&self) -> bool {
        self.path_samples().is_some_and(|s| s < self.scene.quality.path_spp)
    }

    /// Errors wgpu reported outside any error scope since the last call.
    pub fn take_uncaptured(&self) -> Vec<String> {
        std::mem::take(&mut *self.gpu.uncaptured.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// Moves to a new device after the old one was lost: GPU data rebuilt,
    /// every pipeline recreated from its last good module. Returns what
    /// could not be recreated.
    pub fn replace_device(&mut self, gpu: Gpu) -> Vec<Diagnostic> {
        self.gpu = gpu;
        self.pool = ResourcePool::default();
        self.vertex_captures.clear();
        self.capture_generations.clear();
        // The selection's buffer and variants were the old device's.
        self.prints = self.prints.as_ref().map(|p| PrintSelection::new(&self.gpu.device, p.pixel()));
        self.scene_gpu =
            SceneGpu::new(&self.gpu.device, &self.gpu.queue, &self.scene, &self.meshes, &self.materials, self.network.as_ref(), None);
        self.cache.recreate_all(&self.gpu.device, &self.lib)
    }

    /// The frame's passes, live ones in execution order, then culled ones.
    pub fn passes(&self) -> Vec<PassSummary> {
        let graph = &self.graph;
        let mut out: Vec<PassSummary> = graph
            .passes
            .iter()
            .map(|p| {
                let entries: Vec<_> = p.pipelines.iter().map(|k| self.cache.entries.get(k)).collect();
                let worst = entries.iter().map(|e| e.map_or(Status::Failed, |e| e.status())).max().unwrap_or(Status::Ok);
                let status = match worst {
                    Status::Ok => PassState::Ok,
                    Status::Stale => PassState::Stale,
                    Status::Failed => PassState::Failed,
                };
                PassSummary {
                    name: p.name.clone(),
                    kind: Some(p.kind),
                    status,
                    reason: (status == PassState::Failed).then(|| "its pipeline has never built".to_owned()),
                    pipelines: p.pipelines.iter().map(PipelineKey::label).collect(),
                    reads: p.reads().map(|h| graph.resource(h).name.clone()).collect(),
                    writes: p.writes().map(|h| output_summary(graph, h, &self.scene.camera)).collect(),
                    diagnostics: entries.iter().flatten().map(|e| e.diagnostics.len()).sum(),
                }
            })
            .collect();
        out.extend(graph.culled.iter().map(|c| PassSummary {
            name: c.name.clone(),
            kind: None,
            status: PassState::Culled,
            reason: Some(c.reason.clone()),
            pipelines: Vec::new(),
            reads: Vec::new(),
            writes: Vec::new(),
            diagnostics: 0,
        }));
        out
    }
}

fn output_summary(graph: &Graph, h: super::resource::Handle, camera: &Camera) -> OutputSummary {
    let r = graph.resource(h);
    let history = r.lifetime == Lifetime::History;
    let meaning = r.meaning.name();
    let depth = match r.meaning {
        Meaning::Depth(projection) => Some(DepthProjection::of(projection, camera)),
        _ => None,
    };
    match &r.desc {
        ResourceDesc::Texture(d) => OutputSummary {
            name: r.output().to_owned(),
            kind: "texture",
            format: format!("{:?}", d.format),
            width: d.width,
            height: d.height,
            tensor: None,
            meaning,
            depth,
            history,
        },
        ResourceDesc::Buffer(t) => OutputSummary {
            name: r.output().to_owned(),
            kind: "buffer",
            format: format!("{:?}", t.element).to_lowercase(),
            width: t.len() as u32,
            height: 1,
            tensor: Some(t.clone()),
            meaning,
            depth,
            history,
        },
    }
}

/// Puts `program`'s generated material modules into `lib` (never on disk;
/// they sit among the shaders at their displays): the raster's
/// `loupe::material`, the path tracer's `loupe::material_path`, and the
/// simple and single tile classes' `loupe::material_simple` and
/// `loupe::material_single`. Returns the displays whose
/// text changed: only the pipelines importing those rebuild.
pub fn material_module(lib: &mut Library, shader_root: &Path, program: &Program) -> Vec<&'static str> {
    [
        (material::back::DISPLAY, program.wgsl()),
        (material::back::PATH_DISPLAY, program.path_wgsl()),
        (material::simple::DISPLAY, material::simple::wgsl(&program.definitions)),
        (material::single::DISPLAY, material::single::wgsl(&program.raster_definitions())),
    ]
    .into_iter()
    .filter_map(|(display, text)| generated_module(lib, shader_root, display, text).then_some(display))
    .collect()
}

/// Puts generated module `text` into `lib` at `display`; whether it changed.
fn generated_module(lib: &mut Library, shader_root: &Path, display: &str, text: String) -> bool {
    if lib.get(display).is_some_and(|f| *f.text == *text) {
        return false;
    }
    lib.upsert(SourceFile::from_text(display.to_owned(), shader_root.join(display), text.into()));
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::overrides::Overrides;
    use crate::scene::settings::Value;
    use crate::shader::library;

    fn pattern(two_triangles: bool) -> Loaded {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/pattern.toml");
        crate::loaded::load_with(&scenes, &Overrides::from([("post.two_triangles".to_owned(), Value::Bool(two_triangles))])).unwrap()
    }

    /// Each output says what its pass declared it means; the camera's
    /// depth carries the scene camera's planes, a light's shadow map none.
    #[test]
    fn outputs_carry_their_meaning_and_camera_depth_its_planes() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/minimal.toml");
        let mut loaded = crate::loaded::load_with(&scenes, &Overrides::new()).unwrap();
        (loaded.scene.camera.near, loaded.scene.camera.far) = (0.25, 40.0);
        let graph = super::super::build_graph(&loaded.scene, None, FrameOptions::default());
        let output = |name: &str| {
            let h = graph.resources.iter().position(|r| r.name == name).unwrap_or_else(|| panic!("{name} in the graph"));
            output_summary(&graph, super::super::resource::Handle(h), &loaded.scene.camera)
        };
        let meaning = |name: &str| (output(name).meaning, output(name).depth);
        let planes = DepthProjection { near: Some(0.25), far: Some(40.0), reversed: false };
        assert_eq!(meaning("depth_prepass/depth"), ("depth", Some(planes)));
        let light = DepthProjection { near: None, far: None, reversed: false };
        assert_eq!(meaning("shadows/depth"), ("depth", Some(light)));
        assert_eq!(meaning("gbuffer/normal"), ("normal", None));
        assert_eq!(meaning("gbuffer/albedo"), ("color", None));
        assert_eq!(meaning("gbuffer/material"), ("data", None));
        assert_eq!(meaning("gbuffer/uv"), ("data", None));
        assert_eq!(meaning("tonemap/color"), ("color", None));
    }

    /// With timestamp queries every pass has a time and they add up to the
    /// frame; without them only the frame's wall clock is known, and no
    /// pass is given a time it did not measure.
    #[test]
    fn without_timestamp_queries_only_the_frame_total_is_reported() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &pattern(false));
        assert_eq!(s.install_missing(), vec![]);
        if s.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            let pending = s.submit(Some(&BTreeSet::new()), 0.0);
            let r = s.wait(pending);
            assert_eq!(r.timing, "gpu");
            let names: Vec<&str> = r.timings.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(names, ["test_pattern", "tonemap"]);
            assert_eq!(r.total_ms, r.timings.iter().map(|(_, t)| t).sum::<f64>());
        }
        s.gpu.features.remove(wgpu::Features::TIMESTAMP_QUERY);
        let pending = s.submit(Some(&BTreeSet::new()), 0.0);
        let r = s.wait(pending);
        assert_eq!(r.timing, "cpu");
        assert_eq!(r.timings, vec![], "no pass gets a time it did not measure");
        assert!(r.total_ms > 0.0, "the frame's wall clock is reported");
    }

    /// With no pixel selected the plain pipelines run and nothing prints;
    /// selecting one builds the variant of the pipeline that prints (and
    /// of no other), kept across frames while selected; clearing it
    /// drops it.
    #[test]
    fn a_selected_pixel_runs_the_printing_pipeline_instrumented_and_only_then() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let mut lib = library::read_tree(&root).unwrap();
        let file = lib.files().find(|f| f.display.ends_with("passes/test_pattern.wgsl")).unwrap().clone();
        let text = format!("enable wgpu_debug_printf;\n{}", file.text).replacen(
            "fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {\n",
            "fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {\n    debugPrintf(\"at %v2f\", in.position.xy);\n",
            1,
        );
        assert!(text.contains("debugPrintf"), "the premise: fs_main is written so");
        lib.upsert(SourceFile::from_text(file.display.clone(), file.path.clone(), text.into()));
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, lib, &pattern(false));
        assert_eq!(s.install_missing(), vec![]);
        let frame = |s: &mut Session| {
            let pending = s.submit(Some(&BTreeSet::new()), 0.0);
            s.wait(pending).prints
        };
        assert_eq!(frame(&mut s), None);
        assert!(s.debug_prints().is_none());

        s.set_debug_pixel(Some([2, 3]));
        for _ in 0..2 {
            let printed = frame(&mut s).expect("a pixel is selected");
            let texts: Vec<(&str, &str)> = printed.lines.iter().map(|l| (l.pass.as_str(), l.text.as_str())).collect();
            assert_eq!(texts, [("test_pattern", "at 2.500000, 3.500000")]);
            let selection = s.debug_prints().unwrap();
            assert_eq!(selection.printing().map(PipelineKey::label).collect::<Vec<_>>(), ["debug.test_pattern"]);
            assert_eq!(selection.built(), 1, "built once, kept while selected");
        }
        // Paused (how `loupe bench` times the plain pipelines): nothing
        // printed, and nothing rebuilt when it resumes.
        s.pause_prints(true);
        assert_eq!(frame(&mut s), None);
        s.pause_prints(false);
        assert_eq!(frame(&mut s).map(|p| p.lines.len()), Some(1));
        assert_eq!(s.debug_prints().unwrap().built(), 1);
        s.set_debug_pixel(None);
        assert_eq!(frame(&mut s), None);
        assert!(s.debug_prints().is_none());
    }

    /// A print added to the tiled lighting's `shade(texel)` (a compute
    /// stage whose workgroups follow tile lists, not its global id) and
    /// reloaded as the daemon reloads a save prints in the next frame for
    /// the selected pixel only: one line, at three pixels of the knot, its
    /// texel the pixel and its depth the one the frame's capture holds
    /// there.
    #[test]
    fn a_print_in_the_tiled_lighting_prints_for_the_selected_pixel_only() {
        const DEPTH: &str = "depth_prepass/depth";
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/minimal.toml");
        let mut loaded = crate::loaded::load_with(&scenes, &Overrides::new()).unwrap();
        (loaded.scene.width, loaded.scene.height) = (96, 54);
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &loaded);
        assert_eq!(s.install_missing(), vec![]);
        let frame = |s: &mut Session| {
            let pending = s.submit(Some(&BTreeSet::from([DEPTH.to_owned()])), 0.0);
            s.wait(pending)
        };
        let first = frame(&mut s);
        let depth = first.captures.iter().find(|c| c.key() == DEPTH).expect("the depth is captured");
        let depth_at = |[x, y]: [u32; 2]| depth.data[4 * (y * depth.width + x) as usize];
        let knot: Vec<[u32; 2]> =
            (0..depth.height).flat_map(|y| (0..depth.width).map(move |x| [x, y])).filter(|&p| depth_at(p) < 1.0).collect();
        assert!(knot.len() > 100, "the knot covers {} pixels", knot.len());
        let pixels = [knot[0], knot[knot.len() / 2], knot[knot.len() - 1]];
        s.set_debug_pixel(Some(pixels[0]));
        assert_eq!(frame(&mut s).prints.map(|p| p.lines), Some(vec![]), "nothing prints yet");

        // The save, reloaded as the daemon does.
        let display = s.shader_display(&super::super::passes::lighting::DEFERRED);
        let mut lib = (**s.library()).clone();
        let file = lib.get(&display).unwrap().clone();
        let at = "    let z = textureLoad(depth, pixel, 0);\n";
        let print = "    debugPrintf(\"texel %v2u depth %f sum %u\", texel, z, texel.x * 1000u + texel.y);\n";
        assert!(file.text.contains(at), "the premise: `shade` reads the depth so");
        let text = format!("enable wgpu_debug_printf;\n{}", file.text.replacen(at, &format!("{at}{print}"), 1));
        lib.upsert(SourceFile::from_text(display.clone(), file.path.clone(), text.into()));
        s.apply_sources(lib);
        let rebuilt = s.built_from(&BTreeSet::from([display.clone()]));
        assert_eq!(s.install_now(rebuilt), vec![]);

        for pixel in pixels {
            s.set_debug_pixel(Some(pixel));
            let r = frame(&mut s);
            let lines = r.prints.expect("a pixel is selected").lines;
            assert_eq!(lines.len(), 1, "{pixel:?}: the first of them {:?}", lines.first());
            let line = &lines[0];
            assert!(line.pass.starts_with("lighting_"), "a tile class's pass: {}", line.pass);
            assert_eq!((line.file.as_str(), line.line), (display.as_str(), 128), "{pixel:?}");
            let depth = r.captures.iter().find(|c| c.key() == DEPTH).unwrap();
            let z = depth.data[4 * (pixel[1] * depth.width + pixel[0]) as usize];
            let values = [serde_json::json!(pixel), serde_json::json!(z), serde_json::json!(pixel[0] * 1000 + pixel[1])];
            assert_eq!(line.values, values, "{pixel:?}: {}", line.text);
        }
    }

    /// Pipeline statistics count each raster pass's fragment-shader
    /// invocations where the adapter can (lavapipe can), only while asked.
    #[test]
    fn quad_statistics_count_fragment_invocations_per_raster_pass() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        if !gpu.features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY) {
            return;
        }
        let mut s = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &pattern(false));
        assert_eq!(s.install_missing(), vec![]);
        let pixels = u64::from(s.scene().width * s.scene().height);
        let pending = s.submit(Some(&BTreeSet::new()), 0.0);
        assert_eq!(s.wait(pending).fragment_invocations, vec![], "not asked for");
        s.set_quads(true);
        let pending = s.submit(Some(&BTreeSet::new()), 0.0);
        let counts = s.wait(pending).fragment_invocations;
        let names: Vec<&str> = counts.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["test_pattern", "tonemap"]);
        // Two fullscreen passes: every pixel shaded at least once, helper
        // lanes at most a quad's worth per pixel.
        for (name, n) in &counts {
            assert!((pixels..=4 * pixels).contains(n), "{name}: {n} invocations for {pixels} pixels");
        }
    }

    /// Quad statistics replay a render target only when what it was
    /// recorded with changed: the second frame of a static scene reuses
    /// every replay, figures and maps alike; a moved camera replays the
    /// camera's passes, not the light's shadow map, and their figures
    /// follow it.
    #[test]
    fn quad_statistics_replay_only_the_render_targets_that_changed() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/minimal.toml");
        let small_shadows = Overrides::from([("quality.shadow_map_size".to_owned(), Value::Int(64))]);
        let mut loaded = crate::loaded::load_with(&scenes, &small_shadows).unwrap();
        (loaded.scene.width, loaded.scene.height) = (96, 64);
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &loaded);
        assert_eq!(s.install_missing(), vec![]);
        s.set_quads(true);
        let frame = |s: &mut Session| {
            let pending = s.submit(Some(&BTreeSet::new()), 0.0);
            let quads = s.wait(pending).quads;
            quads.iter().map(|p| (p.pass.clone(), serde_json::to_value(p).unwrap(), p.stacked_maps())).collect::<Vec<_>>()
        };
        let pass = |frame: &[(String, serde_json::Value, _)], name: &str| frame.iter().position(|p| p.0 == name).unwrap();

        let first = frame(&mut s);
        let targets = s.quad_replays();
        let layers = first[pass(&first, "shadows")].1["draws"].as_array().unwrap().len() as u64;
        assert_eq!(layers, 6, "a point light's cube");
        assert!(targets > layers, "the camera's passes too: {targets}");
        let second = frame(&mut s);
        assert_eq!(s.quad_replays(), targets, "a static scene replays nothing again");
        assert!(second == first, "the figures and maps are the first frame's");

        loaded.scene.camera.position = [0.6, 1.3, 2.7];
        assert_eq!(s.set_scene_now(&loaded), vec![]);
        let moved = frame(&mut s);
        let names: Vec<&str> = first.iter().map(|p| p.0.as_str()).collect();
        assert_eq!(names, ["shadows", "depth_prepass", "gbuffer", "tonemap"]);
        assert_eq!(targets, layers + 3);
        assert_eq!(s.quad_replays(), targets + 2, "the prepass and G-buffer again, not the light's nor the fullscreen passes");
        for (name, same) in [("shadows", true), ("depth_prepass", false), ("gbuffer", false), ("tonemap", true)] {
            let (a, b) = (&first[pass(&first, name)], &moved[pass(&moved, name)]);
            assert_eq!(a == b, same, "{name}: {} then {}", a.1["quads"], b.1["quads"]);
        }

        // Kept through frames without quad statistics, let go after
        // QUAD_REPLAYS_KEPT_IDLE of them in a row.
        for idle in [QUAD_REPLAYS_KEPT_IDLE - 1, QUAD_REPLAYS_KEPT_IDLE] {
            s.set_quads(false);
            for _ in 0..idle {
                let pending = s.submit(Some(&BTreeSet::new()), 0.0);
                s.wait(pending);
            }
            s.set_quads(true);
            let replayed = s.quad_replays();
            assert!(frame(&mut s) == moved);
            let again = if idle < QUAD_REPLAYS_KEPT_IDLE { 0 } else { targets };
            assert_eq!(s.quad_replays(), replayed + again, "after {idle} frames without quad statistics");
        }
    }

    /// A module composed before a save and installed after it is that old
    /// version: the compile of the saved file still swaps in.
    #[test]
    fn a_compile_from_older_sources_does_not_pass_for_the_newer_ones() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &pattern(false));
        let key = s.wanted().into_iter().find(|k| k.spec.name == "post.tonemap").unwrap();
        let before_save = s.compose_job(&key);
        let mut lib = (**s.library()).clone();
        let display = s.shader_display(key.spec);
        let text = lib.get(&display).unwrap().text.replace("let c = max(", "let c = 0.5 * max(");
        let path = lib.get(&display).unwrap().path.clone();
        lib.upsert(crate::shader::SourceFile::from_bytes(&path, display.clone(), text.into_bytes()).unwrap());
        s.apply_sources(lib);
        assert_eq!(s.install(&key, before_save()), Installed::Swapped);
        let after_save = s.compose_job(&key);
        assert_eq!(s.install(&key, after_save()), Installed::Swapped, "the saved version is new");
        let again = s.compose_job(&key);
        assert_eq!(s.install(&key, again()), Installed::Unchanged, "the same sources again change nothing");
    }

    /// Culled permutations are neither reported nor rebuilt: a change to a
    /// file they were built from drops them, and switching back builds
    /// them again from the sources of the day.
    #[test]
    fn pipelines_the_frame_does_not_use_are_neither_reported_nor_rebuilt() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let lib = library::read_tree(&root).unwrap();
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu, &root, lib, &pattern(false));
        assert_eq!(s.install_missing(), vec![]);
        let one: BTreeSet<String> = s.wanted().iter().map(PipelineKey::label).collect();
        assert_eq!(one, BTreeSet::from(["debug.test_pattern".to_owned(), "post.tonemap".to_owned()]));

        assert_eq!(s.set_scene_now(&pattern(true)), vec![]);
        let two: BTreeSet<String> = s.wanted().iter().map(PipelineKey::label).collect();
        let reported: BTreeSet<String> = s.pipeline_summaries().into_iter().map(|p| p.name).collect();
        assert_eq!(reported, two, "only what the frame uses is reported");
        assert_eq!(s.pipelines().entries.len(), 4, "the one-triangle pipelines are kept for switching back");

        let fullscreen = BTreeSet::from([display_path(&root.join("lib/fullscreen.wgsl"))]);
        let rebuilt: BTreeSet<String> = s.built_from(&fullscreen).iter().map(PipelineKey::label).collect();
        assert_eq!(rebuilt, two, "a change rebuilds only what the frame uses");
        assert_eq!(s.pipelines().entries.len(), 2, "the unused ones built from the changed file are dropped");

        s.set_scene(&pattern(false));
        let missing: BTreeSet<String> = s.missing().iter().map(PipelineKey::label).collect();
        assert_eq!(missing, one, "switching back builds them again");
    }

    /// A new budget regenerates the material modules: `set_scene_now`
    /// rebuilds the pipelines built from them, so the frame is the one a
    /// fresh session renders at that budget, not the old budget's through
    /// the old pipelines (the tradeoffs sweep once rendered every budget
    /// from 40 B up as the first one it built).
    #[test]
    fn a_scene_whose_materials_change_renders_with_the_new_code_at_once() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/tiles.toml");
        let at = |bytes: i64| {
            let mut l =
                crate::loaded::load_with(&scenes, &Overrides::from([("quality.material_bytes".to_owned(), Value::Int(bytes))])).unwrap();
            (l.scene.width, l.scene.height) = (48, 27);
            l
        };
        let lit = |s: &mut Session| {
            let wanted = BTreeSet::from(["lighting/color".to_owned()]);
            let pending = s.submit(Some(&wanted), 0.0);
            s.wait(pending).captures.into_iter().find(|c| c.key() == "lighting/color").expect("captured").data
        };
        let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("a GPU device (lavapipe will do): {e}"));
        let mut s = Session::new(gpu.clone(), &root, library::read_tree(&root).unwrap(), &at(256));
        assert_eq!(s.install_missing(), vec![]);
        let full = lit(&mut s);
        // 24 B: the car paint's coat and flakes folded into one closure.
        assert_eq!(s.set_scene_now(&at(24)), vec![]);
        let swapped = lit(&mut s);
        let mut fresh = Session::new(gpu, &root, library::read_tree(&root).unwrap(), &at(24));
        assert_eq!(fresh.install_missing(), vec![]);
        let differing = |a: &[f32], b: &[f32]| a.iter().zip(b).filter(|(x, y)| x != y).count();
        assert_eq!(differing(&swapped, &lit(&mut fresh)), 0, "the new budget's frame");
        assert!(differing(&swapped, &full) > 0, "the budget changes the car paint");
    }
}
