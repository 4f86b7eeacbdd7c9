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

/// How a texture copy lays out its rows: tight rows of `row` bytes, each
/// starting `padded` bytes after the previous one, as copies require.
#[derive(Debug, Clone, Copy)]
pub struct Rows {
    row: usize,
    padded: usize,
    count: usize,
}

impl Rows {
    /// The tight rows of a mapped copy.
    pub fn of<'b>(&self, bytes: &'b [u8]) -> impl Iterator<Item = &'b [u8]> {
        let row = self.row;
        bytes.chunks(self.padded).take(self.count).map(move |r| &r[..row])
    }
}

/// A texture row of `bytes` in a buffer, padded to what copies between
/// buffers and textures require.
pub fn padded_row(bytes: u32) -> u32 {
    bytes.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}

/// Copies `layers` layers of `texture` from `base_layer` on (the depth
/// aspect of a depth format) into a new readback, one layer under
/// another, texels of `bytes_per_texel`.
pub fn copy_texture(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    texture: &wgpu::Texture,
    base_layer: u32,
    layers: u32,
    bytes_per_texel: u32,
) -> (Readback, Rows) {
    let origin = wgpu::Origin3d { x: 0, y: 0, z: base_layer };
    let extent = wgpu::Extent3d { width: texture.width(), height: texture.height(), depth_or_array_layers: layers };
    copy_box(device, encoder, label, texture, origin, extent, bytes_per_texel)
}

/// Copies the texel at `[x, y]` of `layer` into a new readback: a value
/// under the cursor, without the rest of the image.
pub fn copy_texel(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    texture: &wgpu::Texture,
    [x, y, layer]: [u32; 3],
    bytes_per_texel: u32,
) -> Readback {
    let readback = Readback::new(device, label, u64::from(bytes_per_texel.max(4)));
    copy_texel_into(encoder, texture, [x, y, layer], readback.buffer(), 0);
    readback
}

/// Copies the texel at `[x, y, layer]` to `offset` (a multiple of 256) in
/// `buffer`: one of many texels sharing a readback.
pub fn copy_texel_into(
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    [x, y, layer]: [u32; 3],
    buffer: &wgpu::Buffer,
    offset: u64,
) {
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d { x, y, z: layer }, aspect: aspect(texture) },
        wgpu::TexelCopyBufferInfo { buffer, layout: wgpu::TexelCopyBufferLayout { offset, bytes_per_row: None, rows_per_image: None } },
        wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
    );
}

/// A depth texture copies its depth alone.
fn aspect(texture: &wgpu::Texture) -> wgpu::TextureAspect {
    if texture.format().has_depth_aspect() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All }
}

fn copy_box(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    texture: &wgpu::Texture,
    origin: wgpu::Origin3d,
    extent: wgpu::Extent3d,
    bytes_per_texel: u32,
) -> (Readback, Rows) {
    let (width, height, layers) = (extent.width, extent.height, extent.depth_or_array_layers);
    let row = width * bytes_per_texel;
    let padded = padded_row(row);
    let readback = Readback::new(device, label, u64::from(padded) * u64::from(height) * u64::from(layers));
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin, aspect: aspect(texture) },
        wgpu::TexelCopyBufferInfo {
            buffer: readback.buffer(),
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded), rows_per_image: Some(height) },
        },
        extent,
    );
    (readback, Rows { row: row as usize, padded: padded as usize, count: (height * layers) as usize })
}
