//! What a frame's pass times may be shown as: each measured figure with the
//! clock that measured it, or none with the reason, and the frame's wall
//! time split into the passes' sum and what no pass accounts for.
//!
//! The design: GPU timestamps are kept where they bracket a pass's work.
//! Where they do not, the pass is timed by the wall clock, submitted alone
//! and waited for (`loupe bench --serial`'s measure). Two rules find out:
//! - a known adapter: a CPU adapter (llvmpipe/lavapipe, whose timestamps
//!   do not bracket compute work) or one without timestamp queries is
//!   timed by the wall clock from the first frame (`wall_clock_needed`);
//! - per frame, on any other adapter: a compute pass stamped under
//!   `UNBRACKETED_MS` while the frame's wall time lies far beyond the
//!   stamped sum (`UNEXPLAINED_MS`, `UNEXPLAINED_RATIO`) gets no figure,
//!   `n/a` with the reason, and the daemon times the frames after it by
//!   the wall clock.
//!
//! A figure known to be wrong is never shown.

use crate::protocol::{Clock, PassTime};
use crate::render::graph::PassKind;

/// A compute pass stamped under this many milliseconds is suspect: it is
/// about what an empty dispatch measures (llvmpipe stamps `path_trace` at
/// 0.013 ms of a 1.2-second frame).
pub const UNBRACKETED_MS: f64 = 0.05;
/// ... when the frame's wall time exceeds the stamped sum by more than this
/// (a real GPU's readback and queueing stay well under it) ...
const UNEXPLAINED_MS: f64 = 100.0;
/// ... and by more than this factor.
const UNEXPLAINED_RATIO: f64 = 10.0;

/// Whether an adapter is known not to give per-pass GPU times that bracket
/// the work: a CPU adapter, or one without timestamp queries.
pub fn wall_clock_needed(cpu_adapter: bool, timestamp_queries: bool) -> bool {
    cpu_adapter || !timestamp_queries
}

/// A frame's times as shown.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrameTimes {
    /// Per pass that ran, in execution order.
    pub passes: Vec<(String, PassTime)>,
    /// The frame's wall time, from the start of its recording to its
    /// publication.
    pub frame_ms: f64,
    /// The sum of the passes' figures.
    pub passes_ms: f64,
    /// `frame_ms` less `passes_ms`: recording, readback, conversion and
    /// waiting; never negative (overlapping GPU passes can sum past the
    /// frame).
    pub unattributed_ms: f64,
    /// Some pass's timestamps were found not to bracket its work.
    pub unbracketed: bool,
}

impl FrameTimes {
    /// The time shown for `pass`, if it ran in this frame.
    pub fn of(&self, pass: &str) -> Option<&PassTime> {
        self.passes.iter().find(|(n, _)| n == pass).map(|(_, t)| t)
    }
}

