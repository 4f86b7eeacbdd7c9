//! `/api/files`: each source file that broke a pass, diffed against its
//! last good version, and `POST /api/files/revert`, which writes a file's
//! last good text back. Only a client on this machine may revert: writing
//! a project file is not something a page served to the network may do.

use std::net::SocketAddr;
use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::{ConnectInfo, State};
use axum::http::StatusCode;
use axum::response::Response;
use serde::Deserialize;

use super::AppState;
use super::guard::{error, json};
use crate::serve::last_good::RevertError;
use crate::serve::shared::read;

/// `GET /api/files`: `{ "files": [FileDiff…] }`, empty when every file is
/// good (or was never good: nothing to diff against).
pub(super) async fn list(State(st): State<Arc<AppState>>) -> Response {
    json(&serde_json::json!({ "files": read(&st.shared.files).diffs }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RevertRequest {
    file: String,
}

/// `POST /api/files/revert` with `{ "file": "shaders/…" }`: writes the
/// file's last good text over it, as an editor saves (a temporary file
/// renamed over it); the watcher then reloads it like any save.
pub(super) async fn revert(State(st): State<Arc<AppState>>, ConnectInfo(peer): ConnectInfo<SocketAddr>, body: Bytes) -> Response {
    if !peer.ip().is_loopback() {
        return error(StatusCode::FORBIDDEN, "revert refused: only a client on this machine (loopback) may write project files");
    }
    let request: RevertRequest = match serde_json::from_slice(&body) {
        Ok(r) => r,
        Err(e) => return error(StatusCode::BAD_REQUEST, &format!("invalid revert request: {e}; expected {{\"file\": \"…\"}}")),
    };
    match crate::serve::last_good::revert(&st.shared, &request.file) {
        Ok(()) => json(&serde_json::json!({ "file": request.file, "reverted": true })),
        Err(e @ RevertError::NoLastGood(_) | e @ RevertError::NotASource(_)) => error(StatusCode::NOT_FOUND, &e.to_string()),
        Err(e @ RevertError::Write(..)) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}
