//! Following a NaN/Inf: the NaN watch output of each frame decides when
//! to trace a frame (capture every output) to find where it started.

use super::Daemon;
use crate::protocol::{NanCount, NanReport, ServerEvent};
use crate::render::frame::FrameResult;
use crate::render::passes::nan_watch;
use crate::serve::shared;

impl Daemon {
    /// Traces a frame when the NaN watch sees a NaN/Inf that no current
    /// report explains; publishes a traced frame's report; clears it once
    /// a frame is clean.
    pub(super) fn follow_nan(&mut self, result: &FrameResult, trace: Option<&'static str>) {
        if let Some(trigger) = trace {
            let outputs = result
                .captures
                .iter()
                .filter(|c| c.stats.has_non_finite())
                .map(|c| NanCount { pass: c.pass.clone(), output: c.output.clone(), nan: c.stats.nan, inf: c.stats.inf })
                .chain(result.tensors.iter().filter(|t| t.stats.has_non_finite()).map(|t| NanCount {
                    pass: t.pass.clone(),
                    output: t.output.clone(),
                    nan: t.stats.nan,
                    inf: t.stats.inf,
                }))
                .collect();
            let report = NanReport { frame: result.frame, trigger: trigger.to_owned(), origin: result.nan.clone(), outputs };
            self.trace_stale = false;
            self.set_nan_report(Some(report));
            return;
        }
        let Some(counts) = result.tensors.iter().find(|t| t.key() == nan_watch::OUTPUT) else { return };
        let bad = counts.data.iter().any(|n| *n > 0.0);
        let explained = self.nan_report.as_ref().is_some_and(|r| r.origin.is_some()) && !self.trace_stale;
        if bad && !explained && self.trace_next.is_none() {
            self.trace_next = Some("auto");
            self.dirty = true;
        } else if !bad && self.nan_report.as_ref().is_some_and(|r| r.frame < result.frame) {
            self.set_nan_report(None);
        }
    }

    pub(super) fn set_nan_report(&mut self, report: Option<NanReport>) {
        if report != self.nan_report {
            shared::write(&self.shared.nan, report.clone());
            self.shared.publish(ServerEvent::Nan { report: report.clone() });
            self.nan_report = report;
        }
    }
}
