//! The HTTP + WebSocket layer: the JSON API, capture downloads, source
//! excerpts, the live event/frame stream and the embedded UI. PROTOCOL.md at
//! the repository root documents every route and shape.
//!
//! Architecture Invariant: this is the only module that encodes JSON for the
//! daemon's clients. Handlers never block the render thread: they read the
//! snapshots in [`Shared`] and send [`Event`]s back.
//!
//! Security (a dev server on localhost is still reachable from every web page
//! the user opens):
//! - every request must carry a `Host` that is one of the allowed hosts
//!   (DNS-rebinding defence), else 403;
//! - WebSocket upgrades and state-changing requests (any method but GET,
//!   HEAD, OPTIONS) that carry an `Origin` must come from `http://` + an
//!   allowed host, else 403 (cross-site request and WebSocket hijacking
//!   defence); a missing `Origin` is allowed (non-browser clients);
//! - `/api/sources/...` serves only regular files whose canonical path lies
//!   inside a canonicalized source root.
//!
//! Startup: [`bind`] the address (port 0 picks a free port and returns the
//! real one), compute [`allowed_hosts`] from the bound address, then
//! [`serve`] until the shutdown future completes.

use std::collections::{BTreeMap, BTreeSet};
use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use axum::Router;
use axum::body::Body;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path as UrlPath, Query, Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, Uri, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get, post};
use rust_embed::RustEmbed;
use serde::{Deserialize, Serialize};
use tokio::net::TcpListener;
use tokio::sync::broadcast::error::RecvError;
use tokio::sync::watch;

use super::event::{Event, SceneCommand};
use super::shared::{FrameImages, Shared, read};
use crate::protocol::{ClientMessage, DiagnosticsReport, Encoding, ServerEvent, VERSION};
use crate::render::capture::{CapturedImage, ImageStats};

/// The web UI, from the repository's `client/` directory (the path is
/// relative to `server/Cargo.toml`). Debug builds read it from disk.
#[derive(RustEmbed)]
#[folder = "../client/"]
struct Client;

/// The largest source file `/api/sources` serves.
const MAX_SOURCE_BYTES: u64 = 16 * 1024 * 1024;
/// The largest message a WebSocket client may send.
const MAX_CLIENT_MESSAGE: usize = 1024 * 1024;
/// How often pending skipped-frame counts are reported when no event is
/// flowing to carry them.
const DROPPED_REPORT_INTERVAL: Duration = Duration::from_secs(1);

struct AppState {
    shared: Arc<Shared>,
    /// Lowercased `host:port` values a request's `Host` may name.
    hosts: Vec<String>,
    /// Set to true when the server shuts down: WebSocket tasks close.
    stop: watch::Sender<bool>,
    /// Ids for WebSocket clients (their subscriptions are per client).
    next_client: AtomicU64,
}

/// Binds a TCP listener; port 0 picks a free port. Returns the listener and
/// the address actually bound (what [`allowed_hosts`] needs).
pub async fn bind(addr: SocketAddr) -> io::Result<(TcpListener, SocketAddr)> {
    let listener = TcpListener::bind(addr).await?;
    let local = listener.local_addr()?;
    Ok((listener, local))
}

/// The `Host` values to accept for a server bound to `local`:
/// `127.0.0.1:PORT`, `localhost:PORT`, `[::1]:PORT`, plus `local` itself when
/// it is neither loopback nor unspecified (`0.0.0.0`/`::` accept only the
/// loopback names; add others explicitly). On port 80 the port-less forms
/// are accepted too, since browsers omit a default port.
pub fn allowed_hosts(local: SocketAddr) -> Vec<String> {
    let port = local.port();
    let mut hosts = vec![format!("127.0.0.1:{port}"), format!("localhost:{port}"), format!("[::1]:{port}")];
    if !local.ip().is_loopback() && !local.ip().is_unspecified() {
        hosts.push(local.to_string());
    }
    if port == 80 {
        let bare: Vec<String> = hosts.iter().filter_map(|h| h.rsplit_once(':').map(|(h, _)| h.to_owned())).collect();
        hosts.extend(bare);
    }
    hosts
}

/// The whole application: API, WebSocket, static UI, and the Host/Origin
/// guard. `allowed_hosts` are `host:port` strings compared
/// case-insensitively (see [`allowed_hosts`]).
pub fn router(shared: Arc<Shared>, allowed_hosts: Vec<String>) -> Router {
    build(shared, allowed_hosts).0
}

/// Serves `router(shared, allowed_hosts)` on `listener` until `shutdown`
/// completes, then closes every WebSocket (code 1001) and waits for open
/// HTTP requests to finish. It does not tell the daemon to stop: send
/// `Event::Shutdown` after it returns if that is wanted.
pub async fn serve(
    listener: TcpListener,
    shared: Arc<Shared>,
    allowed_hosts: Vec<String>,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> io::Result<()> {
    let (app, stop) = build(shared, allowed_hosts);
    axum::serve(listener, app)
        .with_graceful_shutdown(async move {
            shutdown.await;
            stop.send_replace(true);
        })
        .await
}

fn build(shared: Arc<Shared>, allowed_hosts: Vec<String>) -> (Router, watch::Sender<bool>) {
    let stop = watch::Sender::new(false);
    let state = Arc::new(AppState {
        shared,
        hosts: allowed_hosts.into_iter().map(|h| h.to_ascii_lowercase()).collect(),
        stop: stop.clone(),
        next_client: AtomicU64::new(1),
    });
    let mut app = Router::new();
    if state.shared.debug_api {
        app = app.route("/api/debug/lose-device", post(lose_device));
    }
    let app = app
        .route("/api/status", get(status))
        .route("/api/passes", get(passes))
        .route("/api/pipelines", get(pipelines))
        .route("/api/diagnostics", get(diagnostics))
        .route("/api/captures", get(captures))
        .route("/api/captures/{pass}/{file}", get(capture))
        .route("/api/sources/{*path}", get(source))
        .route("/api/reload", post(reload))
        .route("/api/controls", get(controls))
        .route("/api/scene/save", post(save_scene))
        .route("/api", any(api_not_found))
        .route("/api/{*rest}", any(api_not_found))
        .route("/ws", get(ws))
        .route("/", get(index))
        .fallback(static_file)
        .layer(middleware::from_fn_with_state(state.clone(), guard))
        .with_state(state);
    (app, stop)
}

// ---------------------------------------------------------------- responses

#[derive(Serialize)]
struct ErrorBody<'a> {
    error: &'a str,
}

fn json_response<T: Serialize + ?Sized>(status: StatusCode, value: &T) -> Response {
    match serde_json::to_vec(value) {
        Ok(body) => (status, [(header::CONTENT_TYPE, "application/json")], body).into_response(),
        Err(e) => {
            let body = serde_json::to_vec(&ErrorBody { error: &format!("cannot encode response: {e}") })
                .unwrap_or_default();
            (StatusCode::INTERNAL_SERVER_ERROR, [(header::CONTENT_TYPE, "application/json")], body).into_response()
        }
    }
}

fn json<T: Serialize + ?Sized>(value: &T) -> Response {
    json_response(StatusCode::OK, value)
}

fn error(status: StatusCode, message: &str) -> Response {
    json_response(status, &ErrorBody { error: message })
}

fn is_api(path: &str) -> bool {
    path == "/api" || path.starts_with("/api/")
}

fn is_json(headers: &HeaderMap) -> bool {
    headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"))
}

