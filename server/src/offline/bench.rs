//! `loupe bench`: each pass's time and what captures cost, as medians
//! over frames with the capture settings interleaved.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use serde::Serialize;

use super::{FRAME_DT, Job, OfflineError, frame, prepare};
use crate::diag::display_path;

/// Per-pass times and capture overhead of one scene.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub adapter: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub timing: String,
    /// Median per pass, milliseconds, in frame order.
    pub passes: Vec<(String, f64)>,
    /// Median wall time from submit to every readback landed (what the
    /// thread that submits frames waits for), per capture setting,
    /// measured interleaved so drift hits each alike.
    pub frame_ms_no_capture: f64,
    pub frame_ms_final_capture: f64,
    pub frame_ms_all_captures: f64,
    /// Median time converting the landed readbacks and taking their
    /// statistics, which `serve` does on a thread of its own.
    pub convert_ms_final_capture: f64,
    pub convert_ms_all_captures: f64,
    /// The same two times with quad statistics on (no captures): the
    /// vertex captures and depth copies on the GPU, then the model's replay
    /// on the conversion thread.
    pub frame_ms_quads: f64,
    pub convert_ms_quads: f64,
    /// With `--debug-pixel`: the frame (no capture, converted) with that
    /// pixel selected (its prints and history), and with none, timed
    /// interleaved after the others; `null` without.
    pub frame_ms_debug_pixel: Option<f64>,
    pub frame_ms_debug_pixel_off: Option<f64>,
    /// With `--debug-pixel`: from selecting the pixel to the first frame's
    /// history converted (the instrumented pipelines built on the way).
    pub first_history_ms: Option<f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

/// `serial`: per-pass times from an extra frame each round that submits
/// each pass alone and waits for it (wall clock), instead of from the
/// uncaptured frame's timestamps.
pub fn run(job: &Job, frames: u32, serial: bool, debug_pixel: Option<[u32; 2]>) -> Result<BenchReport, OfflineError> {
    let mut session = prepare(job)?;
    let none = BTreeSet::new();
    let fin: BTreeSet<String> = session.graph().final_name().into_iter().collect();
    // Warm up: first use compiles driver-side state and allocates targets.
    for _ in 0..3 {
        frame(&mut session, None);
    }
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let [mut t_none, mut t_final, mut t_all, mut t_quads, mut c_none, mut c_final, mut c_all, mut c_quads] =
        std::array::from_fn(|_| Vec::new());
    let mut timing = String::new();
    for _ in 0..frames {
        let settings = [
            (Some(&none), false, &mut t_none, &mut c_none),
            (Some(&fin), false, &mut t_final, &mut c_final),
            (None, false, &mut t_all, &mut c_all),
            (Some(&none), true, &mut t_quads, &mut c_quads),
        ];
        for (set, quads, times, converts) in settings {
            session.set_quads(quads);
            let start = Instant::now();
            let pending = session.submit(set, FRAME_DT);
            session.land(&pending);
            let landed = Instant::now();
            let r = pending.finish();
            times.push((landed - start).as_secs_f64() * 1e3);
            converts.push(landed.elapsed().as_secs_f64() * 1e3);
            if set.is_some_and(BTreeSet::is_empty) && !quads && !serial {
                timing = r.timing.to_owned();
                for (name, t) in r.timings {
                    per_pass.entry(name).or_default().push(t);
                }
            }
        }
        if serial {
            session.set_quads(false);
            session.set_serial(true);
            let r = frame(&mut session, Some(&none));
            session.set_serial(false);
            timing = r.timing.to_owned();
            for (name, t) in r.timings {
                per_pass.entry(name).or_default().push(t);
            }
        }
    }
    let (frame_ms_debug_pixel, frame_ms_debug_pixel_off, first_history_ms) = match debug_pixel {
        Some(pixel) => {
            session.set_quads(false);
            let start = Instant::now();
            session.set_debug_pixel(Some(pixel));
            // The first frames build the instrumented pipelines.
            let first = frame(&mut session, Some(&none));
            let first_ms = first.history.is_some().then(|| start.elapsed().as_secs_f64() * 1e3);
            for _ in 0..2 {
                frame(&mut session, Some(&none));
            }
            let (mut on, mut off) = (Vec::new(), Vec::new());
            for _ in 0..frames {
                for (paused, times) in [(false, &mut on), (true, &mut off)] {
                    session.pause_prints(paused);
                    let start = Instant::now();
                    let pending = session.submit(Some(&none), FRAME_DT);
                    // Converted too: the history's replay runs there.
                    let _ = session.wait(pending);
                    times.push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
            session.pause_prints(false);
            (Some(median(on)), Some(median(off)), first_ms)
        }
        None => (None, None, None),
    };
    let order: Vec<String> = session.graph().passes.iter().map(|x| x.name.clone()).collect();
    Ok(BenchReport {
        scene: display_path(&job.scene),
        adapter: session.gpu().adapter_name(),
        width: session.scene().width,
        height: session.scene().height,
        frames,
        timing,
        passes: order.into_iter().map(|n| (n.clone(), median(per_pass.remove(&n).unwrap_or_default()))).collect(),
        frame_ms_no_capture: median(t_none),
        frame_ms_final_capture: median(t_final),
        frame_ms_all_captures: median(t_all),
        convert_ms_final_capture: median(c_final),
        convert_ms_all_captures: median(c_all),
        frame_ms_quads: median(t_quads),
        convert_ms_quads: median(c_quads),
        frame_ms_debug_pixel,
        frame_ms_debug_pixel_off,
        first_history_ms,
    })
}
