//! What `loupe view`'s window shows, drawn on the daemon's device with no
//! readback of images:
//! - the frame: after each clean frame the render thread copies the final
//!   output (8-bit sRGB) into a texture of its own, viewed as `Rgba8Unorm`;
//! - the Inspector: the output the window inspects, drawn by the display
//!   pass (`pass`) into another such texture, its range measured on
//!   request, and the one texel under the cursor read back.
//!
//! The window samples these textures on the same device and queue. Its
//! draw is submitted after the render thread's commands, so it always
//! samples a finished frame, and the next frame's passes never write what
//! it samples.
//!
//! Architecture Invariant: this is the only display work the render thread
//! does; the frame copy is skipped while the window shows no frame
//! (minimised, the Inspector open, no space for it), the display pass
//! while nothing is inspected, and a readback is at most one texel or one
//! range (40 bytes) in flight.

mod pass;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use loupe_view::{DisplayImage, Inspect, Inspected, Probe, Probed, Range};

use crate::gpu::Gpu;
use crate::render::capture::Layout;
use crate::render::readback::{self, Readback};

/// The format of what the window samples: sRGB-encoded bytes viewed as
/// unorm, what egui's shader expects of a texture.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// An output of the newest frame, as the display work needs it.
pub struct Source<'a> {
    pub texture: &'a wgpu::Texture,
    /// Its clear value when it holds depth: no surface wrote it.
    pub clear: Option<f32>,
}

impl<'a> Source<'a> {
    pub fn new(texture: &'a wgpu::Texture, meaning: crate::render::resource::Meaning) -> Self {
        let clear = matches!(meaning, crate::render::resource::Meaning::Depth(_)).then_some(crate::render::context::DEPTH_CLEAR);
        Source { texture, clear }
    }
}

/// The window's textures and requests, shared by the render thread and
/// the window.
pub struct Display {
    /// The device the window renders with: frames of any other are not
    /// shown. After a loss, the daemon's new one (the window reopens on it).
    window: Mutex<Gpu>,
    /// How many times the device was replaced.
    replaced: AtomicU64,
    frame: Mutex<Option<Target>>,
    shown: AtomicBool,
    /// The window is minimised: the daemon renders continuously only
    /// while a browser is connected (it still renders what changes).
    minimised: AtomicBool,
    state: Mutex<State>,
    /// The render thread's own: pipelines and readbacks in flight.
    work: Mutex<Work>,
}

/// What the window asks for and what it gets back.
#[derive(Default)]
struct State {
    inspect: Option<Inspect>,
    probe: Option<Probe>,
    measure: Option<Inspect>,
    inspected: Option<Inspected>,
    probed: Option<Probed>,
    measured: Option<Range>,
}

#[derive(Default)]
struct Work {
    /// Built on first use; `Err` once they failed (logged, not retried).
    pipelines: Option<Result<pass::Pipelines, ()>>,
    /// The uniforms of `show` and `measure`: apart, since both can be
    /// recorded for one submit with different options.
    show_params: Option<wgpu::Buffer>,
    measure_params: Option<wgpu::Buffer>,
    range: Option<wgpu::Buffer>,
    inspected: Option<Target>,
    probe: Option<(Probe, u64, Texel, Readback)>,
    /// `pick`'s uniform and result.
    pick_params: Option<wgpu::Buffer>,
    picked: Option<wgpu::Buffer>,
    measure: Option<(Inspect, u64, Readback)>,
}

/// How a texel read back is laid out.
enum Texel {
    /// Copied as the texture stores it.
    Copied(Layout),
    /// Loaded by `pick` as RGBA f32.
    Picked,
}