/// Every error becomes `{"error": "..."}` (axum's own rejections — 405,
/// a bad query, a failed WebSocket handshake — are plain text), `/api`
/// responses get `Cache-Control: no-store`, everything gets `nosniff`.
fn finish(mut resp: Response, api: bool) -> Response {
    let status = resp.status();
    if (status.is_client_error() || status.is_server_error()) && !is_json(resp.headers()) {
        let message = status.canonical_reason().unwrap_or("error").to_ascii_lowercase();
        let fresh = error(status, &message);
        let (mut parts, _) = resp.into_parts();
        let (fresh_parts, body) = fresh.into_parts();
        parts.headers.remove(header::CONTENT_LENGTH);
        for (name, value) in fresh_parts.headers.iter() {
            parts.headers.insert(name, value.clone());
        }
        resp = Response::from_parts(parts, body);
    }
    let headers = resp.headers_mut();
    if api {
        headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    }
    headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    resp
}

// -------------------------------------------------------------------- guard

fn host_allowed(hosts: &[String], req: &Request) -> bool {
    let mut values = req.headers().get_all(header::HOST).iter();
    let host = match (values.next(), values.next()) {
        (Some(v), None) => match v.to_str() {
            Ok(v) => Some(v.to_ascii_lowercase()),
            Err(_) => return false,
        },
        (None, _) => None,
        (Some(_), Some(_)) => return false,
    };
    // An absolute-form request target names its own authority; it must be
    // allowed too (and it is what HTTP/2 clients send instead of Host).
    let authority = req.uri().authority().map(|a| a.as_str().to_ascii_lowercase());
    let ok = |h: &str| hosts.iter().any(|a| a == h);
    match (host, authority) {
        (None, None) => false,
        (Some(h), None) | (None, Some(h)) => ok(&h),
        (Some(h), Some(a)) => ok(&h) && ok(&a),
    }
}

fn origin_allowed(hosts: &[String], origin: &HeaderValue) -> bool {
    let Ok(origin) = origin.to_str() else { return false };
    let origin = origin.to_ascii_lowercase();
    origin.strip_prefix("http://").is_some_and(|h| hosts.iter().any(|a| a == h))
}

async fn guard(State(st): State<Arc<AppState>>, req: Request, next: Next) -> Response {
    let api = is_api(req.uri().path());
    if !host_allowed(&st.hosts, &req) {
        return finish(
            error(StatusCode::FORBIDDEN, "host not allowed: open the UI through localhost or 127.0.0.1"),
            api,
        );
    }
    let state_changing = !matches!(*req.method(), Method::GET | Method::HEAD | Method::OPTIONS);
    let upgrade = req.headers().contains_key(header::UPGRADE) || req.uri().path() == "/ws";
    if state_changing || upgrade {
        let origins: Vec<&HeaderValue> = req.headers().get_all(header::ORIGIN).iter().collect();
        let ok = match origins.as_slice() {
            [] => true,
            [one] => origin_allowed(&st.hosts, one),
            _ => false,
        };
        if !ok {
            return finish(error(StatusCode::FORBIDDEN, "cross-origin request refused"), api);
        }
    }
    let resp = next.run(req).await;
    finish(resp, api)
}

// ---------------------------------------------------------------------- api

async fn status(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.status))
}

async fn passes(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.passes))
}

async fn pipelines(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.pipelines))
}

async fn diagnostics(State(st): State<Arc<AppState>>) -> Response {
    json(&DiagnosticsReport { diagnostics: read(&st.shared.diagnostics) })
}

async fn api_not_found() -> Response {
    error(StatusCode::NOT_FOUND, "no such API route")
}

#[derive(Deserialize)]
struct VersionQuery {
    version: Option<String>,
}

type Captures = Arc<std::collections::BTreeMap<String, Arc<CapturedImage>>>;

/// Which set of captures a request asks for; a 400 for an unknown version.
fn capture_set(shared: &Shared, version: Option<&str>) -> Result<Captures, Box<Response>> {
    match version {
        None | Some("current") => Ok(read(&shared.captures)),
        Some("last_good") => Ok(read(&shared.last_good)),
        Some(other) => Err(Box::new(error(
            StatusCode::BAD_REQUEST,
            &format!("unknown version `{other}`: expected `current` or `last_good`"),
        ))),
    }
}

#[derive(Serialize)]
struct CaptureInfo<'a> {
    pass: &'a str,
    output: &'a str,
    frame: u64,
    width: u32,
    height: u32,
    format: &'a str,
    stats: &'a ImageStats,
    /// Whether `?version=last_good` has this output too (always true when
    /// the list itself is the last good set).
    last_good: bool,
    /// Whether this is the frame's final output.
    #[serde(rename = "final")]
    is_final: bool,
}

async fn captures(State(st): State<Arc<AppState>>, Query(q): Query<VersionQuery>) -> Response {
    let set = match capture_set(&st.shared, q.version.as_deref()) {
        Ok(set) => set,
        Err(resp) => return *resp,
    };
    let last_good = read(&st.shared.last_good);
    let final_key = st.shared.frames.borrow().as_ref().and_then(|f| f.final_key.clone());
    let list: Vec<CaptureInfo> = set
        .iter()
        .map(|(key, img)| CaptureInfo {
            pass: &img.pass,
            output: &img.output,
            frame: img.frame,
            width: img.width,
            height: img.height,
            format: &img.format,
            stats: &img.stats,
            last_good: last_good.contains_key(key),
            is_final: final_key.as_ref() == Some(key),
        })
        .collect();
    json(&list)
}

async fn capture(
    State(st): State<Arc<AppState>>,
    UrlPath((pass, file)): UrlPath<(String, String)>,
    Query(q): Query<VersionQuery>,
) -> Response {
    let Some((output, ext)) = file.rsplit_once('.') else {
        return error(StatusCode::BAD_REQUEST, "missing extension: expected .png, .f32, .f16 or .exr");
    };
    if !matches!(ext, "png" | "f32" | "f16" | "exr") {
        return error(
            StatusCode::BAD_REQUEST,
            &format!("unknown extension `.{ext}`: expected .png, .f32, .f16 or .exr"),
        );
    }
    let set = match capture_set(&st.shared, q.version.as_deref()) {
        Ok(set) => set,
        Err(resp) => return *resp,
    };
    let key = format!("{pass}/{output}");
    let Some(img) = set.get(&key).cloned() else {
        let which = if q.version.as_deref() == Some("last_good") { "last good capture" } else { "capture" };
        return error(StatusCode::NOT_FOUND, &format!("no {which} of `{key}`"));
    };
    let ext = ext.to_owned();
    let (mime, channels) = match ext.as_str() {
        "png" => ("image/png", None),
        "exr" => ("image/x-exr", None),
        _ => ("application/octet-stream", Some("4")),
    };
    // Encoding a large float image takes a while: keep it off the reactor.
    let encoded = tokio::task::spawn_blocking(move || {
        let body = match ext.as_str() {
            "png" => Ok(img.to_png()),
            "exr" => img.to_exr(),
            "f32" => Ok(img.raw_f32()),
            _ => Ok(img.raw_f16()),
        };
        (img, body)
    })
    .await;
    let (img, body) = match encoded {
        Ok(x) => x,
        Err(e) => return error(StatusCode::INTERNAL_SERVER_ERROR, &format!("encoding failed: {e}")),
    };
    let body = match body {
        Ok(b) => b,
        Err(e) => return error(StatusCode::INTERNAL_SERVER_ERROR, &format!("encoding failed: {e}")),
    };
    let mut resp = (StatusCode::OK, [(header::CONTENT_TYPE, mime)], body).into_response();
    let h = resp.headers_mut();
    let num = |n: u64| HeaderValue::from(n);
    h.insert("x-loupe-width", num(img.width.into()));
    h.insert("x-loupe-height", num(img.height.into()));
    h.insert("x-loupe-frame", num(img.frame));
    if let Ok(v) = HeaderValue::from_str(&img.format) {
        h.insert("x-loupe-format", v);
    }
    if let Some(c) = channels {
        h.insert("x-loupe-channels", HeaderValue::from_static(c));
    }
    resp
}

