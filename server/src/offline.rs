//! Rendering without a server: `loupe render` writes every pass output and
//! a frame report for scripts and CI golden images; `loupe bench` times
//! each pass and the cost of captures. Both run the same chain as the
//! daemon — scene → graph → pipelines → frame → captures — on the calling
//! thread.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::diag::Diagnostic;
use crate::gpu::{self, Gpu, pipeline};
use crate::render::capture::ImageStats;
use crate::render::frame::{self, FrameResult, NanOrigin, TexturePool};
use crate::render::graph::{Graph, PipelineKey};
use crate::render::pipelines::{self, PipelineCache};
use crate::render::scene_gpu::SceneGpu;
use crate::render::{self};
use crate::scene::{self, overrides::Overrides};
use crate::shader::{NagaOil, library};

#[derive(Debug, thiserror::Error)]
pub enum OfflineError {
    #[error(transparent)]
    NoDevice(#[from] gpu::OpenError),
    /// The scene or a shader has errors; nothing was rendered.
    #[error("{} error(s)", .0.len())]
    Input(Vec<Diagnostic>),
    #[error("{0}")]
    Io(String),
}

/// What to render.
pub struct Job {
    pub scene: PathBuf,
    pub shader_root: PathBuf,
    /// Replaces the scene's output size.
    pub size: Option<(u32, u32)>,
    pub overrides: Overrides,
}

/// A device with the job's scene loaded and its pipelines built.
pub struct Prepared {
    pub gpu: Gpu,
    pub scene_display: String,
    /// The output size the scene renders at (after `Job::size`).
    pub size: (u32, u32),
    pub graph: Graph,
    pub scene_gpu: SceneGpu,
    pub pipelines: BTreeMap<PipelineKey, pipeline::Pipeline>,
    pub pool: TexturePool,
}

/// Opens the device, loads the scene (with overrides and size applied),
/// builds the graph and every pipeline it needs.
pub fn prepare(job: &Job) -> Result<Prepared, OfflineError> {
    let mut loaded = scene::load_with(&job.scene, &job.overrides).map_err(|d| OfflineError::Input(vec![d]))?;
    if let Some((w, h)) = job.size {
        loaded.scene.width = w;
        loaded.scene.height = h;
    }
    let gpu = gpu::open()?;
    let graph = render::build_graph(&loaded.scene, 1);
    let lib = library::read_tree(&job.shader_root).map_err(OfflineError::Io)?;
    let mut cache = PipelineCache::default();
    let mut errors = Vec::new();
    for key in graph.pipelines() {
        let spec = pipeline::spec(key.spec).expect("keys come from specs");
        let display = library::display_path(&job.shader_root.join(spec.shader));
        cache.install(&gpu.device, &key, pipelines::compose(&NagaOil, &lib, &key, &display), &lib, &display);
        errors.extend(cache.entries[&key].diagnostics.iter().cloned());
    }
    if !errors.is_empty() {
        return Err(OfflineError::Input(errors));
    }
    let scene_gpu = SceneGpu::new(&gpu.device, &gpu.queue, &loaded.scene, &loaded.meshes);
    Ok(Prepared {
        scene_display: library::display_path(&job.scene),
        size: (loaded.scene.width, loaded.scene.height),
        graph,
        scene_gpu,
        pipelines: cache.live(),
        pool: TexturePool::default(),
        gpu,
    })
}

impl Prepared {
    /// Renders one frame and waits for it. `capture`: `None` captures every
    /// output; otherwise the named ones.
    pub fn frame(&mut self, capture: Option<&BTreeSet<String>>, n: u64) -> FrameResult {
        let pending = frame::submit(
            &self.gpu.device,
            &self.gpu.queue,
            self.gpu.features,
            &self.scene_gpu,
            &self.graph,
            &mut self.pool,
            &self.pipelines,
            capture,
            n,
        );
        while !pending.ready() {
            let _ = self.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        }
        pending.finish()
    }

