//! Debug prints on the device: the storage buffer an instrumented module
//! (`shader::instrument_printf`) writes the selected pixel's prints into,
//! cleared before the frame, copied back after it, and decoded with the
//! format strings kept by `shader::printf` into printed lines.

use std::sync::Arc;

use serde::Serialize;

use super::readback::Readback;
use super::resource::PipelineKey;
use crate::shader::SourceFile;
use crate::shader::instrument_printf::{HEADER_WORDS, SiteId};

/// What a frame binds for prints: the buffer, the group each
/// instrumented pipeline binds it at, and what its records mean.
#[derive(Clone, Copy)]
pub struct PrintBinding<'a> {
    pub buffer: &'a PrintBuffer,
    pub groups: &'a std::collections::BTreeMap<PipelineKey, u32>,
    pub table: &'a Arc<Vec<Option<TableSite>>>,
    pub pixel: [u32; 2],
}

/// A frame's prints on their way back: its own copy of the buffer, so
/// frames in flight never share a readback.
pub struct PendingPrints {
    readback: Readback,
    table: Arc<Vec<Option<TableSite>>>,
    pixel: [u32; 2],
}

impl PendingPrints {
    pub fn map(&self) {
        self.readback.map();
    }

    pub fn landed(&self) -> bool {
        self.readback.landed()
    }

    /// The decoded prints; `None` when the readback failed.
    pub fn read(&self) -> Option<Printed> {
        let words = self
            .readback
            .read(|bytes| bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect::<Vec<u32>>())?;
        Some(Printed { pixel: self.pixel, ..decode(&words, &self.table) })
    }
}

/// Where a record number comes from: the pass and the site.
#[derive(Debug, Clone)]
pub struct TableSite {
    pub pass: String,
    pub file: Arc<SourceFile>,
    /// Index in the file's prints.
    pub site: usize,
}

/// The table entries of one instrumented module's `sites`, looked up in
/// `files` (the files it was composed from) by tag; `None` keeps the
/// numbering where no file has the tag.
pub fn table(pass: &str, sites: &[SiteId], files: &[Arc<SourceFile>]) -> Vec<Option<TableSite>> {
    sites
        .iter()
        .map(|&(tag, site)| {
            let file = files.iter().find(|f| f.prints.tag == tag)?;
            Some(TableSite { pass: pass.to_owned(), file: file.clone(), site })
        })
        .collect()
}

/// Record words a buffer holds by default: 64 KiB, about four thousand
/// prints of a vec3.
pub const DEFAULT_WORDS: u64 = 16 * 1024;

/// One print as it came out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PrintLine {
    /// The pass whose pipeline printed it.
    pub pass: String,
    pub file: String,
    pub line: u32,
    pub column: u32,
    /// The format string with the values in.
    pub text: String,
    /// Each argument: a number, or an array for a vector.
    pub values: Vec<serde_json::Value>,
}

/// What one buffer held after a frame.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Printed {
    /// The pixel selected when the frame was recorded.
    pub pixel: [u32; 2],
    pub lines: Vec<PrintLine>,
    /// Prints that did not fit the buffer.
    pub dropped: u32,
}

/// The buffer the instrumented pipelines write.
pub struct PrintBuffer {
    buffer: wgpu::Buffer,
}

impl PrintBuffer {
    /// A buffer for `words` record words (at least one).
    pub fn new(device: &wgpu::Device, words: u64) -> PrintBuffer {
        let size = (HEADER_WORDS + words.max(1)) * 4;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("debug prints"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        PrintBuffer { buffer }
    }

    /// What the instrumented module binds at `@group(group) @binding(0)`.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// Empties the buffer: recorded before the frame's passes.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.buffer, 0, None);
    }

    /// Copies the buffer out: recorded after the frame's passes; map the
    /// result once submitted.
    pub fn copy_out(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, binding: &PrintBinding<'_>) -> PendingPrints {
        let readback = Readback::new(device, "debug prints: readback", self.buffer.size());
        encoder.copy_buffer_to_buffer(&self.buffer, 0, readback.buffer(), 0, self.buffer.size());
        PendingPrints { readback, table: binding.table.clone(), pixel: binding.pixel }
    }
}

/// Decodes a buffer's words, each record by its number in `table` (the
/// pixel is left for the caller to say). A record that names no known site
/// ends the decoding: what follows cannot be framed.
pub fn decode(words: &[u32], table: &[Option<TableSite>]) -> Printed {
    let header = HEADER_WORDS as usize;
    let (used, dropped) = (words.first().copied().unwrap_or(0), words.get(1).copied().unwrap_or(0));
    let end = words.len().min(header.saturating_add(used as usize));
    let mut records = words.get(header..end).unwrap_or_default();
    let mut lines = Vec::new();
    while let Some((&number, rest)) = records.split_first() {
        let found = table.get(number as usize).and_then(Option::as_ref).and_then(|t| Some((t, t.file.prints.sites.get(t.site)?)));
        let Some((entry, site)) = found else { break };
        let file = &entry.file;
        let Some(args) = rest.get(..site.words()) else { break };
        let (text, values) = site.render(args);
        let at = file.location(site.call.clone());
        lines.push(PrintLine { pass: entry.pass.clone(), file: file.display.clone(), line: at.line, column: at.column, text, values });
        records = &rest[site.words()..];
    }
    Printed { pixel: [0, 0], lines, dropped }
}

#[cfg(test)]
mod tests;
