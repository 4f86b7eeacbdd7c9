//! What the panels show, built from the protocol's JSON events alone
//! (PROTOCOL.md): the same shapes the browser reads, so an in-process and
//! a remote link feed it alike. Unknown events and fields are ignored, as
//! the browser ignores them.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::frame_times::FrameTimes;
use crate::pixel::{PixelHistory, Prints};

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
    /// Its draws' quad statistics summed, from the newest `quads` event
    /// that held the pass (raster passes, while quad statistics are on).
    #[serde(skip)]
    pub quads: Option<QuadTotals>,
}

/// A source file that broke a pass, diffed against its last good version
/// (a FileDiff of the `files` event).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct FileDiff {
    pub file: String,
    pub pipelines: Vec<String>,
    pub hunks: Vec<Hunk>,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct Hunk {
    pub old_start: usize,
    pub new_start: usize,
    pub lines: Vec<DiffLine>,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct DiffLine {
    /// `" "`, `"-"` or `"+"`.
    pub tag: String,
    pub old: Option<usize>,
    pub new: Option<usize>,
    pub text: String,
    pub failing: bool,
}

/// A raster pass's quad statistics summed over its draws (`quads` of a
/// `GET /api/quads` pass).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct QuadTotals {
    pub pixels: u64,
    pub quads: u64,
    pub helper_lanes: u64,
    /// pixels ÷ 4·quads; `None` without quads.
    pub quad_efficiency: Option<f64>,
}

#[derive(Deserialize)]
struct PassQuads {
    pass: String,
    quads: QuadTotals,
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
    /// A buffer's dimensions, outermost first, as `(name, size)`; `None`
    /// for a texture.
    pub shape: Option<Vec<(String, u32)>>,
}

