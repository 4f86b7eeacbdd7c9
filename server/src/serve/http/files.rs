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
    let state = read(&st.shared.files);
    let Some((path, text)) = state.last_good.get(&request.file) else {
        return error(
            StatusCode::NOT_FOUND,
            &format!("`{}` has no last good version to revert to: it is good, or never was", request.file),
        );
    };
    // Only a project source (not a generated module) is written.
    let inside = |root: &std::path::PathBuf| Some(path.canonicalize().ok()?.starts_with(root.canonicalize().ok()?));
    if !st.shared.source_roots.iter().any(|r| inside(r) == Some(true)) {
        return error(StatusCode::NOT_FOUND, &format!("`{}` is not a source file under the project's source roots", request.file));
    }
    match write_like_an_editor(path, text.as_bytes()) {
        Ok(()) => json(&serde_json::json!({ "file": request.file, "reverted": true })),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &format!("cannot write `{}`: {e}", request.file)),
    }
}

/// Writes a sibling temporary file and renames it over `path`, so the file
/// is never seen half written.
fn write_like_an_editor(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let temporary = path.with_file_name(format!(".{name}.loupe-revert"));
    std::fs::write(&temporary, bytes)?;
    std::fs::rename(&temporary, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&temporary);
    })
}
