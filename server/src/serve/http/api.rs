//! The JSON API (status, passes, pipelines, diagnostics, controls,
//! materials), the capture list and downloads, and the requests that go to
//! the daemon (reload, save, the debug API's lose-device).

use std::collections::BTreeMap;
use std::sync::Arc;

use axum::extract::{Path as UrlPath, Query, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

use super::AppState;
use super::guard::{error, json, json_response, state};
use crate::protocol::DiagnosticsReport;
use crate::render::capture::{CapturedImage, ImageStats};
use crate::serve::event::SceneCommand;
use crate::serve::inbox::Command;
use crate::serve::shared::{Shared, read};

pub(super) async fn status(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.status))
}

pub(super) async fn passes(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.passes))
}

pub(super) async fn pipelines(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.pipelines))
}

pub(super) async fn diagnostics(State(st): State<Arc<AppState>>) -> Response {
    json(&DiagnosticsReport { diagnostics: read(&st.shared.diagnostics) })
}

pub(super) async fn not_found() -> Response {
    error(StatusCode::NOT_FOUND, "no such API route")
}

#[derive(Deserialize)]
pub(super) struct VersionQuery {
    version: Option<String>,
}

type Captures = Arc<BTreeMap<String, Arc<CapturedImage>>>;

/// Which set of captures a request asks for; a 400 for an unknown version.
fn capture_set(shared: &Shared, version: Option<&str>) -> Result<Captures, Box<Response>> {
    match version {
        None | Some("current") => Ok(read(&shared.captures)),
        Some("last_good") => Ok(read(&shared.last_good)),
        Some(other) => {
            Err(Box::new(error(StatusCode::BAD_REQUEST, &format!("unknown version `{other}`: expected `current` or `last_good`"))))
        }
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

pub(super) async fn captures(State(st): State<Arc<AppState>>, Query(q): Query<VersionQuery>) -> Response {
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

pub(super) async fn capture(
    State(st): State<Arc<AppState>>,
    UrlPath((pass, file)): UrlPath<(String, String)>,
    Query(q): Query<VersionQuery>,
) -> Response {
    let Some((output, ext)) = file.rsplit_once('.') else {
        return error(StatusCode::BAD_REQUEST, "missing extension: expected .png, .f32, .f16 or .exr");
    };
    if !matches!(ext, "png" | "f32" | "f16" | "exr") {
        return error(StatusCode::BAD_REQUEST, &format!("unknown extension `.{ext}`: expected .png, .f32, .f16 or .exr"));
    }
    let set = match capture_set(&st.shared, q.version.as_deref()) {
        Ok(set) => set,
        Err(resp) => return *resp,
    };
    let key = format!("{pass}/{output}");
    let Some(img) = set.get(&key).cloned() else {
        if writes(&st.shared, &pass, output) {
            return state(NOT_CAPTURED);
        }
        return error(StatusCode::NOT_FOUND, &format!("`{pass}` writes no output `{output}`"));
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

/// The state of an output the frame graph writes that no frame has
/// captured yet (or, asked for `last_good`, that no reload has replaced).
pub(super) const NOT_CAPTURED: &str = "not-captured";

/// Whether `pass` writes `output` in the current frame graph: such an
/// output without a capture is a state; any other name is unknown (404).
pub(super) fn writes(shared: &Shared, pass: &str, output: &str) -> bool {
    shared.passes.read().unwrap_or_else(|e| e.into_inner()).iter().any(|p| p.name == pass && p.writes.iter().any(|w| w.name == output))
}

/// Hands `command` to the daemon: 202, or 503 when it is gone or too many
/// commands already wait for it.
fn to_daemon(st: &AppState, command: Command) -> Response {
    match st.shared.clients.command(command) {
        Ok(()) => json_response(StatusCode::ACCEPTED, &serde_json::json!({ "accepted": true })),
        Err(refused) => error(StatusCode::SERVICE_UNAVAILABLE, &refused.to_string()),
    }
}

pub(super) async fn reload(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Command::Rebuild)
}

pub(super) async fn controls(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.controls))
}

pub(super) async fn materials(State(st): State<Arc<AppState>>) -> Response {
    json(&*read(&st.shared.materials))
}

pub(super) async fn save_scene(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Command::Scene(SceneCommand::Save))
}

/// `POST /api/frame/trace`: capture every output of the next frame and
/// report where a NaN/Inf started.
pub(super) async fn trace(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Command::Trace)
}

/// `GET /api/nan`: the newest NaN report, or `null`.
pub(super) async fn nan(State(st): State<Arc<AppState>>) -> Response {
    json(&serde_json::json!({ "report": read(&st.shared.nan) }))
}

/// Debug API only: the render thread destroys its device, which is then
/// lost and recovered as if the driver had lost it.
pub(super) async fn lose_device(State(st): State<Arc<AppState>>) -> Response {
    to_daemon(&st, Command::LoseDevice)
}

#[cfg(test)]
mod tests;
