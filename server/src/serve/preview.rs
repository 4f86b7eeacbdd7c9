//! Material previews for the browser (`GET /api/materials/{index}/preview`):
//! one thread renders them with `render::preview` on the daemon's device,
//! so the render thread never waits for a preview's pipelines or its
//! path-traced samples. The daemon hands each request over with its
//! current sources and scene; requests wait in a queue of `PREVIEW_QUEUE`, and one
//! more is refused as busy.

use std::sync::Arc;
use std::sync::mpsc::{self, SyncSender, TrySendError};

use tokio::sync::oneshot;

use crate::gpu::Gpu;
use crate::loaded::Loaded;
use crate::render::preview::{Materials, Preview, PreviewError, Previewer, Source};
use crate::scene::Renderer;
use crate::shader::Library;

/// Previews that may wait for the preview thread at once.
pub const PREVIEW_QUEUE: usize = 4;

/// A client's request, answered on `reply`.
pub struct Request {
    pub material: usize,
    pub renderer: Renderer,
    pub materials: Materials,
    pub reply: oneshot::Sender<Result<Preview, Failed>>,
}

#[derive(Debug, thiserror::Error)]
pub enum Failed {
    #[error("{PREVIEW_QUEUE} previews are already waiting to be rendered; try again later")]
    Busy,
    #[error(transparent)]
    Preview(#[from] PreviewError),
    #[error("rendering the preview panicked: {0}")]
    Panicked(String),
}

/// What the daemon hands over with a request: the scene and sources as
/// installed now.
pub struct Current {
    pub gpu: Gpu,
    pub device: u32,
    pub lib: Arc<Library>,
    pub loaded: Arc<Loaded>,
}

struct Job {
    request: Request,
    current: Current,
}

/// The way to the preview thread; dropping it ends the thread once the
/// queue is empty.
pub struct Previews {
    tx: SyncSender<Job>,
}

impl Previews {
    /// Starts the preview thread.
    pub fn start(shader_root: &std::path::Path) -> Previews {
        let (tx, rx) = mpsc::sync_channel::<Job>(PREVIEW_QUEUE);
        let root = shader_root.to_owned();
        let spawned = std::thread::Builder::new().name("loupe-preview".into()).stack_size(64 << 20).spawn(move || {
            let mut previewer = Previewer::new(&root);
            for Job { request, current } in rx {
                let source = Source { gpu: &current.gpu, device: current.device, lib: &current.lib, loaded: &current.loaded };
                let rendered = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    previewer.render(source, request.material, request.renderer, request.materials)
                }));
                let answer = match rendered {
                    Ok(r) => r.map_err(Failed::from),
                    Err(panic) => {
                        // Its session may be half-updated: the next starts anew.
                        previewer = Previewer::new(&root);
                        Err(Failed::Panicked(crate::shader::guard::panic_message(&*panic)))
                    }
                };
                // The client may have gone meanwhile.
                let _ = request.reply.send(answer);
            }
        });
        if let Err(e) = spawned {
            log::error!("cannot start the preview thread: {e}");
        }
        Previews { tx }
    }

    /// Queues `request`, or answers it at once when the queue is full.
    pub fn submit(&self, request: Request, current: Current) {
        match self.tx.try_send(Job { request, current }) {
            Ok(()) => {}
            Err(TrySendError::Full(job)) => {
                let _ = job.request.reply.send(Err(Failed::Busy));
            }
            // Without its thread the request's reply is dropped: the
            // client hears that the daemon could not answer.
            Err(TrySendError::Disconnected(_)) => {}
        }
    }
}
