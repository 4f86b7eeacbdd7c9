//! Rendering without a server, on the calling thread over one
//! `render::Session`: `render` writes every pass output and a frame report
//! for scripts and CI golden images; `bench` times each pass and the cost of
//! captures; `denoise` runs the U-Net on image files (`loupe denoise`). All
//! run the same chain as the daemon — scene → graph → pipelines → frame →
//! captures. The tradeoffs sweep (`crate::tradeoffs`) builds on `prepare`
//! and `frame` here.

pub mod bench;
pub mod denoise;
pub mod render;

use std::collections::BTreeSet;
use std::path::PathBuf;

use crate::diag::Diagnostic;
use crate::gpu;
use crate::render::frame::FrameResult;
use crate::render::session::Session;
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
    /// An argument that does not fit the scene (a pixel outside it).
    #[error("{0}")]
    Usage(String),
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

/// Frames a finished image of `scene` takes: the path tracer adds one
/// sample a frame up to `quality.path_spp`; the raster needs one.
pub fn frames_to_finish(scene: &scene::Scene) -> u32 {
    if scene.quality.renderer == Renderer::Path { scene.quality.path_spp } else { 1 }
}
