//! `loupe serve`: the hot-reload daemon.
//!
//! Three kinds of threads: the render thread (`daemon`, owns the device),
//! the watcher (`watch`, turns file-system noise into content changes), and
//! tokio's (`http`, clients). They talk only through `Event`s into the render
//! thread (clients' bounded by `inbox`) and `Shared` snapshots out of it.

pub mod daemon;
pub mod display;
pub mod event;
pub mod http;
pub mod inbox;
pub mod last_good;
pub mod materials;
pub mod preview;
pub mod reference_jobs;
pub mod references;
pub mod shared;
pub mod viewer;
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
    start(opts, None)?.serve(async {
        let _ = tokio::signal::ctrl_c().await;
    })
}

/// What `loupe view` lends the daemon: its device, already open (the
/// window renders with it), and the display the daemon copies frames into.
pub struct Attached {
    pub gpu: crate::gpu::Gpu,
    pub display: std::sync::Arc<display::Display>,
}

/// A started daemon whose HTTP side is bound but not yet serving.
pub struct Running {
    shared: std::sync::Arc<shared::Shared>,
    tx: mpsc::Sender<Event>,
    render: std::thread::JoinHandle<()>,
    _watch: watch::WatchGuard,
    runtime: tokio::runtime::Runtime,
    listener: tokio::net::TcpListener,
    local: SocketAddr,
}

/// Starts the watcher and the render thread (opening a device on it,
/// unless `attached` lends one) and binds the port.
pub fn start(opts: ServeOptions, attached: Option<Attached>) -> Result<Running, ServeError> {
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
    let (gpu, display) = match attached {
        Some(a) => (Some(a.gpu), Some(a.display)),
        None => (None, None),
    };
    // The image cases' comparison, idle until a client asks for it.
    references::start(shared.clone(), opts.root.clone(), opts.scene.clone(), shader_root.clone());
    let config =
        Config { shader_root, scene_path: opts.scene.clone(), mode: opts.mode, max_fps: opts.max_fps, watch_files: watch.files(), display };
    let (shared_r, tx_r) = (shared.clone(), tx.clone());
    let render = std::thread::Builder::new()
        .name("loupe-render".into())
        .spawn(move || match gpu.map_or_else(crate::gpu::open, Ok) {
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
    let (listener, local) = runtime.block_on(http::bind(addr)).map_err(|source| ServeError::Bind { addr, source })?;
    if !opts.bind.is_loopback() {
        eprintln!("loupe: warning: listening on {local}, reachable from other machines; loupe has no authentication");
    }
    if opts.debug_api {
        eprintln!("loupe: warning: the debug API is on (POST /api/debug/lose-device destroys the GPU device)");
    }
    Ok(Running { shared, tx, render, _watch: watch, runtime, listener, local })
}

impl Running {
    /// What the daemon publishes, and the clients' way back to it.
    pub fn shared(&self) -> &std::sync::Arc<shared::Shared> {
        &self.shared
    }

    /// The address the port is bound on.
    pub fn local(&self) -> SocketAddr {
        self.local
    }

    /// Serves HTTP until `shutdown` completes (or serving fails), then
    /// stops the render thread.
    pub fn serve(self, shutdown: impl std::future::Future<Output = ()> + Send + 'static) -> Result<(), ServeError> {
        let Running { shared, tx, render, _watch, runtime, listener, local } = self;
        println!("listening on http://{local}");
        let result = runtime
            .block_on(http::serve(listener, shared, http::allowed_hosts(local), shutdown))
            .map_err(|e| ServeError::Other(format!("server error: {e}")));
        let _ = tx.send(Event::Shutdown);
        let _ = render.join();
        result
    }
}
