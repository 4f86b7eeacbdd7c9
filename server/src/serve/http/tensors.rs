//! Captured buffers as tensors: the list, one tensor's layout and
//! statistics as JSON, and its values as raw little-endian f32.

use std::sync::Arc;

use axum::extract::{Path as UrlPath, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use super::AppState;
use super::guard::{error, json};
use crate::render::capture::{CapturedTensor, TensorStats};
use crate::render::resource::TensorLayout;
use crate::serve::shared::read;

#[derive(Serialize)]
struct TensorInfo<'a> {
    pass: &'a str,
    output: &'a str,
    frame: u64,
    layout: &'a TensorLayout,
    stats: &'a TensorStats,
}

fn info(t: &CapturedTensor) -> TensorInfo<'_> {
    TensorInfo { pass: &t.pass, output: &t.output, frame: t.frame, layout: &t.layout, stats: &t.stats }
}

/// `GET /api/tensors`: every captured buffer of the newest frames.
pub(super) async fn list(State(st): State<Arc<AppState>>) -> Response {
    let tensors = read(&st.shared.tensors);
    json(&tensors.values().map(|t| info(t)).collect::<Vec<_>>())
}

/// `GET /api/tensors/{pass}/{output}` (JSON) and `…/{output}.f32` (values).
pub(super) async fn tensor(State(st): State<Arc<AppState>>, UrlPath((pass, file)): UrlPath<(String, String)>) -> Response {
    let (output, raw) = match file.rsplit_once('.') {
        Some((output, "f32")) => (output, true),
        Some((_, ext)) => return error(StatusCode::BAD_REQUEST, &format!("unknown extension `.{ext}`: expected none (JSON) or .f32")),
        None => (file.as_str(), false),
    };
    let key = format!("{pass}/{output}");
    let Some(t) = read(&st.shared.tensors).get(&key).cloned() else {
        // Subscribing makes a later frame capture it.
        if super::api::writes(&st.shared, &pass, output) {
            return super::guard::state(super::api::NOT_CAPTURED);
        }
        return error(StatusCode::NOT_FOUND, &format!("`{pass}` writes no tensor `{output}`"));
    };
    if !raw {
        return json(&info(&t));
    }
    let mut resp = (StatusCode::OK, [(header::CONTENT_TYPE, "application/octet-stream")], t.raw_f32()).into_response();
    let h = resp.headers_mut();
    h.insert("x-loupe-frame", HeaderValue::from(t.frame));
    if let Ok(v) = HeaderValue::from_str(&t.layout.dims.iter().map(|(_, n)| n.to_string()).collect::<Vec<_>>().join(",")) {
        h.insert("x-loupe-shape", v);
    }
    resp
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use crate::render::capture::CapturedTensor;
    use crate::render::resource::{Element, TensorLayout};
    use crate::serve::shared;

    #[tokio::test]
    async fn tensors_are_listed_and_served_as_json_and_raw_f32() {
        let s = start(vec![]).await;
        let bins: Vec<u8> = [3u32, 0, 5, 1].iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = CapturedTensor::new("exposure_histogram", "histogram", 7, TensorLayout::new(&[("bin", 4)], Element::U32), &bins);
        shared::write(&s.shared.tensors, std::sync::Arc::new([(t.key(), std::sync::Arc::new(t))].into()));

        let list = get(s.addr, "/api/tensors").await.json();
        assert_eq!(list[0]["pass"], "exposure_histogram");
        assert_eq!(list[0]["layout"]["dims"], serde_json::json!([["bin", 4]]));
        assert_eq!(list[0]["layout"]["element"], "u32");

        let one = get(s.addr, "/api/tensors/exposure_histogram/histogram").await.json();
        assert_eq!(one["frame"], 7);
        assert_eq!(one["stats"]["max"], serde_json::json!([5.0]));

        let raw = get(s.addr, "/api/tensors/exposure_histogram/histogram.f32").await;
        assert_eq!(raw.status, 200);
        assert_eq!(raw.header("x-loupe-shape").as_deref(), Some("4"));
        let values: Vec<f32> = raw.body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        assert_eq!(values, [3.0, 0.0, 5.0, 1.0]);

        assert_eq!(get(s.addr, "/api/tensors/exposure_histogram/nope").await.status, 404);
        assert_eq!(get(s.addr, "/api/tensors/exposure_histogram/histogram.png").await.status, 400);
    }
}
