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
use crate::gpu;
use crate::render::capture::{ImageStats, TensorStats};
use crate::render::frame::{FrameResult, NanOrigin};
use crate::render::quads::{DrawReport, WhatIf};
use crate::render::resource::TensorLayout;
use crate::render::session::{PassState, PassSummary, Session};
use crate::scene::{self, Renderer, overrides::Overrides};
use crate::shader::library;

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

/// Offline frames are a fixed time apart, so temporal passes (auto
/// exposure) give the same result on every run and machine.
pub const FRAME_DT: f32 = 1.0 / 30.0;

/// Opens the device, loads the scene (with overrides and size applied)
/// and builds every pipeline its graph needs.
pub fn prepare(job: &Job) -> Result<Session, OfflineError> {
    let mut loaded = crate::loaded::load_with(&job.scene, &job.overrides).map_err(|d| OfflineError::Input(vec![d]))?;
    if let Some((w, h)) = job.size {
        loaded.scene.width = w;
        loaded.scene.height = h;
    }
    let gpu = gpu::open()?;
    let lib = library::read_tree(&job.shader_root).map_err(OfflineError::Io)?;
    let mut session = Session::new(gpu, &job.shader_root, lib, &loaded);
    let errors = session.install_missing();
    if !errors.is_empty() {
        return Err(OfflineError::Input(errors));
    }
    Ok(session)
}

/// Renders one frame and waits for it. `capture`: `None` captures every
/// output; otherwise the named ones.
pub fn frame(session: &mut Session, capture: Option<&BTreeSet<String>>) -> FrameResult {
    let pending = session.submit(capture, FRAME_DT);
    session.wait(pending)
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

/// A live pass: the session's summary, its time and what was written.
#[derive(Debug, Serialize)]
pub struct PassReport {
    #[serde(flatten)]
    pub pass: PassSummary,
    /// `null` without timestamp queries (only the frame total is known).
    pub time_ms: Option<f64>,
    pub outputs: Vec<OutputReport>,
    /// Raster passes: each draw's quad statistics (docs/quads.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub draws: Option<Vec<DrawReport>>,
    /// The draws summed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quads: Option<DrawReport>,
    /// Fullscreen passes: the other mode (one triangle or two) modelled.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub what_if: Option<WhatIf>,
    /// Fragment-shader invocations the adapter counted over the pass
    /// (pipeline statistics), where it can.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fragment_invocations: Option<u64>,
}

#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum OutputReport {
    Image {
        name: String,
        format: String,
        width: u32,
        height: u32,
        stats: ImageStats,
        /// Files written, relative to the output directory.
        png: String,
        exr: String,
    },
    Tensor {
        name: String,
        layout: TensorLayout,
        stats: TensorStats,
        /// A NumPy array of f32, relative to the output directory.
        npy: String,
    },
}

#[derive(Debug, Serialize)]
pub struct CulledReport {
    pub name: String,
    pub reason: String,
}

/// Frames a finished image of `scene` takes: the path tracer adds one
/// sample a frame up to `quality.path_spp`; the raster needs one.
pub fn frames_to_finish(scene: &scene::Scene) -> u32 {
    if scene.quality.renderer == Renderer::Path { scene.quality.path_spp } else { 1 }
}

