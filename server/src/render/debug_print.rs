//! Debug prints on the device: the storage buffer an instrumented module
//! (`shader::instrument_printf`) writes the selected pixel's prints into,
//! cleared before the frame, copied back after it, and decoded with the
//! format strings kept by `shader::printf` into printed lines.

use std::sync::Arc;

use serde::Serialize;

use super::readback::Readback;
use crate::shader::SourceFile;
use crate::shader::instrument_printf::{HEADER_WORDS, SiteId};

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
    pub lines: Vec<PrintLine>,
    /// Prints that did not fit the buffer.
    pub dropped: u32,
}

/// The buffer and its readback.
pub struct PrintBuffer {
    buffer: wgpu::Buffer,
    readback: Readback,
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
        PrintBuffer { buffer, readback: Readback::new(device, "debug prints: readback", size) }
    }

    /// What the instrumented module binds at `@group(group) @binding(0)`.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// Empties the buffer: recorded before the frame's passes.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.buffer, 0, None);
    }

    /// Copies the buffer out: recorded after the frame's passes; call
    /// [`PrintBuffer::map`] once submitted.
    pub fn copy_out(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.buffer, 0, self.readback.buffer(), 0, self.buffer.size());
    }

    pub fn map(&self) {
        self.readback.map();
    }

    /// The buffer's words once mapping has landed (poll the device first);
    /// `None` while pending or when mapping failed.
    pub fn read(&self) -> Option<Vec<u32>> {
        if !self.readback.landed() {
            return None;
        }
        self.readback.read(|bytes| bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect())
    }
}

/// Decodes a buffer's words: the records of `sites` (the instrumented
/// module's table), each located in the one of `files` whose prints hold
/// it. A record that names no known site ends the decoding: what follows
/// cannot be framed.
pub fn decode(words: &[u32], sites: &[SiteId], files: &[Arc<SourceFile>], pass: &str) -> Printed {
    let header = HEADER_WORDS as usize;
    let (used, dropped) = (words.first().copied().unwrap_or(0), words.get(1).copied().unwrap_or(0));
    let end = words.len().min(header.saturating_add(used as usize));
    let mut records = words.get(header..end).unwrap_or_default();
    let mut lines = Vec::new();
    while let Some((&number, rest)) = records.split_first() {
        let found = sites.get(number as usize).and_then(|&(tag, k)| {
            let file = files.iter().find(|f| f.prints.tag == tag)?;
            Some((file, file.prints.sites.get(k)?))
        });
        let Some((file, site)) = found else { break };
        let Some(args) = rest.get(..site.words()) else { break };
        let (text, values) = site.render(args);
        let at = file.location(site.call.clone());
        lines.push(PrintLine { pass: pass.to_owned(), file: file.display.clone(), line: at.line, column: at.column, text, values });
        records = &rest[site.words()..];
    }
    Printed { lines, dropped }
}

#[cfg(test)]
mod tests;