    /// Errors wgpu reported outside any error scope since the last call.
    pub fn uncaptured(&self) -> Vec<String> {
        std::mem::take(&mut *self.gpu.uncaptured.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

#[derive(Debug, Serialize)]
pub struct FrameReport {
    pub scene: String,
    pub adapter: String,
    pub cpu_adapter: bool,
    pub width: u32,
    pub height: u32,
    /// `gpu` (timestamp queries) or `cpu`.
    pub timing: String,
    pub total_ms: f64,
    pub passes: Vec<PassReport>,
    pub culled: Vec<CulledReport>,
    /// Where a NaN or Inf first appeared; `null` for a clean frame.
    pub nan: Option<NanOrigin>,
    /// wgpu errors no error scope caught (an invalid frame).
    pub gpu_errors: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct PassReport {
    pub name: String,
    pub time_ms: f64,
    pub pipelines: Vec<String>,
    pub reads: Vec<String>,
    pub outputs: Vec<OutputReport>,
}

#[derive(Debug, Serialize)]
pub struct OutputReport {
    pub name: String,
    pub format: String,
    pub width: u32,
    pub height: u32,
    pub stats: ImageStats,
    /// Files written, relative to the output directory.
    pub png: String,
    pub exr: String,
}

#[derive(Debug, Serialize)]
pub struct CulledReport {
    pub name: String,
    pub reason: String,
}

/// Renders `job` once and writes `<pass>.<output>.png` and `.exr` for every
/// output into `out`; returns the report (the caller writes it as JSON).
pub fn render(job: &Job, out: &Path) -> Result<FrameReport, OfflineError> {
    let mut p = prepare(job)?;
    let result = p.frame(None, 1);
    std::fs::create_dir_all(out).map_err(|e| OfflineError::Io(format!("cannot create {}: {e}", out.display())))?;
    let mut passes = Vec::new();
    for pass in &p.graph.passes {
        let mut outputs = Vec::new();
        for c in result.captures.iter().filter(|c| c.pass == pass.name) {
            let stem = format!("{}.{}", c.pass, c.output);
            let write = |name: String, bytes: Vec<u8>| {
                std::fs::write(out.join(&name), bytes).map_err(|e| OfflineError::Io(format!("cannot write {name}: {e}"))).map(|()| name)
            };
            let png = write(format!("{stem}.png"), c.to_png())?;
            let exr = write(format!("{stem}.exr"), c.to_exr().map_err(OfflineError::Io)?)?;
            outputs.push(OutputReport { name: c.output.clone(), format: c.format.clone(), width: c.width, height: c.height, stats: c.stats.clone(), png, exr });
        }
        passes.push(PassReport {
            name: pass.name.clone(),
            time_ms: result.timings.iter().find(|(n, _)| *n == pass.name).map_or(0.0, |(_, t)| *t),
            pipelines: pass.pipelines.iter().map(PipelineKey::label).collect(),
            reads: pass.reads.iter().map(|h| p.graph.texture(*h).name.clone()).collect(),
            outputs,
        });
    }
    Ok(FrameReport {
        scene: p.scene_display.clone(),
        adapter: p.gpu.adapter_name(),
        cpu_adapter: p.gpu.is_cpu(),
        width: p.size.0,
        height: p.size.1,
        timing: result.timing.to_owned(),
        total_ms: result.timings.iter().map(|(_, t)| t).sum(),
        passes,
        culled: p.graph.culled.iter().map(|c| CulledReport { name: c.name.clone(), reason: c.reason.clone() }).collect(),
        nan: result.nan.clone(),
        gpu_errors: p.uncaptured(),
    })
}

/// Per-pass times and capture overhead of one scene.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub adapter: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub timing: String,
    /// Median per pass, milliseconds, in frame order.
    pub passes: Vec<(String, f64)>,
    /// Median wall time from submit to every readback landed, per capture
    /// setting, measured interleaved so drift hits each alike.
    pub frame_ms_no_capture: f64,
    pub frame_ms_final_capture: f64,
    pub frame_ms_all_captures: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

pub fn bench(job: &Job, frames: u32) -> Result<BenchReport, OfflineError> {
    let mut p = prepare(job)?;
    let final_name = p.graph.final_output().map(|h| p.graph.texture(h).name.clone());
    let none = BTreeSet::new();
    let fin: BTreeSet<String> = final_name.into_iter().collect();
    // Warm up: first use compiles driver-side state and allocates targets.
    for i in 0..3 {
        p.frame(None, i);
    }
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut t_none, mut t_final, mut t_all) = (Vec::new(), Vec::new(), Vec::new());
    let mut timing = String::new();
    for i in 0..frames {
        for (set, times) in [(Some(&none), &mut t_none), (Some(&fin), &mut t_final), (None, &mut t_all)] {
            let start = Instant::now();
            let r = p.frame(set, u64::from(i));
            times.push(start.elapsed().as_secs_f64() * 1e3);
            if set.is_some_and(BTreeSet::is_empty) {
                timing = r.timing.to_owned();
                for (name, t) in r.timings {
                    per_pass.entry(name).or_default().push(t);
                }
            }
        }
    }
    let order: Vec<String> = p.graph.passes.iter().map(|x| x.name.clone()).collect();
    Ok(BenchReport {
        scene: p.scene_display.clone(),
        adapter: p.gpu.adapter_name(),
        width: p.size.0,
        height: p.size.1,
        frames,
        timing,
        passes: order.into_iter().map(|n| (n.clone(), median(per_pass.remove(&n).unwrap_or_default()))).collect(),
        frame_ms_no_capture: median(t_none),
        frame_ms_final_capture: median(t_final),
        frame_ms_all_captures: median(t_all),
    })
}
