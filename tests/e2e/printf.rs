//! `debugPrintf` through `loupe serve`: a pixel selected over the
//! WebSocket gets a `prints` event each frame, from the pass's own
//! shader, and a `pixel_history` event; an edit to the print shows in the
//! next ones, and the selection outlives a lost device and a reload.

use std::time::Duration;

use loupe_tests::ws::{Msg, Ws};
use loupe_tests::{Project, Server};
use serde_json::{Value, json};

const LIMIT: Duration = Duration::from_secs(60);
pub const TONEMAP: &str = "shaders/post/tonemap.wgsl";
const AFTER: &str = "    let c = max(texel.rgb, vec3(0.0));\n";

/// The tonemap shader with `print` after its `c`, the directive on top.
pub fn with_print(good: &str, print: &str) -> String {
    assert!(good.contains(AFTER), "the premise: tonemap computes `c` so");
    format!("enable wgpu_debug_printf;\n{}", good.replacen(AFTER, &format!("{AFTER}    {print}\n"), 1))
}

/// The next `prints` event whose first line's text starts with `start`.
fn prints(ws: &mut Ws, start: &str) -> Value {
    ws.until(&format!("a `prints` event starting {start:?}"), LIMIT, |m| match m {
        Msg::Event(v) if v["type"] == "prints" && v["lines"][0]["text"].as_str().is_some_and(|t| t.starts_with(start)) => Some(v.clone()),
        _ => None,
    })
}

#[test]
fn a_selected_pixel_streams_its_prints_and_follows_edits() {
    let p = Project::copy_of_repo("printf-serve");
    let good = p.read(TONEMAP);
    let printing = with_print(&good, "debugPrintf(\"at %v2f\", in.position.xy);");
    let at = printing.lines().position(|l| l.contains("debugPrintf")).unwrap() as u64 + 1;
    p.write(TONEMAP, printing);
    let s = Server::start(&p.root, &["--scene", "scenes/minimal.toml", "--render", "on-change", "--debug-api"]);
    let mut ws = s.ws();
    ws.until("hello", LIMIT, |m| matches!(m, Msg::Event(v) if v["type"] == "hello").then_some(()));

    ws.send(json!({ "type": "debug_pixel", "x": 7, "y": 4 }));
    let event = prints(&mut ws, "at ");
    assert_eq!(event["pixel"], json!([7, 4]));
    let line = &event["lines"][0];
    assert_eq!(line["text"], "at 7.500000, 4.500000", "{event}");
    assert_eq!((line["pass"].as_str(), line["file"].as_str(), line["line"].as_u64()), (Some("tonemap"), Some(TONEMAP), Some(at)));
    assert_eq!(event["lines"].as_array().unwrap().len(), 1, "one invocation is the pixel: {event}");

    // An edit to the print shows in the frames after its reload.
    p.write(TONEMAP, with_print(&good, "debugPrintf(\"now %.1v2f\", in.position.xy);"));
    assert_eq!(prints(&mut ws, "now ")["lines"][0]["text"], "now 7.5, 4.5");

    // A device lost while selected: the selection survives on the new one.
    assert_eq!(s.post("/api/debug/lose-device").0, 202);
    ws.until("the device recovered", LIMIT, |m| {
        matches!(m, Msg::Event(v) if v["type"] == "device_lost" && v["recovered"] == true).then_some(())
    });
    assert_eq!(prints(&mut ws, "now ")["pixel"], json!([7, 4]));
    let history = ws.until("the pixel's history after the loss", LIMIT, |m| match m {
        Msg::Event(v) if v["type"] == "pixel_history" => Some(v.clone()),
        _ => None,
    });
    assert_eq!(history["pixel"], json!([7, 4]));
    assert!(history["passes"].as_array().unwrap().iter().any(|p| p["pass"] == "tonemap"), "{history}");

    // A pixel selected while a reload is under way: its history comes
    // once the frame does.
    p.write(TONEMAP, with_print(&good, "debugPrintf(\"then %.1v2f\", in.position.xy);"));
    ws.send(json!({ "type": "debug_pixel", "x": 5, "y": 6 }));
    // The edit and the selection land in either order: wait for both.
    let then = ws.until("the edited print at (5, 6)", LIMIT, |m| match m {
        Msg::Event(v)
            if v["type"] == "prints"
                && v["pixel"] == json!([5, 6])
                && v["lines"][0]["text"].as_str().is_some_and(|t| t.starts_with("then ")) =>
        {
            Some(v.clone())
        }
        _ => None,
    });
    assert_eq!(then["lines"][0]["text"], "then 5.5, 6.5");
    ws.until("the history of (5, 6)", LIMIT, |m| {
        matches!(m, Msg::Event(v) if v["type"] == "pixel_history" && v["pixel"] == json!([5, 6])).then_some(())
    });

    // Another pixel; one outside the frame is refused and changes nothing.
    ws.send(json!({ "type": "debug_pixel", "x": 1000, "y": 0 }));
    let refused = ws.until("an error", LIMIT, |m| match m {
        Msg::Event(v) if v["type"] == "error" => Some(v["message"].as_str().unwrap_or_default().to_owned()),
        _ => None,
    });
    assert!(refused.contains("(1000, 0) is outside the"), "{refused}");
    ws.send(json!({ "type": "debug_pixel", "x": 2, "y": 9 }));
    ws.until("prints at (2, 9)", LIMIT, |m| {
        matches!(m, Msg::Event(v) if v["type"] == "prints" && v["pixel"] == json!([2, 9])).then_some(())
    });
    ws.send(json!({ "type": "debug_pixel", "x": 2 }));
    ws.until("an error", LIMIT, |m| {
        matches!(m, Msg::Event(v) if v["type"] == "error" && v["message"].as_str().is_some_and(|t| t.contains("both `x` and `y`")))
            .then_some(())
    });
}
