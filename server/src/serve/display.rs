//! The frame as `loupe view`'s window shows it, with no readback: after
//! each clean frame the render thread copies the final output (8-bit sRGB)
//! into a texture of its own, viewed as `Rgba8Unorm`, which the window
//! samples on the same device and queue. The window's draw is submitted
//! after the copy on that queue, so it always samples a finished frame,
//! and the next frame's passes never write what it samples.
//!
//! Architecture Invariant: the copy is the only display work the render
//! thread does, and it is skipped while the window shows no frame
//! (minimised, or no space for it).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use loupe_view::DisplayImage;

/// The window's texture, shared by the render thread (writer) and the
/// window (reader).
pub struct Display {
    /// The device the window renders with: frames of any other (a device
    /// replaced after a loss) are not copied.
    device: wgpu::Device,
    target: Mutex<Option<Target>>,
    shown: AtomicBool,
}

/// The copy's texture and what the window is handed of it.
struct Target {
    texture: wgpu::Texture,
    image: DisplayImage,
}

impl Display {
    pub fn new(device: wgpu::Device) -> Arc<Self> {
        Arc::new(Display { device, target: Mutex::new(None), shown: AtomicBool::new(true) })
    }

    /// The newest copied frame's texture.
    pub fn current(&self) -> Option<DisplayImage> {
        self.target.lock().unwrap_or_else(|e| e.into_inner()).as_ref().map(|t| t.image.clone())
    }

    pub fn set_shown(&self, shown: bool) {
        self.shown.store(shown, Ordering::Relaxed);
    }

    /// Copies `source`, the final output of the frame just submitted, for
    /// the window: when the window shows it, `device` is the window's, and
    /// `source` is 8-bit RGBA (the tonemapped frame).
    pub fn copy(&self, device: &wgpu::Device, queue: &wgpu::Queue, source: &wgpu::Texture) {
        let displayable = matches!(source.format(), wgpu::TextureFormat::Rgba8UnormSrgb | wgpu::TextureFormat::Rgba8Unorm);
        if !self.shown.load(Ordering::Relaxed) || *device != self.device || !displayable {
            return;
        }
        let size = [source.width(), source.height()];
        let mut slot = self.target.lock().unwrap_or_else(|e| e.into_inner());
        if slot.as_ref().is_none_or(|t| t.image.size != size) {
            let generation = slot.as_ref().map_or(0, |t| t.image.generation + 1);
            *slot = Some(Target::new(device, size, generation));
        }
        let target = slot.as_ref().expect("made above");
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("display copy") });
        // sRGB and linear views of RGBA8 are copy-compatible: the bytes stay
        // sRGB encoded, which is what egui's shader expects of a texture.
        encoder.copy_texture_to_texture(source.as_image_copy(), target.texture.as_image_copy(), source.size());
        queue.submit([encoder.finish()]);
    }
}

impl Target {
    fn new(device: &wgpu::Device, [width, height]: [u32; 2], generation: u64) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("display"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Target { texture, image: DisplayImage { view, size: [width, height], generation } }
    }
}
