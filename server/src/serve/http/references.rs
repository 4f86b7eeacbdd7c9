//! `/api/references`: the scene's image cases compared with their
//! references ("against reference", `serve::references`), their images,
//! and the bless that writes what a page shows as the new references. Only
//! a client on this machine may bless: it writes project files.

use std::net::SocketAddr;
use std::sync::Arc;

use axum::extract::{ConnectInfo, Path as UrlPath, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::guard::{error, json};
use crate::serve::references;
use crate::serve::shared::read;

/// `GET /api/references`: the newest comparison (ReferenceReport).
pub(super) async fn report(State(st): State<Arc<AppState>>) -> Response {
    json(&read(&st.shared.references).report)
}

/// `GET /api/references/{case}/{index}/{actual|reference|flip}.png`: an
/// output's image from the newest comparison.
pub(super) async fn image(State(st): State<Arc<AppState>>, UrlPath((case, index, file)): UrlPath<(String, usize, String)>) -> Response {
    let state = read(&st.shared.references);
    let Some(images) = state.images.get(&(case.clone(), index)) else {
        return error(StatusCode::NOT_FOUND, &format!("case `{case}` has no output {index} in the newest comparison"));
    };
    let bytes = match file.as_str() {
        "actual.png" => Some(&images.actual),
        "reference.png" => images.reference.as_ref(),
        "flip.png" => images.flip.as_ref(),
        _ => return error(StatusCode::BAD_REQUEST, &format!("unknown image `{file}`: expected actual.png, reference.png or flip.png")),
    };
    match bytes {
        Some(b) => ([(header::CONTENT_TYPE, "image/png")], b.clone()).into_response(),
        None => {
            error(StatusCode::NOT_FOUND, &format!("case `{case}`'s output {index} has no {file}: it has no reference it compared with"))
        }
    }
}

/// `POST /api/references/{case}/bless`: writes the case's outputs as last
/// compared as its references, then compares again.
pub(super) async fn bless(
    State(st): State<Arc<AppState>>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    UrlPath(case): UrlPath<String>,
) -> Response {
    if !peer.ip().is_loopback() {
        return error(StatusCode::FORBIDDEN, "bless refused: only a client on this machine (loopback) may write references");
    }
    match references::bless(&st.shared, &case) {
        Ok(outputs) => json(&serde_json::json!({ "case": case, "blessed": outputs })),
        Err(e @ references::BlessError::NotCompared(_)) => error(StatusCode::NOT_FOUND, &e.to_string()),
        Err(e @ references::BlessError::Write(_)) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}
