//! The display pass's pipelines: `show` draws an output for the Inspector
//! as one fullscreen triangle into an `Rgba8Unorm` target, `measure`
//! reduces its finite range. One variant per way a texel is loaded (float
//! colour, depth), built once per device on first use.

use std::fmt::Write;

use loupe_view::presets::{self, Channel, DisplayOptions};

/// The uniform both entry points read (`Params` in display.wgsl).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Params {
    channel: u32,
    flags: u32,
    scale: f32,
    lo: f32,
    hi: f32,
    near: f32,
    far: f32,
    clear: f32,
    texel: [u32; 2],
    // The uniform's size is a multiple of 16 bytes.
    pad: [u32; 2],
}

const SRGB: u32 = 1;
const FALSE_COLOUR: u32 = 2;
const OVERLAY: u32 = 4;
const LINEARIZE: u32 = 8;
const REVERSED: u32 = 16;
const SKIP_CLEAR: u32 = 32;

impl Params {
    /// `clear`: the output's clear value when it is depth, left out of the
    /// measured range.
    pub fn new(o: &DisplayOptions, clear: Option<f32>) -> Self {
        let channel = match o.channel {
            Channel::Rgb => 0,
            Channel::Luminance => 5,
            single => single.single().expect("a single channel") as u32 + 1,
        };
        let mut flags = 0;
        for (on, flag) in [(o.srgb, SRGB), (o.false_colour, FALSE_COLOUR), (o.overlay, OVERLAY), (clear.is_some(), SKIP_CLEAR)] {
            if on {
                flags |= flag;
            }
        }
        let (mut near, mut far) = (0.0, 0.0);
        if let Some(p) = o.linearize {
            flags |= LINEARIZE | if p.reversed { REVERSED } else { 0 };
            (near, far) = (p.near, p.far);
        }
        let (lo, hi, clear) = (o.min, o.max, clear.unwrap_or(0.0));
        Params { channel, flags, scale: o.exposure.exp2(), lo, hi, near, far, clear, texel: [0; 2], pad: [0; 2] }
    }

    /// What `pick` reads texel `[x, y]` by.
    pub fn pick(texel: [u32; 2]) -> Self {
        Params { texel, ..bytemuck::Zeroable::zeroed() }
    }
}

/// How the source texture is bound and loaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Float,
    Depth,
}

impl Source {
    /// `None`: a format the pass cannot show (integers).
    pub fn of(format: wgpu::TextureFormat) -> Option<Source> {
        match format.sample_type(Some(wgpu::TextureAspect::DepthOnly), None).or_else(|| format.sample_type(None, None))? {
            wgpu::TextureSampleType::Float { .. } => Some(Source::Float),
            wgpu::TextureSampleType::Depth => Some(Source::Depth),
            _ => None,
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

struct Variant {
    textures: wgpu::BindGroupLayout,
    measures: wgpu::BindGroupLayout,
    picks: wgpu::BindGroupLayout,
    show: wgpu::RenderPipeline,
    measure: wgpu::ComputePipeline,
    pick: wgpu::ComputePipeline,
}

pub struct Pipelines {
    variants: [Variant; 2],
}

impl Pipelines {
    /// Builds both variants; an error is a bug of loupe's, not the user's.
    pub fn new(device: &wgpu::Device) -> Result<Self, String> {
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let variants = [Source::Float, Source::Depth].map(|s| Variant::new(device, s));
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(e.to_string()),
            None => Ok(Pipelines { variants }),
        }
    }

    /// Records `show` of the input into `target`.
    pub fn show(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, input: Input<'_>, target: &wgpu::TextureView) {
        let v = &self.variants[input.source.index()];
        let group = bind(device, &v.textures, input, None);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("display: show"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&v.show);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Records `measure` of the input (`size` texels) into `range`, which
    /// must hold the starting bounds.
    pub fn measure(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        input: Input<'_>,
        size: [u32; 2],
        range: &wgpu::Buffer,
    ) {
        let v = &self.variants[input.source.index()];
        let group = bind(device, &v.measures, input, Some((2, range)));
        dispatch(encoder, &v.measure, &group, [size[0].div_ceil(8), size[1].div_ceil(8)]);
    }

    /// Records `pick` of the texel the params name into `picked` (16
    /// bytes: RGBA f32).
    pub fn pick(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, input: Input<'_>, picked: &wgpu::Buffer) {
        let v = &self.variants[input.source.index()];
        let group = bind(device, &v.picks, input, Some((3, picked)));
        dispatch(encoder, &v.pick, &group, [1, 1]);
    }
}

/// What every entry point reads: the source (layer 0, as a 2D view) and
/// the uniform.
#[derive(Clone, Copy)]
pub struct Input<'a> {
    pub source: Source,
    pub params: &'a wgpu::Buffer,
    pub view: &'a wgpu::TextureView,
}

fn dispatch(encoder: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, [x, y]: [u32; 2]) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("display"), timestamp_writes: None });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(x, y, 1);
}

