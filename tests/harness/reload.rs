//! Driving hot reloads the way a user does — an editor saves a shader, the
//! frame changes — and measuring them: the save-to-frame latency benchmark
//! and the edit/break/fix soak. Used by `bench-reload` and by the e2e tests
//! (a short soak).

use std::time::{Duration, Instant};

use crate::ws::{Msg, Ws};
use crate::{Project, Server};

/// The shader the drivers edit: the final pass, so its output is the frame.
pub const TONEMAP: &str = "shaders/post/tonemap.wgsl";
/// Its output, as `/api/captures` names it.
pub const FINAL: &str = "tonemap/color";
/// How long one save may take to come back as an event before it counts
/// as lost.
pub const EVENT_LIMIT: Duration = Duration::from_secs(60);

/// `good` (the repository's tonemap shader) made to output the constant
/// linear colour `rgb` everywhere.
pub fn constant_colour(good: &str, rgb: [f32; 3]) -> String {
    let from = "return vec4(tonemap_aces(c), texel.a);";
    assert!(good.contains(from), "the tonemap shader still ends in `{from}`");
    let [r, g, b] = rgb;
    good.replace(from, &format!("return vec4(tonemap_aces(c) * 0.0 + vec3({r:?}, {g:?}, {b:?}), texel.a);"))
}

/// `shader` with a call to an undefined function: it fails to validate.
pub fn broken(shader: &str) -> String {
    let from = "let c = max(";
    assert!(shader.contains(from), "the tonemap shader still has `{from}`");
    shader.replace(from, "let c = mux(")
}

/// A colour for each `i`, every channel in [0.05, 0.95] and far (at least
/// 0.1, linear) from the same channel of `colour(i - 1)` and `colour(i + 1)`,
/// so a frame from the wrong save cannot pass for the right one.
pub fn colour(i: usize) -> [f32; 3] {
    let c = |k: usize| 0.05 + (k % 91) as f32 / 100.0;
    [c(37 * i), c(53 * i + 11), c(71 * i + 29)]
}

/// Linear to sRGB-encoded, as an `…Srgb` target stores a value. Captures
/// report linear values, so colours are compared encoded: one step of the
/// stored byte is 1/255 there.
pub fn srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// What one save led to.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub reload: u64,
    pub succeeded: bool,
    /// For a success, the `timings` of `reload_succeeded`.
    pub timings: Option<serde_json::Value>,
    /// For a success, the frame that shows it.
    pub frame: Option<u64>,
    /// From the write to the `frame` event carrying the reload (success)
    /// or to `reload_failed` (failure), in milliseconds.
    pub total_ms: f64,
}

/// Saves files of a project and follows `/ws` until each save's reload has
/// finished. Counts what the server said this client dropped.
pub struct Driver<'a> {
    pub project: &'a Project,
    pub ws: Ws,
    pub dropped_events: u64,
    pub dropped_frames: u64,
    /// Every event read while following the latest save.
    pub events: Vec<serde_json::Value>,
}

impl<'a> Driver<'a> {
    pub fn new(project: &'a Project, server: &Server) -> Self {
        let mut ws = server.ws();
        ws.event("hello", EVENT_LIMIT, |_| true);
        Driver { project, ws, dropped_events: 0, dropped_frames: 0, events: Vec::new() }
    }

