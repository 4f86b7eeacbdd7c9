//! `GET /api/materials/{index}/preview?renderer=raster|path`: a material
//! instance on a sphere, as a PNG, rendered on the daemon's preview thread
//! (`serve::preview`) while the request waits.

use std::sync::Arc;

use axum::extract::{Path as UrlPath, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use tokio::sync::oneshot;

use super::AppState;
use super::guard::{error, json_response};
use crate::render::preview::PreviewError;
use crate::scene::Renderer;
use crate::serve::inbox::Command;
use crate::serve::preview::{Failed, Request};

#[derive(Deserialize)]
pub(super) struct PreviewQuery {
    renderer: Option<String>,
}

pub(super) async fn preview(State(st): State<Arc<AppState>>, UrlPath(index): UrlPath<String>, Query(q): Query<PreviewQuery>) -> Response {
    let Ok(material) = index.parse::<usize>() else {
        return error(StatusCode::NOT_FOUND, &format!("`{index}` is not a material index"));
    };
    let renderer = match q.renderer.as_deref() {
        None | Some("raster") => Renderer::Raster,
        Some("path") => Renderer::Path,
        Some(other) => return error(StatusCode::BAD_REQUEST, &format!("unknown renderer `{other}`: expected `raster` or `path`")),
    };
    let (reply, answer) = oneshot::channel();
    if let Err(refused) = st.shared.clients.command(Command::Preview(Request { material, renderer, reply })) {
        return error(StatusCode::SERVICE_UNAVAILABLE, &refused.to_string());
    }
    match answer.await {
        Ok(Ok(p)) => {
            let samples = p.samples.to_string();
            (StatusCode::OK, [(header::CONTENT_TYPE, "image/png"), (header::HeaderName::from_static("x-loupe-samples"), &samples)], p.png)
                .into_response()
        }
        Ok(Err(missing @ Failed::Preview(PreviewError::NoSuchMaterial { .. }))) => error(StatusCode::NOT_FOUND, &missing.to_string()),
        Ok(Err(Failed::Preview(PreviewError::Pipelines(diagnostics)))) => json_response(
            StatusCode::UNPROCESSABLE_ENTITY,
            &serde_json::json!({ "error": "the preview's pipelines did not build", "diagnostics": diagnostics }),
        ),
        Ok(Err(busy @ Failed::Busy)) => error(StatusCode::SERVICE_UNAVAILABLE, &busy.to_string()),
        Ok(Err(panicked @ Failed::Panicked(_))) => error(StatusCode::INTERNAL_SERVER_ERROR, &panicked.to_string()),
        Err(_) => error(StatusCode::SERVICE_UNAVAILABLE, "the daemon stopped before the preview was rendered"),
    }
}
