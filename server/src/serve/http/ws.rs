//! `/ws`: one task per client. It sends `hello`, then every event the
//! daemon publishes and every frame's images (the final output, and the
//! outputs this client subscribed to), and hands the client's messages to
//! the daemon.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use axum::extract::State;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade, close_code};
use axum::http::StatusCode;
use axum::response::Response;
use serde::Serialize;
use tokio::sync::broadcast::error::RecvError;

use super::AppState;
use super::guard::error;
use crate::protocol::{ClientMessage, Encoding, QUAD_STATISTICS, REFERENCES, ServerEvent};
use crate::serve::event::SceneCommand;
use crate::serve::inbox::{Client, Command, MAX_CONNECTIONS, Refused};
use crate::serve::shared::{FrameImages, Shared};

/// The largest message a WebSocket client may send.
const MAX_CLIENT_MESSAGE: usize = 1024 * 1024;
/// How often pending skipped-frame counts are reported when no event is
/// flowing to carry them.
const DROPPED_REPORT_INTERVAL: Duration = Duration::from_secs(1);
/// How long a connection closed over a message too big to read is held
/// before the socket goes, so that the close frame reaches the client.
const CLOSE_LINGER: Duration = Duration::from_secs(1);
/// How many outputs one WebSocket client may subscribe to.
pub const MAX_SUBSCRIPTIONS: usize = 64;

/// Upgrades to a WebSocket, or answers 503 when [`MAX_CONNECTIONS`]
/// clients hold a slot.
pub(super) async fn upgrade(State(st): State<Arc<AppState>>, upgrade: WebSocketUpgrade) -> Response {
    let Some(client) = st.shared.clients.join() else {
        return error(
            StatusCode::SERVICE_UNAVAILABLE,
            &format!("too many WebSocket connections: at most {MAX_CONNECTIONS} at once; try again when one closes"),
        );
    };
    upgrade
        .max_message_size(MAX_CLIENT_MESSAGE)
        .max_frame_size(MAX_CLIENT_MESSAGE)
        .on_upgrade(move |socket| client_loop(st, socket, client))
}

fn event_message(event: &ServerEvent) -> Option<Message> {
    serde_json::to_string(event).ok().map(|s| Message::Text(s.into()))
}

/// The header of a binary image message.
#[derive(Serialize)]
struct ImageHeader<'a> {
    /// `frame`: the final output as PNG, sent to every client; `capture`:
    /// an output this client subscribed to.
    kind: &'static str,
    frame: u64,
    pass: &'a str,
    output: &'a str,
    width: u32,
    height: u32,
    format: &'a str,
    encoding: Encoding,
    mime: &'static str,
    #[serde(rename = "final")]
    is_final: bool,
}

