//! One pixel's history through a frame: for every pass that wrote or read
//! that pixel, in frame order, the value of each output there before and
//! after the pass, the denoiser's tensors there, and, for raster passes,
//! every fragment the draws launched at it (from the quad model's trace,
//! `render::quads::trace`).
//!
//! The values come from texel-sized copies recorded around each pass into
//! one small readback, so selecting a pixel costs a few hundred bytes of
//! copies a frame, not a capture of every output.

use serde::Serialize;

use super::capture::{Layout, decode_elements};
use super::graph::{Graph, PassKind, Resource};
use super::quads::{DrawTrace, RecordedTarget};
use super::readback::{Readback, Rows, copy_texture};
use super::resource::{Access, Lifetime, Meaning, Physical, Projection, ResourceDesc, TensorLayout, TextureKind};
use crate::quads::Verdict;

/// Copies into the readback start at multiples of this: a texture copy's
/// row pitch.
const SLOT: u64 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as u64;

/// A pixel's history through one frame.
#[derive(Debug, Clone, Serialize)]
pub struct PixelHistory {
    pub frame: u64,
    pub pixel: [u32; 2],
    pub passes: Vec<PassHistory>,
}

/// What one pass did at the pixel.
#[derive(Debug, Clone, Serialize)]
pub struct PassHistory {
    pub pass: String,
    pub kind: PassKind,
    /// Each image it wrote, at the pixel.
    pub outputs: Vec<TexelChange>,
    /// The images it read at the pixel (`pass/output`): their values there
    /// are their writers' `after`.
    pub inputs: Vec<String>,
    /// Each tensor it wrote that is laid out over the image, at the pixel.
    pub tensors: Vec<TensorAtPixel>,
    /// Raster passes: every draw that launched a fragment at the pixel, in
    /// submission order; `null` for other passes, and for a raster pass
    /// whose draws could not be replayed.
    pub draws: Option<Vec<DrawTrace>>,
    /// Raster passes: the fragment whose output the pass's images hold at
    /// the pixel (loupe's pipelines do not blend: the last one that passed
    /// its depth test, or ran without one); `null` when none did.
    pub survivor: Option<Survivor>,
    /// A compute pass that runs one invocation per pixel of its output:
    /// the global id of the invocation at this pixel.
    pub invocation: Option<[u32; 3]>,
}

/// A fragment named by its draw and primitive.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Survivor {
    pub draw: String,
    pub primitive: u32,
}

/// An output at the pixel, before and after the pass.
#[derive(Debug, Clone, Serialize)]
pub struct TexelChange {
    /// `pass/output`.
    pub output: String,
    /// The texel the pixel falls on (the output may be smaller than the
    /// frame): x, y, layer.
    pub texel: [u32; 3],
    /// Where the value before the pass comes from.
    pub origin: Origin,
    /// RGBA (unused channels 0) before the pass, when `origin` is `read`.
    pub before: Option<[f32; 4]>,
    /// RGBA after the pass; `null` when the readback failed.
    pub after: Option<[f32; 4]>,
}

/// What an output held at the pixel before the pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// A render target the pass clears first.
    Cleared,
    /// Written earlier in the frame, or kept from the frame before: read.
    Read,
    /// Nothing has written it this frame and it is not kept between
    /// frames: whatever the memory held, which the pass overwrites.
    Undefined,
    /// It should have been read, but the readback failed.
    Unread,
}

/// A tensor's channels at the pixel.
#[derive(Debug, Clone, Serialize)]
pub struct TensorAtPixel {
    /// `pass/output`.
    pub output: String,
    /// The tensor's own x and y at the pixel (a level of the U-Net is the
    /// image halved `level` times).
    pub at: [u32; 2],
    /// Channel → value.
    pub channels: Vec<f32>,
}

/// One copy recorded for the history, at `offset` in the readback.
enum Copy {
    Texel { output: String, texel: [u32; 3], layout: Layout, at: Slot, before: bool },
    Tensor { output: String, at: [u32; 2], element: super::resource::Element, channels: u32, skip: u64, offset: u64 },
}

/// Where a texel's copy lands.
enum Slot {
    /// At this offset of the shared readback.
    Shared(u64),
    /// A depth texture, copied whole into a readback of its own: WebGPU
    /// copies depth only as whole subresources.
    Whole { readback: Readback, rows: Rows, width: u32 },
}

