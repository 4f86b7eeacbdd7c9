//! What every request and response passes through: the Host/Origin check
//! (DNS-rebinding, cross-site request and WebSocket-hijacking defences; see
//! PROTOCOL.md, "Security rules") and the finishing of responses (errors as
//! JSON, `no-store` on `/api`, `nosniff` everywhere).

use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use super::AppState;

#[derive(Serialize)]
struct ErrorBody<'a> {
    error: &'a str,
}

pub(super) fn json_response<T: Serialize + ?Sized>(status: StatusCode, value: &T) -> Response {
    match serde_json::to_vec(value) {
        Ok(body) => (status, [(header::CONTENT_TYPE, "application/json")], body).into_response(),
        Err(e) => {
            let body = serde_json::to_vec(&ErrorBody { error: &format!("cannot encode response: {e}") }).unwrap_or_default();
            (StatusCode::INTERNAL_SERVER_ERROR, [(header::CONTENT_TYPE, "application/json")], body).into_response()
        }
    }
}

pub(super) fn json<T: Serialize + ?Sized>(value: &T) -> Response {
    json_response(StatusCode::OK, value)
}

pub(super) fn error(status: StatusCode, message: &str) -> Response {
    json_response(status, &ErrorBody { error: message })
}

/// A documented state, not an error (PROTOCOL.md, "States"): what was
/// asked for exists but has nothing to show yet. `204 No Content` with
/// `X-Loupe-State: {name}`, so a browser logs no failed request.
pub(super) fn state(name: &'static str) -> Response {
    (StatusCode::NO_CONTENT, [("x-loupe-state", name)]).into_response()
}

fn is_api(path: &str) -> bool {
    path == "/api" || path.starts_with("/api/")
}

fn is_json(headers: &HeaderMap) -> bool {
    headers.get(header::CONTENT_TYPE).and_then(|v| v.to_str().ok()).is_some_and(|v| v.starts_with("application/json"))
}

/// Every error becomes `{"error": "..."}` (axum's own rejections — 405,
/// a bad query, a failed WebSocket handshake — are plain text), `/api`
/// responses get `Cache-Control: no-store`, everything gets `nosniff`.
fn finish(mut resp: Response, api: bool) -> Response {
    let status = resp.status();
    if (status.is_client_error() || status.is_server_error()) && !is_json(resp.headers()) {
        let message = status.canonical_reason().unwrap_or("error").to_ascii_lowercase();
        let fresh = error(status, &message);
        let (mut parts, _) = resp.into_parts();
        let (fresh_parts, body) = fresh.into_parts();
        parts.headers.remove(header::CONTENT_LENGTH);
        for (name, value) in fresh_parts.headers.iter() {
            parts.headers.insert(name, value.clone());
        }
        resp = Response::from_parts(parts, body);
    }
    let headers = resp.headers_mut();
    if api {
        headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    }
    headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    resp
}

fn host_allowed(hosts: &[String], req: &Request) -> bool {
    let mut values = req.headers().get_all(header::HOST).iter();
    let host = match (values.next(), values.next()) {
        (Some(v), None) => match v.to_str() {
            Ok(v) => Some(v.to_ascii_lowercase()),
            Err(_) => return false,
        },
        (None, _) => None,
        (Some(_), Some(_)) => return false,
    };
    // An absolute-form request target names its own authority; it must be
    // allowed too (and it is what HTTP/2 clients send instead of Host).
    let authority = req.uri().authority().map(|a| a.as_str().to_ascii_lowercase());
    let ok = |h: &str| hosts.iter().any(|a| a == h);
    match (host, authority) {
        (None, None) => false,
        (Some(h), None) | (None, Some(h)) => ok(&h),
        (Some(h), Some(a)) => ok(&h) && ok(&a),
    }
}

fn origin_allowed(hosts: &[String], origin: &HeaderValue) -> bool {
    let Ok(origin) = origin.to_str() else { return false };
    let origin = origin.to_ascii_lowercase();
    origin.strip_prefix("http://").is_some_and(|h| hosts.iter().any(|a| a == h))
}

