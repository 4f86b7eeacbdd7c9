//! Buffers copied back from the GPU: created for reading, mapped once the
//! frame is submitted, read once mapping has landed, on any thread.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

const PENDING: u8 = 0;
const OK: u8 = 1;
const FAILED: u8 = 2;

pub struct Readback {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
}

impl Readback {
    /// A buffer of `size` bytes to copy into and read back.
    pub fn new(device: &wgpu::Device, label: &str, size: u64) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Readback { buffer, state: Arc::new(AtomicU8::new(PENDING)) }
    }

    /// Where copies go.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Asks for the mapping: after the commands copying into it are
    /// submitted.
    pub fn map(&self) {
        let state = self.state.clone();
        self.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            state.store(if r.is_ok() { OK } else { FAILED }, Ordering::Release);
        });
    }

    /// Whether mapping has finished, well or not (poll the device first).
    pub fn landed(&self) -> bool {
        self.state.load(Ordering::Acquire) != PENDING
    }

    /// `f` of the mapped bytes, unmapped after; `None` when mapping failed.
    pub fn read<T>(&self, f: impl FnOnce(&[u8]) -> T) -> Option<T> {
        if self.state.load(Ordering::Acquire) != OK {
            return None;
        }
        let mapped = self.buffer.slice(..).get_mapped_range().ok()?;
        let out = f(&mapped);
        drop(mapped);
        self.buffer.unmap();
        Some(out)
    }
}