/// The history's copies on their way back, with what the graph says of
/// each pass.
pub struct PendingHistory {
    pixel: [u32; 2],
    size: (u32, u32),
    readback: Readback,
    passes: Vec<PassPlan>,
}

struct PassPlan {
    pass: String,
    kind: PassKind,
    copies: Vec<Copy>,
    /// Outputs the pass clears or first writes: their `Before` is known
    /// without a copy.
    known: Vec<(String, [u32; 3], Origin)>,
    inputs: Vec<String>,
    invocation: Option<[u32; 3]>,
}

/// Where a screen-space image of `desc`'s size has the frame's pixel; `None`
/// for images that are not laid over the frame (shadow maps, volumes).
fn texel_of(r: &Resource, pixel: [u32; 2], (width, height): (u32, u32)) -> Option<[u32; 3]> {
    let ResourceDesc::Texture(desc) = &r.desc else { return None };
    if desc.kind != TextureKind::D2 || r.meaning == Meaning::Depth(Projection::Light) {
        return None;
    }
    let (rx, ry) = (f64::from(desc.width) / f64::from(width), f64::from(desc.height) / f64::from(height));
    // The same aspect, to within a texel of rounding (a half-size image of
    // an odd-sized frame).
    if (rx - ry).abs() * f64::from(desc.width.max(desc.height)) > 1.0 {
        return None;
    }
    let scale = |p: u32, ratio: f64, size: u32| ((f64::from(p) * ratio) as u32).min(size - 1);
    Some([scale(pixel[0], rx, desc.width), scale(pixel[1], ry, desc.height), 0])
}

/// The element range of a tensor laid out over the image at the pixel: its
/// channels last, after `y, x` (the image halved a whole number of times,
/// maybe padded) or after one `pixel` dimension of the frame's size.
fn tensor_at(layout: &TensorLayout, pixel: [u32; 2], (width, height): (u32, u32)) -> Option<([u32; 2], u64, u32)> {
    match layout.dims.as_slice() {
        [("y", th), ("x", tw), (_, c)] => {
            // The smallest halving that fits the frame into the tensor.
            let shift = (0..16).find(|&s| width >> s <= *tw && height >> s <= *th)?;
            let at = [(pixel[0] >> shift).min(tw - 1), (pixel[1] >> shift).min(th - 1)];
            Some((at, (u64::from(at[1]) * u64::from(*tw) + u64::from(at[0])) * u64::from(*c), *c))
        }
        [("pixel", n), (_, c)] if *n == width * height => {
            Some((pixel, (u64::from(pixel[1]) * u64::from(width) + u64::from(pixel[0])) * u64::from(*c), *c))
        }
        _ => None,
    }
}

/// Where in the frame's recording the recorder is: pass `pass` of `graph`,
/// with the memory behind each resource.
#[derive(Clone, Copy)]
pub struct AtPass<'a> {
    pub device: &'a wgpu::Device,
    pub graph: &'a Graph,
    pub physical: &'a [Option<&'a Physical>],
    pub pass: usize,
}

/// Plans and records the copies of one frame's history: `before` ahead of
/// each pass, `after` behind it.
pub struct HistoryRecorder {
    pixel: [u32; 2],
    size: (u32, u32),
    readback: Readback,
    next: u64,
    passes: Vec<PassPlan>,
}

impl HistoryRecorder {
    /// A recorder for `pixel` of a `size` frame; the readback is sized from
    /// the graph up front.
    pub fn new(device: &wgpu::Device, graph: &Graph, pixel: [u32; 2], size: (u32, u32)) -> HistoryRecorder {
        let mut bytes = 0;
        for p in &graph.passes {
            for h in p.writes() {
                let r = graph.resource(h);
                bytes += match &r.desc {
                    ResourceDesc::Texture(_) if texel_of(r, pixel, size).is_some() => 2 * SLOT,
                    ResourceDesc::Buffer(l) => tensor_at(l, pixel, size).map_or(0, |(_, _, c)| slot(u64::from(c) * l.element.bytes() + 4)),
                    _ => 0,
                };
            }
        }
        let readback = Readback::new(device, "pixel history", bytes.max(SLOT));
        HistoryRecorder { pixel, size, readback, next: 0, passes: Vec::new() }
    }

    fn take(&mut self, bytes: u64) -> u64 {
        let at = self.next;
        self.next += slot(bytes);
        at
    }