/// A binary image message: a little-endian u32 header length N, N bytes of
/// JSON header, then the encoded image.
fn image_message(kind: &'static str, frame: &FrameImages, key: &str, encoding: Encoding, bytes: &[u8]) -> Option<Message> {
    let img = frame.captures.get(key)?;
    let header = serde_json::to_vec(&ImageHeader {
        kind,
        frame: frame.frame,
        pass: &img.pass,
        output: &img.output,
        width: img.width,
        height: img.height,
        format: &img.format,
        encoding,
        mime: encoding.mime(),
        is_final: frame.final_key.as_deref() == Some(key),
    })
    .ok()?;
    let mut out = Vec::with_capacity(4 + header.len() + bytes.len());
    out.extend_from_slice(&u32::try_from(header.len()).ok()?.to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(bytes);
    Some(Message::Binary(out.into()))
}

/// Sends one frame's images: the final output as a `frame` message, then
/// every output this client subscribed to that the frame captured.
/// Encoding runs off the reactor, once per frame and encoding whatever the
/// number of clients.
async fn send_images(
    socket: &mut WebSocket,
    frame: &Arc<FrameImages>,
    subscriptions: &BTreeMap<String, Encoding>,
) -> Result<(), axum::Error> {
    let wanted = frame
        .final_key
        .iter()
        .map(|k| ("frame", k, Encoding::Png))
        .chain(subscriptions.iter().map(|(k, e)| ("capture", k, *e)))
        .filter(|(_, k, _)| frame.captures.contains_key(*k));
    for (kind, key, encoding) in wanted {
        let (f, k) = (frame.clone(), key.clone());
        let Ok(Some(bytes)) = tokio::task::spawn_blocking(move || f.encoded(&k, encoding)).await else { continue };
        if let Some(m) = image_message(kind, frame, key, encoding, &bytes) {
            socket.send(m).await?;
        }
    }
    Ok(())
}

/// What a client missed and has not been told yet.
#[derive(Default)]
struct Missed {
    frames: u64,
    events: u64,
}

impl Missed {
    /// Sends the pending `Dropped` counts, if any.
    async fn flush(&mut self, socket: &mut WebSocket) -> Result<(), axum::Error> {
        if self.frames + self.events > 0 {
            let Missed { frames, events } = std::mem::take(self);
            if let Some(m) = event_message(&ServerEvent::Dropped { frames, events }) {
                socket.send(m).await?;
            }
        }
        Ok(())
    }
}

/// Applies a client's message: subscriptions change this client's set
/// (and the daemon learns the new set), commands go to the daemon. `Err`:
/// what to tell the client (a subscription over [`MAX_SUBSCRIPTIONS`], a
/// command refused because
/// [`COMMAND_QUEUE`](crate::serve::inbox::COMMAND_QUEUE) wait); nothing changed then.
fn client_message(
    shared: &Shared,
    client: &mut Client,
    subscriptions: &mut BTreeMap<String, Encoding>,
    msg: ClientMessage,
) -> Result<(), String> {
    let (kind, command) = match msg {
        ClientMessage::Subscribe { pass, output, encoding } => {
            let key = format!("{pass}/{output}");
            room_for(subscriptions, &key, &format!("subscription to `{key}`"))?;
            if subscriptions.insert(key, encoding).is_none() {
                client.subscribe(subscriptions.keys().cloned().collect());
            }
            return Ok(());
        }
        ClientMessage::Unsubscribe { pass, output } => {
            if subscriptions.remove(&format!("{pass}/{output}")).is_some() {
                client.subscribe(subscriptions.keys().cloned().collect());
            }
            return Ok(());
        }
        ClientMessage::QuadStatistics { on } => return toggle(client, subscriptions, QUAD_STATISTICS, "`quad_statistics`", on),
        ClientMessage::ReferenceComparison { on } => return toggle(client, subscriptions, REFERENCES, "`reference_comparison`", on),
        ClientMessage::Rebuild {} => ("rebuild", Command::Rebuild),
        ClientMessage::SetOverride { path, value } => ("set_override", Command::Scene(SceneCommand::Set { path, value })),
        ClientMessage::ClearOverrides {} => ("clear_overrides", Command::Scene(SceneCommand::Clear)),
        ClientMessage::SaveScene {} => ("save_scene", Command::Scene(SceneCommand::Save)),
        ClientMessage::ResetHistory {} => ("reset_history", Command::ResetHistory),
        ClientMessage::DebugPixel { x, y } => match (x, y) {
            (Some(x), Some(y)) => ("debug_pixel", Command::DebugPixel(Some([x, y]))),
            (None, None) => ("debug_pixel", Command::DebugPixel(None)),
            _ => return Err("`debug_pixel` needs both `x` and `y`, or neither to clear the selection".to_owned()),
        },
    };
    match shared.clients.command(command) {
        Err(busy @ Refused::Busy) => Err(format!("`{kind}` refused: {busy}")),
        // The daemon may be gone while the server drains; nothing to tell
        // the client then.
        Ok(()) | Err(Refused::Gone) => Ok(()),
    }
}

/// Adds or drops `key` (something computed for the client, not an output)
/// in the client's subscriptions, telling the daemon when that changed.
fn toggle(client: &mut Client, subscriptions: &mut BTreeMap<String, Encoding>, key: &str, what: &str, on: bool) -> Result<(), String> {
    let changed = if on {
        room_for(subscriptions, key, what)?;
        subscriptions.insert(key.to_owned(), Encoding::default()).is_none()
    } else {
        subscriptions.remove(key).is_some()
    };
    if changed {
        client.subscribe(subscriptions.keys().cloned().collect());
    }
    Ok(())
}

/// Whether `key` may join a connection's subscriptions: it is there
/// already, or fewer than [`MAX_SUBSCRIPTIONS`] are (quad statistics count
/// as one). `Err`: what to tell the client, naming the request as `what`.
fn room_for(subscriptions: &BTreeMap<String, Encoding>, key: &str, what: &str) -> Result<(), String> {
    if subscriptions.len() >= MAX_SUBSCRIPTIONS && !subscriptions.contains_key(key) {
        return Err(format!("{what} refused: a connection may subscribe to at most {MAX_SUBSCRIPTIONS} outputs"));
    }
    Ok(())
}

/// One WebSocket client. Memory per client is bounded: events wait in the
/// shared broadcast ring (`EVENT_QUEUE` deep; a lagging client loses the
/// oldest and is told how many), images in a `watch` (only the newest
/// frame's), at most one message is in flight to the socket at a time,
/// and it subscribes to at most [`MAX_SUBSCRIPTIONS`] outputs.
///
/// Dropping `client` when this ends tells the daemon the client left.
async fn client_loop(st: Arc<AppState>, mut socket: WebSocket, mut client: Client) {
    let shared = st.shared.clone();
    let mut subscriptions: BTreeMap<String, Encoding> = BTreeMap::new();
    // Subscribe before the Hello snapshot so nothing after it is missed.
    let mut events = shared.events.subscribe();
    let mut frames = shared.frames.subscribe();
    frames.mark_changed(); // send the current frame, if any, right away
    let mut stop = st.stop.subscribe();
    if *stop.borrow_and_update() {
        return;
    }
    let Some(m) = event_message(&shared.hello()) else { return };
    if socket.send(m).await.is_err() {
        return;
    }

    let mut missed = Missed::default();
    let mut last_frame: Option<u64> = None;
    let mut frames_open = true;
    let mut report = tokio::time::interval(DROPPED_REPORT_INTERVAL);
    report.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);

    loop {
        // Biased: events go before images, so an image being encoded or
        // sent never holds back the events that say what happened.
        let step: Result<bool, axum::Error> = tokio::select! {
            biased;
            _ = stop.changed() => {
                let close = CloseFrame { code: 1001, reason: "server shutting down".into() };
                let _ = socket.send(Message::Close(Some(close))).await;
                return;
            }
            received = events.recv() => match received {
                Ok(event) => async {
                    missed.flush(&mut socket).await?;
                    if let Some(m) = event_message(&event) {
                        socket.send(m).await?;
                    }
                    Ok(true)
                }.await,
                Err(RecvError::Lagged(n)) => {
                    missed.events += n;
                    missed.flush(&mut socket).await.map(|()| true)
                }
                Err(RecvError::Closed) => Ok(false),
            },
            incoming = socket.recv() => match incoming {
                None | Some(Ok(Message::Close(_))) => Ok(false),
                Some(Err(e)) => unreadable(&mut socket, e).await,
                Some(Ok(Message::Text(text))) => match serde_json::from_str::<ClientMessage>(text.as_str()) {
                    Ok(msg) => match client_message(&shared, &mut client, &mut subscriptions, msg) {
                        Ok(()) => Ok(true),
                        Err(refused) => send_error(&mut socket, refused).await,
                    },
                    Err(e) => send_error(&mut socket, format!("invalid message: {e}")).await,
                },
                Some(Ok(Message::Binary(_))) => send_error(&mut socket, "binary messages are not accepted".into()).await,
                // Pings are answered by the WebSocket layer itself.
                Some(Ok(_)) => Ok(true),
            },
            changed = frames.changed(), if frames_open => match changed {
                Err(_) => {
                    frames_open = false;
                    Ok(true)
                }
                Ok(()) => {
                    let frame = frames.borrow_and_update().clone();
                    match frame {
                        Some(frame) => {
                            // Frames published while this client was busy
                            // were skipped: count the gap in frame numbers.
                            if let Some(last) = last_frame {
                                missed.frames += frame.frame.saturating_sub(last).saturating_sub(1);
                            }
                            last_frame = Some(frame.frame);
                            send_images(&mut socket, &frame, &subscriptions).await.map(|()| true)
                        }
                        None => Ok(true),
                    }
                }
            },
            _ = report.tick() => missed.flush(&mut socket).await.map(|()| true),
        };
        match step {
            Ok(true) => {}
            Ok(false) | Err(_) => return,
        }
    }
}