/// Classifies a frame's measured pass times. `how` is how the frame was
/// timed (`FrameResult::timing`: `gpu`, `serial` or `cpu`), `kind_of` the
/// kind of a pass by name, `frame_ms` the frame's wall time.
pub fn attribute(measured: &[(String, f64)], how: &str, kind_of: impl Fn(&str) -> Option<PassKind>, frame_ms: f64) -> FrameTimes {
    let stamped: f64 = measured.iter().map(|(_, ms)| ms).sum();
    let unexplained = frame_ms - stamped > UNEXPLAINED_MS && frame_ms > UNEXPLAINED_RATIO * stamped;
    let mut unbracketed = false;
    let passes: Vec<(String, PassTime)> = measured
        .iter()
        .map(|(name, ms)| {
            let time = match how {
                "serial" => PassTime::measured(*ms, Clock::Wall),
                _ if unexplained && *ms < UNBRACKETED_MS && kind_of(name) == Some(PassKind::Compute) => {
                    unbracketed = true;
                    PassTime::none(format!(
                        "n/a: the adapter's timestamps read {ms:.3} ms while {:.0} ms of the frame's wall time lie outside every \
                         pass: they do not bracket this compute pass's work (the next frames are timed by the wall clock)",
                        frame_ms - stamped
                    ))
                }
                _ => PassTime::measured(*ms, Clock::Gpu),
            };
            (name.clone(), time)
        })
        .collect();
    let passes_ms = passes.iter().filter_map(|(_, t)| t.time_ms).sum();
    FrameTimes { passes, frame_ms, passes_ms, unattributed_ms: (frame_ms - passes_ms).max(0.0), unbracketed }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(name: &str) -> Option<PassKind> {
        Some(if name.starts_with("path") || name.starts_with("dec") { PassKind::Compute } else { PassKind::Raster })
    }

    fn pass(name: &str, ms: f64) -> (String, f64) {
        (name.to_owned(), ms)
    }

    /// llvmpipe, as issue 21 found it: `path_trace` stamped at 0.013 ms of
    /// a 1.2-second frame. The compute passes get no figure, the raster
    /// pass keeps its stamp, and the frame is flagged for the wall clock.
    #[test]
    fn a_compute_pass_stamped_near_zero_in_a_long_frame_is_not_shown_as_measured() {
        let measured = [pass("gbuffer", 3.0), pass("path_trace", 0.013), pass("dec_conv0", 0.007), pass("tonemap", 1.0)];
        let t = attribute(&measured, "gpu", kinds, 1200.0);
        assert!(t.unbracketed);
        for name in ["path_trace", "dec_conv0"] {
            let p = t.of(name).unwrap();
            assert_eq!((p.time_ms, p.timing), (None, None), "{name}: {p:?}");
            assert!(p.timing_reason.as_deref().unwrap().starts_with("n/a: the adapter's timestamps read"), "{p:?}");
        }
        assert_eq!(t.of("gbuffer").unwrap(), &PassTime::measured(3.0, Clock::Gpu));
        assert_eq!(t.passes_ms, 4.0, "the sum holds only shown figures");
        assert_eq!(t.passes_ms + t.unattributed_ms, t.frame_ms, "they reconcile with the frame");
    }

    /// A real GPU: a one-workgroup compute pass really takes microseconds,
    /// and a frame whose wall time the stamps explain is believed.
    #[test]
    fn a_short_compute_pass_in_a_frame_its_stamps_explain_keeps_its_gpu_time() {
        let measured = [pass("gbuffer", 2.0), pass("path_adapt", 0.004), pass("tonemap", 0.5)];
        for frame_ms in [16.0, 90.0] {
            let t = attribute(&measured, "gpu", kinds, frame_ms);
            assert!(!t.unbracketed, "{frame_ms} ms");
            assert_eq!(t.of("path_adapt").unwrap(), &PassTime::measured(0.004, Clock::Gpu));
        }
        // Stamps that cover a tenth of a long frame or more are not doubted.
        let heavy = [pass("path_trace", 0.01), pass("gbuffer", 150.0)];
        assert!(!attribute(&heavy, "gpu", kinds, 1200.0).unbracketed);
    }

    /// A slow raster pass is not suspect: timestamps bracket draws.
    #[test]
    fn only_compute_passes_are_doubted() {
        let t = attribute(&[pass("tonemap", 0.01)], "gpu", kinds, 1200.0);
        assert_eq!(t.of("tonemap").unwrap(), &PassTime::measured(0.01, Clock::Gpu));
    }

    /// Serial frames are wall-clock figures, whatever their size.
    #[test]
    fn serial_frames_are_timed_by_the_wall_clock() {
        let t = attribute(&[pass("path_trace", 0.01), pass("tonemap", 900.0)], "serial", kinds, 1000.0);
        assert!(!t.unbracketed);
        assert!(t.passes.iter().all(|(_, p)| p.timing == Some(Clock::Wall) && p.time_ms.is_some()));
        assert_eq!((t.passes_ms, t.unattributed_ms), (900.01, 1000.0 - 900.01));
    }

    /// Overlapping GPU passes can sum past the frame: nothing is negative.
    #[test]
    fn the_unattributed_time_is_never_negative() {
        let t = attribute(&[pass("gbuffer", 12.0)], "gpu", kinds, 10.0);
        assert_eq!(t.unattributed_ms, 0.0);
    }

    #[test]
    fn a_cpu_adapter_or_one_without_timestamps_is_timed_by_the_wall_clock() {
        assert!(wall_clock_needed(true, true));
        assert!(wall_clock_needed(false, false));
        assert!(!wall_clock_needed(false, true));
    }
}
