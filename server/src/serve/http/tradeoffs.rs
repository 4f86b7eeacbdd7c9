//! `/api/tradeoffs`: the newest `loupe bench tradeoffs` results in the
//! project (`tradeoffs/` under the root, the command's default output), for
//! the browser's accuracy-against-time chart; and each point's image. The
//! files are the command's own: served as written, never rendered here.
//!
//! Whether they are this scene's is told in `X-Loupe-State` (PROTOCOL.md):
//! `current` (the hash of what they measured is the scene file's and the
//! shader sources' now), `stale` (this scene, but it or a shader changed
//! since), `other-scene`; none written yet is the state `not-written`
//! (204), not an error.

use std::path::PathBuf;
use std::sync::Arc;

use axum::extract::{Path, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

use serde::Deserialize;

use super::AppState;
use super::guard::{error, state};
use crate::serve::shared::read as read_shared;

/// The largest results file and point image served.
const MAX_BYTES: u64 = 64 * 1024 * 1024;

/// What the results say they measured (`loupe bench tradeoffs` writes
/// both; an older file has no hash).
#[derive(Deserialize)]
struct Made {
    scene: Option<String>,
    hash: Option<String>,
}

/// The results' state against the scene and sources being rendered.
fn verdict(results: &[u8], now: &crate::tradeoffs::Provenance) -> &'static str {
    let made: Option<Made> = serde_json::from_slice(results).ok();
    match made {
        Some(m) if m.hash.as_deref() == Some(now.hash.as_str()) => "current",
        Some(m) if m.scene.as_deref() == Some(now.scene.as_str()) => "stale",
        _ => "other-scene",
    }
}

async fn read(path: PathBuf, missing: String) -> Result<Vec<u8>, Response> {
    let found = tokio::task::spawn_blocking(move || {
        let len = std::fs::metadata(&path).map_err(|_| (StatusCode::NOT_FOUND, missing.clone()))?.len();
        if len > MAX_BYTES {
            return Err((StatusCode::PAYLOAD_TOO_LARGE, format!("{} is larger than {MAX_BYTES} bytes", path.display())));
        }
        std::fs::read(&path).map_err(|_| (StatusCode::NOT_FOUND, missing))
    })
    .await;
    match found {
        Ok(Ok(bytes)) => Ok(bytes),
        Ok(Err((status, message))) => Err(error(status, &message)),
        Err(e) => Err(error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string())),
    }
}

pub(super) async fn results(State(st): State<Arc<AppState>>) -> Response {
    let path = st.shared.tradeoffs.join("tradeoffs.json");
    if !path.exists() {
        return state("not-written");
    }
    match read(path, "tradeoffs.json went away while being read".into()).await {
        Ok(bytes) => {
            let verdict = verdict(&bytes, &read_shared(&st.shared.measured));
            (
                StatusCode::OK,
                [(header::CONTENT_TYPE, "application/json"), (header::HeaderName::from_static("x-loupe-state"), verdict)],
                bytes,
            )
                .into_response()
        }
        Err(r) => r,
    }
}

/// A point's image: `points/<name>.png`, the name of plain characters only.
pub(super) async fn point(State(st): State<Arc<AppState>>, Path(file): Path<String>) -> Response {
    let plain = file.strip_suffix(".png").is_some_and(|s| {
        !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')) && !s.contains("..")
    });
    if !plain {
        return error(StatusCode::FORBIDDEN, "only a point's image, `<name>.png`, is served");
    }
    match read(st.shared.tradeoffs.join("points").join(&file), format!("no point image `{file}`")).await {
        Ok(bytes) => (StatusCode::OK, [(header::CONTENT_TYPE, "image/png")], bytes).into_response(),
        Err(r) => r,
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{get, start, temp_dir};

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn results_and_point_images_are_served_from_the_project_and_nothing_else() {
        let root = temp_dir("tradeoffs");
        let s = start(vec![root.clone()]).await;
        let missing = get(s.addr, "/api/tradeoffs").await;
        assert_eq!((missing.status, missing.header("x-loupe-state").as_deref()), (204, Some("not-written")));
        let dir = root.join("tradeoffs");
        std::fs::create_dir_all(dir.join("points")).unwrap();
        std::fs::write(dir.join("tradeoffs.json"), br#"{"scene":"scenes/a.toml","series":[]}"#).unwrap();
        std::fs::write(dir.join("points/0-4.png"), b"\x89PNG").unwrap();
        std::fs::write(root.join("secret.png"), b"TOPSECRET").unwrap();
        let r = get(s.addr, "/api/tradeoffs").await;
        assert_eq!((r.status, r.header("content-type").as_deref()), (200, Some("application/json")));
        assert_eq!(r.body, br#"{"scene":"scenes/a.toml","series":[]}"#);
        assert_eq!(r.header("x-loupe-state").as_deref(), Some("other-scene"));
        let r = get(s.addr, "/api/tradeoffs/points/0-4.png").await;
        assert_eq!((r.status, r.body.as_slice()), (200, &b"\x89PNG"[..]));
        for bad in ["/api/tradeoffs/points/..%2Fsecret.png", "/api/tradeoffs/points/secret.txt", "/api/tradeoffs/points/%2E%2E.png"] {
            let r = get(s.addr, bad).await;
            assert_eq!(r.status, 403, "{bad}: {}", String::from_utf8_lossy(&r.body));
            assert!(!String::from_utf8_lossy(&r.body).contains("TOPSECRET"));
        }
        assert_eq!(get(s.addr, "/api/tradeoffs/points/nope.png").await.status, 404);
    }

    #[test]
    fn results_are_current_for_the_hash_stale_for_the_scene_else_another_scenes() {
        let now = crate::tradeoffs::Provenance { scene: "scenes/a.toml".into(), hash: "abc".into() };
        let v = |json: &str| super::verdict(json.as_bytes(), &now);
        assert_eq!(v(r#"{"scene":"scenes/a.toml","hash":"abc"}"#), "current");
        assert_eq!(v(r#"{"scene":"elsewhere/a.toml","hash":"abc"}"#), "current", "the hash covers the scene file's bytes");
        assert_eq!(v(r#"{"scene":"scenes/a.toml","hash":"old"}"#), "stale");
        assert_eq!(v(r#"{"scene":"scenes/a.toml"}"#), "stale");
        assert_eq!(v(r#"{"scene":"scenes/b.toml","hash":"old"}"#), "other-scene");
        assert_eq!(v("not json"), "other-scene");
    }
}