/// Hands `event` to the daemon: 202, or 503 when it is gone.
fn to_daemon(st: &AppState, event: Event) -> Response {
    match st.shared.to_daemon.send(event) {
        Ok(()) => json_response(StatusCode::ACCEPTED, &serde_json::json!({ "accepted": true })),
        Err(_) => error(StatusCode::SERVICE_UNAVAILABLE, "the daemon is not running"),
    }
}

async fn reload(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Event::Rebuild)
}

async fn controls(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.controls))
}

async fn save_scene(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Event::Scene(SceneCommand::Save))
}

/// Debug API only: the render thread destroys its device, which is then
/// lost and recovered as if the driver had lost it.
async fn lose_device(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Event::LoseDevice)
}

// ------------------------------------------------------------------ sources

/// Decodes `%XX` escapes once; `None` for a malformed escape or a result
/// that is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = |c: u8| (c as char).to_digit(16);
            let hi = hex(*b.get(i + 1)?)?;
            let lo = hex(*b.get(i + 2)?)?;
            out.push((hi * 16 + lo) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Turns the raw (still percent-encoded) tail of a URL path into a relative
/// path with only normal components, or refuses it: backslashes, `:` (drive
/// letters, streams), control characters, a `%` left after one decoding
/// (double encoding), a leading `/` (absolute), and empty, `.` or `..`
/// segments are all refused. This is the first line only; the canonical
/// path is checked against the roots after.
fn safe_relative(raw: &str) -> Option<String> {
    if raw.contains('\\') {
        return None;
    }
    let decoded = percent_decode(raw)?;
    if decoded.is_empty() || decoded.starts_with('/') {
        return None;
    }
    if decoded.chars().any(|c| matches!(c, '%' | '\\' | ':') || c.is_control()) {
        return None;
    }
    if decoded.split('/').any(|seg| seg.is_empty() || seg == "." || seg == "..") {
        return None;
    }
    Some(decoded)
}

/// The canonical path of a regular file named by `rel` — relative to the
/// working directory (how diagnostics show paths), to a root, or to a
/// root's parent — that lies inside a canonicalized root; `None` otherwise.
fn resolve_source(roots: &[PathBuf], rel: &str) -> Option<PathBuf> {
    let canonical_roots: Vec<PathBuf> = roots.iter().filter_map(|r| r.canonicalize().ok()).collect();
    let mut bases: Vec<PathBuf> = Vec::new();
    if let Ok(cwd) = std::env::current_dir() {
        bases.push(cwd);
    }
    for (raw, canonical) in roots.iter().zip(roots.iter().map(|r| r.canonicalize().ok())) {
        bases.push(raw.clone());
        bases.extend(raw.parent().map(Path::to_owned));
        if let Some(c) = canonical {
            bases.extend(c.parent().map(Path::to_owned));
            bases.push(c);
        }
    }
    bases.into_iter().find_map(|base| {
        let found = base.join(rel).canonicalize().ok()?;
        let inside = canonical_roots.iter().any(|r| found.starts_with(r));
        (inside && found.is_file()).then_some(found)
    })
}

async fn source(State(st): State<Arc<AppState>>, uri: Uri) -> Response {
    let raw = uri.path().strip_prefix("/api/sources/").unwrap_or("");
    let Some(rel) = safe_relative(raw) else {
        return error(StatusCode::FORBIDDEN, "path refused: only relative paths inside the source roots are served");
    };
    let roots = st.shared.source_roots.clone();
    let found = tokio::task::spawn_blocking(move || -> Result<Vec<u8>, (StatusCode, String)> {
        let not_found = || (StatusCode::NOT_FOUND, format!("no source file `{rel}`"));
        let path = resolve_source(&roots, &rel).ok_or_else(not_found)?;
        let len = std::fs::metadata(&path).map_err(|_| not_found())?.len();
        if len > MAX_SOURCE_BYTES {
            return Err((StatusCode::PAYLOAD_TOO_LARGE, format!("`{rel}` is larger than {MAX_SOURCE_BYTES} bytes")));
        }
        std::fs::read(&path).map_err(|_| not_found())
    })
    .await;
    match found {
        Ok(Ok(bytes)) => {
            (StatusCode::OK, [(header::CONTENT_TYPE, "text/plain; charset=utf-8")], bytes).into_response()
        }
        Ok(Err((status, message))) => error(status, &message),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}

// ------------------------------------------------------------------- static

fn content_type(path: &str) -> &'static str {
    let ext = path.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "html" | "htm" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "json" | "map" => "application/json",
        "ico" => "image/x-icon",
        "txt" | "wgsl" => "text/plain; charset=utf-8",
        "wasm" => "application/wasm",
        "woff2" => "font/woff2",
        _ => "application/octet-stream",
    }
}

fn embedded(path: &str) -> Response {
    match Client::get(path) {
        Some(file) => (
            StatusCode::OK,
            [(header::CONTENT_TYPE, content_type(path)), (header::CACHE_CONTROL, "no-cache")],
            Body::from(file.data.into_owned()),
        )
            .into_response(),
        None => error(StatusCode::NOT_FOUND, &format!("no such file `{path}`")),
    }
}

async fn index() -> Response {
    embedded("index.html")
}

async fn static_file(method: Method, uri: Uri) -> Response {
    if method != Method::GET && method != Method::HEAD {
        return error(StatusCode::METHOD_NOT_ALLOWED, "method not allowed");
    }
    let raw = uri.path().trim_start_matches('/');
    match safe_relative(raw) {
        Some(rel) => embedded(&rel),
        None => error(StatusCode::NOT_FOUND, "no such file"),
    }
}

// ---------------------------------------------------------------- websocket

async fn ws(State(st): State<Arc<AppState>>, upgrade: WebSocketUpgrade) -> Response {
    upgrade
        .max_message_size(MAX_CLIENT_MESSAGE)
        .max_frame_size(MAX_CLIENT_MESSAGE)
        .on_upgrade(move |socket| client_loop(st, socket))
}

fn event_message(event: &ServerEvent) -> Option<Message> {
    serde_json::to_string(event).ok().map(|s| Message::Text(s.into()))
}

/// The header of a binary image message.
#[derive(Serialize)]
struct ImageHeader<'a> {
    /// `frame`: the final output as PNG, sent to every client; `capture`:
    /// an output this client subscribed to.
    kind: &'static str,
    frame: u64,
    pass: &'a str,
    output: &'a str,
    width: u32,
    height: u32,
    format: &'a str,
    encoding: Encoding,
    mime: &'static str,
    #[serde(rename = "final")]
    is_final: bool,
}

