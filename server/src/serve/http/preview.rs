//! `GET /api/materials/{index}/preview?renderer=raster|path&budget=full|N`:
//! a material instance on a sphere (as the scene renders it, with its full
//! definition, or simplified to N bytes per pixel), as a PNG, rendered on the daemon's preview thread
//! (`serve::preview`) while the request waits.

use std::sync::Arc;

use axum::extract::{Path as UrlPath, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use tokio::sync::oneshot;

use super::AppState;
use super::guard::{error, json_response};
use crate::render::preview::{Materials, PreviewError};
use crate::scene::Renderer;
use crate::serve::inbox::Command;
use crate::serve::preview::{Failed, Request};

#[derive(Deserialize)]
pub(super) struct PreviewQuery {
    renderer: Option<String>,
    budget: Option<String>,
}

/// `budget`: absent (as the scene renders), `full`, or bytes per pixel
/// within `quality.material_bytes`'s range.
fn materials(budget: Option<&str>) -> Result<Materials, String> {
    let Some(text) = budget else { return Ok(Materials::AsScene) };
    if text == "full" {
        return Ok(Materials::Full);
    }
    let setting = crate::scene::settings::find("quality.material_bytes").expect("the budget is a setting");
    let n = text.parse::<i64>().map_err(|_| format!("budget `{text}`: expected `full` or bytes per pixel (`{}`)", setting.path))?;
    let value = crate::scene::settings::Value::Int(n);
    setting.check(&value).map_err(|e| format!("budget: `{}` {e}", setting.path))?;
    Ok(Materials::Budget(n as u32))
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
    let materials = match materials(q.budget.as_deref()) {
        Ok(m) => m,
        Err(message) => return error(StatusCode::BAD_REQUEST, &message),
    };
    let (reply, answer) = oneshot::channel();
    if let Err(refused) = st.shared.clients.command(Command::Preview(Request { material, renderer, materials, reply })) {
        return error(StatusCode::SERVICE_UNAVAILABLE, &refused.to_string());
    }
    match answer.await {
        Ok(Ok(p)) => {
            let (samples, bytes) = (p.samples.to_string(), p.material_bytes.to_string());
            let headers = [
                (header::CONTENT_TYPE, "image/png"),
                (header::HeaderName::from_static("x-loupe-samples"), &samples),
                (header::HeaderName::from_static("x-loupe-material-bytes"), &bytes),
            ];
            (StatusCode::OK, headers, p.png).into_response()
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