    /// Saves `content` into `rel` as vim and VS Code do (temporary file,
    /// renamed over) and follows the reload it causes; `None` when no
    /// outcome came within `EVENT_LIMIT`.
    pub fn save(&mut self, rel: &str, content: &str) -> Option<Outcome> {
        let start = Instant::now();
        self.project.save_by_rename(rel, content);
        let deadline = start + EVENT_LIMIT;
        let (mut reload, mut success) = (None::<u64>, None::<serde_json::Value>);
        self.events.clear();
        loop {
            let Msg::Event(v) = self.ws.next_before(deadline)? else { continue };
            self.events.push(v.clone());
            let id = v["id"].as_u64();
            match v["type"].as_str().unwrap_or("") {
                "reload_started" if reload.is_none() && v["files"].as_array().is_some_and(|f| f.iter().any(|f| f == rel)) => {
                    reload = id;
                }
                "reload_succeeded" if reload.is_some() && id == reload => success = Some(v["timings"].clone()),
                "reload_failed" if reload.is_some() && id == reload => {
                    let total_ms = start.elapsed().as_secs_f64() * 1e3;
                    return Some(Outcome { reload: reload?, succeeded: false, timings: None, frame: None, total_ms });
                }
                "frame" if success.is_some() && v["reloads"].as_array().is_some_and(|r| r.iter().any(|r| r.as_u64() == reload)) => {
                    let total_ms = start.elapsed().as_secs_f64() * 1e3;
                    let frame = v["frame"].as_u64();
                    return Some(Outcome { reload: reload?, succeeded: true, timings: success, frame, total_ms });
                }
                "dropped" => {
                    self.dropped_events += v["events"].as_u64().unwrap_or(0);
                    self.dropped_frames += v["frames"].as_u64().unwrap_or(0);
                }
                _ => {}
            }
        }
    }
}

/// One save-to-frame measurement, in milliseconds.
#[derive(Debug, Clone, Copy)]
pub struct Split {
    pub total: f64,
    pub watch: f64,
    pub compose: f64,
    pub pipeline: f64,
    pub render: f64,
    /// The rest: the write until the first file event, queueing between
    /// threads, and sending the events to this client.
    pub send: f64,
}

impl Split {
    pub fn of(o: &Outcome) -> Option<Split> {
        let t = o.timings.as_ref()?;
        let ms = |k: &str| t[k].as_f64();
        let (watch, compose, pipeline, render) = (ms("watch_ms")?, ms("compose_ms")?, ms("pipeline_ms")?, ms("render_ms")?);
        Some(Split { total: o.total_ms, watch, compose, pipeline, render, send: o.total_ms - watch - compose - pipeline - render })
    }
}

/// The `q`-quantile (0..=1) of `values` by nearest rank.
pub fn percentile(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// The material file the material series edits, and the scene using it:
/// `minimal.toml` with its material taken from that file.
pub const MATERIAL: &str = "scenes/bench_paint.mat";
pub const MATERIAL_SCENE: &str = "scenes/bench_paint.toml";

/// Writes `MATERIAL_SCENE` and `MATERIAL` (in minimal's blue: the first
/// edit, at `colour(0)`, changes it) into `project`.
pub fn material_scene(project: &Project) {
    let minimal = project.read("scenes/minimal.toml");
    let shorthand = "base_color = [0.2, 0.45, 0.8]\nmetallic = 0.0\nroughness = 0.35\n";
    assert!(minimal.contains(shorthand), "minimal.toml still has its shorthand material");
    project.write(MATERIAL_SCENE, minimal.replace(shorthand, "file = \"bench_paint.mat\"\n"));
    project.write(MATERIAL, material([0.2, 0.45, 0.8]));
}

/// The material file with `rgb` as its colour's default: a value edit,
/// which rebuilds no pipeline (new parameters only).
pub fn material(rgb: [f32; 3]) -> String {
    let [r, g, b] = rgb;
    format!(
        "// The benchmark's paint: a plastic whose colour each edit changes.\nparam colour: color = rgb({r:?}, {g:?}, {b:?})\n\nmaterial bench_paint = slab {{\n    base_color: colour,\n    specular_roughness: 0.35,\n}}\n"
    )
}

/// One kind of edit: the file an editor saves, and its `i`th content.
pub struct Edits<'a> {
    pub file: &'a str,
    pub content: Box<dyn Fn(usize) -> String + 'a>,
}

impl Edits<'_> {
    /// The tonemap shader at a new constant colour each time.
    pub fn shader(project: &Project) -> Edits<'static> {
        let good = project.read(TONEMAP);
        Edits { file: TONEMAP, content: Box::new(move |i| constant_colour(&good, colour(i))) }
    }

    /// `MATERIAL` at a new colour each time.
    pub fn material() -> Edits<'static> {
        Edits { file: MATERIAL, content: Box::new(|i| material(colour(i))) }
    }
}