/// A message the WebSocket layer could not read ends the connection. A
/// text message that is not UTF-8 (close code 1007) or one over
/// [`MAX_CLIENT_MESSAGE`] (1009) is said first in an `error` event; any
/// other failure (the peer went away) just ends it.
async fn unreadable(socket: &mut WebSocket, e: axum::Error) -> Result<bool, axum::Error> {
    let (code, reason, message, unread) = match e.into_inner().downcast::<tungstenite::Error>().map(|e| *e) {
        Ok(tungstenite::Error::Utf8(_)) => {
            (close_code::INVALID, "text message not UTF-8", "a text message that is not UTF-8".to_owned(), false)
        }
        Ok(tungstenite::Error::Capacity(_)) => {
            (close_code::SIZE, "message too big", format!("a message larger than {MAX_CLIENT_MESSAGE} bytes (1 MiB)"), true)
        }
        _ => return Ok(false),
    };
    send_error(socket, format!("invalid message: {message}; the connection closes")).await?;
    socket.send(Message::Close(Some(CloseFrame { code, reason: reason.into() }))).await?;
    if unread {
        // The rest of the message is never read: closing the socket over
        // it resets the connection, and a reset can discard the close frame
        // before the client reads it. Held a moment, the client reads it.
        tokio::time::sleep(CLOSE_LINGER).await;
    }
    Ok(false)
}

/// Sends an `error` event; the connection stays open.
async fn send_error(socket: &mut WebSocket, message: String) -> Result<bool, axum::Error> {
    match event_message(&ServerEvent::Error { message }) {
        Some(m) => socket.send(m).await.map(|()| true),
        None => Ok(true),
    }
}

#[cfg(test)]
mod tests;