    /// Before pass `i` records: copies each output it does not clear and an
    /// earlier pass (or the frame before) wrote.
    pub fn before(&mut self, encoder: &mut wgpu::CommandEncoder, at: &AtPass<'_>) {
        let AtPass { device, graph, physical, pass: i } = *at;
        let pass = &graph.passes[i];
        let mut plan = PassPlan {
            pass: pass.name.clone(),
            kind: pass.kind,
            copies: Vec::new(),
            known: Vec::new(),
            inputs: pass
                .reads()
                .filter(|h| texel_of(graph.resource(*h), self.pixel, self.size).is_some())
                .map(|h| graph.resource(h).name.clone())
                .collect(),
            invocation: None,
        };
        for h in pass.writes() {
            let r = graph.resource(h);
            let Some(texel) = texel_of(r, self.pixel, self.size) else { continue };
            let clears = pass.accesses.iter().any(|(a, acc)| *a == h && matches!(acc, Access::ColorTarget | Access::DepthTarget));
            let written = graph.passes[..i].iter().any(|p| p.writes().any(|w| w == h)) || r.lifetime == Lifetime::History;
            if clears || !written {
                plan.known.push((r.name.clone(), texel, if clears { Origin::Cleared } else { Origin::Undefined }));
                continue;
            }
            if let Some(copy) = self.copy_texel(device, encoder, r, physical[h.0], texel, true) {
                plan.copies.push(copy);
            }
        }
        if pass.kind == PassKind::Compute && pass.per_pixel {
            plan.invocation = pass.writes().find_map(|h| {
                let r = graph.resource(h);
                match &r.desc {
                    ResourceDesc::Texture(_) => texel_of(r, self.pixel, self.size),
                    ResourceDesc::Buffer(l) => tensor_at(l, self.pixel, self.size).map(|([x, y], _, _)| [x, y, 0]),
                }
            });
        }
        self.passes.push(plan);
    }

    /// After pass `i` (the one `before` saw last): copies each output at
    /// the pixel.
    pub fn after(&mut self, encoder: &mut wgpu::CommandEncoder, at: &AtPass<'_>) {
        let AtPass { device, graph, physical, pass: i } = *at;
        let pass = &graph.passes[i];
        let mut copies = Vec::new();
        for h in pass.writes() {
            let r = graph.resource(h);
            let copy = match (&r.desc, physical[h.0]) {
                (ResourceDesc::Texture(_), _) => {
                    texel_of(r, self.pixel, self.size).and_then(|t| self.copy_texel(device, encoder, r, physical[h.0], t, false))
                }
                (ResourceDesc::Buffer(l), Some(Physical::Buffer(buffer))) => {
                    tensor_at(l, self.pixel, self.size).map(|(at, first, channels)| {
                        let element = l.element;
                        let start = first * element.bytes();
                        let aligned = start & !3;
                        let end = (start + u64::from(channels) * element.bytes()).next_multiple_of(4);
                        let offset = self.take(end - aligned);
                        encoder.copy_buffer_to_buffer(buffer, aligned, self.readback.buffer(), offset, end - aligned);
                        Copy::Tensor { output: r.name.clone(), at, element, channels, skip: start - aligned, offset }
                    })
                }
                _ => None,
            };
            copies.extend(copy);
        }
        self.passes.last_mut().expect("`before` ran first").copies.extend(copies);
    }

    fn copy_texel(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        r: &Resource,
        physical: Option<&Physical>,
        texel: [u32; 3],
        before: bool,
    ) -> Option<Copy> {
        let (ResourceDesc::Texture(desc), Some(Physical::Texture { texture, .. })) = (&r.desc, physical) else { return None };
        let layout = Layout::of(desc.format)?;
        let at = if desc.format.has_depth_aspect() {
            let (readback, rows) = copy_texture(device, encoder, &r.name, texture, 0, 1, layout.bytes_per_texel() as u32);
            Slot::Whole { readback, rows, width: desc.width }
        } else {
            let offset = self.take(SLOT);
            super::readback::copy_texel_into(encoder, texture, texel, self.readback.buffer(), offset);
            Slot::Shared(offset)
        };
        Some(Copy::Texel { output: r.name.clone(), texel, layout, at, before })
    }

    pub fn finish(self) -> PendingHistory {
        PendingHistory { pixel: self.pixel, size: self.size, readback: self.readback, passes: self.passes }
    }
}

fn slot(bytes: u64) -> u64 {
    bytes.next_multiple_of(SLOT)
}

