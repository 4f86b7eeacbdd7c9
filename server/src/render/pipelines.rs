//! The pipeline cache: one entry per (spec, defs), holding the last good
//! pipeline until a new version is known to work.
//!
//! Architecture Invariant: an entry's pipeline is replaced only by one that
//! composed, validated and was created without a wgpu error. A failed
//! rebuild marks the entry stale and keeps rendering the old one.

use std::collections::BTreeMap;

use serde::Serialize;

use super::resource::PipelineKey;
use crate::diag::Diagnostic;
use crate::gpu::{
    self,
    pipeline::{self, Pipeline},
};
use crate::shader::{Compose, Composed, Library};

/// A composed module and the content of the sources it was composed from.
pub struct Compiled {
    pub composed: Composed,
    /// Taken when composing, from the same version of the sources: a save
    /// landing before the module is installed must not pass for it.
    pub sources: blake3::Hash,
}

/// Composes and validates the shader of pipeline `key`, which lives at
/// `display` in `lib`, with `composer`. Runs on any thread; a missing file
/// and a compiler panic come back as diagnostics like any other error.
pub fn compose(composer: &dyn Compose, lib: &Library, key: &PipelineKey, display: &str) -> Result<Compiled, Vec<Diagnostic>> {
    let Some(file) = lib.get(display) else {
        return Err(vec![pipeline::missing_shader(key.spec.name, display)]);
    };
    let caps = gpu::capabilities_without_device();
    crate::shader::guard::guarded(display, "the WGSL compiler", || composer.compose(lib, file, &key.defs, caps))
        .map(|composed| Compiled { sources: sources_hash(lib, &composed.files), composed })
}

pub struct Entry {
    pub current: Option<Pipeline>,
    /// The module `current` was built from, to rebuild after device loss.
    pub last_good: Option<Composed>,
    pub generation: u64,
    pub diagnostics: Vec<Diagnostic>,
    /// Files the newest attempt was composed from.
    pub files: Vec<String>,
    /// The content of the files `current` was built from: a compile of the
    /// same content changes nothing.
    sources: Option<blake3::Hash>,
}

/// How a pipeline stands, worst last.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Its current version renders.
    Ok,
    /// Its newest source failed; the last good pipeline still renders.
    Stale,
    /// It has never built: it does not render.
    Failed,
}

impl Entry {
    pub fn status(&self) -> Status {
        match (&self.current, self.diagnostics.is_empty()) {
            (Some(_), true) => Status::Ok,
            (Some(_), false) => Status::Stale,
            (None, _) => Status::Failed,
        }
    }
}

/// One pipeline as reports show it.
#[derive(Debug, Clone, Serialize)]
pub struct PipelineSummary {
    /// `spec[DEFS]`.
    pub name: String,
    pub shader: String,
    pub defs: String,
    pub status: Status,
    /// Increases each time a new version is swapped in.
    pub generation: u64,
    pub files: Vec<String>,
}

#[derive(Default)]
pub struct PipelineCache {
    pub entries: BTreeMap<PipelineKey, Entry>,
}

/// What installing a compile result did.
#[derive(Debug, PartialEq, Eq)]
pub enum Installed {
    Swapped,
    /// It built from the same sources as the current pipeline, which stays.
    Unchanged,
    KeptLastGood,
    Failed,
}

/// The content of `files` as the library holds them.
fn sources_hash(lib: &Library, files: &[String]) -> blake3::Hash {
    let mut h = blake3::Hasher::new();
    for f in files {
        h.update(f.as_bytes());
        h.update(lib.get(f).map_or(&[0u8; 32], |s| s.hash.as_bytes()));
    }
    h.finalize()
}

impl PipelineCache {
    /// Takes a compile result: creates the pipeline and swaps it in when
    /// everything succeeded; otherwise keeps the old one and records why.
    pub fn install(
        &mut self,
        device: &wgpu::Device,
        key: &PipelineKey,
        result: Result<Compiled, Vec<Diagnostic>>,
        lib: &Library,
        shader_display: &str,
    ) -> Installed {
        let entry = self.entries.entry(key.clone()).or_insert_with(|| Entry {
            current: None,
            last_good: None,
            generation: 0,
            diagnostics: Vec::new(),
            files: vec![shader_display.to_owned()],
            sources: None,
        });
        if let Ok(c) = &result
            && entry.current.is_some()
            && Some(c.sources) == entry.sources
        {
            entry.files = c.composed.files.clone();
            entry.diagnostics.clear();
            return Installed::Unchanged;
        }
        let created = result.and_then(|Compiled { composed, sources }| {
            entry.files = composed.files.clone();
            pipeline::create(device, key.spec, &key.defs, &composed, lib, shader_display, None).map(|p| (p, composed, sources))
        });
        match created {
            Ok((p, composed, sources)) => {
                entry.sources = Some(sources);
                entry.current = Some(p);
                entry.last_good = Some(composed);
                entry.generation += 1;
                entry.diagnostics.clear();
                Installed::Swapped
            }
            Err(diags) => {
                entry.diagnostics = diags;
                if entry.current.is_some() { Installed::KeptLastGood } else { Installed::Failed }
            }
        }
    }

    /// Recreates every pipeline from its last good module on a new device.
    pub fn recreate_all(&mut self, device: &wgpu::Device, lib: &Library) -> Vec<Diagnostic> {
        let mut problems = Vec::new();
        for (key, entry) in &mut self.entries {
            entry.current = None;
            let Some(composed) = &entry.last_good else { continue };
            let display = entry.files.last().cloned().unwrap_or_default();
            match pipeline::create(device, key.spec, &key.defs, composed, lib, &display, None) {
                Ok(p) => entry.current = Some(p),
                Err(d) => problems.extend(d),
            }
        }
        problems
    }

    pub fn live(&self) -> BTreeMap<PipelineKey, Pipeline> {
        self.entries.iter().filter_map(|(k, e)| e.current.clone().map(|p| (k.clone(), p))).collect()
    }

    /// The entries `keep` selects, as reports show them.
    pub fn summaries_of(&self, keep: impl Fn(&PipelineKey) -> bool) -> Vec<PipelineSummary> {
        self.entries
            .iter()
            .filter(|(k, _)| keep(k))
            .map(|(k, e)| PipelineSummary {
                name: k.label(),
                shader: e.files.last().cloned().unwrap_or_default(),
                defs: crate::shader::defs_key(&k.defs),
                status: e.status(),
                generation: e.generation,
                files: e.files.clone(),
            })
            .collect()
    }

    /// The diagnostics of the entries `keep` selects, each once.
    pub fn diagnostics_of(&self, keep: impl Fn(&PipelineKey) -> bool) -> Vec<Diagnostic> {
        let mut seen = std::collections::BTreeSet::new();
        self.entries
            .iter()
            .filter(|(k, _)| keep(k))
            .flat_map(|(_, e)| e.diagnostics.iter())
            .filter(|d| seen.insert(d.to_string()))
            .cloned()
            .collect()
    }
}
