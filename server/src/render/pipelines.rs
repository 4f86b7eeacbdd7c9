//! The pipeline cache: one entry per (spec, defs), holding the last good
//! pipeline until a new version is known to work.
//!
//! Architecture Invariant: an entry's pipeline is replaced only by one that
//! composed, validated and was created without a wgpu error. A failed
//! rebuild marks the entry stale and keeps rendering the old one.

use std::collections::BTreeMap;

use super::graph::PipelineKey;
use crate::diag::{Code, Diagnostic, Location};
use crate::gpu::{self, pipeline::{self, Pipeline}};
use crate::protocol::{PassStatus, PipelineInfo};
use crate::shader::{Compose, Composed, Library};

/// Composes and validates the shader of pipeline `key`, which lives at
/// `display` in `lib`, with `composer`. Runs on any thread; a missing file
/// and a compiler panic come back as diagnostics like any other error.
pub fn compose(composer: &dyn Compose, lib: &Library, key: &PipelineKey, display: &str) -> Result<Composed, Vec<Diagnostic>> {
    let Some(file) = lib.get(display) else {
        return Err(vec![pipeline::missing_shader(key.spec, display)]);
    };
    let caps = gpu::capabilities_without_device();
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| composer.compose(lib, file, &key.defs, caps))).unwrap_or_else(|_| {
        Err(vec![Diagnostic::error(Code::CompilerPanic, "the WGSL compiler crashed on this file").at(Location::file_start(display))])
    })
}

pub struct Entry {
    pub current: Option<Pipeline>,
    /// The module `current` was built from, to rebuild after device loss.
    pub last_good: Option<Composed>,
    pub generation: u64,
    pub diagnostics: Vec<Diagnostic>,
    /// Files the newest attempt was composed from.
    pub files: Vec<String>,
}

impl Entry {
    pub fn status(&self) -> PassStatus {
        match (&self.current, self.diagnostics.is_empty()) {
            (Some(_), true) => PassStatus::Ok,
            (Some(_), false) => PassStatus::Stale,
            (None, _) => PassStatus::Failed,
        }
    }
}

#[derive(Default)]
pub struct PipelineCache {
    pub entries: BTreeMap<PipelineKey, Entry>,
}

/// What installing a compile result did.
#[derive(Debug, PartialEq, Eq)]
pub enum Installed {
    Swapped,
    KeptLastGood,
    Failed,
}

impl PipelineCache {
    /// Takes a compile result: creates the pipeline and swaps it in when
    /// everything succeeded; otherwise keeps the old one and records why.
    pub fn install(
        &mut self,
        device: &wgpu::Device,
        key: &PipelineKey,
        result: Result<Composed, Vec<Diagnostic>>,
        lib: &Library,
        shader_display: &str,
    ) -> Installed {
        let entry = self.entries.entry(key.clone()).or_insert_with(|| Entry {
            current: None,
            last_good: None,
            generation: 0,
            diagnostics: Vec::new(),
            files: vec![shader_display.to_owned()],
        });
        let spec = pipeline::spec(key.spec).expect("keys come from specs");
        let created = result.and_then(|composed| {
            entry.files = composed.files.clone();
            pipeline::create(device, spec, &key.defs, &composed, lib, shader_display).map(|p| (p, composed))
        });
        match created {
            Ok((p, composed)) => {
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
            let spec = pipeline::spec(key.spec).expect("keys come from specs");
            let display = entry.files.last().cloned().unwrap_or_default();
            match pipeline::create(device, spec, &key.defs, composed, lib, &display) {
                Ok(p) => entry.current = Some(p),
                Err(d) => problems.extend(d),
            }
        }
        problems
    }

    pub fn live(&self) -> BTreeMap<PipelineKey, Pipeline> {
        self.entries.iter().filter_map(|(k, e)| e.current.clone().map(|p| (k.clone(), p))).collect()
    }

    pub fn info(&self) -> Vec<PipelineInfo> {
        self.entries
            .iter()
            .map(|(k, e)| PipelineInfo {
                name: k.label(),
                shader: e.files.last().cloned().unwrap_or_default(),
                defs: crate::shader::defs_key(&k.defs),
                status: e.status(),
                generation: e.generation,
                files: e.files.clone(),
            })
            .collect()
    }

    pub fn diagnostics(&self) -> Vec<Diagnostic> {
        let mut seen = std::collections::BTreeSet::new();
        self.entries
            .values()
            .flat_map(|e| e.diagnostics.iter())
            .filter(|d| seen.insert(d.to_string()))
            .cloned()
            .collect()
    }
}