/// The range buffer's starting bounds: every least above every value,
/// every greatest below.
pub const START: [u32; 10] = [u32::MAX, u32::MAX, u32::MAX, u32::MAX, u32::MAX, 0, 0, 0, 0, 0];

/// The measured bounds per channel, `None` where no value was finite.
pub fn decode(words: &[u32; 10]) -> [Option<(f32, f32)>; 5] {
    let float = |u: u32| f32::from_bits(if u & 0x8000_0000 != 0 { u & 0x7fff_ffff } else { !u });
    std::array::from_fn(|c| (words[c] <= words[5 + c]).then(|| (float(words[c]), float(words[5 + c]))))
}

/// The params and the source, and a storage buffer at its binding.
fn bind(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, input: Input<'_>, storage: Option<(u32, &wgpu::Buffer)>) -> wgpu::BindGroup {
    let mut entries = vec![
        wgpu::BindGroupEntry { binding: 0, resource: input.params.as_entire_binding() },
        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(input.view) },
    ];
    if let Some((binding, buffer)) = storage {
        entries.push(wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() });
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("display"), layout, entries: &entries })
}

impl Variant {
    fn new(device: &wgpu::Device, source: Source) -> Variant {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(shader(source).into()),
        });
        let sample_type = match source {
            Source::Float => wgpu::TextureSampleType::Float { filterable: false },
            Source::Depth => wgpu::TextureSampleType::Depth,
        };
        let stages = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let entries = [
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: stages,
                ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: stages,
                ty: wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
                count: None,
            },
        ];
        let textures =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("display: show"), entries: &entries });
        let with_storage = |binding: u32, label: &'static str| {
            let entries = [entries[0], entries[1], crate::gpu::pipeline::storage_rw(label, binding).entry];
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
        };
        let measures = with_storage(2, "display: measure");
        let picks = with_storage(3, "display: pick");
        let layout = |group: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("display"),
                bind_group_layouts: &[Some(group)],
                immediate_size: 0,
            })
        };
        let show = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display: show"),
            layout: Some(&layout(&textures)),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("show"),
                compilation_options: Default::default(),
                targets: &[Some(super::FORMAT.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let compute = |group: &wgpu::BindGroupLayout, entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout(group)),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let (measure, pick) = (compute(&measures, "measure"), compute(&picks, "pick"));
        Variant { textures, measures, picks, show, measure, pick }
    }
}

/// display.wgsl with the source's type and load, and the viridis table.
fn shader(source: Source) -> String {
    let (ty, load) = match source {
        Source::Float => ("texture_2d<f32>", "textureLoad(source, p, 0)"),
        Source::Depth => ("texture_depth_2d", "vec4<f32>(textureLoad(source, p, 0), 0.0, 0.0, 1.0)"),
    };
    let mut table = String::from("array<vec3<f32>, 7>(");
    let coefficients = presets::viridis();
    assert_eq!(coefficients.len(), 7, "client/presets.json: viridis has seven coefficients");
    for (i, [r, g, b]) in coefficients.iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        let _ = write!(table, "{sep}vec3<f32>({r:?}, {g:?}, {b:?})");
    }
    table.push(')');
    include_str!("display.wgsl")
        .replace("SOURCE;", &format!("{ty};"))
        .replace("LOAD;", &format!("{load};"))
        .replace("VIRIDIS_TABLE", &table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_variants_validate() {
        for source in [Source::Float, Source::Depth] {
            let text = shader(source);
            let module = naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| panic!("{source:?}: {}", e.emit_to_string(&text)));
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
                .validate(&module)
                .unwrap_or_else(|e| panic!("{source:?}: {e:?}"));
        }
    }

    #[test]
    fn ranges_decode_in_order_and_empty_channels_are_none() {
        let ordered = |x: f32| {
            let b = x.to_bits();
            if b & 0x8000_0000 != 0 { !b } else { b | 0x8000_0000 }
        };
        let mut words = START;
        for (c, (lo, hi)) in [(-2.5f32, 3.0f32), (0.0, 0.0), (-1e-30, 1e30), (1.0, 1.0)].into_iter().enumerate() {
            (words[c], words[5 + c]) = (ordered(lo), ordered(hi));
        }
        let got = decode(&words);
        assert_eq!(got[..4], [Some((-2.5, 3.0)), Some((0.0, 0.0)), Some((-1e-30, 1e30)), Some((1.0, 1.0))]);
        assert_eq!(got[4], None);
        assert!(ordered(-1.0) < ordered(-0.5) && ordered(-0.5) < ordered(0.0) && ordered(0.0) < ordered(2.0));
    }
}
