//! The HTTP + WebSocket layer: the JSON API, capture downloads, source
//! excerpts, the live event/frame stream and the embedded UI. PROTOCOL.md at
//! the repository root documents every route and shape.
//!
//! Architecture Invariant: this is the only module that encodes JSON for the
//! daemon's clients. Handlers never block the render thread: they read the
//! snapshots in [`Shared`] and send [`Event`](super::event::Event)s back.
//!
//! Security (a dev server on localhost is still reachable from every web page
//! the user opens):
//! - every request must carry a `Host` that is one of the allowed hosts
//!   (DNS-rebinding defence), else 403;
//! - WebSocket upgrades and state-changing requests (any method but GET,
//!   HEAD, OPTIONS) that carry an `Origin` must come from `http://` + an
//!   allowed host, else 403 (cross-site request and WebSocket hijacking
//!   defence); a missing `Origin` is allowed (non-browser clients);
//! - `/api/sources/...` serves only regular files whose canonical path lies
//!   inside a canonicalized source root.
//!
//! One module per job: [`guard`] (the Host/Origin check every request
//! passes, and the JSON error / `no-store` finishing every response gets),
//! [`api`] (the JSON API and capture downloads), [`preview`] (material
//! previews, rendered while the request waits), [`sources`] (source files
//! for diagnostic excerpts, with the path-traversal defences), [`ui`] (the
//! embedded browser UI) and [`ws`] (the WebSocket stream).
//!
//! Startup: [`bind`] the address (port 0 picks a free port and returns the
//! real one), compute [`allowed_hosts`] from the bound address, then
//! [`serve`] until the shutdown future completes.

mod api;
mod files;
mod guard;
mod preview;
mod quads;
mod references;
mod sources;
mod tensors;
#[cfg(test)]
mod testing;
mod tradeoffs;
mod ui;
mod ws;

pub use ws::MAX_SUBSCRIPTIONS;

use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::sync::Arc;

use axum::Router;
use axum::middleware;
use axum::routing::{any, get, post};
use tokio::net::TcpListener;
use tokio::sync::watch;

use super::shared::Shared;

struct AppState {
    shared: Arc<Shared>,
    /// Lowercased `host:port` values a request's `Host` may name.
    hosts: Vec<String>,
    /// Set to true when the server shuts down: WebSocket tasks close.
    stop: watch::Sender<bool>,
}

/// Binds a TCP listener; port 0 picks a free port. Returns the listener and
/// the address actually bound (what [`allowed_hosts`] needs).
pub async fn bind(addr: SocketAddr) -> io::Result<(TcpListener, SocketAddr)> {
    let listener = TcpListener::bind(addr).await?;
    let local = listener.local_addr()?;
    Ok((listener, local))
}

/// The `Host` values to accept for a server bound to `local`:
/// `127.0.0.1:PORT`, `localhost:PORT`, `[::1]:PORT`, plus `local` itself when
/// it is neither loopback nor unspecified (`0.0.0.0`/`::` accept only the
/// loopback names; add others explicitly). On port 80 the port-less forms
/// are accepted too, since browsers omit a default port.
pub fn allowed_hosts(local: SocketAddr) -> Vec<String> {
    let port = local.port();
    let mut hosts = vec![format!("127.0.0.1:{port}"), format!("localhost:{port}"), format!("[::1]:{port}")];
    if !local.ip().is_loopback() && !local.ip().is_unspecified() {
        hosts.push(local.to_string());
    }
    if port == 80 {
        let bare: Vec<String> = hosts.iter().filter_map(|h| h.rsplit_once(':').map(|(h, _)| h.to_owned())).collect();
        hosts.extend(bare);
    }
    hosts
}

/// The whole application: API, WebSocket, static UI, and the Host/Origin
/// guard. `allowed_hosts` are `host:port` strings compared
/// case-insensitively (see [`allowed_hosts`]).
pub fn router(shared: Arc<Shared>, allowed_hosts: Vec<String>) -> Router {
    build(shared, allowed_hosts).0
}

