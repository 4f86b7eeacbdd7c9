//! Publishing: what the render thread writes into `Shared` (the
//! snapshots HTTP serves) and the events it sends clients, after a frame
//! and whenever the state they describe changes.

use crate::render::debug_print::Printed;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use super::{Daemon, InFlight, RenderMode};
use crate::diag::{Diagnostic, Severity, display_path};
use crate::loaded::Loaded;
use crate::protocol::{
    self, ControlsReport, PassInfo, PassQuadReport, PassStatus, PassTime, PassTiming, QuadReport, ReloadTimings, ServerEvent, Status,
};
use crate::render::frame::FrameResult;
use crate::render::passes;
use crate::render::session::PassState;
use crate::scene;
use crate::serve::shared::{self, FrameImages};

pub(super) fn materials_report(scene_path: &Path, loaded: &Loaded) -> Arc<protocol::MaterialsReport> {
    Arc::new(crate::serve::materials::report(&display_path(scene_path), loaded))
}

impl Daemon {
    pub(super) fn publish_controls(&self) {
        let report = ControlsReport {
            scene: display_path(&self.config.scene_path),
            controls: scene::overrides::controls(self.session.scene(), passes::affected),
            overrides: self.overrides.clone(),
        };
        shared::write(&self.shared.controls, report.clone());
        self.shared.publish(ServerEvent::Controls(report));
    }

    /// The materials of a scene being installed (`/api/materials` and the
    /// `materials` event). Only a good scene gets here, so a broken
    /// material file leaves the last good report.
    pub(super) fn publish_materials(&self, loaded: &Loaded) {
        let report = materials_report(&self.config.scene_path, loaded);
        shared::write(&self.shared.materials, report.clone());
        self.shared.publish(ServerEvent::Materials((*report).clone()));
    }

    /// What `/api/tradeoffs` compares results with: after the scene file
    /// or a shader source changed.
    pub(super) fn publish_measured(&self) {
        let text = std::fs::read(&self.config.scene_path).unwrap_or_default();
        let measured = crate::tradeoffs::Provenance::new(&self.config.scene_path, &text, self.session.library());
        shared::write(&self.shared.measured, measured);
    }

    pub(super) fn publish_frame(&mut self, done: InFlight, result: FrameResult) {
        let InFlight { results: _, reloads, started, final_key, clean, replaced, trace, samples } = done;
        if clean {
            self.follow_nan(&result, trace);
        }
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let graph = self.session.graph();
        let kind_of = |name: &str| graph.passes.iter().find(|p| p.name == name).map(|p| p.kind);
        let times = super::timing::attribute(&result.timings, result.timing, kind_of, render_ms);
        if times.unbracketed && !self.session.serial() {
            log::warn!("the adapter's timestamps do not bracket compute work: passes are timed by the wall clock from now on");
            self.session.set_serial(true);
        }
        let tiles = crate::render::passes::classify::Statistics::of_frame(&result.tensors);
        // A path tracer whose pipeline never built drew nothing.
        let samples = samples.filter(|_| !result.skipped.iter().any(|p| p == "path_trace"));
        let mut images = None;
        if clean {
            let mut captures = (*shared::read(&self.shared.captures)).clone();
            if !replaced.is_empty() {
                // What a pass showed before its pipelines changed is what
                // A/B compares against; other passes keep theirs.
                let mut last_good = (*shared::read(&self.shared.last_good)).clone();
                last_good.extend(replaced.iter().filter_map(|k| captures.get(k).map(|c| (k.clone(), c.clone()))));
                shared::write(&self.shared.last_good, Arc::new(last_good));
            }
            let this_frame: BTreeMap<String, Arc<_>> = result.captures.into_iter().map(|c| (c.key(), Arc::new(c))).collect();
            captures.extend(this_frame.iter().map(|(k, c)| (k.clone(), c.clone())));
            shared::write(&self.shared.captures, Arc::new(captures));
            let mut tensors = (*shared::read(&self.shared.tensors)).clone();
            tensors.extend(result.tensors.into_iter().map(|t| (t.key(), Arc::new(t))));
            shared::write(&self.shared.tensors, Arc::new(tensors));
            images = Some(FrameImages::new(result.frame, final_key, this_frame));
        }
        // A frame begun while a client still asked for statistics can end
        // after the last one stopped: its maps would outlive the request.
        if clean && !result.quads.is_empty() && self.wants_quads() {
            self.publish_quads(result.frame, result.quads, &result.fragment_invocations);
        }
        if let Some(Printed { pixel, lines, dropped }) = result.prints {
            self.shared.publish(ServerEvent::Prints { frame: result.frame, pixel, lines, dropped });
        }
        if let Some(history) = result.history {
            self.shared.publish(ServerEvent::PixelHistory(history));
        }
        self.last_times = times;
        for r in &reloads {
            let timings = ReloadTimings { render_ms, ..r.timings };
            self.shared.publish(ServerEvent::ReloadSucceeded { id: r.id, files: r.files.clone(), pipelines: r.pipelines.clone(), timings });
        }
        self.publish_passes();
        let t = &self.last_times;
        let passes: Vec<PassTiming> = t.passes.iter().map(|(n, time)| PassTiming { name: n.clone(), time: time.clone() }).collect();
        let ids: Vec<u64> = reloads.iter().map(|r| r.id).collect();
        self.shared.publish(ServerEvent::Frame {
            frame: result.frame,
            passes,
            frame_ms: t.frame_ms,
            passes_ms: t.passes_ms,
            unattributed_ms: t.unattributed_ms,
            reload: ids.last().copied(),
            reloads: ids,
            tiles,
            samples,
        });
        let mut status = shared::read(&self.shared.status);
        status.frame = result.frame;
        shared::write(&self.shared.status, status);
        // Images last: encoding and sending them takes a client a while,
        // and the events say what they show.
        if let Some(images) = images {
            self.shared.frames.send_replace(Some(Arc::new(images)));
        }
    }

