//! The reload state machine: which reloads are open and which pipelines
//! each still waits for, which compile of a pipeline is the newest (an
//! older one is never installed), what a finished reload reports, and which
//! reloads and swapped pipelines the next frame is the first to show.
//!
//! It holds no device and no sources: the daemon feeds it what happened
//! (a reload started, a compile came back, a pipeline was installed, a
//! frame was submitted, the device was replaced) and acts on what it
//! answers, so the rules are tested without a GPU.

use std::collections::{BTreeMap, BTreeSet};

use crate::diag::Diagnostic;
use crate::protocol::ReloadTimings;
use crate::render::pipelines::Installed;
use crate::render::resource::PipelineKey;

/// One reload between its start and its last pipeline's result.
struct Open {
    files: Vec<String>,
    pipelines: Vec<String>,
    pending: BTreeSet<PipelineKey>,
    diagnostics: Vec<Diagnostic>,
    watch_ms: f64,
    compose_ms: f64,
    pipeline_ms: f64,
    /// Some of its pipelines are swapped in, others still compiling: a
    /// frame now would mix old and new.
    swapped_any: bool,
}

/// A reload whose pipelines all swapped in, waiting for the first frame
/// that uses them: `reload_succeeded` is sent once that frame is rendered,
/// with its render time.
#[derive(Debug, Clone)]
pub struct Succeeded {
    pub id: u64,
    pub files: Vec<String>,
    pub pipelines: Vec<String>,
    pub timings: ReloadTimings,
}

/// A reload that ended with errors: the pipelines that failed keep their
/// last good version.
#[derive(Debug, Clone, PartialEq)]
pub struct Failed {
    pub id: u64,
    pub files: Vec<String>,
    pub pipelines: Vec<String>,
    pub diagnostics: Vec<Diagnostic>,
}

/// What to do with a compile that came back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Create the pipeline and report how that went (`Reloads::installed`).
    Install,
    /// A newer reload compiles the same pipeline: installing this one
    /// would put back what the user replaced.
    Superseded,
}

/// What the next frame shows for the first time.
pub struct ForFrame {
    /// Reloads to announce as succeeded once the frame is rendered.
    pub reloads: Vec<Succeeded>,
    /// Pipelines swapped in since the previous frame.
    pub swapped: BTreeSet<PipelineKey>,
}

pub struct Reloads {
    next_id: u64,
    open: BTreeMap<u64, Open>,
    /// Per pipeline, the newest reload that compiled it: results of older
    /// ones are dropped, also after the newest one's has arrived (bounded by
    /// the pipelines the specs can make).
    newest_compile: BTreeMap<PipelineKey, u64>,
    /// Reloads finished since the last frame, to tag that frame with.
    finished: Vec<Succeeded>,
    /// Pipelines swapped in since the last frame was submitted.
    swapped_since_frame: BTreeSet<PipelineKey>,
}

impl Default for Reloads {
    fn default() -> Self {
        Reloads {
            next_id: 1,
            open: BTreeMap::new(),
            newest_compile: BTreeMap::new(),
            finished: Vec::new(),
            swapped_since_frame: BTreeSet::new(),
        }
    }
}