impl PendingHistory {
    /// The depth textures copied whole.
    fn own_readbacks(&self) -> impl Iterator<Item = &Readback> {
        self.passes.iter().flat_map(|p| &p.copies).filter_map(|c| match c {
            Copy::Texel { at: Slot::Whole { readback, .. }, .. } => Some(readback),
            _ => None,
        })
    }

    pub fn map(&self) {
        self.readback.map();
        self.own_readbacks().for_each(Readback::map);
    }

    pub fn landed(&self) -> bool {
        self.readback.landed() && self.own_readbacks().all(Readback::landed)
    }

    /// The history, with each raster pass's fragments from the frame's
    /// recorded draws (`targets`).
    pub fn read(self, frame: u64, targets: &[RecordedTarget]) -> PixelHistory {
        let bytes = self.readback.read(<[u8]>::to_vec);
        if bytes.is_none() {
            log::warn!("the readback of pixel {:?}'s history failed", self.pixel);
        }
        let traces = super::quads::trace(targets, self.pixel, self.size);
        let mut passes = Vec::new();
        for plan in self.passes {
            let mut outputs: Vec<TexelChange> = plan
                .known
                .into_iter()
                .map(|(output, texel, origin)| TexelChange { output, texel, origin, before: None, after: None })
                .collect();
            let mut tensors = Vec::new();
            for copy in &plan.copies {
                match copy {
                    Copy::Texel { output, texel, layout, at, before } => {
                        let value = match at {
                            Slot::Shared(offset) => bytes.as_deref().map(|b| texel_value(layout, &b[*offset as usize..])),
                            Slot::Whole { readback, rows, width } => readback.read(|b| {
                                let row = rows.of(b).nth(texel[1] as usize).expect("the texel's row was copied");
                                let at = (texel[0] as usize).min(*width as usize - 1) * layout.bytes_per_texel();
                                texel_value(layout, &row[at..])
                            }),
                        };
                        let i = match outputs.iter().position(|o| o.output == *output) {
                            Some(i) => i,
                            None => {
                                outputs.push(TexelChange {
                                    output: output.clone(),
                                    texel: *texel,
                                    origin: Origin::Unread,
                                    before: None,
                                    after: None,
                                });
                                outputs.len() - 1
                            }
                        };
                        match (before, value) {
                            (true, Some(v)) => (outputs[i].origin, outputs[i].before) = (Origin::Read, Some(v)),
                            (true, None) => {}
                            (false, v) => outputs[i].after = v,
                        }
                    }
                    Copy::Tensor { output, at, element, channels, skip, offset } => {
                        let Some(b) = bytes.as_deref() else { continue };
                        let start = (offset + skip) as usize;
                        let data = &b[start..start + *channels as usize * element.bytes() as usize];
                        tensors.push(TensorAtPixel { output: output.clone(), at: *at, channels: decode_elements(*element, data) });
                    }
                }
            }
            let mine = || traces.iter().filter(|t| t.pass == plan.pass);
            let draws = (plan.kind == PassKind::Raster && mine().next().is_some())
                .then(|| mine().flat_map(|t| t.draws.iter().cloned()).collect::<Vec<_>>());
            let survivor = draws.as_ref().and_then(|draws| {
                let mut fragments = draws.iter().flat_map(|d| d.fragments.iter().map(move |f| (d, f)));
                fragments.rfind(|(_, f)| !f.helper && matches!(f.verdict, Verdict::Passed | Verdict::NotTested))
            });
            let survivor = survivor.map(|(d, f)| Survivor { draw: d.name.clone(), primitive: f.primitive });
            let touched =
                !outputs.is_empty() || !tensors.is_empty() || !plan.inputs.is_empty() || draws.as_ref().is_some_and(|d| !d.is_empty());
            if touched {
                passes.push(PassHistory {
                    pass: plan.pass,
                    kind: plan.kind,
                    outputs,
                    inputs: plan.inputs,
                    tensors,
                    draws,
                    survivor,
                    invocation: plan.invocation,
                });
            }
        }
        PixelHistory { frame, pixel: self.pixel, passes }
    }
}

/// One texel's RGBA from the start of its slot.
fn texel_value(layout: &Layout, bytes: &[u8]) -> [f32; 4] {
    let mut out = Vec::with_capacity(4);
    layout.extend_rgba_f32(&bytes[..layout.bytes_per_texel()], &mut out);
    [out[0], out[1], out[2], out[3]]
}
