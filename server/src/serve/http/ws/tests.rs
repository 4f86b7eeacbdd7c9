//! `/ws` through a real server on a free port and a WebSocket client
//! (`super::super::testing`).

use std::net::SocketAddr;

use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite;

use super::super::testing::{Ws, connect, daemon_event_async, frame_images, next_json, next_message, start};
use super::*;
use crate::protocol::VERSION;
use crate::scene::settings::Value;
use crate::serve::event::Event;
use crate::serve::inbox::COMMAND_QUEUE;
use crate::serve::shared::{EVENT_QUEUE, write};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn websocket_origin_check_hello_and_events() {
    let s = start(vec![]).await;
    match connect(s.addr, Some("http://evil.example")).await {
        Err(tungstenite::Error::Http(resp)) => assert_eq!(resp.status(), 403),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("cross-origin websocket was accepted"),
    }
    match connect(s.addr, Some(&format!("http://127.0.0.1:{}.evil.example", s.addr.port()))).await {
        Err(tungstenite::Error::Http(resp)) => assert_eq!(resp.status(), 403),
        _ => panic!("look-alike origin was accepted"),
    }

    write(&s.shared.status, crate::protocol::Status { protocol: VERSION, frame: 3, ..Default::default() });
    for origin in [Some(format!("http://127.0.0.1:{}", s.addr.port())), None] {
        let mut ws = connect(s.addr, origin.as_deref()).await.unwrap();
        let hello = next_json(&mut ws).await;
        assert_eq!(hello["type"], "hello");
        assert_eq!(hello["protocol"], VERSION);
        assert_eq!(hello["status"]["frame"], 3);

        s.shared.publish(ServerEvent::DeviceLost { message: "gone".into(), recovered: true });
        s.shared.publish(ServerEvent::ReloadStarted { id: 7, files: vec!["a.wgsl".into()], pipelines: vec![] });
        let a = next_json(&mut ws).await;
        assert_eq!(a, serde_json::json!({ "type": "device_lost", "message": "gone", "recovered": true }));
        let b = next_json(&mut ws).await;
        assert_eq!(b["type"], "reload_started");
        assert_eq!(b["id"], 7);
    }
}

