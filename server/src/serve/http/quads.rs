//! Quad statistics over HTTP: the newest frame's report as JSON, and each
//! raster pass's quad-overdraw and helper-lane maps as raw f32 images the
//! inspector lays over the pass's outputs.

use std::sync::Arc;

use axum::extract::{Path as UrlPath, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::guard::{error, json, state};
use crate::serve::shared::read;

/// No client asks for quad statistics (`quad_statistics`), or none has come
/// yet: a state (PROTOCOL.md "States"), not an error.
const NOT_COMPUTED: &str = "not-computed";

/// `GET /api/quads`: the newest frame's quad statistics.
pub(super) async fn report(State(st): State<Arc<AppState>>) -> Response {
    match read(&st.shared.quads) {
        Some(r) => json(&*r),
        None => state(NOT_COMPUTED),
    }
}

/// `GET /api/quads/{pass}/overdraw.f32` (quads launched over each pixel's
/// 2×2 block) and `…/helpers.f32` (times each pixel ran as a helper lane):
/// one f32 a pixel, rows top first, a pass's render targets one under
/// another.
pub(super) async fn map(State(st): State<Arc<AppState>>, UrlPath((pass, file)): UrlPath<(String, String)>) -> Response {
    let overdraw = match file.as_str() {
        "overdraw.f32" => true,
        "helpers.f32" => false,
        _ => return error(StatusCode::BAD_REQUEST, &format!("unknown map `{file}`: expected overdraw.f32 or helpers.f32")),
    };
    let Some(report) = read(&st.shared.quads) else {
        return state(NOT_COMPUTED);
    };
    let Some(p) = report.passes.iter().find(|p| p.quads.pass == pass) else {
        return error(StatusCode::NOT_FOUND, &format!("no quad statistics for pass `{pass}`: not a raster pass of this frame"));
    };
    let Some((width, height, quads, helpers)) = p.quads.stacked_maps() else {
        return error(StatusCode::NOT_FOUND, &format!("pass `{pass}` drew nothing"));
    };
    let values = if overdraw { quads } else { helpers };
    let body: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut resp = (StatusCode::OK, [(header::CONTENT_TYPE, "application/octet-stream")], body).into_response();
    let h = resp.headers_mut();
    h.insert("x-loupe-width", HeaderValue::from(width));
    h.insert("x-loupe-height", HeaderValue::from(height));
    h.insert("x-loupe-frame", HeaderValue::from(report.frame));
    h.insert("x-loupe-channels", HeaderValue::from_static("1"));
    resp
}