/// A binary image message: a little-endian u32 header length N, N bytes of
/// JSON header, then the encoded image.
fn image_message(kind: &'static str, frame: &FrameImages, key: &str, encoding: Encoding, bytes: &[u8]) -> Option<Message> {
    let img = frame.captures.get(key)?;
    let header = serde_json::to_vec(&ImageHeader {
        kind,
        frame: frame.frame,
        pass: &img.pass,
        output: &img.output,
        width: img.width,
        height: img.height,
        format: &img.format,
        encoding,
        mime: encoding.mime(),
        is_final: frame.final_key.as_deref() == Some(key),
    })
    .ok()?;
    let mut out = Vec::with_capacity(4 + header.len() + bytes.len());
    out.extend_from_slice(&u32::try_from(header.len()).ok()?.to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(bytes);
    Some(Message::Binary(out.into()))
}

/// Sends one frame's images: the final output as a `frame` message, then
/// every output this client subscribed to that the frame captured.
/// Encoding runs off the reactor, once per frame and encoding whatever the
/// number of clients.
async fn send_images(socket: &mut WebSocket, frame: &Arc<FrameImages>, subscriptions: &BTreeMap<String, Encoding>) -> Result<(), axum::Error> {
    let wanted = frame
        .final_key
        .iter()
        .map(|k| ("frame", k, Encoding::Png))
        .chain(subscriptions.iter().map(|(k, e)| ("capture", k, *e)))
        .filter(|(_, k, _)| frame.captures.contains_key(*k));
    for (kind, key, encoding) in wanted {
        let (f, k) = (frame.clone(), key.clone());
        let Ok(Some(bytes)) = tokio::task::spawn_blocking(move || f.encoded(&k, encoding)).await else { continue };
        if let Some(m) = image_message(kind, frame, key, encoding, &bytes) {
            socket.send(m).await?;
        }
    }
    Ok(())
}

/// What a client missed and has not been told yet.
#[derive(Default)]
struct Missed {
    frames: u64,
    events: u64,
}

impl Missed {
    /// Sends the pending `Dropped` counts, if any.
    async fn flush(&mut self, socket: &mut WebSocket) -> Result<(), axum::Error> {
        if self.frames + self.events > 0 {
            let Missed { frames, events } = std::mem::take(self);
            if let Some(m) = event_message(&ServerEvent::Dropped { frames, events }) {
                socket.send(m).await?;
            }
        }
        Ok(())
    }
}

/// Tells the daemon, however the client's task ends, that it wants
/// nothing captured any more.
struct Unsubscribe {
    to_daemon: std::sync::mpsc::Sender<Event>,
    client: u64,
}

impl Drop for Unsubscribe {
    fn drop(&mut self) {
        let _ = self.to_daemon.send(Event::Subscriptions { client: self.client, outputs: BTreeSet::new() });
    }
}

/// Applies a client's message: subscriptions change this client's set
/// (and the daemon learns the new set), `rebuild` goes to the daemon.
fn client_message(shared: &Shared, client: u64, subscriptions: &mut BTreeMap<String, Encoding>, msg: ClientMessage) {
    let before: BTreeSet<String> = subscriptions.keys().cloned().collect();
    match msg {
        ClientMessage::Subscribe { pass, output, encoding } => {
            subscriptions.insert(format!("{pass}/{output}"), encoding);
        }
        ClientMessage::Unsubscribe { pass, output } => {
            subscriptions.remove(&format!("{pass}/{output}"));
        }
        // The daemon may be gone while the server drains; nothing to tell
        // the client then.
        ClientMessage::Rebuild {} => {
            let _ = shared.to_daemon.send(Event::Rebuild);
        }
        ClientMessage::SetOverride { path, value } => {
            let _ = shared.to_daemon.send(Event::Scene(SceneCommand::Set { path, value }));
        }
        ClientMessage::ClearOverrides {} => {
            let _ = shared.to_daemon.send(Event::Scene(SceneCommand::Clear));
        }
        ClientMessage::SaveScene {} => {
            let _ = shared.to_daemon.send(Event::Scene(SceneCommand::Save));
        }
    }
    let outputs: BTreeSet<String> = subscriptions.keys().cloned().collect();
    if outputs != before {
        let _ = shared.to_daemon.send(Event::Subscriptions { client, outputs });
    }
}

/// One WebSocket client. Memory per client is bounded: events wait in the
/// shared broadcast ring (`EVENT_QUEUE` deep; a lagging client loses the
/// oldest and is told how many), images in a `watch` (only the newest
/// frame's), and at most one message is in flight to the socket at a time.
async fn client_loop(st: Arc<AppState>, mut socket: WebSocket) {
    let shared = st.shared.clone();
    let client = st.next_client.fetch_add(1, Ordering::Relaxed);
    let _leave = Unsubscribe { to_daemon: shared.to_daemon.clone(), client };
    let mut subscriptions: BTreeMap<String, Encoding> = BTreeMap::new();
    // Subscribe before the Hello snapshot so nothing after it is missed.
    let mut events = shared.events.subscribe();
    let mut frames = shared.frames.subscribe();
    frames.mark_changed(); // send the current frame, if any, right away
    let mut stop = st.stop.subscribe();
    if *stop.borrow_and_update() {
        return;
    }
    let hello = ServerEvent::Hello { protocol: VERSION, status: read(&shared.status) };
    let Some(m) = event_message(&hello) else { return };
    if socket.send(m).await.is_err() {
        return;
    }

    let mut missed = Missed::default();
    let mut last_frame: Option<u64> = None;
    let mut frames_open = true;
    let mut report = tokio::time::interval(DROPPED_REPORT_INTERVAL);
    report.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);

    loop {
        // Biased: events go before images, so an image being encoded or
        // sent never holds back the events that say what happened.
        let step: Result<bool, axum::Error> = tokio::select! {
            biased;
            _ = stop.changed() => {
                let close = CloseFrame { code: 1001, reason: "server shutting down".into() };
                let _ = socket.send(Message::Close(Some(close))).await;
                return;
            }
            received = events.recv() => match received {
                Ok(event) => async {
                    missed.flush(&mut socket).await?;
                    if let Some(m) = event_message(&event) {
                        socket.send(m).await?;
                    }
                    Ok(true)
                }.await,
                Err(RecvError::Lagged(n)) => {
                    missed.events += n;
                    missed.flush(&mut socket).await.map(|()| true)
                }
                Err(RecvError::Closed) => Ok(false),
            },
            incoming = socket.recv() => match incoming {
                None | Some(Err(_)) | Some(Ok(Message::Close(_))) => Ok(false),
                Some(Ok(Message::Text(text))) => match serde_json::from_str::<ClientMessage>(text.as_str()) {
                    Ok(msg) => {
                        client_message(&shared, client, &mut subscriptions, msg);
                        Ok(true)
                    }
                    Err(e) => send_error(&mut socket, format!("invalid message: {e}")).await,
                },
                Some(Ok(Message::Binary(_))) => send_error(&mut socket, "binary messages are not accepted".into()).await,
                // Pings are answered by the WebSocket layer itself.
                Some(Ok(_)) => Ok(true),
            },
            changed = frames.changed(), if frames_open => match changed {
                Err(_) => {
                    frames_open = false;
                    Ok(true)
                }
                Ok(()) => {
                    let frame = frames.borrow_and_update().clone();
                    match frame {
                        Some(frame) => {
                            // Frames published while this client was busy
                            // were skipped: count the gap in frame numbers.
                            if let Some(last) = last_frame {
                                missed.frames += frame.frame.saturating_sub(last).saturating_sub(1);
                            }
                            last_frame = Some(frame.frame);
                            send_images(&mut socket, &frame, &subscriptions).await.map(|()| true)
                        }
                        None => Ok(true),
                    }
                }
            },
            _ = report.tick() => missed.flush(&mut socket).await.map(|()| true),
        };
        match step {
            Ok(true) => {}
            Ok(false) | Err(_) => return,
        }
    }
}