impl Reloads {
    /// Opens a reload of `keys` for a change to `files`; returns its id
    /// (ids grow from 1). Each key's compile by this reload is from now on
    /// the newest. A reload of no keys is finished by the next `finish`.
    pub fn start(&mut self, keys: &BTreeSet<PipelineKey>, files: Vec<String>, watch_ms: f64) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        for key in keys {
            self.newest_compile.insert(key.clone(), id);
        }
        let pipelines = keys.iter().map(PipelineKey::label).collect();
        let open = Open {
            files,
            pipelines,
            pending: keys.clone(),
            diagnostics: Vec::new(),
            watch_ms,
            compose_ms: 0.0,
            pipeline_ms: 0.0,
            swapped_any: false,
        };
        self.open.insert(id, open);
        id
    }

    /// The files and pipeline labels of an open reload, as announced.
    pub fn describe(&self, id: u64) -> Option<(&[String], &[String])> {
        self.open.get(&id).map(|r| (r.files.as_slice(), r.pipelines.as_slice()))
    }

    /// A compile of `key` by reload `id` came back. A superseded one no
    /// longer holds its reload up.
    pub fn compiled(&mut self, id: u64, key: &PipelineKey) -> Verdict {
        if self.newest_compile.get(key).is_some_and(|&newest| newest > id) {
            if let Some(reload) = self.open.get_mut(&id) {
                reload.pending.remove(key);
            }
            return Verdict::Superseded;
        }
        Verdict::Install
    }

    /// How installing `key` for reload `id` went; `diagnostics`: the
    /// pipeline's, when it was not swapped in.
    pub fn installed(
        &mut self,
        id: u64,
        key: &PipelineKey,
        installed: Installed,
        compose_ms: f64,
        pipeline_ms: f64,
        diagnostics: Vec<Diagnostic>,
    ) {
        let swapped = installed == Installed::Swapped;
        if swapped {
            self.swapped_since_frame.insert(key.clone());
        }
        if let Some(reload) = self.open.get_mut(&id) {
            reload.pending.remove(key);
            reload.compose_ms = reload.compose_ms.max(compose_ms);
            reload.pipeline_ms += pipeline_ms;
            if swapped {
                reload.swapped_any = true;
            } else {
                reload.diagnostics.extend(diagnostics);
            }
        }
    }

    /// Closes reload `id` once it waits for no pipeline. `extra` gives the
    /// errors outside its pipelines (the files it named that failed to
    /// load, the scene's): with them or a failed pipeline it failed, and the
    /// failure is returned to be published; otherwise it waits for the next
    /// frame (`for_frame`). `None` while it is still open, or unknown.
    pub fn finish(&mut self, id: u64, extra: impl FnOnce(&[String]) -> Vec<Diagnostic>) -> Option<Result<(), Failed>> {
        if !self.open.get(&id).is_some_and(|r| r.pending.is_empty()) {
            return None;
        }
        let mut r = self.open.remove(&id).expect("checked");
        r.diagnostics.extend(extra(&r.files));
        if !r.diagnostics.is_empty() {
            return Some(Err(Failed { id, files: r.files, pipelines: r.pipelines, diagnostics: r.diagnostics }));
        }
        let timings = ReloadTimings { watch_ms: r.watch_ms, compose_ms: r.compose_ms, pipeline_ms: r.pipeline_ms, render_ms: 0.0 };
        self.finished.push(Succeeded { id, files: r.files, pipelines: r.pipelines, timings });
        Some(Ok(()))
    }

    /// Whether a frame now would show a half-applied reload: some of its
    /// pipelines swapped, others not yet, or a pipeline it waits for that
    /// has no current version (`built` says which have one).
    pub fn half_applied(&self, built: impl Fn(&PipelineKey) -> bool) -> bool {
        self.open.values().any(|r| r.swapped_any || r.pending.iter().any(|k| !built(k)))
    }

    /// Whether a reload is still compiling or installing.
    pub fn in_flight(&self) -> bool {
        !self.open.is_empty()
    }

    /// Whether finished reloads wait for a frame to show them.
    pub fn waiting(&self) -> bool {
        !self.finished.is_empty()
    }

    /// Hands what the frame being submitted shows for the first time.
    pub fn for_frame(&mut self) -> ForFrame {
        ForFrame { reloads: std::mem::take(&mut self.finished), swapped: std::mem::take(&mut self.swapped_since_frame) }
    }

    /// The device was replaced: frames of the old one never come back, so
    /// the reloads they were to announce (`lost`) go with the next frame,
    /// before those finished since; nothing new is swapped in on the new
    /// device.
    pub fn device_replaced(&mut self, lost: Vec<Succeeded>) {
        self.finished.splice(0..0, lost);
        self.swapped_since_frame.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Code;
    use crate::render::passes;

    /// Two distinct pipelines; which ones does not matter to the rules.
    fn keys() -> (PipelineKey, PipelineKey) {
        let mut specs = passes::specs();
        (PipelineKey::new(specs.next().unwrap(), &[]), PipelineKey::new(specs.next().unwrap(), &[]))
    }

    fn set(keys: &[&PipelineKey]) -> BTreeSet<PipelineKey> {
        keys.iter().map(|k| (*k).clone()).collect()
    }

    fn no_errors(_: &[String]) -> Vec<Diagnostic> {
        Vec::new()
    }

    /// Compiles and installs `key` for reload `id` with the given outcome.
    fn complete(r: &mut Reloads, id: u64, key: &PipelineKey, outcome: Installed, diagnostics: Vec<Diagnostic>) {
        assert_eq!(r.compiled(id, key), Verdict::Install);
        r.installed(id, key, outcome, 1.0, 2.0, diagnostics);
    }

    #[test]
    fn a_successful_reload_is_announced_with_the_next_frame() {
        let (a, b) = keys();
        let mut r = Reloads::default();
        let id = r.start(&set(&[&a, &b]), vec!["shaders/x.wgsl".into()], 5.0);
        assert_eq!(id, 1);
        assert_eq!(r.describe(id), Some((&["shaders/x.wgsl".to_owned()][..], &[a.label(), b.label()][..])));
        assert!(r.half_applied(|_| false), "a pipeline with no version yet holds frames back");
        assert!(!r.half_applied(|_| true), "until one swaps, frames show the old pipelines");

        complete(&mut r, id, &a, Installed::Swapped, Vec::new());
        assert!(r.half_applied(|_| true), "a swapped and b still compiling: a frame would mix them");
        assert_eq!(r.finish(id, no_errors), None, "b is still pending");

        complete(&mut r, id, &b, Installed::Swapped, Vec::new());
        assert_eq!(r.finish(id, no_errors), Some(Ok(())));
        assert!(!r.half_applied(|_| true));
        assert!(r.waiting());
        let frame = r.for_frame();
        assert_eq!(frame.swapped, set(&[&a, &b]));
        let [done] = frame.reloads.as_slice() else { panic!("one reload: {:?}", frame.reloads) };
        assert_eq!((done.id, done.files.as_slice()), (1, &["shaders/x.wgsl".to_owned()][..]));
        assert_eq!((done.timings.watch_ms, done.timings.compose_ms, done.timings.pipeline_ms), (5.0, 1.0, 4.0));
        assert!(!r.waiting() && r.for_frame().reloads.is_empty(), "announced once");
    }

    #[test]
    fn a_failed_reload_keeps_the_last_good_pipeline() {
        let (a, _) = keys();
        let mut r = Reloads::default();
        let first = r.start(&set(&[&a]), Vec::new(), 0.0);
        complete(&mut r, first, &a, Installed::Swapped, Vec::new());
        assert_eq!(r.finish(first, no_errors), Some(Ok(())));
        r.for_frame();

        let error = Diagnostic::error(Code::Parse, "expected `;`");
        let second = r.start(&set(&[&a]), vec!["shaders/a.wgsl".into()], 0.0);
        complete(&mut r, second, &a, Installed::KeptLastGood, vec![error.clone()]);
        let failed = r.finish(second, no_errors).expect("finished").expect_err("failed");
        assert_eq!((failed.id, failed.diagnostics), (second, vec![error]));
        assert!(!r.half_applied(|_| true), "frames go on with the last good pipeline");
        let frame = r.for_frame();
        assert!(frame.swapped.is_empty(), "nothing swapped: the last good images stay");
        assert!(frame.reloads.is_empty(), "a failed reload is never announced as succeeded");
    }

    #[test]
    fn a_reload_superseded_by_a_newer_save_never_installs() {
        let (a, _) = keys();
        let mut r = Reloads::default();
        let old = r.start(&set(&[&a]), vec!["shaders/a.wgsl".into()], 0.0);
        let new = r.start(&set(&[&a]), vec!["shaders/a.wgsl".into()], 0.0);
        assert!(new > old);
        // The newer compile comes back first, the older one after it.
        complete(&mut r, new, &a, Installed::Swapped, Vec::new());
        assert_eq!(r.finish(new, no_errors), Some(Ok(())));
        assert_eq!(r.compiled(old, &a), Verdict::Superseded, "installing it would put back what the user replaced");
        assert_eq!(r.finish(old, no_errors), Some(Ok(())), "it no longer waits");

        // And the other way round: the older result first.
        let older = r.start(&set(&[&a]), Vec::new(), 0.0);
        let newer = r.start(&set(&[&a]), Vec::new(), 0.0);
        assert_eq!(r.compiled(older, &a), Verdict::Superseded);
        assert_eq!(r.finish(older, no_errors), Some(Ok(())));
        assert_eq!(r.finish(newer, no_errors), None, "the newer one still waits for its compile");
        complete(&mut r, newer, &a, Installed::Swapped, Vec::new());
        assert_eq!(r.finish(newer, no_errors), Some(Ok(())));
    }

    #[test]
    fn a_scene_reload_failure_fails_the_reload() {
        let mut r = Reloads::default();
        let scene_error = Diagnostic::error(Code::Scene, "unknown field `exposur`");
        let id = r.start(&BTreeSet::new(), vec!["scenes/a.toml".into()], 0.0);
        let failed = r
            .finish(id, |files| {
                assert_eq!(files, ["scenes/a.toml"], "asked about the reload's own files");
                vec![scene_error.clone()]
            })
            .expect("a reload of no pipelines finishes at once")
            .expect_err("the scene's error fails it");
        assert_eq!(failed.diagnostics, vec![scene_error]);
        assert!(!r.waiting(), "nothing to announce");
    }

    #[test]
    fn reloads_of_a_lost_device_go_with_the_next_frame_first() {
        let (a, b) = keys();
        let mut r = Reloads::default();
        let lost = r.start(&set(&[&a]), Vec::new(), 0.0);
        complete(&mut r, lost, &a, Installed::Swapped, Vec::new());
        r.finish(lost, no_errors);
        let in_flight = r.for_frame().reloads;
        let later = r.start(&set(&[&b]), Vec::new(), 0.0);
        complete(&mut r, later, &b, Installed::Swapped, Vec::new());
        r.finish(later, no_errors);

        r.device_replaced(in_flight);
        let frame = r.for_frame();
        assert_eq!(frame.reloads.iter().map(|s| s.id).collect::<Vec<_>>(), [lost, later]);
        assert!(frame.swapped.is_empty(), "nothing is swapped in on the new device yet");
    }
}
