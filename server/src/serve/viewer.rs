//! `loupe view`: the daemon of `loupe serve` with a native window on its
//! own device. The window (`loupe_view`) reads the daemon through
//! [`InProcess`], the in-process [`Link`]: the events every WebSocket
//! client gets, the inbox commands they send, the display texture the
//! render thread copies each frame into (`display`), and the buffers it
//! captures while the window subscribes to them, as a client does.

use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use loupe_view::{Command, DisplayImage, Inspect, Inspected, Link, Probe, Probed, QuadMap, Range, Tensor, egui_wgpu, window};
use tokio::sync::broadcast::{self, error::TryRecvError};

use super::display::Display;
use super::event::SceneCommand;
use super::http::MAX_SUBSCRIPTIONS;
use super::inbox::{self, Client, MAX_CONNECTIONS};
use super::shared::{self, Shared};
use super::{Attached, ServeError, ServeOptions};
use crate::protocol::{QUAD_STATISTICS, ServerEvent};
use crate::render::capture::CapturedTensor;

#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(transparent)]
    Window(#[from] window::WindowError),
    #[error(transparent)]
    Serve(#[from] ServeError),
}

/// Runs the daemon and the window until the window is closed or Ctrl-C.
/// Checks for a display before opening the device, and opens the device
/// before the window (the window renders with it).
pub fn run(opts: ServeOptions) -> Result<(), ViewError> {
    window::check_display()?;
    let gpu = crate::gpu::open().map_err(ServeError::NoDevice)?;
    let display = Display::new(&gpu);
    let running = super::start(opts, Some(Attached { gpu, display: display.clone() }))?;
    let shared = running.shared().clone();
    let stopped = Arc::new(AtomicBool::new(false));
    let (close_tx, close_rx) = tokio::sync::oneshot::channel::<()>();
    // HTTP on a thread of its own: the window needs the main thread.
    let stop = stopped.clone();
    let http = std::thread::Builder::new()
        .name("loupe-http".into())
        .spawn(move || {
            let result = running.serve(async {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = close_rx => {}
                }
            });
            stop.store(true, Ordering::Relaxed);
            result
        })
        .map_err(|e| ServeError::Other(format!("cannot start the HTTP thread: {e}")))?;
    let shown = windows(&shared, &display, &stopped);
    let _ = close_tx.send(());
    let served = http.join().unwrap_or_else(|_| Err(ServeError::Other("the HTTP thread panicked".into())));
    shown?;
    Ok(served?)
}

/// Runs the window until it is closed. When the device is lost under it,
/// egui's renderer fails on it (panics): the window then reopens on the
/// device the daemon recovered with, and says so.
fn windows(shared: &Arc<Shared>, display: &Arc<Display>, stopped: &Arc<AtomicBool>) -> Result<(), window::WindowError> {
    // Why the window reopens, and how often it failed at once since.
    let mut reopened: Option<(String, u32)> = None;
    loop {
        let replaced = display.replaced();
        let mut link = InProcess::new(shared.clone(), display.clone(), stopped.clone());
        if let Some((message, _)) = &reopened {
            link.snapshot.push(ServerEvent::DeviceLost { message: message.clone(), recovered: true });
        }
        let device = window_device(&display.gpu());
        let shown = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| window::run("loupe view", device, Box::new(link))));
        let panic = match shown {
            Ok(result) => return result,
            Err(panic) => panic,
        };
        // The daemon learns of a loss on its own thread: give it a moment.
        let since = Instant::now();
        while display.replaced() == replaced && since.elapsed() < REPLACEMENT_WAIT {
            std::thread::sleep(Duration::from_millis(50));
        }
        reopened = match reopened {
            _ if display.replaced() != replaced => {
                eprintln!("loupe view: the window's device was lost; reopening on the daemon's new device");
                Some(("the window's device was lost; it reopened on the daemon's new device".to_owned(), 0))
            }
            // On lavapipe the first window on the new device can fail to
            // configure its surface while the old one is torn down.
            Some((message, failed)) if failed < REOPEN_TRIES => Some((message, failed + 1)),
            _ => std::panic::resume_unwind(panic),
        };
        let _ = display.gpu().device.poll(wgpu::PollType::wait_indefinitely());
        std::thread::sleep(REOPEN_PAUSE);
    }
}

/// How long a window that failed waits for the daemon to replace a lost
/// device, how often a reopened window may fail at once, and the pause
/// before each reopening.
const REPLACEMENT_WAIT: Duration = Duration::from_secs(10);
const REOPEN_TRIES: u32 = 3;
const REOPEN_PAUSE: Duration = Duration::from_millis(500);