/// Sends an `error` event; the connection stays open.
async fn send_error(socket: &mut WebSocket, message: String) -> Result<bool, axum::Error> {
    match event_message(&ServerEvent::Error { message }) {
        Some(m) => socket.send(m).await.map(|()| true),
        None => Ok(true),
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::sync::mpsc;

    use futures_util::{SinkExt, StreamExt};
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    use tokio::net::TcpStream;
    use tokio_tungstenite::tungstenite::{self, client::IntoClientRequest};

    use super::*;
    use crate::serve::shared::{EVENT_QUEUE, write};

    struct Server {
        addr: SocketAddr,
        shared: Arc<Shared>,
        daemon: mpsc::Receiver<Event>,
        stop: Option<tokio::sync::oneshot::Sender<()>>,
        done: tokio::task::JoinHandle<io::Result<()>>,
    }

    async fn start(roots: Vec<PathBuf>) -> Server {
        start_with(roots, false).await
    }

    async fn start_with(roots: Vec<PathBuf>, debug_api: bool) -> Server {
        let (tx, daemon) = mpsc::channel();
        let shared = Shared::new(tx, roots, debug_api);
        let (listener, addr) = bind("127.0.0.1:0".parse().unwrap()).await.unwrap();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let done = tokio::spawn(serve(listener, shared.clone(), allowed_hosts(addr), async move {
            let _ = stopped.await;
        }));
        Server { addr, shared, daemon, stop: Some(stop), done }
    }

    struct Reply {
        status: u16,
        headers: String,
        body: Vec<u8>,
    }

    impl Reply {
        fn header(&self, name: &str) -> Option<String> {
            self.headers.lines().find_map(|l| {
                let (n, v) = l.split_once(':')?;
                n.trim().eq_ignore_ascii_case(name).then(|| v.trim().to_owned())
            })
        }
        fn text(&self) -> String {
            String::from_utf8_lossy(&self.body).into_owned()
        }
        fn json(&self) -> serde_json::Value {
            serde_json::from_slice(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text()))
        }
    }

    /// Sends `request` byte for byte (no client normalizes it) and reads the
    /// whole reply.
    async fn raw(addr: SocketAddr, request: &str) -> Reply {
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

    async fn request(addr: SocketAddr, method: &str, path: &str, extra: &str) -> Reply {
        let req = format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\n{extra}Connection: close\r\nContent-Length: 0\r\n\r\n");
        raw(addr, &req).await
    }

    async fn get(addr: SocketAddr, path: &str) -> Reply {
        request(addr, "GET", path, "").await
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("loupe-http-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    type Ws = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<TcpStream>>;

    async fn connect(addr: SocketAddr, origin: Option<&str>) -> Result<Ws, tungstenite::Error> {
        let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
        if let Some(o) = origin {
            req.headers_mut().insert("origin", o.parse().unwrap());
        }
        tokio_tungstenite::connect_async(req).await.map(|(ws, _)| ws)
    }

    async fn next_message(ws: &mut Ws) -> tungstenite::Message {
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

    async fn next_json(ws: &mut Ws) -> serde_json::Value {
        match next_message(ws).await {
            tungstenite::Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            other => panic!("expected text, got {other:?}"),
        }
    }

    fn daemon_event(server: &Server) -> Option<Event> {
        server.daemon.recv_timeout(Duration::from_secs(5)).ok()
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn json_endpoints_have_their_shapes_and_no_store() {
        let s = start(vec![]).await;
        write(&s.shared.status, crate::protocol::Status { protocol: VERSION, frame: 42, ..Default::default() });

        let r = get(s.addr, "/api/status").await;
        assert_eq!(r.status, 200);
        assert_eq!(r.header("content-type").as_deref(), Some("application/json"));
        assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));
        let v = r.json();
        assert_eq!(v["protocol"], VERSION);
        assert_eq!(v["frame"], 42);
        for key in [
            "version", "adapter", "cpu_adapter", "features", "degraded", "scene", "pipelines_ok", "pipelines_stale",
            "pipelines_failed", "device_resets", "errors", "warnings", "render_mode",
        ] {
            assert!(v.get(key).is_some(), "status lacks `{key}`: {v}");
        }

        assert_eq!(get(s.addr, "/api/passes").await.json(), serde_json::json!([]));
        assert_eq!(get(s.addr, "/api/pipelines").await.json(), serde_json::json!([]));
        assert_eq!(get(s.addr, "/api/diagnostics").await.json(), serde_json::json!({ "diagnostics": [] }));
        assert_eq!(get(s.addr, "/api/captures").await.json(), serde_json::json!([]));

        let r = get(s.addr, "/api/nope").await;
        assert_eq!(r.status, 404);
        assert!(r.json()["error"].is_string());
        assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));

        let r = request(s.addr, "POST", "/api/status", "").await;
        assert_eq!(r.status, 405);
        assert_eq!(r.json()["error"], "method not allowed");
        assert!(r.header("allow").is_some_and(|a| a.contains("GET")));
        assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));

        let r = request(s.addr, "HEAD", "/api/status", "").await;
        assert_eq!(r.status, 200);
        assert!(r.body.is_empty());
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn captures_are_listed_and_served_in_every_format() {
        let s = start(vec![]).await;
        let (w, h) = (3u32, 2u32);
        let data: Vec<f32> = (0..w * h * 4).map(|i| i as f32 * 0.25 - 1.0).collect();
        let img = CapturedImage::new("hdr", "color", 9, w, h, wgpu::TextureFormat::Rgba16Float, data.clone());
        write(&s.shared.captures, Arc::new(BTreeMap::from([(img.key(), Arc::new(img))])));

        let list = get(s.addr, "/api/captures").await.json();
        let c = &list[0];
        assert_eq!(c["pass"], "hdr");
        assert_eq!(c["output"], "color");
        assert_eq!(c["frame"], 9);
        assert_eq!(c["width"], 3);
        assert_eq!(c["height"], 2);
        assert_eq!(c["format"], "Rgba16Float");
        assert_eq!(c["last_good"], false);
        assert!(c["stats"]["negative"].as_u64().unwrap() > 0);

        let png = get(s.addr, "/api/captures/hdr/color.png").await;
        assert_eq!(png.status, 200);
        assert_eq!(png.header("content-type").as_deref(), Some("image/png"));
        assert!(png.body.starts_with(b"\x89PNG\r\n\x1a\n"));

        let f32s = get(s.addr, "/api/captures/hdr/color.f32").await;
        assert_eq!(f32s.status, 200);
        assert_eq!(f32s.header("x-loupe-width").as_deref(), Some("3"));
        assert_eq!(f32s.header("x-loupe-height").as_deref(), Some("2"));
        assert_eq!(f32s.header("x-loupe-channels").as_deref(), Some("4"));
        assert_eq!(f32s.header("x-loupe-frame").as_deref(), Some("9"));
        let back: Vec<f32> = f32s.body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        assert_eq!(back, data);

        let f16s = get(s.addr, "/api/captures/hdr/color.f16").await;
        assert_eq!(f16s.status, 200);
        assert_eq!(f16s.body.len(), (w * h * 4 * 2) as usize);
        assert_eq!(f16s.header("x-loupe-channels").as_deref(), Some("4"));
        assert_eq!(half::f16::from_le_bytes([f16s.body[2], f16s.body[3]]).to_f32(), data[1]);

        let exr = get(s.addr, "/api/captures/hdr/color.exr").await;
        assert_eq!(exr.status, 200);
        assert!(exr.body.starts_with(&[0x76, 0x2f, 0x31, 0x01]));

        for (path, status) in [
            ("/api/captures/hdr/missing.png", 404),
            ("/api/captures/nope/color.png", 404),
            ("/api/captures/hdr/color.jpg", 400),
            ("/api/captures/hdr/color", 400),
            ("/api/captures/hdr/color.png?version=last_good", 404),
            ("/api/captures/hdr/color.png?version=bogus", 400),
        ] {
            let r = get(s.addr, path).await;
            assert_eq!(r.status, status, "{path}: {}", r.text());
            assert!(r.json()["error"].is_string(), "{path}");
        }

        let old = CapturedImage::new("hdr", "color", 5, 1, 1, wgpu::TextureFormat::Rgba16Float, vec![0.0; 4]);
        write(&s.shared.last_good, Arc::new(BTreeMap::from([(old.key(), Arc::new(old))])));
        let r = get(s.addr, "/api/captures/hdr/color.f32?version=last_good").await;
        assert_eq!(r.status, 200);
        assert_eq!(r.header("x-loupe-frame").as_deref(), Some("5"));
        assert_eq!(r.body.len(), 16);
        assert_eq!(get(s.addr, "/api/captures").await.json()[0]["last_good"], true);
        assert_eq!(get(s.addr, "/api/captures?version=last_good").await.json()[0]["frame"], 5);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn sources_are_served_only_from_inside_the_roots() {
        let base = temp_dir("sources");
        let root = base.join("root");
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::write(root.join("a.wgsl"), "legit shader").unwrap();
        std::fs::write(root.join("sub/b.wgsl"), "nested shader").unwrap();
        std::fs::write(base.join("secret.txt"), "TOPSECRET").unwrap();
        std::os::unix::fs::symlink(base.join("secret.txt"), root.join("link.wgsl")).unwrap();
        std::os::unix::fs::symlink(&base, root.join("dirlink")).unwrap();
        std::os::unix::fs::symlink(root.join("a.wgsl"), root.join("inner.wgsl")).unwrap();
        let s = start(vec![root.clone()]).await;

        for (path, want) in [
            ("/api/sources/a.wgsl", "legit shader"),
            ("/api/sources/sub/b.wgsl", "nested shader"),
            ("/api/sources/sub%2Fb.wgsl", "nested shader"),
            ("/api/sources/root/a.wgsl", "legit shader"),
            ("/api/sources/inner.wgsl", "legit shader"),
        ] {
            let r = get(s.addr, path).await;
            assert_eq!(r.status, 200, "{path}: {}", r.text());
            assert_eq!(r.text(), want, "{path}");
            assert_eq!(r.header("content-type").as_deref(), Some("text/plain; charset=utf-8"));
        }
        let r = request(s.addr, "HEAD", "/api/sources/a.wgsl", "").await;
        assert_eq!((r.status, r.body.len()), (200, 0));
        assert_eq!(r.header("content-length").as_deref(), Some("12"));

        let abs = base.join("secret.txt").display().to_string();
        let abs_inside = root.join("a.wgsl").display().to_string();
        let refused = [
            "/api/sources/../secret.txt".to_owned(),
            "/api/sources/sub/../../secret.txt".to_owned(),
            "/api/sources/..%2fsecret.txt".to_owned(),
            "/api/sources/..%2Fsecret.txt".to_owned(),
            "/api/sources/%2e%2e/secret.txt".to_owned(),
            "/api/sources/%2E%2E%2Fsecret.txt".to_owned(),
            "/api/sources/.%2e/secret.txt".to_owned(),
            "/api/sources/%252e%252e%252fsecret.txt".to_owned(),
            "/api/sources/%252e%252e/secret.txt".to_owned(),
            "/api/sources/..%255csecret.txt".to_owned(),
            "/api/sources/..%5csecret.txt".to_owned(),
            "/api/sources/..%5Csecret.txt".to_owned(),
            "/api/sources/..\\secret.txt".to_owned(),
            "/api/sources/sub\\..\\..\\secret.txt".to_owned(),
            "/api/sources/..%c0%afsecret.txt".to_owned(),
            "/api/sources/a.wgsl%00".to_owned(),
            format!("/api/sources/{abs}"),
            format!("/api/sources//{abs}"),
            format!("/api/sources/{}", abs.replace('/', "%2f")),
            format!("/api/sources/{abs_inside}"),
            "/api/sources/%2fetc%2fpasswd".to_owned(),
            "/api/sources//etc/passwd".to_owned(),
            "/api/sources/C:%5cWindows%5cwin.ini".to_owned(),
            "/api/sources/link.wgsl".to_owned(),
            "/api/sources/dirlink/secret.txt".to_owned(),
            "/api/sources/./a.wgsl".to_owned(),
            "/api/sources/missing.wgsl".to_owned(),
            "/api/sources/sub".to_owned(),
            "/api/sources/".to_owned(),
            "/api/../secret.txt".to_owned(),
        ];
        for path in &refused {
            let r = get(s.addr, path).await;
            assert!(matches!(r.status, 400 | 403 | 404), "{path}: {} {}", r.status, r.text());
            assert!(!r.text().contains("TOPSECRET"), "{path} leaked the secret");
            assert!(!r.text().contains("root:"), "{path} leaked /etc/passwd");
        }
        let _ = std::fs::remove_dir_all(&base);
    }

    #[test]
    fn safe_relative_refuses_every_escape() {
        assert_eq!(safe_relative("shaders/a.wgsl").as_deref(), Some("shaders/a.wgsl"));
        assert_eq!(safe_relative("a%20b.wgsl").as_deref(), Some("a b.wgsl"));
        for bad in [
            "", "..", "../x", "a/../x", "./a", "a//b", "a/", "/etc", "%2e%2e/x", "..%2fx", "%252e%252e", "a%5cb",
            "a\\b", "c:/x", "a%00", "%zz", "%2", "..%c0%af",
        ] {
            assert_eq!(safe_relative(bad), None, "{bad:?}");
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn wrong_host_is_refused() {
        let s = start(vec![]).await;
        let port = s.addr.port();
        for host in [format!("127.0.0.1:{port}"), format!("localhost:{port}"), format!("LOCALHOST:{port}"), format!("[::1]:{port}")]
        {
            let r = raw(s.addr, &format!("GET /api/status HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n")).await;
            assert_eq!(r.status, 200, "{host}");
        }
        for host in [
            "evil.example".to_owned(),
            format!("evil.example:{port}"),
            format!("127.0.0.1:{}", port.wrapping_add(1)),
            "127.0.0.1".to_owned(),
            format!("localhost.evil.example:{port}"),
        ] {
            for path in ["/api/status", "/", "/ws"] {
                let r = raw(s.addr, &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n")).await;
                assert_eq!(r.status, 403, "{host} {path}");
                assert!(r.json()["error"].is_string());
            }
        }
        // No Host at all, and two of them.
        let r = raw(s.addr, "GET /api/status HTTP/1.0\r\n\r\n").await;
        assert_eq!(r.status, 403);
        let r = raw(
            s.addr,
            &format!("GET /api/status HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nHost: evil.example\r\nConnection: close\r\n\r\n"),
        )
        .await;
        assert_eq!(r.status, 403);
        // An absolute-form target naming another authority.
        let r = raw(
            s.addr,
            &format!("GET http://evil.example/api/status HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"),
        )
        .await;
        assert_eq!(r.status, 403);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn reload_needs_a_same_origin_or_no_origin() {
        let s = start(vec![]).await;
        for origin in ["http://evil.example", "null", "https://127.0.0.1", &format!("https://127.0.0.1:{}", s.addr.port())] {
            let r = request(s.addr, "POST", "/api/reload", &format!("Origin: {origin}\r\n")).await;
            assert_eq!(r.status, 403, "{origin}");
            assert!(r.json()["error"].is_string());
        }
        assert!(s.daemon.try_recv().is_err(), "a refused request reached the daemon");

        let r = request(s.addr, "POST", "/api/reload", &format!("Origin: http://localhost:{}\r\n", s.addr.port())).await;
        assert_eq!(r.status, 202, "{}", r.text());
        assert_eq!(r.json()["accepted"], true);
        assert!(matches!(daemon_event(&s), Some(Event::Rebuild)));

        let r = request(s.addr, "POST", "/api/reload", "").await;
        assert_eq!(r.status, 202);
        assert!(matches!(daemon_event(&s), Some(Event::Rebuild)));

        // A cross-site GET is harmless (the browser won't let the page read
        // it) and is allowed.
        let r = request(s.addr, "GET", "/api/status", "Origin: http://evil.example\r\n").await;
        assert_eq!(r.status, 200);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn websocket_origin_check_hello_and_events() {
        let s = start(vec![]).await;
        match connect(s.addr, Some("http://evil.example")).await {
            Err(tungstenite::Error::Http(resp)) => assert_eq!(resp.status(), 403),
            Err(e) => panic!("unexpected error {e}"),
            Ok(_) => panic!("cross-origin websocket was accepted"),
        }
        match connect(s.addr, Some(&format!("http://127.0.0.1:{}.evil.example", s.addr.port()))).await {
            Err(tungstenite::Error::Http(resp)) => assert_eq!(resp.status(), 403),
            _ => panic!("look-alike origin was accepted"),
        }

        write(&s.shared.status, crate::protocol::Status { protocol: VERSION, frame: 3, ..Default::default() });
        for origin in [Some(format!("http://127.0.0.1:{}", s.addr.port())), None] {
            let mut ws = connect(s.addr, origin.as_deref()).await.unwrap();
            let hello = next_json(&mut ws).await;
            assert_eq!(hello["type"], "hello");
            assert_eq!(hello["protocol"], VERSION);
            assert_eq!(hello["status"]["frame"], 3);

            s.shared.publish(ServerEvent::DeviceLost { message: "gone".into(), recovered: true });
            s.shared.publish(ServerEvent::ReloadStarted { id: 7, files: vec!["a.wgsl".into()], pipelines: vec![] });
            let a = next_json(&mut ws).await;
            assert_eq!(a, serde_json::json!({ "type": "device_lost", "message": "gone", "recovered": true }));
            let b = next_json(&mut ws).await;
            assert_eq!(b["type"], "reload_started");
            assert_eq!(b["id"], 7);
        }
    }

    /// The next event the daemon got, from a blocking receive.
    async fn daemon_event_async(s: Server) -> (Option<Event>, Server) {
        tokio::task::spawn_blocking(move || (daemon_event(&s), s)).await.unwrap()
    }

    fn subscriptions(e: Option<Event>) -> (u64, Vec<String>) {
        match e {
            Some(Event::Subscriptions { client, outputs }) => (client, outputs.into_iter().collect()),
            _ => panic!("expected a subscriptions event"),
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn client_messages_reach_the_daemon_and_bad_ones_get_an_error() {
        let s = start(vec![]).await;
        let mut ws = connect(s.addr, None).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "hello");

        for bad in [
            "not json",
            "{\"type\":\"no_such_thing\"}",
            "{\"type\":\"subscribe\"}",
            "{\"type\":\"subscribe\",\"pass\":\"a\",\"output\":\"b\",\"encoding\":\"jpeg\"}",
            "{\"type\":\"unsubscribe\",\"pass\":\"a\"}",
            "[]",
        ] {
            ws.send(tungstenite::Message::text(bad)).await.unwrap();
            let e = next_json(&mut ws).await;
            assert_eq!(e["type"], "error", "{bad}");
            assert!(e["message"].as_str().unwrap().starts_with("invalid message: "), "{e}");
        }
        ws.send(tungstenite::Message::binary(vec![1u8, 2, 3])).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "error");

        // The daemon learns this client's whole set each time it changes,
        // and only then: a repeated subscribe changes nothing.
        for m in [
            r#"{"type":"subscribe","pass":"hdr","output":"color"}"#,
            r#"{"type":"subscribe","pass":"hdr","output":"color","encoding":"f32"}"#,
            r#"{"type":"subscribe","pass":"bloom","output":"mip0","encoding":"f16"}"#,
            r#"{"type":"unsubscribe","pass":"hdr","output":"color"}"#,
            r#"{"type":"unsubscribe","pass":"never","output":"subscribed"}"#,
            r#"{"type":"rebuild"}"#,
        ] {
            ws.send(tungstenite::Message::text(m)).await.unwrap();
        }
        let (e, s) = daemon_event_async(s).await;
        let (client, outputs) = subscriptions(e);
        assert_eq!(outputs, ["hdr/color"]);
        let (e, s) = daemon_event_async(s).await;
        assert_eq!(subscriptions(e), (client, vec!["bloom/mip0".to_owned(), "hdr/color".to_owned()]));
        let (e, s) = daemon_event_async(s).await;
        assert_eq!(subscriptions(e), (client, vec!["bloom/mip0".to_owned()]));
        let (e, s) = daemon_event_async(s).await;
        assert!(matches!(e, Some(Event::Rebuild)));

        // Still connected.
        s.shared.publish(ServerEvent::Dropped { frames: 0, events: 0 });
        assert_eq!(next_json(&mut ws).await["type"], "dropped");

        // Leaving clears its subscriptions.
        drop(ws);
        let (e, _s) = daemon_event_async(s).await;
        assert_eq!(subscriptions(e), (client, vec![]));
    }

    fn parse_image(bytes: &[u8]) -> (serde_json::Value, &[u8]) {
        let n = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
        let header = serde_json::from_slice(&bytes[4..4 + n]).unwrap();
        (header, &bytes[4 + n..])
    }

    async fn next_image(ws: &mut Ws) -> (serde_json::Value, Vec<u8>) {
        match next_message(ws).await {
            tungstenite::Message::Binary(bytes) => {
                let (h, b) = parse_image(&bytes);
                (h, b.to_vec())
            }
            other => panic!("expected binary, got {other:?}"),
        }
    }

    /// A frame with a final output `tonemap/color` (1x1 sRGB) and an HDR
    /// `hdr/color` (2x1) whose values say which frame it is.
    fn frame_images(frame: u64) -> Option<Arc<FrameImages>> {
        let v = frame as f32;
        let ldr = CapturedImage::new("tonemap", "color", frame, 1, 1, wgpu::TextureFormat::Rgba8UnormSrgb, vec![1.0, 0.0, 0.0, 1.0]);
        let hdr = CapturedImage::new("hdr", "color", frame, 2, 1, wgpu::TextureFormat::Rgba16Float, vec![v, -1.5, 2.0, 1.0, 0.5, v, 0.0, 1.0]);
        let captures = BTreeMap::from([(ldr.key(), Arc::new(ldr)), (hdr.key(), Arc::new(hdr))]);
        Some(Arc::new(FrameImages::new(frame, Some("tonemap/color".into()), captures)))
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn each_client_gets_the_final_frame_and_its_own_subscriptions_newest_only() {
        let s = start(vec![]).await;
        // The current frame is sent on connect.
        s.shared.frames.send_replace(frame_images(7));
        let mut a = connect(s.addr, None).await.unwrap();
        let mut b = connect(s.addr, None).await.unwrap();
        for ws in [&mut a, &mut b] {
            assert_eq!(next_json(ws).await["type"], "hello");
            let (h, png) = next_image(ws).await;
            assert_eq!(
                h,
                serde_json::json!({ "kind": "frame", "frame": 7, "pass": "tonemap", "output": "color", "width": 1, "height": 1,
                    "format": "Rgba8UnormSrgb", "encoding": "png", "mime": "image/png", "final": true })
            );
            assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
        }

        // A subscribes to the HDR output as exact floats; B to nothing.
        a.send(tungstenite::Message::text(r#"{"type":"subscribe","pass":"hdr","output":"color","encoding":"f32"}"#)).await.unwrap();
        let (e, s) = daemon_event_async(s).await;
        assert_eq!(subscriptions(e).1, ["hdr/color"]);
        s.shared.frames.send_replace(frame_images(8));
        assert_eq!(next_image(&mut a).await.0["kind"], "frame");
        let (h, raw) = next_image(&mut a).await;
        assert_eq!(
            h,
            serde_json::json!({ "kind": "capture", "frame": 8, "pass": "hdr", "output": "color", "width": 2, "height": 1,
                "format": "Rgba16Float", "encoding": "f32", "mime": "application/octet-stream", "final": false })
        );
        let values: Vec<f32> = raw.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
        assert_eq!(values, [8.0, -1.5, 2.0, 1.0, 0.5, 8.0, 0.0, 1.0]);
        let (h, _) = next_image(&mut b).await;
        assert_eq!((h["kind"].as_str(), h["frame"].as_u64()), (Some("frame"), Some(8)));

        // Frames 9..=11 never reached A: it gets the newest and the count.
        s.shared.frames.send_replace(frame_images(12));
        assert_eq!(next_image(&mut a).await.0["frame"], 12);
        let (h, raw) = next_image(&mut a).await;
        assert_eq!((h["kind"].as_str(), h["frame"].as_u64(), raw.len()), (Some("capture"), Some(12), 32));
        assert_eq!(next_json(&mut a).await, serde_json::json!({ "type": "dropped", "frames": 3, "events": 0 }));

        // B never subscribed: it got only final frames, and an event is the
        // next thing it reads, not a capture.
        assert_eq!(next_image(&mut b).await.0["frame"], 12);
        assert_eq!(next_json(&mut b).await, serde_json::json!({ "type": "dropped", "frames": 3, "events": 0 }));
        s.shared.publish(ServerEvent::DeviceLost { message: "marker".into(), recovered: true });
        assert_eq!(next_json(&mut b).await["message"], "marker");

        // Unsubscribed, A gets only the final frame again.
        a.send(tungstenite::Message::text(r#"{"type":"unsubscribe","pass":"hdr","output":"color"}"#)).await.unwrap();
        let (e, s) = daemon_event_async(s).await;
        assert!(subscriptions(e).1.is_empty());
        assert_eq!(next_json(&mut a).await["message"], "marker");
        s.shared.frames.send_replace(frame_images(13));
        assert_eq!(next_image(&mut a).await.0["kind"], "frame");
        s.shared.publish(ServerEvent::DeviceLost { message: "after 13".into(), recovered: true });
        assert_eq!(next_json(&mut a).await["message"], "after 13");
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn captures_say_which_is_final() {
        let s = start(vec![]).await;
        let images = frame_images(3).unwrap();
        write(&s.shared.captures, Arc::new(images.captures.clone()));
        s.shared.frames.send_replace(Some(images));
        let list = get(s.addr, "/api/captures").await.json();
        let finals: Vec<(String, bool)> =
            list.as_array().unwrap().iter().map(|c| (c["pass"].as_str().unwrap().to_owned(), c["final"].as_bool().unwrap())).collect();
        assert_eq!(finals, [("hdr".to_owned(), false), ("tonemap".to_owned(), true)]);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn the_debug_api_exists_only_when_enabled() {
        let s = start(vec![]).await;
        let r = request(s.addr, "POST", "/api/debug/lose-device", "").await;
        assert_eq!(r.status, 404, "{}", r.text());
        assert!(r.json()["error"].is_string());
        assert_eq!(request(s.addr, "POST", "/api/nope", "").await.status, 404);
        assert!(s.daemon.try_recv().is_err());

        let s = start_with(vec![], true).await;
        let cross = "Origin: http://evil.example\r\n";
        assert_eq!(request(s.addr, "POST", "/api/debug/lose-device", cross).await.status, 403);
        let r = request(s.addr, "POST", "/api/debug/lose-device", "").await;
        assert_eq!(r.status, 202, "{}", r.text());
        assert!(matches!(daemon_event(&s), Some(Event::LoseDevice)));
        assert_eq!(request(s.addr, "GET", "/api/debug/lose-device", "").await.status, 405);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_client_that_never_reads_costs_bounded_memory_and_learns_what_it_lost() {
        let s = start(vec![]).await;
        let mut ws = connect(s.addr, None).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "hello");

        // The client stops reading while 10,000 events (80 MB, far more than
        // the socket buffers hold) are published.
        const N: usize = 10_000;
        let payload = "x".repeat(8 * 1024);
        for i in 0..N {
            s.shared.publish(ServerEvent::DeviceLost { message: format!("{i} {payload}"), recovered: false });
            assert!(s.shared.events.len() <= EVENT_QUEUE);
            if i % 16 == 0 {
                tokio::task::yield_now().await;
            }
        }
        s.shared.publish(ServerEvent::DeviceLost { message: "end".into(), recovered: true });
        assert!(s.shared.events.len() <= EVENT_QUEUE);

        // Resume: every event is either delivered or counted as dropped.
        let (mut delivered, mut dropped, mut last_seen) = (0u64, 0u64, None::<u64>);
        loop {
            let v = next_json(&mut ws).await;
            match v["type"].as_str().unwrap() {
                "dropped" => {
                    assert_eq!(v["frames"], 0);
                    dropped += v["events"].as_u64().unwrap()
                }
                "device_lost" if v["message"] == "end" => break,
                "device_lost" => {
                    let i: u64 = v["message"].as_str().unwrap().split(' ').next().unwrap().parse().unwrap();
                    assert!(last_seen.is_none_or(|l| i > l), "events out of order");
                    last_seen = Some(i);
                    delivered += 1;
                }
                other => panic!("unexpected {other}"),
            }
        }
        assert!(dropped > 0, "a stalled client was never told it lost events");
        assert!(delivered < N as u64);
        assert_eq!(delivered + dropped, N as u64);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn static_ui_is_served_with_content_types() {
        let s = start(vec![]).await;
        let files: Vec<String> = Client::iter().map(|f| f.into_owned()).collect();
        for f in &files {
            let r = get(s.addr, &format!("/{f}")).await;
            assert_eq!(r.status, 200, "{f}");
            assert_eq!(r.header("content-type").as_deref(), Some(content_type(f)), "{f}");
        }
        let r = get(s.addr, "/").await;
        if files.iter().any(|f| f == "index.html") {
            assert_eq!(r.status, 200);
            assert_eq!(r.header("content-type").as_deref(), Some("text/html; charset=utf-8"));
            let head = request(s.addr, "HEAD", "/index.html", "").await;
            assert_eq!((head.status, head.body.len()), (200, 0));
        } else {
            assert_eq!(r.status, 404);
        }
        for path in ["/no-such-file.js", "/..%2fCargo.toml", "/%2e%2e/Cargo.toml", "/../Cargo.toml", "/..%5cCargo.toml"] {
            let r = get(s.addr, path).await;
            assert_eq!(r.status, 404, "{path}");
            assert!(!r.text().contains("[package]"), "{path} leaked a file");
        }
        assert_eq!(content_type("app.js"), "text/javascript; charset=utf-8");
        assert_eq!(content_type("style.css"), "text/css; charset=utf-8");
        assert_eq!(content_type("icon.svg"), "image/svg+xml");
        assert_eq!(content_type("a.png"), "image/png");
        assert_eq!(content_type("data.json"), "application/json");
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn shutdown_closes_websockets_and_returns() {
        let mut s = start(vec![]).await;
        let mut ws = connect(s.addr, None).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "hello");
        s.stop.take().unwrap().send(()).unwrap();
        match next_message(&mut ws).await {
            tungstenite::Message::Close(Some(f)) => assert_eq!(u16::from(f.code), 1001),
            other => panic!("expected close, got {other:?}"),
        }
        drop(ws);
        tokio::time::timeout(Duration::from_secs(10), s.done).await.unwrap().unwrap().unwrap();
    }

    #[test]
    fn allowed_hosts_cover_loopback_names_and_a_public_bind() {
        let h = allowed_hosts("127.0.0.1:8080".parse().unwrap());
        assert_eq!(h, ["127.0.0.1:8080", "localhost:8080", "[::1]:8080"]);
        assert!(allowed_hosts("192.168.1.5:9000".parse().unwrap()).contains(&"192.168.1.5:9000".to_owned()));
        assert_eq!(allowed_hosts("0.0.0.0:9000".parse().unwrap()).len(), 3);
        assert!(allowed_hosts("127.0.0.1:80".parse().unwrap()).contains(&"localhost".to_owned()));
    }
}