/// A texture the window samples and what it is handed of it.
struct Target {
    texture: wgpu::Texture,
    image: DisplayImage,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Display {
    pub fn new(gpu: &Gpu) -> Arc<Self> {
        Arc::new(Display {
            window: Mutex::new(gpu.clone()),
            replaced: AtomicU64::new(0),
            frame: Mutex::new(None),
            shown: AtomicBool::new(true),
            minimised: AtomicBool::new(false),
            state: Default::default(),
            work: Default::default(),
        })
    }

    /// The device the window renders with (after a loss, the one it
    /// reopens on).
    pub fn gpu(&self) -> Gpu {
        lock(&self.window).clone()
    }

    /// How many times the device was replaced.
    pub fn replaced(&self) -> u64 {
        self.replaced.load(Ordering::SeqCst)
    }

    /// The daemon replaced its lost device with `gpu`: everything made on
    /// the old one is dropped, and the window reopens on the new one.
    pub fn replace(&self, gpu: &Gpu) {
        *lock(&self.window) = gpu.clone();
        *lock(&self.frame) = None;
        *lock(&self.work) = Work::default();
        let mut state = lock(&self.state);
        (state.inspected, state.probed, state.measured) = (None, None, None);
        drop(state);
        self.replaced.fetch_add(1, Ordering::SeqCst);
    }

    /// The newest copied frame's texture.
    pub fn current(&self) -> Option<DisplayImage> {
        lock(&self.frame).as_ref().map(|t| t.image.clone())
    }

    pub fn set_shown(&self, shown: bool) {
        self.shown.store(shown, Ordering::Relaxed);
    }

    /// Whether the frame is copied for the window.
    pub fn shown(&self) -> bool {
        self.shown.load(Ordering::Relaxed)
    }

    pub fn set_minimised(&self, minimised: bool) {
        self.minimised.store(minimised, Ordering::Relaxed);
    }

    pub fn minimised(&self) -> bool {
        self.minimised.load(Ordering::Relaxed)
    }

    pub fn inspect(&self, inspect: Option<Inspect>) {
        lock(&self.state).inspect = inspect;
    }

    pub fn inspected(&self) -> Option<Inspected> {
        lock(&self.state).inspected.clone()
    }

    pub fn probe(&self, probe: Option<Probe>) {
        lock(&self.state).probe = probe;
    }

    pub fn probed(&self) -> Option<Probed> {
        lock(&self.state).probed.clone()
    }

    pub fn measure(&self, inspect: Inspect) {
        lock(&self.state).measure = Some(inspect);
    }

    pub fn measured(&self) -> Option<Range> {
        lock(&self.state).measured.clone()
    }

    /// The display work after frame `frame` was submitted cleanly on
    /// `device`: `output` finds an output (`pass/output`) as that frame
    /// left it; `final_output` is the frame's final image (8-bit RGBA).
    pub fn after_frame<'a>(
        &self,
        gpu: &Gpu,
        frame: u64,
        final_output: Option<&wgpu::Texture>,
        output: impl Fn(&str) -> Option<Source<'a>>,
    ) {
        let (device, queue) = (&gpu.device, &gpu.queue);
        if *device != lock(&self.window).device {
            return;
        }
        let mut work = lock(&self.work);
        self.harvest(&mut work);
        if let Some(source) = final_output
            && self.shown()
        {
            self.copy_frame(device, queue, source);
        }
        let (inspect, probe, measure) = {
            let s = lock(&self.state);
            (s.inspect.clone(), s.probe.clone(), s.measure.clone())
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("display") });
        // Whether anything was recorded, and the readbacks recorded now:
        // only those are mapped (one still in flight is mapped already).
        let (mut drawn, mut probed, mut measured) = (false, false, false);
        if let Some(inspect) = inspect
            && let Some(source) = output(&inspect.output)
            && let Some(image) = work.show(gpu, &mut encoder, &inspect, &source)
        {
            lock(&self.state).inspected = Some(Inspected { image, inspect, frame });
            drawn = true;
        }
        if let Some(probe) = probe
            && work.probe.is_none()
            && let Some(source) = output(&probe.output)
            && probe.x < source.texture.width()
            && probe.y < source.texture.height()
            && let Some((read, readback)) = work.probe(gpu, &mut encoder, &probe, &source)
        {
            work.probe = Some((probe, frame, read, readback));
            probed = true;
        }
        if let Some(measure) = measure
            && work.measure.is_none()
            && let Some(source) = output(&measure.output)
            && let Some(readback) = work.measure(gpu, &mut encoder, &measure, &source)
        {
            lock(&self.state).measure = None;
            work.measure = Some((measure, frame, readback));
            measured = true;
        }
        if !(drawn || probed || measured) {
            return;
        }
        queue.submit([encoder.finish()]);
        if let (true, Some((.., r))) = (probed, &work.probe) {
            r.map();
        }
        if let (true, Some((.., r))) = (measured, &work.measure) {
            r.map();
        }
    }

    /// Hands the window what has landed since the last frame.
    fn harvest(&self, work: &mut Work) {
        if work.probe.as_ref().is_some_and(|(.., r)| r.landed())
            && let Some((probe, frame, layout, readback)) = work.probe.take()
        {
            let value = readback.read(|bytes| {
                let mut out = Vec::with_capacity(4);
                match layout {
                    Texel::Copied(layout) => layout.extend_rgba_f32(&bytes[..layout.bytes_per_texel()], &mut out),
                    Texel::Picked => out.extend(bytes[..16].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes")))),
                }
                [out[0], out[1], out[2], out[3]]
            });
            if let Some(value) = value {
                lock(&self.state).probed = Some(Probed { probe, frame, value });
            }
        }
        if work.measure.as_ref().is_some_and(|(.., r)| r.landed())
            && let Some((inspect, frame, readback)) = work.measure.take()
        {
            let words =
                readback.read(|bytes| std::array::from_fn(|i| u32::from_le_bytes(bytes[i * 4..i * 4 + 4].try_into().expect("4 bytes"))));
            if let Some(words) = words {
                lock(&self.state).measured = Some(Range { output: inspect.output, frame, channels: pass::decode(&words) });
            }
        }
    }

    fn copy_frame(&self, device: &wgpu::Device, queue: &wgpu::Queue, source: &wgpu::Texture) {
        if !matches!(source.format(), wgpu::TextureFormat::Rgba8UnormSrgb | wgpu::TextureFormat::Rgba8Unorm) {
            return;
        }
        let size = [source.width(), source.height()];
        let mut slot = lock(&self.frame);
        let target = Target::resized(&mut slot, device, "display: frame", size);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("display: frame copy") });
        // sRGB and linear views of RGBA8 are copy-compatible: the bytes stay
        // sRGB encoded.
        encoder.copy_texture_to_texture(source.as_image_copy(), target.texture.as_image_copy(), source.size());
        queue.submit([encoder.finish()]);
    }
}