/// The daemon's device as egui's renderer takes it: the window draws on
/// it, so the display texture needs no copy between devices.
pub fn window_device(gpu: &crate::gpu::Gpu) -> egui_wgpu::WgpuSetupExisting {
    egui_wgpu::WgpuSetupExisting {
        instance: gpu.instance.clone(),
        adapter: gpu.adapter.clone(),
        device: gpu.device.clone(),
        queue: gpu.queue.clone(),
    }
}

/// The window's link to a daemon in this process.
pub struct InProcess {
    shared: Arc<Shared>,
    events: broadcast::Receiver<ServerEvent>,
    /// The snapshot a client starts from, sent on the first poll.
    snapshot: Vec<ServerEvent>,
    display: Arc<Display>,
    stopped: Arc<AtomicBool>,
    /// Held while the link lives: its wake thread ends once it is gone.
    alive: Arc<()>,
    subscribed: Mutex<Subscribed>,
}

/// What the window asked the daemon to capture (buffers, quad
/// statistics), through a client slot of its own, held only while it asks
/// for something.
#[derive(Default)]
struct Subscribed {
    client: Option<Client>,
    tensors: BTreeSet<String>,
    quads: bool,
}

impl Subscribed {
    /// Tells the daemon what the window wants now (as a WebSocket client's
    /// subscriptions: `QUAD_STATISTICS` among the outputs), joining as a
    /// client when it starts wanting something and leaving when it stops.
    fn resubscribe(&mut self, shared: &Shared, tensors: BTreeSet<String>, quads: bool) -> Result<(), String> {
        if (&tensors, quads) == (&self.tensors, self.quads) {
            return Ok(());
        }
        if tensors.len() + usize::from(quads) > MAX_SUBSCRIPTIONS {
            return Err(format!(
                "a client may subscribe to at most {MAX_SUBSCRIPTIONS} outputs ({} asked)",
                tensors.len() + usize::from(quads)
            ));
        }
        let keys: BTreeSet<String> = tensors.iter().cloned().chain(quads.then(|| QUAD_STATISTICS.to_owned())).collect();
        if keys.is_empty() {
            // Dropped, the client tells the daemon it wants nothing more.
            self.client = None;
        } else {
            let client = match &mut self.client {
                Some(client) => client,
                empty => empty.insert(
                    shared.clients.join().ok_or_else(|| format!("the daemon is busy: {MAX_CONNECTIONS} clients are connected to it"))?,
                ),
            };
            client.subscribe(keys);
        }
        (self.tensors, self.quads) = (tensors, quads);
        Ok(())
    }
}

/// A capture's values, lent to the window without a copy.
struct Values(Arc<CapturedTensor>);

impl AsRef<[f32]> for Values {
    fn as_ref(&self) -> &[f32] {
        &self.0.data
    }
}

impl InProcess {
    /// `stopped`: set once the daemon stopped.
    pub fn new(shared: Arc<Shared>, display: Arc<Display>, stopped: Arc<AtomicBool>) -> Self {
        // Subscribed before the snapshot is read, as a WebSocket client,
        // so nothing after it is missed.
        let events = shared.events.subscribe();
        let mut snapshot = vec![shared.hello()];
        snapshot.extend(shared.state_events());
        InProcess { shared, events, snapshot, display, stopped, subscribed: Mutex::default(), alive: Arc::new(()) }
    }

    /// The newest frame's size: its final output's.
    fn frame_size(&self) -> Option<[u32; 2]> {
        let frames = self.shared.frames.borrow();
        let images = frames.as_ref()?;
        let image = images.captures.get(images.final_key.as_ref()?)?;
        Some([image.width, image.height])
    }
}

impl Link for InProcess {
    fn poll(&mut self) -> Vec<serde_json::Value> {
        let mut out: Vec<ServerEvent> = std::mem::take(&mut self.snapshot);
        loop {
            match self.events.try_recv() {
                Ok(e) => out.push(e),
                // Fell behind the event ring: what the panels show is
                // rebuilt from the snapshots instead.
                Err(TryRecvError::Lagged(_)) => out.extend(self.shared.state_events()),
                Err(TryRecvError::Empty | TryRecvError::Closed) => break,
            }
        }
        out.iter().filter_map(|e| serde_json::to_value(e).ok()).collect()
    }

