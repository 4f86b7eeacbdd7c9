//! The browser UI: the files of the repository's `client/` directory,
//! embedded in the binary.

use axum::body::Body;
use axum::http::{HeaderValue, Method, StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};
use rust_embed::RustEmbed;

use super::guard::error;
use super::sources::safe_relative;

/// The web UI, from the repository's `client/` directory (the path is
/// relative to `server/Cargo.toml`). Debug builds read it from disk.
#[derive(RustEmbed)]
#[folder = "../client/"]
struct Client;
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

pub(super) async fn index() -> Response {
    embedded("index.html")
}

pub(super) async fn static_file(method: Method, uri: Uri) -> Response {
    if method != Method::GET && method != Method::HEAD {
        // As axum answers for the API's routes: the methods that would work.
        let mut refused = error(StatusCode::METHOD_NOT_ALLOWED, "method not allowed");
        refused.headers_mut().insert(header::ALLOW, HeaderValue::from_static("GET,HEAD"));
        return refused;
    }
    let raw = uri.path().trim_start_matches('/');
    match safe_relative(raw) {
        Some(rel) => embedded(&rel),
        None => error(StatusCode::NOT_FOUND, "no such file"),
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{get, request, start};
    use super::*;

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
        // A file is a known route: another method is 405, with the methods
        // that work, as on the API (and on `/`, which axum routes).
        for path in ["/index.html", "/app.js", "/no-such-file.js", "/"] {
            let r = request(s.addr, "POST", path, "").await;
            assert_eq!((r.status, r.header("allow").as_deref()), (405, Some("GET,HEAD")), "POST {path}");
            assert_eq!(r.json()["error"], "method not allowed");
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
}