pub(super) async fn guard(State(st): State<Arc<AppState>>, req: Request, next: Next) -> Response {
    let api = is_api(req.uri().path());
    if !host_allowed(&st.hosts, &req) {
        return finish(error(StatusCode::FORBIDDEN, "host not allowed: open the UI through localhost or 127.0.0.1"), api);
    }
    let state_changing = !matches!(*req.method(), Method::GET | Method::HEAD | Method::OPTIONS);
    let upgrade = req.headers().contains_key(header::UPGRADE) || req.uri().path() == "/ws";
    if state_changing || upgrade {
        let origins: Vec<&HeaderValue> = req.headers().get_all(header::ORIGIN).iter().collect();
        let ok = match origins.as_slice() {
            [] => true,
            [one] => origin_allowed(&st.hosts, one),
            _ => false,
        };
        if !ok {
            return finish(error(StatusCode::FORBIDDEN, "cross-origin request refused"), api);
        }
    }
    let resp = next.run(req).await;
    finish(resp, api)
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::super::testing::{daemon_event, raw, request, start};
    use crate::serve::event::Event;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn wrong_host_is_refused() {
        let s = start(vec![]).await;
        let port = s.addr.port();
        for host in [format!("127.0.0.1:{port}"), format!("localhost:{port}"), format!("LOCALHOST:{port}"), format!("[::1]:{port}")] {
            let r = raw(s.addr, &format!("GET /api/status HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n")).await;
            assert_eq!(r.status, 200, "{host}");
        }
        for host in [
            "evil.example".to_owned(),
            format!("evil.example:{port}"),
            format!("127.0.0.1:{}", port.wrapping_add(1)),
            "127.0.0.1".to_owned(),
            format!("localhost.evil.example:{port}"),
        ] {
            for path in ["/api/status", "/", "/ws"] {
                let r = raw(s.addr, &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n")).await;
                assert_eq!(r.status, 403, "{host} {path}");
                assert!(r.json()["error"].is_string());
            }
        }
        // No Host at all, and two of them.
        let r = raw(s.addr, "GET /api/status HTTP/1.0\r\n\r\n").await;
        assert_eq!(r.status, 403);
        let r =
            raw(s.addr, &format!("GET /api/status HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nHost: evil.example\r\nConnection: close\r\n\r\n"))
                .await;
        assert_eq!(r.status, 403);
        // An absolute-form target naming another authority.
        let r = raw(s.addr, &format!("GET http://evil.example/api/status HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"))
            .await;
        assert_eq!(r.status, 403);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn reload_needs_a_same_origin_or_no_origin() {
        let s = start(vec![]).await;
        for origin in ["http://evil.example", "null", "https://127.0.0.1", &format!("https://127.0.0.1:{}", s.addr.port())] {
            let r = request(s.addr, "POST", "/api/reload", &format!("Origin: {origin}\r\n")).await;
            assert_eq!(r.status, 403, "{origin}");
            assert!(r.json()["error"].is_string());
        }
        assert!(s.daemon.recv_timeout(Duration::ZERO).is_err(), "a refused request reached the daemon");

        let r = request(s.addr, "POST", "/api/reload", &format!("Origin: http://localhost:{}\r\n", s.addr.port())).await;
        assert_eq!(r.status, 202, "{}", r.text());
        assert_eq!(r.json()["accepted"], true);
        assert!(matches!(daemon_event(&s), Some(Event::Rebuild)));

        let r = request(s.addr, "POST", "/api/reload", "").await;
        assert_eq!(r.status, 202);
        assert!(matches!(daemon_event(&s), Some(Event::Rebuild)));

        // A cross-site GET is harmless (the browser won't let the page read
        // it) and is allowed.
        let r = request(s.addr, "GET", "/api/status", "Origin: http://evil.example\r\n").await;
        assert_eq!(r.status, 200);
    }
}