    fn send(&self, command: Command) -> Result<(), String> {
        let command = match command {
            Command::Rebuild => inbox::Command::Rebuild,
            Command::SetOverride { path, value } => {
                // The WebSocket `set_override`'s value, read the same way.
                let value = serde_json::from_value(value).map_err(|e| format!("`{path}`: not a scene value: {e}"))?;
                inbox::Command::Scene(SceneCommand::Set { path, value })
            }
            Command::ClearOverrides => inbox::Command::Scene(SceneCommand::Clear),
            Command::SaveScene => inbox::Command::Scene(SceneCommand::Save),
            Command::ResetHistory => inbox::Command::ResetHistory,
            // Not the daemon's: the watcher sees the write as a save.
            Command::RevertFile { file } => return crate::serve::last_good::revert(&self.shared, &file).map_err(|e| e.to_string()),
        };
        self.shared.clients.command(command).map_err(|e| e.to_string())
    }

    fn source(&self, file: &str) -> Option<String> {
        // Diagnostics name files relative to this process's directory.
        std::fs::read_to_string(file).ok()
    }

    fn display(&self) -> Option<DisplayImage> {
        self.display.current()
    }

    fn set_shown(&self, shown: bool) {
        self.display.set_shown(shown);
    }

    fn set_minimised(&self, minimised: bool) {
        self.display.set_minimised(minimised);
    }

    fn inspect(&self, inspect: Option<Inspect>) {
        self.display.inspect(inspect);
    }

    fn inspected(&self) -> Option<Inspected> {
        self.display.inspected()
    }

    fn probe(&self, probe: Option<Probe>) {
        self.display.probe(probe);
    }

    fn probed(&self) -> Option<Probed> {
        self.display.probed()
    }

    fn measure(&self, inspect: Inspect) {
        self.display.measure(inspect);
    }

    fn measured(&self) -> Option<Range> {
        self.display.measured()
    }

    fn tensors(&self, wanted: BTreeSet<String>) -> Result<(), String> {
        let mut s = self.subscribed.lock().unwrap_or_else(|e| e.into_inner());
        let quads = s.quads;
        s.resubscribe(&self.shared, wanted, quads).map_err(|e| format!("tensors cannot be captured now: {e}"))
    }

    fn quad_statistics(&self, on: bool) -> Result<(), String> {
        let mut s = self.subscribed.lock().unwrap_or_else(|e| e.into_inner());
        let tensors = s.tensors.clone();
        s.resubscribe(&self.shared, tensors, on).map_err(|e| format!("quad statistics refused: {e}"))
    }

    fn quad_map(&self, pass: &str) -> Option<QuadMap> {
        let report = shared::read(&self.shared.quads).clone()?;
        let p = report.passes.iter().find(|p| p.quads.pass == pass)?;
        let (width, height, overdraw, helpers) = p.quads.first_maps()?;
        Some(QuadMap { pass: pass.to_owned(), frame: report.frame, width, height, overdraw, helpers })
    }

    fn debug_pixel(&self, pixel: Option<[u32; 2]>) -> Result<(), String> {
        // The daemon refuses such a pixel too, but only in an event: the
        // window learns it here, before it shows the pixel as pinned.
        if let (Some([x, y]), Some([width, height])) = (pixel, self.frame_size())
            && (x >= width || y >= height)
        {
            return Err(format!("pixel ({x}, {y}) refused: it is outside the {width}x{height} frame"));
        }
        self.shared.clients.command(inbox::Command::DebugPixel(pixel)).map_err(|e| format!("pixel selection refused: {e}"))
    }

    fn tensor(&self, name: &str) -> Option<Tensor> {
        let t = shared::read(&self.shared.tensors).get(name)?.clone();
        Some(Tensor {
            name: t.key(),
            frame: t.frame,
            dims: t.layout.dims.iter().map(|(n, size)| ((*n).to_owned(), *size)).collect(),
            min: t.stats.min.clone(),
            max: t.stats.max.clone(),
            nan: t.stats.nan,
            inf: t.stats.inf,
            values: Arc::new(Values(t)),
        })
    }

    fn wake_with(&mut self, wake: Box<dyn Fn() + Send + Sync>) {
        // A thread of its own waits for the daemon's events; it ends at the
        // first event after this link is dropped (or when the daemon is).
        let mut events = self.shared.events.subscribe();
        let alive = Arc::downgrade(&self.alive);
        let spawned = std::thread::Builder::new().name("loupe-view-wake".into()).spawn(move || {
            while alive.strong_count() > 0 {
                match events.blocking_recv() {
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => wake(),
                    Err(broadcast::error::RecvError::Closed) => break,
                }
            }
        });
        if let Err(e) = spawned {
            log::warn!("loupe view repaints without being woken: {e}");
        }
    }

    fn closed(&self) -> bool {
        self.stopped.load(Ordering::Relaxed)
    }
}