/// `[height, width, channels]` of a tensor laid out as an image, `[y, x,
/// channel]` (the denoiser's): what the browser shows as images
/// (`tensor_image.js` `isImage`).
pub fn image_shape(dims: &[(String, u32)]) -> Option<[u32; 3]> {
    match dims {
        [(y, h), (x, w), (c, n)] if (y.as_str(), x.as_str(), c.as_str()) == ("y", "x", "channel") => Some([*h, *w, *n]),
        _ => None,
    }
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

/// The scene's live controls and the overrides set on top of the file
/// (a `controls` event, as `GET /api/controls`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
pub struct Controls {
    pub scene: String,
    pub controls: Vec<Control>,
    /// Values set from clients, not yet saved, by path.
    pub overrides: BTreeMap<String, serde_json::Value>,
}

impl Controls {
    pub fn get(&self, path: &str) -> Option<&Control> {
        self.controls.iter().find(|c| c.path == path)
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Control {
    /// The scene value it sets, as the file names it (`post.exposure_ev`).
    pub path: String,
    pub label: String,
    #[serde(flatten)]
    pub kind: ControlKind,
    /// A number, a boolean or an option's name, overrides applied.
    pub value: serde_json::Value,
    /// The passes whose output it changes.
    pub affects: Vec<String>,
}

/// What kind of control a scene value takes; the keys of the other kinds
/// (`null` in the protocol) are ignored.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ControlKind {
    Slider { min: f64, max: f64, step: f64 },
    Toggle,
    Choice { options: Vec<String> },
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
    Hello {
        status: Status,
    },
    Passes {
        passes: Vec<Pass>,
    },
    Frame {
        frame: u64,
        passes: Vec<Timing>,
        frame_ms: f64,
        // A daemon older than the field sends none.
        #[serde(default)]
        samples: Option<u32>,
    },
    Diagnostics {
        diagnostics: Vec<Problem>,
    },
    DeviceLost {
        message: String,
        recovered: bool,
    },
    Error {
        message: String,
    },
    Controls(Controls),
    SceneSaved {
        file: String,
        error: Option<String>,
    },
    Nan {
        report: Option<NanReport>,
    },
    Quads {
        frame: u64,
        passes: Vec<PassQuads>,
    },
    Files {
        files: Vec<FileDiff>,
    },
    Prints(Prints),
    PixelHistory(PixelHistory),
    ReloadSucceeded {},
    ReloadFailed {},
}

#[derive(Debug, Default)]
pub struct Model {
    pub status: Status,
    pub passes: Vec<Pass>,
    pub problems: Vec<Problem>,
    /// The newest frame's number and time, once one was shown.
    pub frame: Option<(u64, f64)>,
    /// The newest notice worth a line (device lost, a refused command, a
    /// scene saved or not).
    pub notice: Option<String>,
    /// Where the newest traced frame's NaN/Inf came from, while a frame
    /// holds one.
    pub nan: Option<NanOrigin>,
    pub controls: Controls,
    /// How many `controls` events arrived: a new one replaces what the
    /// Scene panel showed while waiting for it.
    pub controls_seen: u64,
    /// Samples per pixel the path tracer held after the newest frame;
    /// `None` when it did not run.
    pub samples: Option<u32>,
    /// The newest frames' pass times, for the Timings plot.
    pub times: FrameTimes,
    /// The frame of the newest quad statistics, while they are asked for.
    pub quads_frame: Option<u64>,
    /// Each source file that broke a pass, with its diff against its last
    /// good version.
    pub files: Vec<FileDiff>,
    /// How many reloads finished: a source text read before one may be
    /// stale.
    pub reloads: u64,
    /// The frame's pixel pinned in the Inspector (the daemon's debug
    /// pixel), and the newest history and prints of it; events for any
    /// other pixel are ignored.
    pub pixel: Option<[u32; 2]>,
    pub history: Option<PixelHistory>,
    pub prints: Option<Prints>,
}

impl Model {
    /// Applies one event; events the panels do not use change nothing.
    pub fn apply(&mut self, event: serde_json::Value) {
        let Ok(event) = serde_json::from_value::<Event>(event) else { return };
        match event {
            Event::Hello { status } => self.status = status,
            Event::Passes { passes } => self.passes = passes,
            Event::Frame { frame, passes, frame_ms, samples } => {
                self.frame = Some((frame, frame_ms));
                self.samples = samples;
                self.times.push(frame, frame_ms, passes.iter().filter_map(|t| Some((t.name.as_str(), t.time_ms?))));
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
            Event::Controls(controls) => {
                self.controls = controls;
                self.controls_seen += 1;
            }
            Event::Files { files } => self.files = files,
            Event::Prints(prints) => {
                if Some(prints.pixel) == self.pixel {
                    self.prints = Some(prints);
                }
            }
            Event::PixelHistory(history) => {
                if Some(history.pixel) == self.pixel {
                    self.history = Some(history);
                }
            }
            Event::ReloadSucceeded {} | Event::ReloadFailed {} => self.reloads += 1,
            Event::Quads { frame, passes } => {
                self.quads_frame = Some(frame);
                for p in &mut self.passes {
                    p.quads = passes.iter().find(|q| q.pass == p.name).map(|q| q.quads.clone());
                }
            }
            Event::SceneSaved { file, error } => {
                self.notice = Some(match error {
                    None => format!("saved to {file}"),
                    Some(e) => format!("could not save {file}: {e}"),
                });
            }
        }
    }

    /// Pins `pixel` (`None`: unpins); what was shown of another pixel goes.
    pub fn pin(&mut self, pixel: Option<[u32; 2]>) {
        if self.pixel != pixel {
            (self.pixel, self.history, self.prints) = (pixel, None, None);
        }
    }

    /// Quad statistics were turned off: what they showed is gone.
    pub fn forget_quads(&mut self) {
        self.quads_frame = None;
        for p in &mut self.passes {
            p.quads = None;
        }
    }

    /// Every texture output of the passes, as `(pass/output, output)`.
    pub fn textures(&self) -> impl Iterator<Item = (String, &Output)> {
        self.passes.iter().flat_map(|p| p.writes.iter().filter(|w| w.kind == "texture").map(move |w| (format!("{}/{}", p.name, w.name), w)))
    }

    /// Every image-shaped buffer of the passes that run, in graph order
    /// (for the denoiser, the network's), as `(pass/output, [height,
    /// width, channels])`: the tensors the browser lists.
    pub fn image_tensors(&self) -> impl Iterator<Item = (String, [u32; 3])> {
        self.passes.iter().filter(|p| p.status != "culled").flat_map(|p| {
            p.writes
                .iter()
                .filter(|w| w.kind == "buffer")
                .filter_map(move |w| Some((format!("{}/{}", p.name, w.name), image_shape(w.shape.as_deref()?)?)))
        })
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
    fn quad_statistics_give_raster_passes_their_totals_until_forgotten() {
        let mut m = Model::default();
        m.apply(json!({"type": "passes", "passes": [
            {"name": "gbuffer", "status": "ok", "reason": null, "time_ms": null, "timing": null, "timing_reason": null},
            {"name": "lighting", "status": "ok", "reason": null, "time_ms": null, "timing": null, "timing_reason": null},
        ]}));
        let totals = json!({"name": "total", "cull_mode": null, "triangles": 12, "culled_triangles": 2, "pixels": 300,
            "quads": 100, "helper_lanes": 100, "quad_efficiency": 0.75, "rasterized": null});
        m.apply(json!({"type": "quads", "frame": 4, "adapter": "llvmpipe", "passes": [
            {"pass": "gbuffer", "draws": [], "quads": totals, "what_if": null, "fragment_invocations": 400}]}));
        assert_eq!(m.quads_frame, Some(4));
        assert_eq!(m.passes[0].quads, Some(QuadTotals { pixels: 300, quads: 100, helper_lanes: 100, quad_efficiency: Some(0.75) }));
        assert_eq!(m.passes[1].quads, None, "a pass the event does not hold has no totals");
        m.forget_quads();
        assert_eq!((m.quads_frame, &m.passes[0].quads), (None, &None));
    }

    #[test]
    fn controls_take_their_kind_and_saves_say_where_they_went() {
        let mut m = Model::default();
        m.apply(json!({"type": "controls", "scene": "scenes/a.toml", "overrides": {"post.exposure_ev": 0.5}, "controls": [
            {"path": "post.exposure_ev", "label": "Exposure", "kind": "slider", "min": -24.0, "max": 24.0, "step": 0.1, "options": null, "value": 0.5, "affects": ["exposure"]},
            {"path": "quality.shadows", "label": "Shadows", "kind": "toggle", "min": null, "max": null, "step": null, "options": null, "value": true, "affects": []},
            {"path": "post.tonemap", "label": "Tonemap", "kind": "choice", "min": null, "max": null, "step": null, "options": ["aces", "reinhard"], "value": "aces", "affects": ["tonemap"]},
        ]}));
        assert_eq!(m.controls_seen, 1);
        let kinds: Vec<&ControlKind> = m.controls.controls.iter().map(|c| &c.kind).collect();
        assert_eq!(
            kinds,
            [
                &ControlKind::Slider { min: -24.0, max: 24.0, step: 0.1 },
                &ControlKind::Toggle,
                &ControlKind::Choice { options: vec!["aces".into(), "reinhard".into()] },
            ]
        );
        assert_eq!(m.controls.overrides["post.exposure_ev"], json!(0.5));
        m.apply(json!({"type": "scene_saved", "file": "scenes/a.toml", "error": "read-only"}));
        assert_eq!(m.notice.as_deref(), Some("could not save scenes/a.toml: read-only"));
    }

    #[test]
    fn frames_carry_the_path_tracers_samples_and_feed_the_timings() {
        let mut m = Model::default();
        m.apply(json!({"type": "frame", "frame": 1, "frame_ms": 3.0, "samples": 4, "passes": [
            {"name": "path_trace", "time_ms": 2.0, "timing": "gpu", "timing_reason": null},
            {"name": "denoise", "time_ms": null, "timing": null, "timing_reason": "n/a"},
        ]}));
        assert_eq!(m.samples, Some(4));
        let series = m.times.passes();
        assert_eq!(series.len(), 1, "a pass without a time has no point: {series:?}");
        assert_eq!(series[0].runs, [vec![[1.0, 2.0]]]);
        m.apply(json!({"type": "frame", "frame": 2, "frame_ms": 3.0, "samples": null, "passes": []}));
        assert_eq!(m.samples, None);
    }

    #[test]
    fn image_shaped_buffers_of_running_passes_are_the_tensors() {
        let mut m = Model::default();
        let buffer = |name: &str, shape: serde_json::Value| json!({"name": name, "kind": "buffer", "format": "f32", "width": 1, "height": 1, "meaning": "data", "depth": null, "shape": shape});
        let image = json!([["y", 48], ["x", 64], ["channel", 32]]);
        m.apply(json!({"type": "passes", "passes": [
            {"name": "denoise.enc_conv0", "status": "ok", "writes": [buffer("tensor", image.clone()), buffer("overflow", json!([["count", 1]]))]},
            {"name": "exposure_histogram", "status": "ok", "writes": [buffer("histogram", json!([["bin", 256]]))]},
            {"name": "denoise.concat1", "status": "culled", "reason": "fused", "writes": [buffer("tensor", image)]},
            {"name": "tonemap", "status": "ok", "writes": [{"name": "color", "kind": "texture", "format": "Rgba8UnormSrgb", "width": 64, "height": 48, "shape": null}]},
        ]}));
        assert_eq!(m.image_tensors().collect::<Vec<_>>(), [("denoise.enc_conv0/tensor".to_owned(), [48, 64, 32])]);
    }

    #[test]
    fn the_pinned_pixels_history_and_prints_are_kept_and_other_pixels_ignored() {
        use crate::pixel::{DrawTrace, Fragment, PrintLine, TensorAtPixel, TexelChange};
        let history = |pixel: [u32; 2], frame: u64| {
            json!({"type": "pixel_history", "frame": frame, "pixel": pixel, "passes": [
                {"pass": "gbuffer", "kind": "raster", "inputs": [], "tensors": [], "invocation": null,
                 "outputs": [{"output": "gbuffer/normal", "texel": [70, 20, 0], "origin": "cleared", "before": null, "after": [0.1, 0.9, null, 1.0]}],
                 "draws": [{"name": "floor", "fragments": [{"draw": 0, "primitive": 1, "depth": 0.93, "verdict": "failed_depth", "helper": true}]}]},
                {"pass": "denoise.enc_conv0", "kind": "compute", "inputs": ["path_trace/color"], "outputs": [], "draws": null,
                 "invocation": [70, 20, 0], "tensors": [{"output": "denoise.enc_conv0/tensor", "at": [70, 20], "channels": [0.5, null]}]}]})
        };
        let prints = |pixel: [u32; 2], text: &str| {
            json!({"type": "prints", "frame": 40, "pixel": pixel, "dropped": 2, "lines": [
                {"pass": "tonemap", "file": "shaders/post/tonemap.wgsl", "line": 18, "column": 5, "text": text, "values": [[70.5, 20.5]]}]})
        };
        let mut m = Model::default();
        m.apply(history([70, 20], 39));
        assert_eq!(m.history, None, "nothing pinned: ignored");

        m.pin(Some([70, 20]));
        m.apply(history([70, 20], 40));
        m.apply(prints([70, 20], "at 70.5"));
        m.apply(history([1, 1], 41));
        m.apply(prints([1, 1], "another pixel's"));
        let h = m.history.as_ref().expect("the pinned pixel's history");
        assert_eq!((h.frame, h.pixel), (40, [70, 20]), "another pixel's history is ignored");
        let gbuffer = &h.passes[0];
        assert_eq!(
            gbuffer.outputs,
            [TexelChange {
                output: "gbuffer/normal".into(),
                texel: [70, 20, 0],
                origin: "cleared".into(),
                before: None,
                after: Some([Some(0.1), Some(0.9), None, Some(1.0)]),
            }],
            "a channel that is not finite arrives as null"
        );
        let fragment = Fragment { primitive: 1, depth: Some(0.93), verdict: "failed_depth".into(), helper: true };
        assert_eq!(gbuffer.draws, Some(vec![DrawTrace { name: "floor".into(), fragments: vec![fragment] }]));
        let denoise = &h.passes[1];
        assert_eq!((denoise.kind.as_str(), &denoise.inputs[..]), ("compute", &["path_trace/color".to_owned()][..]));
        assert_eq!((denoise.draws.as_ref(), denoise.invocation), (None, Some([70, 20, 0])));
        assert_eq!(
            denoise.tensors,
            [TensorAtPixel { output: "denoise.enc_conv0/tensor".into(), at: [70, 20], channels: vec![Some(0.5), None] }]
        );
        let p = m.prints.as_ref().expect("the pinned pixel's prints");
        let line =
            PrintLine { pass: "tonemap".into(), file: "shaders/post/tonemap.wgsl".into(), line: 18, column: 5, text: "at 70.5".into() };
        assert_eq!((p.frame, p.dropped, &p.lines), (40, 2, &vec![line]));

        // Another pixel pinned: what was shown of the first goes.
        m.pin(Some([1, 1]));
        assert_eq!((&m.history, &m.prints), (&None, &None));
        m.apply(prints([1, 1], "now this one's"));
        assert_eq!(m.prints.as_ref().map(|p| p.lines[0].text.as_str()), Some("now this one's"));
        m.pin(None);
        m.apply(history([1, 1], 42));
        assert_eq!((m.pixel, &m.history, &m.prints), (None, &None, &None), "unpinned, nothing is kept");
    }

    #[test]
    fn finished_reloads_are_counted() {
        let mut m = Model::default();
        m.apply(json!({"type": "reload_started", "id": 1, "files": ["a.wgsl"], "pipelines": []}));
        m.apply(json!({"type": "reload_succeeded", "id": 1, "files": ["a.wgsl"], "pipelines": [], "timings": {}}));
        m.apply(json!({"type": "reload_failed", "id": 2, "files": ["a.wgsl"], "pipelines": [], "diagnostics": []}));
        assert_eq!(m.reloads, 2);
    }

    #[test]
    fn diagnostics_replace_the_problems_and_unknown_events_change_nothing() {
        let mut m = Model::default();
        let diag = json!({"severity": "error", "code": "parse", "message": "expected `;`", "labels": [], "notes": [],
            "location": {"file": "shaders/a.wgsl", "line": 3, "column": 9, "end_line": 3, "end_column": 10}});
        m.apply(json!({"type": "diagnostics", "diagnostics": [diag]}));
        assert_eq!(m.problems[0].location, Some(Location { file: "shaders/a.wgsl".into(), line: 3, column: 9 }));
        m.apply(json!({"type": "tiles", "frame": 1}));
        m.apply(json!({"not": "an event"}));
        assert_eq!(m.problems.len(), 1);
        m.apply(json!({"type": "diagnostics", "diagnostics": []}));
        assert!(m.problems.is_empty());
    }
}