/// Serves `router(shared, allowed_hosts)` on `listener` until `shutdown`
/// completes, then closes every WebSocket (code 1001) and waits for open
/// HTTP requests to finish. It does not tell the daemon to stop: send
/// `Event::Shutdown` after it returns if that is wanted.
pub async fn serve(
    listener: TcpListener,
    shared: Arc<Shared>,
    allowed_hosts: Vec<String>,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> io::Result<()> {
    let (app, stop) = build(shared, allowed_hosts);
    // The peer's address: some routes serve only this machine.
    axum::serve(listener, app.into_make_service_with_connect_info::<SocketAddr>())
        .with_graceful_shutdown(async move {
            shutdown.await;
            stop.send_replace(true);
        })
        .await
}

fn build(shared: Arc<Shared>, allowed_hosts: Vec<String>) -> (Router, watch::Sender<bool>) {
    let stop = watch::Sender::new(false);
    let state =
        Arc::new(AppState { shared, hosts: allowed_hosts.into_iter().map(|h| h.to_ascii_lowercase()).collect(), stop: stop.clone() });
    let mut app = Router::new();
    if state.shared.debug_api {
        app = app.route("/api/debug/lose-device", post(api::lose_device));
    }
    let app = app
        .route("/api/status", get(api::status))
        .route("/api/passes", get(api::passes))
        .route("/api/pipelines", get(api::pipelines))
        .route("/api/diagnostics", get(api::diagnostics))
        .route("/api/captures", get(api::captures))
        .route("/api/captures/{pass}/{file}", get(api::capture))
        .route("/api/tensors", get(tensors::list))
        .route("/api/nan", get(api::nan))
        .route("/api/quads", get(quads::report))
        .route("/api/quads/{pass}/{file}", get(quads::map))
        .route("/api/frame/trace", post(api::trace))
        .route("/api/tensors/{pass}/{file}", get(tensors::tensor))
        .route("/api/sources/{*path}", get(sources::source))
        .route("/api/files", get(files::list))
        .route("/api/files/revert", post(files::revert))
        .route("/api/references", get(references::report))
        .route("/api/references/{case}/bless", post(references::bless))
        .route("/api/references/{case}/{index}/{file}", get(references::image))
        .route("/api/reload", post(api::reload))
        .route("/api/controls", get(api::controls))
        .route("/api/materials", get(api::materials))
        .route("/api/materials/{index}/preview", get(preview::preview))
        .route("/api/tradeoffs", get(tradeoffs::results))
        .route("/api/tradeoffs/points/{file}", get(tradeoffs::point))
        .route("/api/scene/save", post(api::save_scene))
        .route("/api", any(api::not_found))
        .route("/api/{*rest}", any(api::not_found))
        .route("/ws", get(ws::upgrade))
        .route("/", get(ui::index))
        .fallback(ui::static_file)
        .layer(middleware::from_fn_with_state(state.clone(), guard::guard))
        .with_state(state);
    (app, stop)
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use tokio_tungstenite::tungstenite;

    use super::testing::{connect, next_json, next_message, start};
    use super::*;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn shutdown_closes_websockets_and_returns() {
        let mut s = start(vec![]).await;
        let mut ws = connect(s.addr, None).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "hello");
        s.stop.take().unwrap().send(()).unwrap();
        match next_message(&mut ws).await {
            tungstenite::Message::Close(Some(f)) => assert_eq!(u16::from(f.code), 1001),
            other => panic!("expected close, got {other:?}"),
        }
        drop(ws);
        tokio::time::timeout(Duration::from_secs(10), s.done).await.unwrap().unwrap().unwrap();
    }

    #[test]
    fn allowed_hosts_cover_loopback_names_and_a_public_bind() {
        let h = allowed_hosts("127.0.0.1:8080".parse().unwrap());
        assert_eq!(h, ["127.0.0.1:8080", "localhost:8080", "[::1]:8080"]);
        assert!(allowed_hosts("192.168.1.5:9000".parse().unwrap()).contains(&"192.168.1.5:9000".to_owned()));
        assert_eq!(allowed_hosts("0.0.0.0:9000".parse().unwrap()).len(), 3);
        assert!(allowed_hosts("127.0.0.1:80".parse().unwrap()).contains(&"localhost".to_owned()));
    }
}
