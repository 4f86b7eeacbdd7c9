//! The API through a real server on a free port (`super::super::testing`):
//! JSON routes, capture downloads, reload and save, the debug API.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use super::super::testing::{daemon_event, frame_images, get, request, start, start_with};
use crate::protocol::VERSION;
use crate::render::capture::CapturedImage;
use crate::serve::event::Event;
use crate::serve::inbox::COMMAND_QUEUE;
use crate::serve::shared::write;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn json_endpoints_have_their_shapes_and_no_store() {
    let s = start(vec![]).await;
    write(&s.shared.status, crate::protocol::Status { protocol: VERSION, frame: 42, ..Default::default() });

    let r = get(s.addr, "/api/status").await;
    assert_eq!(r.status, 200);
    assert_eq!(r.header("content-type").as_deref(), Some("application/json"));
    assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));
    let v = r.json();
    assert_eq!(v["protocol"], VERSION);
    assert_eq!(v["frame"], 42);
    for key in [
        "version",
        "adapter",
        "cpu_adapter",
        "features",
        "degraded",
        "scene",
        "pipelines_ok",
        "pipelines_stale",
        "pipelines_failed",
        "device_resets",
        "errors",
        "warnings",
        "render_mode",
    ] {
        assert!(v.get(key).is_some(), "status lacks `{key}`: {v}");
    }

    assert_eq!(get(s.addr, "/api/passes").await.json(), serde_json::json!([]));
    assert_eq!(get(s.addr, "/api/pipelines").await.json(), serde_json::json!([]));
    assert_eq!(get(s.addr, "/api/diagnostics").await.json(), serde_json::json!({ "diagnostics": [] }));
    assert_eq!(get(s.addr, "/api/captures").await.json(), serde_json::json!([]));

    let r = get(s.addr, "/api/nope").await;
    assert_eq!(r.status, 404);
    assert!(r.json()["error"].is_string());
    assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));

    let r = request(s.addr, "POST", "/api/status", "").await;
    assert_eq!(r.status, 405);
    assert_eq!(r.json()["error"], "method not allowed");
    assert!(r.header("allow").is_some_and(|a| a.contains("GET")));
    assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));

    let r = request(s.addr, "HEAD", "/api/status", "").await;
    assert_eq!(r.status, 200);
    assert!(r.body.is_empty());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn captures_are_listed_and_served_in_every_format() {
    let s = start(vec![]).await;
    let (w, h) = (3u32, 2u32);
    let data: Vec<f32> = (0..w * h * 4).map(|i| i as f32 * 0.25 - 1.0).collect();
    let img = CapturedImage::new("hdr", "color", 9, w, h, wgpu::TextureFormat::Rgba16Float, data.clone());
    write(&s.shared.captures, Arc::new(BTreeMap::from([(img.key(), Arc::new(img))])));

    let list = get(s.addr, "/api/captures").await.json();
    let c = &list[0];
    assert_eq!(c["pass"], "hdr");
    assert_eq!(c["output"], "color");
    assert_eq!(c["frame"], 9);
    assert_eq!(c["width"], 3);
    assert_eq!(c["height"], 2);
    assert_eq!(c["format"], "Rgba16Float");
    assert_eq!(c["last_good"], false);
    assert!(c["stats"]["negative"].as_u64().unwrap() > 0);

    let png = get(s.addr, "/api/captures/hdr/color.png").await;
    assert_eq!(png.status, 200);
    assert_eq!(png.header("content-type").as_deref(), Some("image/png"));
    assert!(png.body.starts_with(b"\x89PNG\r\n\x1a\n"));

    let f32s = get(s.addr, "/api/captures/hdr/color.f32").await;
    assert_eq!(f32s.status, 200);
    assert_eq!(f32s.header("x-loupe-width").as_deref(), Some("3"));
    assert_eq!(f32s.header("x-loupe-height").as_deref(), Some("2"));
    assert_eq!(f32s.header("x-loupe-channels").as_deref(), Some("4"));
    assert_eq!(f32s.header("x-loupe-frame").as_deref(), Some("9"));
    let back: Vec<f32> = f32s.body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(back, data);

    let f16s = get(s.addr, "/api/captures/hdr/color.f16").await;
    assert_eq!(f16s.status, 200);
    assert_eq!(f16s.body.len(), (w * h * 4 * 2) as usize);
    assert_eq!(f16s.header("x-loupe-channels").as_deref(), Some("4"));
    assert_eq!(half::f16::from_le_bytes([f16s.body[2], f16s.body[3]]).to_f32(), data[1]);

    let exr = get(s.addr, "/api/captures/hdr/color.exr").await;
    assert_eq!(exr.status, 200);
    assert!(exr.body.starts_with(&[0x76, 0x2f, 0x31, 0x01]));

    for (path, status) in [
        ("/api/captures/hdr/missing.png", 404),
        ("/api/captures/nope/color.png", 404),
        ("/api/captures/hdr/color.jpg", 400),
        ("/api/captures/hdr/color", 400),
        ("/api/captures/hdr/color.png?version=last_good", 404),
        ("/api/captures/hdr/color.png?version=bogus", 400),
    ] {
        let r = get(s.addr, path).await;
        assert_eq!(r.status, status, "{path}: {}", r.text());
        assert!(r.json()["error"].is_string(), "{path}");
    }

    let old = CapturedImage::new("hdr", "color", 5, 1, 1, wgpu::TextureFormat::Rgba16Float, vec![0.0; 4]);
    write(&s.shared.last_good, Arc::new(BTreeMap::from([(old.key(), Arc::new(old))])));
    let r = get(s.addr, "/api/captures/hdr/color.f32?version=last_good").await;
    assert_eq!(r.status, 200);
    assert_eq!(r.header("x-loupe-frame").as_deref(), Some("5"));
    assert_eq!(r.body.len(), 16);
    assert_eq!(get(s.addr, "/api/captures").await.json()[0]["last_good"], true);
    assert_eq!(get(s.addr, "/api/captures?version=last_good").await.json()[0]["frame"], 5);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn captures_say_which_is_final() {
    let s = start(vec![]).await;
    let images = frame_images(3).unwrap();
    write(&s.shared.captures, Arc::new(images.captures.clone()));
    s.shared.frames.send_replace(Some(images));
    let list = get(s.addr, "/api/captures").await.json();
    let finals: Vec<(String, bool)> =
        list.as_array().unwrap().iter().map(|c| (c["pass"].as_str().unwrap().to_owned(), c["final"].as_bool().unwrap())).collect();
    assert_eq!(finals, [("hdr".to_owned(), false), ("tonemap".to_owned(), true)]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn requests_for_the_daemon_are_refused_with_503_while_its_queue_is_full() {
    let s = start(vec![]).await;
    for _ in 0..COMMAND_QUEUE {
        assert_eq!(request(s.addr, "POST", "/api/reload", "").await.status, 202);
    }
    for path in ["/api/reload", "/api/scene/save"] {
        let r = request(s.addr, "POST", path, "").await;
        assert_eq!(r.status, 503, "{path}");
        assert_eq!(r.header("cache-control").as_deref(), Some("no-store"));
        let message = r.json()["error"].as_str().unwrap().to_owned();
        assert!(message.starts_with("the daemon is busy"), "{message}");
    }
    // One read by the daemon makes room for one.
    assert!(matches!(daemon_event(&s), Some(Event::Rebuild)));
    assert_eq!(request(s.addr, "POST", "/api/scene/save", "").await.status, 202);
    assert_eq!(request(s.addr, "POST", "/api/reload", "").await.status, 503);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_debug_api_exists_only_when_enabled() {
    let s = start(vec![]).await;
    let r = request(s.addr, "POST", "/api/debug/lose-device", "").await;
    assert_eq!(r.status, 404, "{}", r.text());
    assert!(r.json()["error"].is_string());
    assert_eq!(request(s.addr, "POST", "/api/nope", "").await.status, 404);
    assert!(s.daemon.recv_timeout(Duration::ZERO).is_err());

    let s = start_with(vec![], true).await;
    let cross = "Origin: http://evil.example\r\n";
    assert_eq!(request(s.addr, "POST", "/api/debug/lose-device", cross).await.status, 403);
    let r = request(s.addr, "POST", "/api/debug/lose-device", "").await;
    assert_eq!(r.status, 202, "{}", r.text());
    assert!(matches!(daemon_event(&s), Some(Event::LoseDevice)));
    assert_eq!(request(s.addr, "GET", "/api/debug/lose-device", "").await.status, 405);
}