fn subscriptions(e: Option<Event>) -> (u64, Vec<String>) {
    match e {
        Some(Event::Subscriptions { client, outputs }) => (client, outputs.into_iter().collect()),
        _ => panic!("expected a subscriptions event"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn client_messages_reach_the_daemon_and_bad_ones_get_an_error() {
    let s = start(vec![]).await;
    let mut ws = connect(s.addr, None).await.unwrap();
    assert_eq!(next_json(&mut ws).await["type"], "hello");

    for bad in [
        "not json",
        "{\"type\":\"no_such_thing\"}",
        "{\"type\":\"subscribe\"}",
        "{\"type\":\"subscribe\",\"pass\":\"a\",\"output\":\"b\",\"encoding\":\"jpeg\"}",
        "{\"type\":\"unsubscribe\",\"pass\":\"a\"}",
        "[]",
    ] {
        ws.send(tungstenite::Message::text(bad)).await.unwrap();
        let e = next_json(&mut ws).await;
        assert_eq!(e["type"], "error", "{bad}");
        assert!(e["message"].as_str().unwrap().starts_with("invalid message: "), "{e}");
    }
    ws.send(tungstenite::Message::binary(vec![1u8, 2, 3])).await.unwrap();
    assert_eq!(next_json(&mut ws).await["type"], "error");

    // The daemon learns this client's whole set each time it changes,
    // and only then: a repeated subscribe changes nothing (the daemon
    // reads each change before the next is sent, as sets that wait are
    // replaced by newer ones; a `rebuild` behind a message shows that
    // message queued nothing).
    let send = |m: &'static str| tungstenite::Message::text(m);
    ws.send(send(r#"{"type":"subscribe","pass":"hdr","output":"color"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    let (client, outputs) = subscriptions(e);
    assert_eq!(outputs, ["hdr/color"]);
    ws.send(send(r#"{"type":"subscribe","pass":"hdr","output":"color","encoding":"f32"}"#)).await.unwrap();
    ws.send(send(r#"{"type":"rebuild"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert!(matches!(e, Some(Event::Rebuild)));
    ws.send(send(r#"{"type":"subscribe","pass":"bloom","output":"mip0","encoding":"f16"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert_eq!(subscriptions(e), (client, vec!["bloom/mip0".to_owned(), "hdr/color".to_owned()]));
    ws.send(send(r#"{"type":"unsubscribe","pass":"hdr","output":"color"}"#)).await.unwrap();
    ws.send(send(r#"{"type":"unsubscribe","pass":"never","output":"subscribed"}"#)).await.unwrap();
    ws.send(send(r#"{"type":"rebuild"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert_eq!(subscriptions(e), (client, vec!["bloom/mip0".to_owned()]));
    let (e, s) = daemon_event_async(s).await;
    assert!(matches!(e, Some(Event::Rebuild)));

    // Still connected.
    s.shared.publish(ServerEvent::Dropped { frames: 0, events: 0 });
    assert_eq!(next_json(&mut ws).await["type"], "dropped");

    // Leaving clears its subscriptions.
    drop(ws);
    let (e, _s) = daemon_event_async(s).await;
    assert_eq!(subscriptions(e), (client, vec![]));
}

fn parse_image(bytes: &[u8]) -> (serde_json::Value, &[u8]) {
    let n = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
    let header = serde_json::from_slice(&bytes[4..4 + n]).unwrap();
    (header, &bytes[4 + n..])
}

async fn next_image(ws: &mut Ws) -> (serde_json::Value, Vec<u8>) {
    match next_message(ws).await {
        tungstenite::Message::Binary(bytes) => {
            let (h, b) = parse_image(&bytes);
            (h, b.to_vec())
        }
        other => panic!("expected binary, got {other:?}"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_client_gets_the_final_frame_and_its_own_subscriptions_newest_only() {
    let s = start(vec![]).await;
    // The current frame is sent on connect.
    s.shared.frames.send_replace(frame_images(7));
    let mut a = connect(s.addr, None).await.unwrap();
    let mut b = connect(s.addr, None).await.unwrap();
    for ws in [&mut a, &mut b] {
        assert_eq!(next_json(ws).await["type"], "hello");
        let (h, png) = next_image(ws).await;
        assert_eq!(
            h,
            serde_json::json!({ "kind": "frame", "frame": 7, "pass": "tonemap", "output": "color", "width": 1, "height": 1,
                "format": "Rgba8UnormSrgb", "encoding": "png", "mime": "image/png", "final": true })
        );
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    }

    // A subscribes to the HDR output as exact floats; B to nothing.
    a.send(tungstenite::Message::text(r#"{"type":"subscribe","pass":"hdr","output":"color","encoding":"f32"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert_eq!(subscriptions(e).1, ["hdr/color"]);
    s.shared.frames.send_replace(frame_images(8));
    assert_eq!(next_image(&mut a).await.0["kind"], "frame");
    let (h, raw) = next_image(&mut a).await;
    assert_eq!(
        h,
        serde_json::json!({ "kind": "capture", "frame": 8, "pass": "hdr", "output": "color", "width": 2, "height": 1,
            "format": "Rgba16Float", "encoding": "f32", "mime": "application/octet-stream", "final": false })
    );
    let values: Vec<f32> = raw.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(values, [8.0, -1.5, 2.0, 1.0, 0.5, 8.0, 0.0, 1.0]);
    let (h, _) = next_image(&mut b).await;
    assert_eq!((h["kind"].as_str(), h["frame"].as_u64()), (Some("frame"), Some(8)));

    // Frames 9..=11 never reached A: it gets the newest and the count.
    s.shared.frames.send_replace(frame_images(12));
    assert_eq!(next_image(&mut a).await.0["frame"], 12);
    let (h, raw) = next_image(&mut a).await;
    assert_eq!((h["kind"].as_str(), h["frame"].as_u64(), raw.len()), (Some("capture"), Some(12), 32));
    assert_eq!(next_json(&mut a).await, serde_json::json!({ "type": "dropped", "frames": 3, "events": 0 }));

    // B never subscribed: it got only final frames, and an event is the
    // next thing it reads, not a capture.
    assert_eq!(next_image(&mut b).await.0["frame"], 12);
    assert_eq!(next_json(&mut b).await, serde_json::json!({ "type": "dropped", "frames": 3, "events": 0 }));
    s.shared.publish(ServerEvent::DeviceLost { message: "marker".into(), recovered: true });
    assert_eq!(next_json(&mut b).await["message"], "marker");

    // Unsubscribed, A gets only the final frame again.
    a.send(tungstenite::Message::text(r#"{"type":"unsubscribe","pass":"hdr","output":"color"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert!(subscriptions(e).1.is_empty());
    assert_eq!(next_json(&mut a).await["message"], "marker");
    s.shared.frames.send_replace(frame_images(13));
    assert_eq!(next_image(&mut a).await.0["kind"], "frame");
    s.shared.publish(ServerEvent::DeviceLost { message: "after 13".into(), recovered: true });
    assert_eq!(next_json(&mut a).await["message"], "after 13");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_never_reads_costs_bounded_memory_and_learns_what_it_lost() {
    let s = start(vec![]).await;
    let mut ws = connect(s.addr, None).await.unwrap();
    assert_eq!(next_json(&mut ws).await["type"], "hello");

    // The client stops reading while 10,000 events (80 MB, far more than
    // the socket buffers hold) are published.
    const N: usize = 10_000;
    let payload = "x".repeat(8 * 1024);
    for i in 0..N {
        s.shared.publish(ServerEvent::DeviceLost { message: format!("{i} {payload}"), recovered: false });
        assert!(s.shared.events.len() <= EVENT_QUEUE);
        if i % 16 == 0 {
            tokio::task::yield_now().await;
        }
    }
    s.shared.publish(ServerEvent::DeviceLost { message: "end".into(), recovered: true });
    assert!(s.shared.events.len() <= EVENT_QUEUE);

    // Resume: every event is either delivered or counted as dropped.
    let (mut delivered, mut dropped, mut last_seen) = (0u64, 0u64, None::<u64>);
    loop {
        let v = next_json(&mut ws).await;
        match v["type"].as_str().unwrap() {
            "dropped" => {
                assert_eq!(v["frames"], 0);
                dropped += v["events"].as_u64().unwrap()
            }
            "device_lost" if v["message"] == "end" => break,
            "device_lost" => {
                let i: u64 = v["message"].as_str().unwrap().split(' ').next().unwrap().parse().unwrap();
                assert!(last_seen.is_none_or(|l| i > l), "events out of order");
                last_seen = Some(i);
                delivered += 1;
            }
            other => panic!("unexpected {other}"),
        }
    }
    assert!(dropped > 0, "a stalled client was never told it lost events");
    assert!(delivered < N as u64);
    assert_eq!(delivered + dropped, N as u64);
}

/// The body of a refused upgrade: its status and JSON error.
fn refusal(r: Result<Ws, tungstenite::Error>) -> (u16, String) {
    match r {
        Err(tungstenite::Error::Http(resp)) => {
            let body: serde_json::Value = serde_json::from_slice(resp.body().as_deref().unwrap_or_default()).unwrap();
            (resp.status().as_u16(), body["error"].as_str().unwrap_or_default().to_owned())
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("the connection was accepted"),
    }
}

/// Connects as soon as the server has freed a slot (it notices a
/// closed connection on its own time).
async fn connect_when_free(addr: SocketAddr) -> Ws {
    for _ in 0..400 {
        match connect(addr, None).await {
            Ok(ws) => return ws,
            Err(tungstenite::Error::Http(resp)) if resp.status() == 503 => tokio::time::sleep(Duration::from_millis(25)).await,
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    panic!("no connection slot was freed")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn connections_past_the_limit_are_refused_until_one_closes() {
    let s = start(vec![]).await;
    let mut open = Vec::new();
    for _ in 0..MAX_CONNECTIONS {
        let mut ws = connect(s.addr, None).await.unwrap();
        assert_eq!(next_json(&mut ws).await["type"], "hello");
        open.push(ws);
    }
    let (status, message) = refusal(connect(s.addr, None).await);
    assert_eq!(status, 503);
    assert!(message.contains(&format!("at most {MAX_CONNECTIONS}")), "{message}");

    // A slot frees when a connection closes.
    open.pop().unwrap().close(None).await.unwrap();
    let mut ws = connect_when_free(s.addr).await;
    assert_eq!(next_json(&mut ws).await["type"], "hello");
    assert_eq!(refusal(connect(s.addr, None).await).0, 503);

    // One whose outputs the daemon holds frees its slot once the daemon
    // has read that it left.
    ws.send(tungstenite::Message::text(r#"{"type":"subscribe","pass":"hdr","output":"color"}"#)).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    let (client, outputs) = subscriptions(e);
    assert_eq!(outputs, ["hdr/color"]);
    ws.close(None).await.unwrap();
    let (e, s) = daemon_event_async(s).await;
    assert_eq!(subscriptions(e), (client, vec![]));
    let mut ws = connect_when_free(s.addr).await;
    assert_eq!(next_json(&mut ws).await["type"], "hello");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flood_of_commands_fills_the_queue_to_its_bound_and_the_rest_is_refused() {
    let s = start(vec![]).await;
    let ws = connect(s.addr, None).await.unwrap();
    let (mut sink, mut stream) = ws.split();

    // 10,000 overrides while the daemon reads none, the replies read as
    // they come (the server waits on a client that does not read).
    const N: usize = 10_000;
    let flood = tokio::spawn(async move {
        for i in 0..N {
            let m = format!(r#"{{"type":"set_override","path":"post.exposure_ev","value":{i}}}"#);
            sink.send(tungstenite::Message::text(m)).await.unwrap();
        }
        sink
    });
    let mut next = async || loop {
        let m = tokio::time::timeout(Duration::from_secs(10), stream.next()).await.unwrap().unwrap().unwrap();
        if let tungstenite::Message::Text(t) = m {
            return serde_json::from_str::<serde_json::Value>(t.as_str()).unwrap();
        }
    };
    assert_eq!(next().await["type"], "hello");
    for _ in COMMAND_QUEUE..N {
        let e = next().await;
        assert_eq!(e["type"], "error");
        let message = e["message"].as_str().unwrap();
        assert!(message.starts_with("`set_override` refused: the daemon is busy"), "{message}");
    }
    let mut sink = flood.await.unwrap();
    // A history reset counts like the other commands.
    sink.send(tungstenite::Message::text(r#"{"type":"reset_history"}"#)).await.unwrap();
    let e = next().await;
    assert!(e["message"].as_str().unwrap().starts_with("`reset_history` refused: the daemon is busy"), "{e}");

    // The first COMMAND_QUEUE wait for the daemon, in order; no more.
    for i in 0..COMMAND_QUEUE {
        match s.daemon.recv_timeout(Duration::ZERO) {
            Ok(Event::Scene(SceneCommand::Set { value: Value::Int(v), .. })) => assert_eq!(v, i as i64),
            _ => panic!("expected override {i}"),
        }
    }
    assert!(s.daemon.recv_timeout(Duration::ZERO).is_err(), "more than COMMAND_QUEUE commands waited");

    // Read, they make room.
    sink.send(tungstenite::Message::text(r#"{"type":"reset_history"}"#)).await.unwrap();
    let (e, _s) = daemon_event_async(s).await;
    assert!(matches!(e, Some(Event::ResetHistory)));
}

/// A text frame that is not UTF-8, and a message over the limit: an
/// `error` event, then the close code that says why.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unreadable_messages_close_with_1007_and_1009_after_an_error_event() {
    use tungstenite::protocol::frame::Frame;
    use tungstenite::protocol::frame::coding::{Data, OpCode};
    let s = start(vec![]).await;
    let not_utf8 = tungstenite::Message::Frame(Frame::message(&b"{\"type\":\"caf\xe9\"}"[..], OpCode::Data(Data::Text), true));
    let too_big = tungstenite::Message::text(" ".repeat(MAX_CLIENT_MESSAGE + 1));
    for (message, code, says) in [(not_utf8, 1007, "not UTF-8"), (too_big, 1009, "larger than 1048576 bytes")] {
        let (mut sink, mut stream) = connect(s.addr, None).await.unwrap().split();
        // The server stops reading at the frame's header: the rest of
        // a message too big may never be taken, so it is sent aside.
        let writer = tokio::spawn(async move {
            let _ = sink.send(message).await;
        });
        let mut received = Vec::new();
        let close = loop {
            let m = tokio::time::timeout(Duration::from_secs(10), stream.next()).await.expect("a message in time");
            match m {
                Some(Ok(tungstenite::Message::Text(t))) => received.push(serde_json::from_str::<serde_json::Value>(t.as_str()).unwrap()),
                Some(Ok(tungstenite::Message::Close(f))) => break f,
                other => panic!("expected events, then a close frame with {code}; got {other:?} after {received:?}"),
            }
        };
        assert_eq!(received.iter().map(|e| e["type"].as_str().unwrap()).collect::<Vec<_>>(), ["hello", "error"]);
        assert!(received[1]["message"].as_str().unwrap().contains(says), "{}", received[1]);
        assert_eq!(close.map(|f| u16::from(f.code)), Some(code));
        writer.abort();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn subscriptions_past_the_limit_are_refused_and_the_set_stays() {
    let s = start(vec![]).await;
    let mut ws = connect(s.addr, None).await.unwrap();
    assert_eq!(next_json(&mut ws).await["type"], "hello");
    let subscribe = |pass: &str, encoding: &str| {
        tungstenite::Message::text(format!(r#"{{"type":"subscribe","pass":"{pass}","output":"o","encoding":"{encoding}"}}"#))
    };
    let mut wanted: Vec<String> = (0..MAX_SUBSCRIPTIONS).map(|i| format!("p{i}")).collect();
    for pass in &wanted {
        ws.send(subscribe(pass, "png")).await.unwrap();
    }
    ws.send(subscribe("too_many", "png")).await.unwrap();
    let e = next_json(&mut ws).await;
    assert_eq!(e["type"], "error");
    let message = e["message"].as_str().unwrap();
    assert!(message.contains("`too_many/o`") && message.contains(&format!("at most {MAX_SUBSCRIPTIONS}")), "{message}");
    // Quad statistics count as one subscription (PROTOCOL.md).
    ws.send(tungstenite::Message::text(r#"{"type":"quad_statistics","on":true}"#)).await.unwrap();
    let e = next_json(&mut ws).await;
    assert_eq!(e["type"], "error");
    let message = e["message"].as_str().unwrap();
    assert!(message.contains("`quad_statistics` refused") && message.contains(&format!("at most {MAX_SUBSCRIPTIONS}")), "{message}");

    // At the limit, changing the encoding of an output it has is fine.
    ws.send(subscribe("p0", "f32")).await.unwrap();
    s.shared.publish(ServerEvent::DeviceLost { message: "marker".into(), recovered: true });
    assert_eq!(next_json(&mut ws).await["message"], "marker");

    // The daemon reads the newest set once (the sets that waited were
    // replaced): the first MAX_SUBSCRIPTIONS, without the refused ones.
    let (e, s) = daemon_event_async(s).await;
    let (_, outputs) = subscriptions(e);
    wanted.sort();
    assert_eq!(outputs, wanted.iter().map(|p| format!("{p}/o")).collect::<Vec<_>>());
    assert!(s.daemon.recv_timeout(Duration::ZERO).is_err());
}
