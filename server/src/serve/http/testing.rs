//! Test fixtures of the http layer, for its tests: a server on a free port, a raw HTTP/1.1
//! client (requests go out byte for byte, as no client library would send
//! them), temporary directories and a WebSocket client.

use std::collections::BTreeMap;
use std::io;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use futures_util::StreamExt;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::{self, client::IntoClientRequest};

use super::{allowed_hosts, bind, serve};
use crate::render::capture::CapturedImage;
use crate::serve::event::Event;
use crate::serve::inbox::{self, Inbox};
use crate::serve::shared::{FrameImages, Shared};

/// A server on a free loopback port. `daemon` receives what the server
/// sends to the daemon; no daemon runs, so nothing reads it unless a test
/// does.
pub(super) struct Server {
    pub addr: SocketAddr,
    pub shared: Arc<Shared>,
    pub daemon: Inbox,
    /// Send to shut the server down.
    pub stop: Option<tokio::sync::oneshot::Sender<()>>,
    pub done: tokio::task::JoinHandle<io::Result<()>>,
}

pub(super) async fn start(roots: Vec<PathBuf>) -> Server {
    start_with(roots, false).await
}

pub(super) async fn start_with(roots: Vec<PathBuf>, debug_api: bool) -> Server {
    let (_, clients, daemon) = inbox::open();
    // The first root stands for the project: its results are under it.
    let tradeoffs = roots.first().map(|r| r.join("tradeoffs")).unwrap_or_default();
    let shared = Shared::new(clients, roots, debug_api, tradeoffs);
    let (listener, addr) = bind("127.0.0.1:0".parse().unwrap()).await.unwrap();
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let done = tokio::spawn(serve(listener, shared.clone(), allowed_hosts(addr), async move {
        let _ = stopped.await;
    }));
    Server { addr, shared, daemon, stop: Some(stop), done }
}

pub(super) struct Reply {
    pub status: u16,
    pub headers: String,
    pub body: Vec<u8>,
}

impl Reply {
    pub fn header(&self, name: &str) -> Option<String> {
        self.headers.lines().find_map(|l| {
            let (n, v) = l.split_once(':')?;
            n.trim().eq_ignore_ascii_case(name).then(|| v.trim().to_owned())
        })
    }
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_slice(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text()))
    }
}

/// Sends `request` byte for byte (no client normalizes it) and reads the
/// whole reply.
pub(super) async fn raw(addr: SocketAddr, request: &str) -> Reply {
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(request.as_bytes()).await.unwrap();
    let mut buf = Vec::new();
    tokio::time::timeout(Duration::from_secs(10), s.read_to_end(&mut buf)).await.unwrap().unwrap();
    let split = buf.windows(4).position(|w| w == b"\r\n\r\n").expect("no header end");
    let head = String::from_utf8(buf[..split].to_vec()).unwrap();
    let mut body = buf[split + 4..].to_vec();
    let status = head.split(' ').nth(1).unwrap().parse().unwrap();
    let reply = Reply { status, headers: head, body: Vec::new() };
    if reply.header("transfer-encoding").is_some_and(|v| v.contains("chunked")) {
        let mut out = Vec::new();
        let mut rest = &body[..];
        loop {
            let end = rest.windows(2).position(|w| w == b"\r\n").unwrap();
            let n = usize::from_str_radix(std::str::from_utf8(&rest[..end]).unwrap().trim(), 16).unwrap();
            if n == 0 {
                break;
            }
            out.extend_from_slice(&rest[end + 2..end + 2 + n]);
            rest = &rest[end + 4 + n..];
        }
        body = out;
    }
    Reply { body, ..reply }
}

pub(super) async fn request(addr: SocketAddr, method: &str, path: &str, extra: &str) -> Reply {
    let req = format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\n{extra}Connection: close\r\nContent-Length: 0\r\n\r\n");
    raw(addr, &req).await
}

pub(super) async fn get(addr: SocketAddr, path: &str) -> Reply {
    request(addr, "GET", path, "").await
}

pub(super) fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loupe-http-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(super) type Ws = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<TcpStream>>;

pub(super) async fn connect(addr: SocketAddr, origin: Option<&str>) -> Result<Ws, tungstenite::Error> {
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    if let Some(o) = origin {
        req.headers_mut().insert("origin", o.parse().unwrap());
    }
    tokio_tungstenite::connect_async(req).await.map(|(ws, _)| ws)
}

pub(super) async fn next_message(ws: &mut Ws) -> tungstenite::Message {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), ws.next())
            .await
            .expect("timed out waiting for a message")
            .expect("stream ended")
            .expect("websocket error");
        if !matches!(m, tungstenite::Message::Ping(_) | tungstenite::Message::Pong(_)) {
            return m;
        }
    }
}

pub(super) async fn next_json(ws: &mut Ws) -> serde_json::Value {
    match next_message(ws).await {
        tungstenite::Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
        other => panic!("expected text, got {other:?}"),
    }
}

pub(super) fn daemon_event(server: &Server) -> Option<Event> {
    server.daemon.recv_timeout(Duration::from_secs(5)).ok()
}

/// The next event the daemon got, from a blocking receive.
pub(super) async fn daemon_event_async(s: Server) -> (Option<Event>, Server) {
    tokio::task::spawn_blocking(move || (daemon_event(&s), s)).await.unwrap()
}

/// `hdr/color` (2x1) whose values say which frame it is.
pub(super) fn frame_images(frame: u64) -> Option<Arc<FrameImages>> {
    let v = frame as f32;
    let ldr = CapturedImage::new("tonemap", "color", frame, 1, 1, wgpu::TextureFormat::Rgba8UnormSrgb, vec![1.0, 0.0, 0.0, 1.0]);
    let hdr = CapturedImage::new("hdr", "color", frame, 2, 1, wgpu::TextureFormat::Rgba16Float, vec![v, -1.5, 2.0, 1.0, 0.5, v, 0.0, 1.0]);
    let captures = BTreeMap::from([(ldr.key(), Arc::new(ldr)), (hdr.key(), Arc::new(hdr))]);
    Some(Arc::new(FrameImages::new(frame, Some("tonemap/color".into()), captures)))
}