/// `warmup + edits` rounds, each saving one valid version of every series'
/// file in turn (so the series share the machine's load), the first
/// `warmup` unmeasured; the splits of each series, in `series`' order.
/// Panics when a save never shows.
pub fn latency(driver: &mut Driver, warmup: usize, edits: usize, series: &[Edits]) -> Vec<Vec<Split>> {
    let mut out = vec![Vec::new(); series.len()];
    for i in 0..warmup + edits {
        for (s, splits) in series.iter().zip(&mut out) {
            let o = driver.save(s.file, &(s.content)(i)).unwrap_or_else(|| panic!("edit {i} of {} never reached a frame", s.file));
            assert!(o.succeeded, "edit {i} of {} failed to reload", s.file);
            if i >= warmup {
                splits.push(Split::of(&o).expect("a success has timings"));
            }
        }
    }
    out
}

/// What a soak found.
#[derive(Debug, Default)]
pub struct SoakReport {
    pub cycles: usize,
    /// Cycles done so far.
    pub done: usize,
    /// Saves whose reload outcome was the expected one.
    pub outcomes: usize,
    /// Saves that produced no outcome or the wrong one.
    pub lost: Vec<String>,
    /// `(cycle, VmRSS KiB)`, sampled every `sample_every` cycles and at the end.
    pub rss: Vec<(usize, u64)>,
    pub dropped_events: u64,
    pub dropped_frames: u64,
    /// The last colour written, and the final frame's pixel after it showed.
    pub final_colour: [f32; 3],
    pub final_pixel: [f32; 4],
    pub final_frame: u64,
}

impl SoakReport {
    /// Whether the final frame shows the final file's colour: the pass
    /// writes an sRGB target, whose capture reports the stored, encoded
    /// values (8 bits: within 1.5/255 per channel).
    pub fn final_matches(&self) -> bool {
        self.final_colour.iter().zip(self.final_pixel).all(|(want, got)| (srgb(*want) - srgb(got)).abs() < 1.5 / 255.0)
    }

    pub fn rss_max_kib(&self) -> u64 {
        self.rss.iter().map(|r| r.1).max().unwrap_or(0)
    }
}

/// `cycles` of edit (a new constant colour: succeeds), break (fails),
/// fix (the edit again: succeeds). Every save must produce its outcome;
/// afterwards the final frame's pixel is read back from `/api/captures`.
/// `progress` is called after each cycle.
pub fn soak(server: &Server, driver: &mut Driver, cycles: usize, sample_every: usize, mut progress: impl FnMut(&SoakReport)) -> SoakReport {
    let good = driver.project.read(TONEMAP);
    let mut report = SoakReport { cycles, ..Default::default() };
    let mut last_frame = 0;
    for i in 0..cycles {
        let edited = constant_colour(&good, colour(i));
        for (step, content, want) in [("edit", &edited, true), ("break", &broken(&edited), false), ("fix", &edited, true)] {
            match driver.save(TONEMAP, content) {
                Some(o) if o.succeeded == want => {
                    report.outcomes += 1;
                    last_frame = o.frame.unwrap_or(last_frame);
                }
                Some(o) => {
                    report.lost.push(format!("cycle {i} {step}: reload {} {}", o.reload, if o.succeeded { "succeeded" } else { "failed" }))
                }
                None => report.lost.push(format!("cycle {i} {step}: no reload outcome within {EVENT_LIMIT:?}")),
            }
        }
        report.final_colour = colour(i);
        report.done = i + 1;
        if i % sample_every == 0 || i + 1 == cycles {
            report.rss.push((i, server.rss_kib()));
        }
        progress(&report);
    }
    report.dropped_events = driver.dropped_events;
    report.dropped_frames = driver.dropped_frames;
    let deadline = Instant::now() + EVENT_LIMIT;
    let capture = loop {
        match server.capture_f32(FINAL) {
            Some(c) if c.frame >= last_frame => break c,
            _ if Instant::now() > deadline => panic!("no capture of {FINAL} from frame {last_frame} on"),
            _ => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    report.final_frame = capture.frame;
    report.final_pixel = capture.pixel(capture.width / 2, capture.height / 2);
    report
}
