//! A selected pixel's prints through the frame: the pipelines whose
//! modules hold `debugPrintf` are built a second time, instrumented for
//! that pixel (`shader::instrument_printf`), and run instead of the plain
//! ones while it is selected; one buffer (`debug_print`) collects what
//! they print, cleared before each frame and copied out after it
//! (`frame::submit`). With no pixel
//! selected none of this exists: the plain pipelines run.

use std::collections::BTreeMap;
use std::sync::Arc;

use super::debug_print::{DEFAULT_WORDS, PrintBinding, PrintBuffer, TableSite, table};
use super::pipelines::PipelineCache;
use super::resource::PipelineKey;
use crate::gpu::pipeline::{self, Pipeline};
use crate::shader::{Composed, Library, instrument_printf};

/// Record numbers a selection hands out before it starts over: edits
/// rebuild variants, each numbering its sites after the last.
const MAX_SITES: usize = 1 << 16;

pub struct PrintSelection {
    pixel: [u32; 2],
    buffer: PrintBuffer,
    variants: BTreeMap<PipelineKey, Variant>,
    /// The print group of each variant.
    groups: BTreeMap<PipelineKey, u32>,
    /// Record number → where it was printed (shared with frames in flight).
    table: Arc<Vec<Option<TableSite>>>,
    /// Instrumented pipelines built so far.
    built: u64,
}

struct Variant {
    /// The cache entry's generation it was built from.
    generation: u64,
    pipeline: Pipeline,
}

impl PrintSelection {
    pub fn new(device: &wgpu::Device, pixel: [u32; 2]) -> PrintSelection {
        PrintSelection {
            pixel,
            buffer: PrintBuffer::new(device, DEFAULT_WORDS),
            variants: BTreeMap::new(),
            groups: BTreeMap::new(),
            table: Arc::default(),
            built: 0,
        }
    }

    pub fn pixel(&self) -> [u32; 2] {
        self.pixel
    }

    /// Instrumented pipelines built so far: one per pipeline with prints,
    /// and one more after each edit to it.
    pub fn built(&self) -> u64 {
        self.built
    }

    /// The pipelines running instrumented.
    pub fn printing(&self) -> impl Iterator<Item = &PipelineKey> {
        self.variants.keys()
    }

    /// Builds the variant of each of `keys` (with the pass it serves) whose
    /// current module holds prints and is newer than its variant; drops
    /// the variants of the others. One that cannot be built is left plain,
    /// with a warning.
    pub fn refresh(&mut self, device: &wgpu::Device, cache: &PipelineCache, lib: &Library, keys: &[(PipelineKey, String)]) {
        self.variants.retain(|k, _| keys.iter().any(|(key, _)| key == k));
        if self.table.len() > MAX_SITES {
            self.variants.clear();
            self.table = Arc::default();
        }
        for (key, pass) in keys {
            let Some(entry) = cache.entries.get(key) else { continue };
            let Some(composed) = entry.current.as_ref().and(entry.last_good.as_ref()) else { continue };
            if !instrument_printf::has_prints(&composed.module) {
                self.variants.remove(key);
                continue;
            }
            if self.variants.get(key).is_some_and(|v| v.generation == entry.generation) {
                continue;
            }
            match self.build(device, key, pass, composed, lib) {
                Ok((pipeline, group)) => {
                    self.built += 1;
                    self.groups.insert(key.clone(), group);
                    self.variants.insert(key.clone(), Variant { generation: entry.generation, pipeline });
                }
                Err(e) => {
                    log::warn!("debug prints: {} runs without its prints: {e}", key.label());
                    self.variants.remove(key);
                }
            }
        }
        self.groups.retain(|k, _| self.variants.contains_key(k));
    }

    fn build(
        &mut self,
        device: &wgpu::Device,
        key: &PipelineKey,
        pass: &str,
        composed: &Composed,
        lib: &Library,
    ) -> Result<(Pipeline, u32), String> {
        let min_group = key.spec.layout(&key.defs).len() as u32;
        let first = self.table.len() as u32;
        let out = instrument_printf::instrument(&composed.module, self.pixel, min_group, first).map_err(|e| e.to_string())?;
        let files: Vec<Arc<crate::shader::SourceFile>> = composed.files.iter().filter_map(|d| lib.get(d).cloned()).collect();
        let display = composed.files.last().cloned().unwrap_or_default();
        let instrumented = Composed { module: out.module, info: out.info, files: composed.files.clone() };
        let pipeline = pipeline::create(device, key.spec, &key.defs, &instrumented, lib, &display, Some(out.group))
            .map_err(|d| d.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("; "))?;
        Arc::make_mut(&mut self.table).extend(table(pass, &out.sites, &files));
        Ok((pipeline, out.group))
    }

    /// Puts the variants in place of the plain pipelines.
    pub fn replace(&self, live: &mut BTreeMap<PipelineKey, Pipeline>) {
        for (key, v) in &self.variants {
            live.insert(key.clone(), v.pipeline.clone());
        }
    }

    pub fn binding(&self) -> PrintBinding<'_> {
        PrintBinding { buffer: &self.buffer, groups: &self.groups, table: &self.table, pixel: self.pixel }
    }
}
