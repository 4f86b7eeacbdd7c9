//! Honest pass timings from a running `loupe serve` on this machine's
//! adapter (lavapipe here): no compute pass shows a GPU time its
//! timestamps may not bracket, every pass's time names its clock or says
//! why there is none, and the frame's wall time is the passes' sum plus
//! what no pass accounts for, in `/api/passes` and in `frame` events.

use std::time::Duration;

use loupe_tests::{Project, Server};
use serde_json::Value;

const LIMIT: Duration = Duration::from_secs(120);
/// serve/daemon/timing.rs `UNBRACKETED_MS`: a compute pass's GPU stamp
/// under it is never shown as measured in a frame its stamps do not explain.
const UNBRACKETED_MS: f64 = 0.05;
/// A scene with compute passes (the auto exposure's histogram and adaptation).
pub const AUTO_EXPOSURE: &str = "[output]\nwidth = 320\nheight = 180\n\n[post]\nauto_exposure = true\n";

/// One pass's time as the server shows it: a figure with its clock, or
/// none with the reason. On a CPU adapter (timestamps known not to bracket
/// compute work) a compute pass is never given a GPU time.
pub fn assert_honest(p: &Value, compute: bool, cpu_adapter: bool) {
    match (p["time_ms"].as_f64(), p["timing"].as_str()) {
        (Some(ms), Some("gpu")) => {
            assert!(!(compute && cpu_adapter), "a compute pass's GPU stamp on a CPU adapter: {p}");
            assert!(!compute || ms >= UNBRACKETED_MS, "a compute pass's GPU time under the threshold: {p}");
        }
        (Some(ms), Some("wall")) => assert!(ms >= 0.0, "{p}"),
        (None, None) => assert!(p["timing_reason"].as_str().is_some_and(|r| !r.is_empty()), "no time without a reason: {p}"),
        _ => panic!("a time without its clock, or a clock without a time: {p}"),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn every_pass_time_names_its_clock_and_the_frame_adds_up() {
    let p = Project::copy_of_repo("serve-timings");
    p.write("scenes/auto.toml", AUTO_EXPOSURE);
    let s = Server::start(&p.root, &["--render", "continuous", "--fps", "4", "--scene", "scenes/auto.toml"]);
    let mut ws = s.ws();
    let ran = |f: &Value| f["passes"].as_array().is_some_and(|ps| ps.iter().any(|p| p["name"] == "exposure_histogram"));
    // The first frame runs while the last pipelines may still build: a
    // later one is a settled frame.
    ws.event("frame", LIMIT, ran);
    let frame = ws.event("frame", LIMIT, ran);
    // Asked once the daemon has rendered: before, the status is not yet
    // the adapter's.
    let cpu_adapter = s.get_json("/api/status")["cpu_adapter"].as_bool().unwrap();
    let listed = s.get_json("/api/passes");
    let listed = listed.as_array().unwrap();
    let compute = |name: &str| listed.iter().any(|p| p["name"] == name && p["kind"] == "compute");
    assert!(compute("exposure_histogram"), "{listed:?}");

    let passes = frame["passes"].as_array().unwrap();
    for p in passes {
        assert_honest(p, compute(p["name"].as_str().unwrap()), cpu_adapter);
        if cpu_adapter {
            assert_eq!(p["timing"], "wall", "a CPU adapter's passes are timed by the wall clock: {p}");
        }
    }
    for p in listed.iter().filter(|p| p["status"] != "culled") {
        assert_honest(p, p["kind"] == "compute", cpu_adapter);
    }
    // The frame reconciles: its wall time is the shown passes' sum plus
    // the rest.
    let f = |k: &str| frame[k].as_f64().unwrap_or_else(|| panic!("{k} in {frame}"));
    let sum: f64 = passes.iter().filter_map(|p| p["time_ms"].as_f64()).sum();
    assert!(close(f("passes_ms"), sum), "passes_ms is the passes' sum: {frame}");
    assert!(f("unattributed_ms") >= 0.0 && f("frame_ms") > 0.0, "{frame}");
    assert!(close(f("passes_ms") + f("unattributed_ms"), f("frame_ms")), "passes + unattributed = frame: {frame}");
    assert!(f("passes_ms") <= f("frame_ms") || !cpu_adapter, "serial passes lie inside their frame: {frame}");
}
