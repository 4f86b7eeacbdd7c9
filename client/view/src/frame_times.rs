//! The newest frames' times, for the Timings plot: a ring of the last
//! [`FRAMES`] `frame` events, each with the passes that ran in it and were
//! timed.

use std::collections::VecDeque;

/// How many frames the plot spans.
pub const FRAMES: usize = 300;

#[derive(Debug, Default)]
pub struct FrameTimes {
    frames: VecDeque<Frame>,
}

#[derive(Debug)]
struct Frame {
    frame: u64,
    frame_ms: f64,
    /// The passes that ran and have a time, in execution order.
    passes: Vec<(String, f64)>,
}

/// One pass over the ring: its time per frame as `[frame, ms]` points,
/// split into runs of consecutive frames (a frame it did not run in, or
/// ran in without a time, has no point and breaks the line).
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub runs: Vec<Vec<[f64; 2]>>,
}

impl FrameTimes {
    /// Adds a frame, dropping the oldest past [`FRAMES`].
    pub fn push<'a>(&mut self, frame: u64, frame_ms: f64, passes: impl IntoIterator<Item = (&'a str, f64)>) {
        if self.frames.len() == FRAMES {
            self.frames.pop_front();
        }
        let passes = passes.into_iter().map(|(name, ms)| (name.to_owned(), ms)).collect();
        self.frames.push_back(Frame { frame, frame_ms, passes });
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Each frame's wall time, as `[frame, ms]`.
    pub fn frame_ms(&self) -> Vec<[f64; 2]> {
        self.frames.iter().map(|f| [f.frame as f64, f.frame_ms]).collect()
    }

    /// Every pass that has a point in the ring, in the order they first
    /// appear.
    pub fn passes(&self) -> Vec<Series> {
        let mut series: Vec<Series> = Vec::new();
        // The ring index of each series' last point: a gap starts a run.
        let mut last: Vec<usize> = Vec::new();
        for (i, f) in self.frames.iter().enumerate() {
            for (name, ms) in &f.passes {
                let point = [f.frame as f64, *ms];
                match series.iter().position(|s| s.name == *name) {
                    Some(k) => {
                        if last[k] + 1 == i {
                            series[k].runs.last_mut().expect("a series has a run").push(point);
                        } else {
                            series[k].runs.push(vec![point]);
                        }
                        last[k] = i;
                    }
                    None => {
                        series.push(Series { name: name.clone(), runs: vec![vec![point]] });
                        last.push(i);
                    }
                }
            }
        }
        series
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ring_keeps_the_newest_frames_only() {
        let mut t = FrameTimes::default();
        for frame in 0..FRAMES as u64 + 20 {
            t.push(frame, frame as f64, [("a", 1.0)]);
        }
        assert_eq!(t.len(), FRAMES);
        let ms = t.frame_ms();
        assert_eq!((ms[0], ms[FRAMES - 1]), ([20.0, 20.0], [FRAMES as f64 + 19.0, FRAMES as f64 + 19.0]));
        let a = &t.passes()[0];
        assert_eq!(a.runs.len(), 1);
        assert_eq!(a.runs[0].len(), FRAMES);
    }

    #[test]
    fn each_pass_has_its_own_series_broken_where_it_did_not_run() {
        let mut t = FrameTimes::default();
        t.push(1, 5.0, [("gbuffer", 1.0), ("lighting", 2.0)]);
        t.push(2, 5.0, [("gbuffer", 1.5)]);
        t.push(3, 5.0, [("gbuffer", 1.25), ("lighting", 2.5)]);
        t.push(4, 5.0, [("path_trace", 4.0), ("lighting", 3.0)]);
        let series = t.passes();
        let names: Vec<&str> = series.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["gbuffer", "lighting", "path_trace"]);
        assert_eq!(series[0].runs, [vec![[1.0, 1.0], [2.0, 1.5], [3.0, 1.25]]]);
        assert_eq!(series[1].runs, [vec![[1.0, 2.0]], vec![[3.0, 2.5], [4.0, 3.0]]]);
        assert_eq!(series[2].runs, [vec![[4.0, 4.0]]]);
    }
}
