//! `loupe serve`: the hot-reload daemon.
//!
//! Three kinds of threads: the render thread (`daemon`, owns the device),
//! the watcher (`watch`, turns file-system noise into content changes), and
//! tokio's (`http`, clients). They talk only through `Event`s into the render
//! thread (clients' bounded by `inbox`) and `Shared` snapshots out of it.

pub mod daemon;
pub mod event;
pub mod http;
pub mod inbox;
pub mod materials;
pub mod preview;
pub mod shared;
pub mod watch;

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::mpsc;

use daemon::{Config, Daemon, RenderMode};
use event::Event;

pub struct ServeOptions {
    pub root: PathBuf,
    pub scene: PathBuf,
    pub bind: IpAddr,
    pub port: u16,
    pub mode: RenderMode,
    pub max_fps: f64,
    /// Serve `/api/debug/*` (tests and benchmarks only).
    pub debug_api: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    #[error(transparent)]
    NoDevice(#[from] crate::gpu::OpenError),
    #[error("cannot listen on {addr}: {source}")]
    Bind { addr: SocketAddr, source: std::io::Error },
    #[error("cannot watch sources: {0}")]
    Watch(String),
    #[error("{0}")]
    Other(String),
}

/// Runs the daemon until Ctrl-C. Prints `listening on http://ADDR` once
/// clients can connect.
pub fn run(opts: ServeOptions) -> Result<(), ServeError> {
    let shader_root = opts.root.join("shaders");
    let scene_root = opts.root.join("scenes");
    let (tx, clients, inbox) = inbox::open();
    let shared = shared::Shared::new(clients, vec![shader_root.clone(), scene_root.clone()], opts.debug_api, opts.root.join("tradeoffs"));

    // Watching starts first: the daemon names the scene's files outside the
    // roots to it as soon as it has loaded the scene.
    let roots: Vec<PathBuf> = [shader_root.clone(), scene_root].into_iter().filter(|p| p.is_dir()).collect();
    let watch = watch::NotifyWatcher::default().start(&roots, tx.clone()).map_err(ServeError::Watch)?;

    // The device is opened on the render thread, which then owns it.
    let (ready_tx, ready_rx) = mpsc::channel();
    let config = Config { shader_root, scene_path: opts.scene.clone(), mode: opts.mode, max_fps: opts.max_fps, watch_files: watch.files() };
    let (shared_r, tx_r) = (shared.clone(), tx.clone());
    let render = std::thread::Builder::new()
        .name("loupe-render".into())
        .spawn(move || match crate::gpu::open() {
            Ok(gpu) => {
                for line in &gpu.degraded {
                    eprintln!("loupe: {line}");
                }
                eprintln!("loupe: rendering on {}", gpu.adapter_name());
                // Ready once the daemon has published what the HTTP side
                // reads before the first frame.
                let daemon = Daemon::new(gpu, config, shared_r, tx_r);
                let _ = ready_tx.send(Ok(()));
                daemon.run(inbox);
            }
            Err(e) => {
                let _ = ready_tx.send(Err(e));
            }
        })
        .map_err(|e| ServeError::Other(format!("cannot start the render thread: {e}")))?;
    ready_rx.recv().map_err(|_| ServeError::Other("the render thread died while starting".into()))??;

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| ServeError::Other(format!("cannot start the async runtime: {e}")))?;
    let addr = SocketAddr::new(opts.bind, opts.port);
    let result = runtime.block_on(async {
        let (listener, local) = http::bind(addr).await.map_err(|source| ServeError::Bind { addr, source })?;
        if !opts.bind.is_loopback() {
            eprintln!("loupe: warning: listening on {local}, reachable from other machines; loupe has no authentication");
        }
        if opts.debug_api {
            eprintln!("loupe: warning: the debug API is on (POST /api/debug/lose-device destroys the GPU device)");
        }
        println!("listening on http://{local}");
        let shutdown = async {
            let _ = tokio::signal::ctrl_c().await;
        };
        http::serve(listener, shared, http::allowed_hosts(local), shutdown)
            .await
            .map_err(|e| ServeError::Other(format!("server error: {e}")))
    });
    let _ = tx.send(Event::Shutdown);
    let _ = render.join();
    result
}