    /// A frame's quad statistics, beside the adapter's own counts.
    pub(super) fn publish_quads(&mut self, frame: u64, quads: Vec<crate::render::quads::PassQuads>, invocations: &[(String, u64)]) {
        let passes = quads
            .into_iter()
            .map(|q| PassQuadReport { fragment_invocations: invocations.iter().find(|(p, _)| *p == q.pass).map(|(_, n)| *n), quads: q })
            .collect();
        let report = QuadReport { frame, adapter: self.gpu().adapter_name(), passes };
        shared::write(&self.shared.quads, Some(Arc::new(report.clone())));
        self.shared.publish(ServerEvent::Quads(report));
    }

    /// Writes the pass list snapshot (with the newest times) and announces
    /// it in a `passes` event only when something but the times changed.
    pub(super) fn publish_passes(&mut self) {
        let passes: Vec<PassInfo> = self
            .session
            .passes()
            .into_iter()
            .map(|p| {
                let time = match (p.status, self.last_times.of(&p.name)) {
                    (PassState::Culled, _) => PassTime::none("not run: culled"),
                    (_, Some(t)) => t.clone(),
                    (_, None) => PassTime::none("no frame has run it yet"),
                };
                PassInfo::new(p, time)
            })
            .collect();
        shared::write(&self.shared.passes, passes.clone());
        let shape: Vec<PassInfo> = passes.iter().map(PassInfo::shape).collect();
        if self.announced_passes.as_ref() != Some(&shape) {
            self.announced_passes = Some(shape);
            self.shared.publish(ServerEvent::Passes { passes });
        }
    }

    pub(super) fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut all = self.session.pipeline_diagnostics();
        for d in self.file_errors.values().chain(self.scene_error.iter()).chain(&self.scene_warnings).chain(self.gpu_errors.iter()) {
            if !all.iter().any(|x| x.to_string() == d.to_string()) {
                all.push(d.clone());
            }
        }
        all
    }

    pub(super) fn publish_state(&mut self) {
        let diagnostics = self.diagnostics();
        let infos: Vec<protocol::PipelineInfo> = self.session.pipeline_summaries().into_iter().map(Into::into).collect();
        let count = |s: PassStatus| infos.iter().filter(|i| i.status == s).count();
        let gpu = self.gpu();
        let status = Status {
            protocol: protocol::VERSION,
            version: env!("CARGO_PKG_VERSION").to_owned(),
            adapter: gpu.adapter_name(),
            cpu_adapter: gpu.is_cpu(),
            features: gpu.feature_names(),
            degraded: gpu.degraded.clone(),
            scene: display_path(&self.config.scene_path),
            frame: shared::read(&self.shared.status).frame,
            pipelines_ok: count(PassStatus::Ok),
            pipelines_stale: count(PassStatus::Stale),
            pipelines_failed: count(PassStatus::Failed),
            device_resets: self.device_resets,
            errors: diagnostics.iter().filter(|d| d.severity == Severity::Error).count(),
            warnings: diagnostics.iter().filter(|d| d.severity == Severity::Warning).count(),
            render_mode: match self.config.mode {
                RenderMode::Continuous => "continuous".into(),
                RenderMode::OnChange => "on-change".into(),
            },
        };
        shared::write(&self.shared.status, status);
        self.publish_files(&infos, &diagnostics);
        shared::write(&self.shared.pipelines, infos);
        shared::write(&self.shared.diagnostics, diagnostics.clone());
        self.shared.publish(ServerEvent::Diagnostics { diagnostics });
        self.publish_passes();
    }

    /// The diff of each file that broke a pass against its last good
    /// version, published when it changed.
    fn publish_files(&mut self, pipelines: &[protocol::PipelineInfo], diagnostics: &[Diagnostic]) {
        let settled = !self.reloads.in_flight();
        let diffs = self.last_good.update(self.session.library(), pipelines, diagnostics, settled);
        if diffs == shared::read(&self.shared.files).diffs {
            return;
        }
        let last_good = diffs.iter().filter_map(|d| Some((d.file.clone(), self.last_good.text(&d.file)?))).collect();
        shared::write(&self.shared.files, Arc::new(shared::FilesState { diffs: diffs.clone(), last_good }));
        self.shared.publish(ServerEvent::Files { files: diffs });
    }
}