impl Work {
    fn pipelines(&mut self, device: &wgpu::Device) -> Option<&pass::Pipelines> {
        let built = self.pipelines.get_or_insert_with(|| {
            pass::Pipelines::new(device).map_err(|e| log::error!("the display pass could not be built (a bug in loupe): {e}"))
        });
        built.as_ref().ok()
    }

    fn show(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder, inspect: &Inspect, source: &Source<'_>) -> Option<DisplayImage> {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let kind = pass::Source::of(source.texture.format())?;
        let params = uniform(&mut self.show_params, device, queue, pass::Params::new(&inspect.options, source.clear));
        let size = [source.texture.width(), source.texture.height()];
        let target = Target::resized(&mut self.inspected, device, "display: inspected", size);
        let (view, image) = (layer_zero(source.texture), target.image.clone());
        let target_view = target.texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.pipelines(device)?.show(device, encoder, pass::Input { source: kind, params: &params, view: &view }, &target_view);
        Some(image)
    }

    /// Reads back the texel `probe` names: copied where a copy can take
    /// one texel, else loaded by `pick` (depth, which only copies whole).
    fn probe(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder, probe: &Probe, source: &Source<'_>) -> Option<(Texel, Readback)> {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let format = source.texture.format();
        if !format.is_depth_stencil_format() {
            let layout = Layout::of(format)?;
            let texel = [probe.x, probe.y, 0];
            return Some((
                Texel::Copied(layout),
                readback::copy_texel(device, encoder, "display: probe", source.texture, texel, layout.bytes_per_texel() as u32),
            ));
        }
        let kind = pass::Source::of(format)?;
        self.pipelines(device)?;
        let params = uniform(&mut self.pick_params, device, queue, pass::Params::pick([probe.x, probe.y]));
        let picked = kept(&mut self.picked, device, "display: picked", 16, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let view = layer_zero(source.texture);
        self.pipelines(device)?.pick(device, encoder, pass::Input { source: kind, params: &params, view: &view }, &picked);
        let readback = Readback::new(device, "display: probe", 16);
        encoder.copy_buffer_to_buffer(&picked, 0, readback.buffer(), 0, 16);
        Some((Texel::Picked, readback))
    }

    fn measure(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder, inspect: &Inspect, source: &Source<'_>) -> Option<Readback> {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let kind = pass::Source::of(source.texture.format())?;
        self.pipelines(device)?;
        let params = uniform(&mut self.measure_params, device, queue, pass::Params::new(&inspect.options, source.clear));
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let range = kept(&mut self.range, device, "display: range", 40, usage);
        queue.write_buffer(&range, 0, bytemuck::cast_slice(&pass::START));
        let view = layer_zero(source.texture);
        let size = [source.texture.width(), source.texture.height()];
        self.pipelines(device)?.measure(device, encoder, pass::Input { source: kind, params: &params, view: &view }, size, &range);
        let readback = Readback::new(device, "display: range", 40);
        encoder.copy_buffer_to_buffer(&range, 0, readback.buffer(), 0, 40);
        Some(readback)
    }
}

/// The uniform in `slot` (made on first use) holding `params` from the
/// next submit on.
fn uniform(slot: &mut Option<wgpu::Buffer>, device: &wgpu::Device, queue: &wgpu::Queue, params: pass::Params) -> wgpu::Buffer {
    let size = std::mem::size_of::<pass::Params>() as u64;
    let buffer = kept(slot, device, "display: params", size, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST);
    queue.write_buffer(&buffer, 0, bytemuck::bytes_of(&params));
    buffer
}

/// The buffer in `slot`, made on first use.
fn kept(slot: &mut Option<wgpu::Buffer>, device: &wgpu::Device, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    slot.get_or_insert_with(|| device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false }))
        .clone()
}

/// A 2D view of the first layer (the depth aspect of a depth format).
fn layer_zero(texture: &wgpu::Texture) -> wgpu::TextureView {
    let aspect = if texture.format().has_depth_aspect() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
    texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("display: source"),
        dimension: Some(wgpu::TextureViewDimension::D2),
        aspect,
        base_array_layer: 0,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

impl Target {
    /// The target in `slot`, replaced by one of `size` when it has another
    /// (a new generation, which the window registers again).
    fn resized<'s>(slot: &'s mut Option<Target>, device: &wgpu::Device, label: &str, size: [u32; 2]) -> &'s Target {
        if slot.as_ref().is_none_or(|t| t.image.size != size) {
            let generation = slot.as_ref().map_or(0, |t| t.image.generation + 1);
            *slot = Some(Target::new(device, label, size, generation));
        }
        slot.as_ref().expect("made above")
    }

    fn new(device: &wgpu::Device, label: &str, [width, height]: [u32; 2], generation: u64) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Target { texture, image: DisplayImage { view, size: [width, height], generation } }
    }
}
