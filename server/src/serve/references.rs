//! "Against reference" (the inspector's view of loupe.toml's image cases,
//! docs/images.md): the cases whose scene is the daemon's are rendered and
//! compared with their references as `loupe check` compares them, on a
//! thread of their own with the daemon's current sources, after every
//! reload, so a developer sees before pushing that an edit fails the gate.
//!
//! The thread takes the newest job only (a job waiting is replaced by a
//! newer one), renders each case on a session of its own on the daemon's
//! device, and publishes what it found (`GET /api/references`, the
//! `references` event) with the images a page shows. Blessing writes the
//! outputs last shown as the case's references, then compares again.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::reference_jobs::{Images, Job, State};
use super::shared::{self, Shared};
use crate::check::images::artifacts::png;
use crate::check::images::config::Case;
use crate::check::images::{Renderer, live};
use crate::check::project;
use crate::flip::encode_srgb8;
use crate::protocol::{CaseReport, OutputReport, ReferenceReport, ServerEvent};

/// The default references folder, as `loupe check` has it.
const DEFAULT_REFERENCES: &str = "tests/images";

/// Starts the comparison thread for the daemon's `scene` in the project at
/// `root`.
pub fn start(shared: Arc<Shared>, root: PathBuf, scene: PathBuf, shader_root: PathBuf) {
    let spawned = std::thread::Builder::new().name("loupe-references".into()).stack_size(64 << 20).spawn(move || {
        let queue = shared.reference_jobs.clone();
        while let Some(job) = queue.next() {
            mark_comparing(&shared);
            let state = compare(&job, &root, &scene, &shader_root);
            publish(&shared, state);
        }
    });
    if let Err(e) = spawned {
        log::error!("cannot start the reference comparison thread: {e}");
    }
}

fn mark_comparing(shared: &Shared) {
    let mut next = (*shared::read(&shared.references)).clone();
    next.report.comparing = true;
    let event = ServerEvent::References(next.report.clone());
    // Written before it is announced: a client reads what it was told of.
    shared::write(&shared.references, Arc::new(next));
    shared.publish(event);
}

fn publish(shared: &Shared, mut state: State) {
    let generation = shared::read(&shared.references).report.generation + 1;
    state.report.generation = generation;
    let event = ServerEvent::References(state.report.clone());
    shared::write(&shared.references, Arc::new(state));
    shared.publish(event);
}

/// Renders and compares the cases of `scene` with the job's sources.
fn compare(job: &Job, root: &Path, scene: &Path, shader_root: &Path) -> State {
    let defaults = match project::read(root) {
        Ok(d) => d,
        Err(d) => return State { report: ReferenceReport { config_error: Some(d), ..ReferenceReport::default() }, ..State::default() },
    };
    let references = defaults.references.unwrap_or_else(|| root.join(DEFAULT_REFERENCES));
    let same = |c: &Case| c.scene.canonicalize().ok().zip(scene.canonicalize().ok()).is_some_and(|(a, b)| a == b);
    let cases: Vec<&Case> = defaults.images.iter().filter(|c| same(c)).collect();
    let mut state = State { references: references.clone(), ..State::default() };
    if cases.is_empty() {
        return state;
    }
    let adapter = job.gpu.adapter_name();
    // A session of its own, made for these sources: the daemon's own
    // pipelines are never touched.
    let mut renderer = Renderer::new(job.gpu.clone(), shader_root.to_owned(), (*job.lib).clone());
    for case in cases {
        let compared = live::compare_case(&mut renderer, case, &references, &adapter);
        for (i, o) in compared.outputs.iter().enumerate() {
            let (w, h) = (o.actual.width, o.actual.height);
            let images = Images {
                actual: png(w, h, &encode_srgb8(&o.actual.data)),
                reference: o.reference_image.as_ref().map(|r| png(w, h, &encode_srgb8(&r.rgba))),
                flip: o.map.as_ref().map(|m| m.magma_png()),
                capture: o.actual.clone(),
            };
            state.images.insert((compared.name.clone(), i), Arc::new(images));
        }
        state.report.cases.push(CaseReport {
            name: compared.name,
            verdict: compared.verdict,
            flip_mean: compared.threshold.flip_mean,
            flip_p99: compared.threshold.flip_p99,
            adapter_key: compared.adapter_key,
            outputs: compared
                .outputs
                .iter()
                .map(|o| OutputReport {
                    output: o.output.clone(),
                    reference: o.reference.clone(),
                    flip: o.flip,
                    relative_mse: o.relative_mse,
                })
                .collect(),
            diagnostics: compared.diagnostics,
        });
    }
    state
}

#[derive(Debug, thiserror::Error)]
pub enum BlessError {
    #[error("no image case `{0}` of this scene has been compared")]
    NotCompared(String),
    #[error("{0}")]
    Write(String),
}

/// Writes case `name`'s outputs as last shown as its references; returns
/// the outputs written.
pub fn bless(shared: &Shared, name: &str) -> Result<Vec<String>, BlessError> {
    let state = shared::read(&shared.references);
    let outputs: Vec<&Arc<Images>> = state.images.iter().filter(|((case, _), _)| case == name).map(|(_, i)| i).collect();
    if outputs.is_empty() {
        return Err(BlessError::NotCompared(name.to_owned()));
    }
    let mut written = Vec::new();
    for images in outputs {
        live::bless(&images.capture, name, &state.references).map_err(BlessError::Write)?;
        written.push(images.capture.key());
    }
    shared.reference_jobs.again();
    Ok(written)
}