/// Renders `job` once and writes `<pass>.<output>.png` and `.exr` for every
/// texture and `.npy` for every buffer into `out`; returns the report (the
/// caller writes it as JSON).
pub fn render(job: &Job, out: &Path) -> Result<FrameReport, OfflineError> {
    let mut session = prepare(job)?;
    // The path tracer adds a sample a frame: the frames before the last
    // accumulate, uncaptured.
    for _ in 1..frames_to_finish(session.scene()) {
        frame(&mut session, Some(&BTreeSet::new()));
    }
    session.set_quads(true);
    let result = frame(&mut session, None);
    std::fs::create_dir_all(out).map_err(|e| OfflineError::Io(format!("cannot create {}: {e}", out.display())))?;
    let write = |name: String, bytes: Vec<u8>| {
        std::fs::write(out.join(&name), bytes).map_err(|e| OfflineError::Io(format!("cannot write {name}: {e}"))).map(|()| name)
    };
    let mut passes = Vec::new();
    let mut culled = Vec::new();
    for pass in session.passes() {
        if pass.status == PassState::Culled {
            culled.push(CulledReport { name: pass.name, reason: pass.reason.unwrap_or_default() });
            continue;
        }
        let mut outputs = Vec::new();
        for c in result.captures.iter().filter(|c| c.pass == pass.name) {
            let stem = format!("{}.{}", c.pass, c.output);
            let png = write(format!("{stem}.png"), c.to_png())?;
            let exr = write(format!("{stem}.exr"), c.to_exr().map_err(OfflineError::Io)?)?;
            outputs.push(OutputReport::Image {
                name: c.output.clone(),
                format: c.format.clone(),
                width: c.width,
                height: c.height,
                stats: c.stats.clone(),
                png,
                exr,
            });
        }
        for t in result.tensors.iter().filter(|t| t.pass == pass.name) {
            let shape: Vec<usize> = t.layout.dims.iter().map(|&(_, n)| n as usize).collect();
            let npy = write(format!("{}.{}.npy", t.pass, t.output), crate::npy::encode(&shape, &t.data))?;
            outputs.push(OutputReport::Tensor { name: t.output.clone(), layout: t.layout.clone(), stats: t.stats.clone(), npy });
        }
        let time_ms = result.timings.iter().find(|(n, _)| *n == pass.name).map(|(_, t)| *t);
        let fragment_invocations = result.fragment_invocations.iter().find(|(n, _)| *n == pass.name).map(|(_, c)| *c);
        let q = result.quads.iter().find(|q| q.pass == pass.name).cloned();
        let (draws, quads, what_if) = match q {
            Some(q) => (Some(q.draws), Some(q.quads), q.what_if),
            None => (None, None, None),
        };
        passes.push(PassReport { pass, time_ms, outputs, draws, quads, what_if, fragment_invocations });
    }
    let (width, height) = (session.scene().width, session.scene().height);
    Ok(FrameReport {
        scene: library::display_path(&job.scene),
        adapter: session.gpu().adapter_name(),
        cpu_adapter: session.gpu().is_cpu(),
        width,
        height,
        timing: result.timing.to_owned(),
        total_ms: result.total_ms,
        passes,
        culled,
        nan: result.nan.clone(),
        gpu_errors: session.take_uncaptured(),
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
    /// Median wall time from submit to every readback landed (what the
    /// thread that submits frames waits for), per capture setting,
    /// measured interleaved so drift hits each alike.
    pub frame_ms_no_capture: f64,
    pub frame_ms_final_capture: f64,
    pub frame_ms_all_captures: f64,
    /// Median time converting the landed readbacks and taking their
    /// statistics, which `serve` does on a thread of its own.
    pub convert_ms_final_capture: f64,
    pub convert_ms_all_captures: f64,
    /// The same two times with quad statistics on (no captures): the
    /// vertex captures and depth copies on the GPU, then the model's replay
    /// on the conversion thread.
    pub frame_ms_quads: f64,
    pub convert_ms_quads: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

/// `serial`: per-pass times from an extra frame each round that submits
/// each pass alone and waits for it (wall clock), instead of from the
/// uncaptured frame's timestamps.
pub fn bench(job: &Job, frames: u32, serial: bool) -> Result<BenchReport, OfflineError> {
    let mut session = prepare(job)?;
    let none = BTreeSet::new();
    let fin: BTreeSet<String> = session.graph().final_name().into_iter().collect();
    // Warm up: first use compiles driver-side state and allocates targets.
    for _ in 0..3 {
        frame(&mut session, None);
    }
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let [mut t_none, mut t_final, mut t_all, mut t_quads, mut c_none, mut c_final, mut c_all, mut c_quads] =
        std::array::from_fn(|_| Vec::new());
    let mut timing = String::new();
    for _ in 0..frames {
        let settings = [
            (Some(&none), false, &mut t_none, &mut c_none),
            (Some(&fin), false, &mut t_final, &mut c_final),
            (None, false, &mut t_all, &mut c_all),
            (Some(&none), true, &mut t_quads, &mut c_quads),
        ];
        for (set, quads, times, converts) in settings {
            session.set_quads(quads);
            let start = Instant::now();
            let pending = session.submit(set, FRAME_DT);
            session.land(&pending);
            let landed = Instant::now();
            let r = pending.finish();
            times.push((landed - start).as_secs_f64() * 1e3);
            converts.push(landed.elapsed().as_secs_f64() * 1e3);
            if set.is_some_and(BTreeSet::is_empty) && !quads && !serial {
                timing = r.timing.to_owned();
                for (name, t) in r.timings {
                    per_pass.entry(name).or_default().push(t);
                }
            }
        }
        if serial {
            session.set_quads(false);
            session.set_serial(true);
            let r = frame(&mut session, Some(&none));
            session.set_serial(false);
            timing = r.timing.to_owned();
            for (name, t) in r.timings {
                per_pass.entry(name).or_default().push(t);
            }
        }
    }
    let order: Vec<String> = session.graph().passes.iter().map(|x| x.name.clone()).collect();
    Ok(BenchReport {
        scene: library::display_path(&job.scene),
        adapter: session.gpu().adapter_name(),
        width: session.scene().width,
        height: session.scene().height,
        frames,
        timing,
        passes: order.into_iter().map(|n| (n.clone(), median(per_pass.remove(&n).unwrap_or_default()))).collect(),
        frame_ms_no_capture: median(t_none),
        frame_ms_final_capture: median(t_final),
        frame_ms_all_captures: median(t_all),
        convert_ms_final_capture: median(c_final),
        convert_ms_all_captures: median(c_all),
        frame_ms_quads: median(t_quads),
        convert_ms_quads: median(c_quads),
    })
}
