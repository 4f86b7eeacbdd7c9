//! `loupe render`: one frame, every pass output written as PNG and
//! OpenEXR (tensors as NumPy arrays), and the frame's report.

use std::collections::BTreeSet;
use std::path::Path;

use serde::Serialize;

use super::{Job, OfflineError, frame, frames_to_finish, prepare};
use crate::diag::display_path;
use crate::render::capture::{ImageStats, TensorStats};
use crate::render::debug_print::Printed;
use crate::render::frame::NanOrigin;
use crate::render::passes::classify::Statistics;
use crate::render::quads::{DrawReport, WhatIf};
use crate::render::resource::TensorLayout;
use crate::render::session::{PassState, PassSummary};

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
    /// Tile classification's pixels and tiles per class and the material
    /// bytes written; `null` when the frame classified nothing.
    pub tiles: Option<Statistics>,
    /// wgpu errors no error scope caught (an invalid frame).
    pub gpu_errors: Vec<String>,
    /// With `--debug-pixel`: what the frame's `debugPrintf`s printed there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prints: Option<PrintsReport>,
    /// With `--debug-pixel`: the pixel's history through the frame
    /// (docs/pixel-history.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub history: Option<crate::render::pixel_history::PixelHistory>,
}

/// The prints at the selected pixel (docs/printf.md).
#[derive(Debug, Serialize)]
pub struct PrintsReport {
    /// The pipelines that ran instrumented.
    pub pipelines: Vec<String>,
    #[serde(flatten)]
    pub printed: Printed,
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

/// Renders `job` once and writes `<pass>.<output>.png` and `.exr` for every
/// texture and `.npy` for every buffer into `out`; returns the report (the
/// caller writes it as JSON). With `debug_pixel`, the last frame runs the
/// pipelines that print instrumented for that pixel.
pub fn run(job: &Job, out: &Path, debug_pixel: Option<[u32; 2]>) -> Result<FrameReport, OfflineError> {
    let mut session = prepare(job)?;
    let (width, height) = (session.scene().width, session.scene().height);
    if let Some([x, y]) = debug_pixel
        && (x >= width || y >= height)
    {
        return Err(OfflineError::Usage(format!("--debug-pixel {x},{y} is outside the {width}x{height} frame")));
    }
    // The path tracer adds a sample a frame: the frames before the last
    // accumulate, uncaptured.
    for _ in 1..frames_to_finish(session.scene()) {
        frame(&mut session, Some(&BTreeSet::new()));
    }
    session.set_quads(true);
    session.set_debug_pixel(debug_pixel);
    let result = frame(&mut session, None);
    let prints = session.debug_prints().map(|selection| PrintsReport {
        pipelines: selection.printing().map(|k| k.label()).collect(),
        printed: result.prints.clone().unwrap_or(Printed { pixel: selection.pixel(), ..Printed::default() }),
    });
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
    Ok(FrameReport {
        scene: display_path(&job.scene),
        adapter: session.gpu().adapter_name(),
        cpu_adapter: session.gpu().is_cpu(),
        width,
        height,
        timing: result.timing.to_owned(),
        total_ms: result.total_ms,
        passes,
        culled,
        nan: result.nan.clone(),
        tiles: Statistics::of_frame(&result.tensors),
        gpu_errors: session.take_uncaptured(),
        prints,
        history: result.history.clone(),
    })
}
