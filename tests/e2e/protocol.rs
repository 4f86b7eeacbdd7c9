//! PROTOCOL.md's promise that optional values are `null`, never missing:
//! every documented message, as a running `loupe serve` sends it over real
//! HTTP and WebSocket clients, has every key the document's "Every key"
//! table lists for it.

use std::time::Duration;

use loupe_tests::protocol::{self, Row};
use loupe_tests::reload;
use loupe_tests::ws::{Msg, Ws};
use loupe_tests::{Project, Server};
use serde_json::{Value, json};

const LIMIT: Duration = Duration::from_secs(120);

/// What the server sent, by the table's message names.
#[derive(Default)]
struct Seen(Vec<(String, Value)>);

impl Seen {
    fn add(&mut self, name: impl Into<String>, message: Value) {
        self.0.push((name.into(), message));
    }

    /// Reads `ws`, keeping every message, until an event of type `ty`
    /// for which `f` holds.
    fn until(&mut self, ws: &mut Ws, ty: &str, f: impl Fn(&Value) -> bool) -> Value {
        ws.until(&format!("a `{ty}` event"), LIMIT, |m| {
            match m {
                Msg::Event(v) => self.add(format!("event {}", v["type"].as_str().unwrap_or("?")), v.clone()),
                Msg::Image(header, _) => self.add("binary image header", header.clone()),
            }
            match m {
                Msg::Event(v) if v["type"] == ty && f(v) => Some(v.clone()),
                _ => None,
            }
        })
    }
}

/// The messages of the table a test cannot bring about on demand.
const NOT_PROVOKED: &[&str] = &[
    // Needs a client too slow for the event ring; its keys are the
    // subject of the WebSocket layer's own tests.
    "event dropped",
];

#[test]
fn every_documented_message_has_every_documented_key() {
    let rows: Vec<Row> = protocol::documented();
    let p = Project::copy_of_repo("protocol-keys");
    // One tiny image case of the scene, for "against reference".
    p.write("loupe.toml", "[[images]]\nname = \"tiny\"\nscene = \"scenes/minimal.toml\"\nsize = \"32x18\"\n");
    // The minimal scene has a depth-tested draw (gbuffer: `rasterized`, no
    // `what_if`) and fullscreen passes (`what_if`, no `rasterized`).
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change", "--debug-api"]);
    let mut seen = Seen::default();
    let mut ws = s.ws();
    seen.until(&mut ws, "hello", |_| true);

    ws.send(json!({ "type": "quad_statistics", "on": true }));
    ws.send(json!({ "type": "subscribe", "pass": "tonemap", "output": "color" }));
    seen.until(&mut ws, "quads", |_| true);
    ws.send(json!({ "type": "debug_pixel", "x": 3, "y": 2 }));
    seen.until(&mut ws, "prints", |v| v["pixel"] == json!([3, 2]));
    ws.send(json!({ "type": "debug_pixel", "x": null, "y": null }));
    ws.send(json!({ "type": "no_such_message" }));
    seen.until(&mut ws, "error", |_| true);
    ws.send(json!({ "type": "set_override", "path": "post.exposure_ev", "value": 0.5 }));
    seen.until(&mut ws, "controls", |_| true);
    ws.send(json!({ "type": "save_scene" }));
    seen.until(&mut ws, "scene_saved", |_| true);

    // A broken save and its mend: reload_started, reload_failed with a
    // located diagnostic, diagnostics, passes (stale, then ok),
    // reload_succeeded.
    let good = p.read(reload::TONEMAP);
    p.write(reload::TONEMAP, reload::broken(&good));
    seen.until(&mut ws, "reload_failed", |_| true);
    // A first preview needs the broken tonemap pipeline: it never built.
    let (status, body) = s.get("/api/materials/0/preview");
    assert_eq!(status, 422, "{}", String::from_utf8_lossy(&body));
    seen.add("GET /api/materials/{index}/preview, 422", serde_json::from_slice(&body).expect("JSON"));
    seen.until(&mut ws, "files", |v| v["files"].as_array().is_some_and(|f| !f.is_empty()));
    for (route, name) in
        [("/api/diagnostics", "GET /api/diagnostics"), ("/api/passes", "GET /api/passes"), ("/api/files", "GET /api/files")]
    {
        seen.add(name, s.get_json(route));
    }
    // Mended by reverting to the last good text.
    let (status, body) = s.post_json("/api/files/revert", &json!({ "file": reload::TONEMAP }), None);
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    seen.add("POST /api/files/revert", serde_json::from_slice(&body).expect("JSON"));
    assert_eq!(p.read(reload::TONEMAP), good);
    seen.until(&mut ws, "reload_succeeded", |_| true);

    // Against reference: no reference yet (a failure with its
    // diagnostic), then blessed (a pass, with FLIP's figures).
    ws.send(json!({ "type": "reference_comparison", "on": true }));
    seen.until(&mut ws, "references", |v| v["comparing"] == false && v["cases"][0]["verdict"] == "failed");
    seen.add("GET /api/references", s.get_json("/api/references"));
    let (status, body) = s.post("/api/references/tiny/bless");
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    seen.add("POST /api/references/{case}/bless", serde_json::from_slice(&body).expect("JSON"));
    seen.until(&mut ws, "references", |v| v["comparing"] == false && v["cases"][0]["verdict"] == "passed");
    seen.add("GET /api/references", s.get_json("/api/references"));

    // A traced frame's report: `nan` event and `/api/nan`.
    assert_eq!(s.post("/api/frame/trace").0, 202);
    seen.until(&mut ws, "nan", |v| !v["report"].is_null());

    for route in ["status", "passes", "pipelines", "diagnostics", "captures", "tensors", "nan", "quads", "controls", "materials"] {
        seen.add(format!("GET /api/{route}"), s.get_json(&format!("/api/{route}")));
    }
    let (status, body) = s.post("/api/reload");
    assert_eq!(status, 202);
    seen.add("POST /api/reload", serde_json::from_slice(&body).expect("JSON"));
    let (status, body) = s.get("/api/no_such_route");
    assert_eq!(status, 404);
    seen.add("an error response", serde_json::from_slice(&body).expect("JSON"));

    assert_eq!(s.post("/api/debug/lose-device").0, 202);
    seen.until(&mut ws, "device_lost", |_| true);

    let mut missing = Vec::new();
    for (name, message) in &seen.0 {
        missing.extend(protocol::missing_keys(&rows, name, message));
    }
    missing.dedup();
    assert!(missing.is_empty(), "documented keys are missing:\n{}", missing.join("\n"));
    let mut undocumented: Vec<String> =
        seen.0.iter().flat_map(|(name, message)| protocol::undocumented_keys(&rows, name, message)).collect();
    undocumented.sort();
    undocumented.dedup();
    assert!(undocumented.is_empty(), "keys sent but not in PROTOCOL.md's table:\n{}", undocumented.join("\n"));
    // Every message of the table was checked (what a test cannot provoke
    // aside), and every message checked is in the table.
    for row in &rows {
        let checked = seen.0.iter().any(|(name, _)| *name == row.message);
        assert!(checked || NOT_PROVOKED.contains(&row.message.as_str()), "no `{}` was seen to check", row.message);
    }
    for (name, _) in &seen.0 {
        assert!(rows.iter().any(|r| r.message == *name), "`{name}` is not in PROTOCOL.md's key table");
    }
}
