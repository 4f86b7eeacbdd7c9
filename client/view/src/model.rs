//! What the panels show, built from the protocol's JSON events alone
//! (PROTOCOL.md): the same shapes the browser reads, so an in-process and
//! a remote link feed it alike. Unknown events and fields are ignored, as
//! the browser ignores them.

use serde::Deserialize;

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct Pass {
    pub name: String,
    /// `ok`, `stale`, `failed` or `culled`.
    pub status: String,
    /// Why it is culled or failed.
    pub reason: Option<String>,
    pub time_ms: Option<f64>,
    /// `gpu` or `wall`, the clock of `time_ms`.
    pub timing: Option<String>,
    /// Why there is no time.
    pub timing_reason: Option<String>,
    /// What it writes (`writes` of `GET /api/passes`).
    #[serde(default)]
    pub writes: Vec<Output>,
}

/// One output a pass writes.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct Output {
    pub name: String,
    /// `texture` or `buffer`.
    pub kind: String,
    pub format: String,
    pub width: u32,
    pub height: u32,
    pub meaning: Option<String>,
    pub depth: Option<DepthPlanes>,
}

/// `writes[].depth`: the planes are `null` for a light's depth.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct DepthPlanes {
    pub near: Option<f32>,
    pub far: Option<f32>,
    pub reversed: bool,
}

impl Output {
    /// The planes its depth reads as distance through, where known.
    pub fn planes(&self) -> Option<crate::presets::Planes> {
        let d = self.depth?;
        Some(crate::presets::Planes { near: d.near?, far: d.far?, reversed: d.reversed })
    }
}

/// Where a traced frame's NaN/Inf first appeared (`origin` of the `nan`
/// event's report).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct NanOrigin {
    pub pass: String,
    pub output: String,
    pub pixel: [u32; 2],
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Location {
    pub file: String,
    pub line: u32,
    pub column: u32,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Problem {
    /// `error`, `warning` or `note`.
    pub severity: String,
    pub code: String,
    pub message: String,
    pub location: Option<Location>,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct Status {
    pub adapter: String,
    pub scene: String,
    pub cpu_adapter: bool,
}

/// One `frame` event's pass time.
#[derive(Deserialize)]
struct Timing {
    name: String,
    time_ms: Option<f64>,
    timing: Option<String>,
    timing_reason: Option<String>,
}

#[derive(Deserialize)]
struct NanReport {
    origin: Option<NanOrigin>,
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Event {
    Hello { status: Status },
    Passes { passes: Vec<Pass> },
    Frame { frame: u64, passes: Vec<Timing>, frame_ms: f64 },
    Diagnostics { diagnostics: Vec<Problem> },
    DeviceLost { message: String, recovered: bool },
    Error { message: String },
    Nan { report: Option<NanReport> },
}

#[derive(Debug, Default)]
pub struct Model {
    pub status: Status,
    pub passes: Vec<Pass>,
    pub problems: Vec<Problem>,
    /// The newest frame's number and time, once one was shown.
    pub frame: Option<(u64, f64)>,
    /// The newest notice worth a line (device lost, a refused command).
    pub notice: Option<String>,
    /// Where the newest traced frame's NaN/Inf came from, while a frame
    /// holds one.
    pub nan: Option<NanOrigin>,
}

impl Model {
    /// Applies one event; events the panels do not use change nothing.
    pub fn apply(&mut self, event: serde_json::Value) {
        let Ok(event) = serde_json::from_value::<Event>(event) else { return };
        match event {
            Event::Hello { status } => self.status = status,
            Event::Passes { passes } => self.passes = passes,
            Event::Frame { frame, passes, frame_ms } => {
                self.frame = Some((frame, frame_ms));
                for t in passes {
                    if let Some(p) = self.passes.iter_mut().find(|p| p.name == t.name) {
                        (p.time_ms, p.timing, p.timing_reason) = (t.time_ms, t.timing, t.timing_reason);
                    }
                }
            }
            Event::Diagnostics { diagnostics } => self.problems = diagnostics,
            Event::DeviceLost { message, recovered } => {
                let outcome = if recovered { "recovered" } else { "not recovered" };
                self.notice = Some(format!("device lost ({outcome}): {message}"));
            }
            Event::Error { message } => self.notice = Some(message),
            Event::Nan { report } => self.nan = report.and_then(|r| r.origin),
        }
    }

    /// Every texture output of the passes, as `(pass/output, output)`.
    pub fn textures(&self) -> impl Iterator<Item = (String, &Output)> {
        self.passes.iter().flat_map(|p| p.writes.iter().filter(|w| w.kind == "texture").map(move |w| (format!("{}/{}", p.name, w.name), w)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn passes_take_their_times_from_frames() {
        let mut m = Model::default();
        m.apply(json!({"type": "passes", "passes": [
            {"name": "gbuffer", "kind": "raster", "status": "ok", "reason": null, "time_ms": null, "timing": null, "timing_reason": "no frame yet"},
            {"name": "path_trace", "kind": null, "status": "culled", "reason": "rastering", "time_ms": null, "timing": null, "timing_reason": "culled"},
        ]}));
        m.apply(json!({"type": "frame", "frame": 7, "frame_ms": 3.5, "passes": [{"name": "gbuffer", "time_ms": 1.25, "timing": "gpu", "timing_reason": null}]}));
        assert_eq!(m.frame, Some((7, 3.5)));
        assert_eq!(m.passes[0].time_ms, Some(1.25));
        assert_eq!(m.passes[0].timing.as_deref(), Some("gpu"));
        assert_eq!(m.passes[1].reason.as_deref(), Some("rastering"));
    }

    #[test]
    fn diagnostics_replace_the_problems_and_unknown_events_change_nothing() {
        let mut m = Model::default();
        let diag = json!({"severity": "error", "code": "parse", "message": "expected `;`", "labels": [], "notes": [],
            "location": {"file": "shaders/a.wgsl", "line": 3, "column": 9, "end_line": 3, "end_column": 10}});
        m.apply(json!({"type": "diagnostics", "diagnostics": [diag]}));
        assert_eq!(m.problems[0].location, Some(Location { file: "shaders/a.wgsl".into(), line: 3, column: 9 }));
        m.apply(json!({"type": "quads", "frame": 1}));
        m.apply(json!({"not": "an event"}));
        assert_eq!(m.problems.len(), 1);
        m.apply(json!({"type": "diagnostics", "diagnostics": []}));
        assert!(m.problems.is_empty());
    }
}
