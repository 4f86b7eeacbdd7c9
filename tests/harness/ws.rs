//! A blocking client for `loupe serve`'s `/ws` (PROTOCOL.md): JSON events
//! and binary image messages, read with a deadline.

use std::net::TcpStream;
use std::time::{Duration, Instant};

use tungstenite::{Message, WebSocket};

/// One message from the server.
#[derive(Debug, Clone)]
pub enum Msg {
    /// A JSON text event.
    Event(serde_json::Value),
    /// A binary image: its JSON header and the encoded bytes.
    Image(serde_json::Value, Vec<u8>),
}

impl Msg {
    /// The event's `type`, or `None` for an image.
    pub fn event_type(&self) -> Option<&str> {
        match self {
            Msg::Event(v) => v["type"].as_str(),
            Msg::Image(..) => None,
        }
    }
}

pub struct Ws {
    socket: WebSocket<TcpStream>,
}

impl Ws {
    /// Connects to `ws://ADDR/ws` (ADDR is `host:port`).
    pub fn connect(addr: &str) -> Result<Ws, String> {
        let stream = TcpStream::connect(addr).map_err(|e| e.to_string())?;
        stream.set_nodelay(true).map_err(|e| e.to_string())?;
        let (socket, _) = tungstenite::client(format!("ws://{addr}/ws"), stream).map_err(|e| e.to_string())?;
        Ok(Ws { socket })
    }

    /// The next message, or `None` if none came before `deadline`. Panics
    /// when the connection fails.
    pub fn next_before(&mut self, deadline: Instant) -> Option<Msg> {
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            self.socket.get_ref().set_read_timeout(Some(left)).expect("set a read timeout");
            match self.socket.read() {
                Ok(Message::Text(t)) => {
                    return Some(Msg::Event(serde_json::from_str(t.as_str()).expect("events are JSON")));
                }
                Ok(Message::Binary(b)) => {
                    let n = u32::from_le_bytes(b[..4].try_into().expect("a length")) as usize;
                    let header = serde_json::from_slice(&b[4..4 + n]).expect("image headers are JSON");
                    return Some(Msg::Image(header, b[4 + n..].to_vec()));
                }
                Ok(Message::Close(f)) => panic!("the server closed the WebSocket: {f:?}"),
                Ok(_) => {}
                Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(e) => panic!("WebSocket error: {e}"),
            }
        }
    }

    /// Reads until `f` accepts a message (returning what it returns); every
    /// message read on the way is passed to `f` too. Panics after `limit`,
    /// naming `what`.
    pub fn until<T>(&mut self, what: &str, limit: Duration, mut f: impl FnMut(&Msg) -> Option<T>) -> T {
        let deadline = Instant::now() + limit;
        loop {
            match self.next_before(deadline) {
                Some(m) => {
                    if let Some(v) = f(&m) {
                        return v;
                    }
                }
                None => panic!("timed out after {limit:?} waiting for {what} on /ws"),
            }
        }
    }

    /// Reads until an event of type `ty` for which `f` holds.
    pub fn event(&mut self, ty: &str, limit: Duration, f: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        self.until(&format!("a `{ty}` event"), limit, |m| match m {
            Msg::Event(v) if v["type"] == ty && f(v) => Some(v.clone()),
            _ => None,
        })
    }

    /// Sends a client message.
    pub fn send(&mut self, message: serde_json::Value) {
        self.socket.send(Message::text(message.to_string())).expect("send on /ws");
    }
}
