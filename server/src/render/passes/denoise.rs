//! The denoiser in the frame: OIDN's U-Net (`crate::denoise::network`) run
//! on the path tracer's colour, albedo and normal, one compute pass per op
//! of the network, so that every tensor is a graph buffer captured and
//! inspected like any output (`[y, x, channel]`, channels padded to whole
//! blocks of 4).
//!
//! `denoise_autoexposure` (HDR: the input scale) → `denoise_input` (the
//! `input` tensor: transfer function, normals to [0, 1], zero padding to
//! the network's alignment) → `denoise.<tensor>` per op (convolutions,
//! pools, and the upsamples and concatenations unless
//! `quality.denoiser_fused` runs them inside the convolution after them) →
//! `denoise` (`color`: cropped, inverse transfer, HDR). The processing
//! mirrors the CPU reference (`shaders/denoise/process.wgsl` names the
//! function each kernel mirrors). Culled, with the reason, unless the
//! renderer is the path tracer and the scene has a `[denoiser]`.

pub mod kernels;

use kernels::{CONCAT, CONCAT_CHANNELS, CONV, CONV_TILED, ConcatUniform, F16, LayerUniform, POOL, PoolUniform, TILE, UPSAMPLE, UPSAMPLE_NEAREST, conv_spec, conv_workgroups};

use super::path_trace::COLOR;
use crate::denoise::Precision;
use crate::denoise::network::{Network, Op, TensorId};
use crate::gpu::pipeline::{COMPUTE, Group, PipelineSpec, Stages, sizes, storage, storage_rw, storage_texture, texture, uniform};
use crate::render::context::PassContext;
use crate::render::denoise_weights::{blocks, fused_inputs};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Element, Handle, PipelineKey, TensorLayout, TextureDesc};
use crate::denoise::process::Mode;
use crate::scene::Scene;
use crate::scene::settings::DenoiseAt;

/// The HDR transfer function (PU); without it or `LDR_SRGB`, sRGB.
pub const HDR_DEF: &str = "HDR";
/// The colour is sRGB-encoded already: no transfer function.
pub const LDR_SRGB: &str = "LDR_SRGB";
/// The input scale is the autoexposure's (a buffer), not the uniforms'.
pub const AUTOEXPOSURE: &str = "AUTOEXPOSURE";

/// OIDN's bins of the autoexposure are at most this many pixels a side.
const AUTOEXPOSURE_BIN: u32 = 16;

pub static AUTOEXPOSURE_BINS: PipelineSpec = PipelineSpec {
    name: "denoise.autoexposure_bins",
    shader: "denoise/autoexposure.wgsl",
    stages: Stages::Compute { entry: "autoexposure_bins" },
    groups: &[Group::always(0, &[texture("color", 0), storage_rw("bins", 1)])],
    defs: &[],
};

pub static AUTOEXPOSURE_SCALE: PipelineSpec = PipelineSpec {
    name: "denoise.autoexposure_scale",
    shader: "denoise/autoexposure.wgsl",
    stages: Stages::Compute { entry: "autoexposure_scale" },
    groups: &[Group::always(0, &[texture("color", 0), storage_rw("bins", 1), storage_rw("scale", 2)])],
    defs: &[],
};

/// The measured input scale, read by the input and output kernels.
const SCALE: Group = Group::when(1, AUTOEXPOSURE, &[storage("scale", 0, COMPUTE)]);

pub static INPUT: PipelineSpec = PipelineSpec {
    name: "denoise.input",
    shader: "denoise/process.wgsl",
    stages: Stages::Compute { entry: "input" },
    groups: &[
        Group::always(
            0,
            &[uniform("input_params", 0, COMPUTE, 2 * sizes::VEC4), texture("color", 1), texture("albedo", 2), texture("normal", 3), storage_rw("tensor", 4)],
        ),
        SCALE,
    ],
    defs: &[HDR_DEF, LDR_SRGB, AUTOEXPOSURE, F16],
};

pub static OUTPUT: PipelineSpec = PipelineSpec {
    name: "denoise.output",
    shader: "denoise/process.wgsl",
    stages: Stages::Compute { entry: "output" },
    groups: &[
        Group::always(0, &[uniform("output_params", 5, COMPUTE, sizes::VEC4), storage("network_output", 6, COMPUTE), storage_texture("denoised", 7, COLOR)]),
        SCALE,
    ],
    defs: &[HDR_DEF, LDR_SRGB, AUTOEXPOSURE, F16],
};

pub const SPECS: &[&PipelineSpec] = &[&AUTOEXPOSURE_BINS, &AUTOEXPOSURE_SCALE, &INPUT, &CONV, &CONV_TILED, &POOL, &UPSAMPLE_NEAREST, &CONCAT_CHANNELS, &OUTPUT];

/// The passes every denoised frame has, whatever the network: culled
/// with the reason when the frame is not denoised.
const PASSES: [&str; 3] = ["denoise_autoexposure", "denoise_input", "denoise"];

/// Culls the denoiser of a frame that is not path traced (`why`), or of a
/// scene without a `[denoiser]`.
pub fn cull(g: &mut GraphBuilder, scene: &Scene, why: &str) {
    cull_all(g, if scene.denoiser.is_none() { NO_DENOISER } else { why });
}

const NO_DENOISER: &str = "the scene has no [denoiser]";

fn cull_all(g: &mut GraphBuilder, reason: &str) {
    for pass in PASSES {
        g.cull(pass, reason);
    }
}

/// The tensor a pass makes, as the pass that makes it is named.
fn pass_name(net: &Network, t: TensorId) -> String {
    format!("denoise.{}", net.tensor(t).name)
}

/// Which frames the denoiser runs on (`quality.denoise_at`). On the others
/// its passes record nothing, and their outputs, kept from frame to frame
/// like every frame resource whose description stays, hold the newest
/// denoised image and tensors.
#[derive(Debug, Clone, Copy)]
struct Schedule {
    every: bool,
    /// The samples the accumulation ends at (`quality.path_spp`).
    last: u32,
}

impl Schedule {
    fn due(self, samples: u32) -> bool {
        self.every || samples.is_power_of_two() || samples == self.last
    }

    /// A pass's recording, done only on the frames that are due.
    fn wrap(self, record: impl Fn(&mut PassContext<'_>) + Send + Sync + 'static) -> impl Fn(&mut PassContext<'_>) + Send + Sync + 'static {
        move |ctx| {
            if self.due(ctx.samples) {
                record(ctx);
            }
        }
    }
}

/// What the denoiser reads: the noisy colour (`Rgba32Float`), and the
/// albedo and normal the network may take.
pub struct Noisy {
    pub color: Handle,
    pub albedo: Handle,
    pub normal: Handle,
}

/// The denoised colour (`traced.color` as it is when the scene has no
/// `[denoiser]`, its network is not loaded, or a tensor would be larger
/// than `max_buffer` bytes).
pub fn denoise(g: &mut GraphBuilder, scene: &Scene, network: Option<&Network>, traced: &Noisy, max_buffer: Option<u64>) -> Handle {
    let Some(settings) = &scene.denoiser else {
        cull_all(g, NO_DENOISER);
        return traced.color;
    };
    if !scene.quality.denoise {
        cull_all(g, "quality.denoise is off");
        return traced.color;
    }
    let Some(net) = network else {
        cull_all(g, "the denoiser's weights are not loaded");
        return traced.color;
    };
    let mode = settings.mode;
    let schedule = Schedule { every: scene.quality.denoise_at == DenoiseAt::Every, last: scene.quality.path_spp };
    let f16 = settings.precision == Precision::F16;
    let (w, h) = (scene.width, scene.height);
    let align = net.alignment() as u32;
    let (pw, ph) = (w.next_multiple_of(align), h.next_multiple_of(align));
    // Every tensor is the padded image's size halved `level` times.
    let size = |t: TensorId| (pw >> net.tensor(t).level, ph >> net.tensor(t).level);
    let layout = |t: TensorId| {
        let (tw, th) = size(t);
        let element = if f16 { Element::F16 } else { Element::F32 };
        TensorLayout::new(&[("y", th), ("x", tw), ("channel", (blocks(net.tensor(t).channels) * 4) as u32)], element)
    };
    let channel_blocks = |t: TensorId| blocks(net.tensor(t).channels) as u32;
    // With fusion, the convolutions that read an upsample's concatenation
    // read both of its inputs instead; those two tensors are never made.
    let fused: Vec<_> = net
        .ops
        .iter()
        .map(|op| match op {
            Op::Conv(c) if scene.quality.denoiser_fused => fused_inputs(net, c).map(|f| (f, pass_name(net, c.dst))),
            _ => None,
        })
        .collect();
    let fused_into = |t: TensorId| fused.iter().flatten().find(|(f, _)| f.upsampled == t || f.concatenated == t).map(|(_, conv)| conv.clone());

    let made = (0..net.tensors.len()).map(TensorId).filter(|&t| fused_into(t).is_none());
    let largest = made.map(|t| (layout(t).bytes(), net.tensor(t))).max_by_key(|(bytes, _)| *bytes);
    if let (Some(limit), Some((bytes, t))) = (max_buffer, largest)
        && bytes > limit
    {
        let reason = format!(
            "the denoiser's tensor {} would take {:.1} MiB at {w}×{h}, more than the device binds in one buffer ({:.1} MiB): render smaller, with precision = \"f16\", or denoise the image with `loupe denoise`, which cuts it into tiles",
            t.name,
            mib(bytes),
            mib(limit)
        );
        cull_all(g, &reason);
        return traced.color;
    }

    // The measured scale, or the uniforms' (`given`).
    let given = settings.input_scale.or((!mode.hdr()).then_some(1.0));
    let scale = match given {
        None => Some(autoexposure(g, traced.color, w, h, schedule)),
        Some(_) if settings.input_scale.is_some() => {
            g.cull("denoise_autoexposure", "denoiser.input_scale is given");
            None
        }
        Some(_) => {
            let name = if mode == Mode::Ldr { "ldr" } else { "ldr_srgb" };
            g.cull("denoise_autoexposure", format!("denoiser.mode is {name}: the input scale is 1"));
            None
        }
    };
    let given = given.unwrap_or(0.0).to_bits();
    let defs = [(HDR_DEF, mode == Mode::Hdr), (LDR_SRGB, mode == Mode::LdrSrgb), (AUTOEXPOSURE, scale.is_some()), (F16, f16)];

    let mut tensors: Vec<Option<Handle>> = vec![None; net.tensors.len()];
    let mut p = g.pass("denoise_input", PassKind::Compute);
    p.one_invocation_per_pixel();
    let key = p.pipeline(PipelineKey::new(&INPUT, &defs));
    let (color, albedo, normal) = (p.sample(traced.color), p.sample(traced.albedo), p.sample(traced.normal));
    if let Some(s) = scale {
        p.access(s, Access::StorageRead);
    }
    let input = p.create("tensor", Meaning::Data, layout(net.input), Access::StorageWrite);
    tensors[net.input.0] = Some(input);
    let params = [w, h, pw, ph, channel_blocks(net.input), given, 0, 0];
    p.execute(schedule.wrap(move |ctx| {
        let u = ctx.uniform(bytemuck::cast_slice(&params));
        let mut b = vec![
            ("input_params", u.as_entire_binding()),
            ("color", ctx.bind(color)),
            ("albedo", ctx.bind(albedo)),
            ("normal", ctx.bind(normal)),
            ("tensor", ctx.bind(input)),
        ];
        if let Some(s) = scale {
            b.push(("scale", ctx.bind(s)));
        }
        ctx.dispatch(&key, &b, [pw.div_ceil(TILE), ph.div_ceil(TILE), 1]);
    }));

    for (i, op) in net.ops.iter().enumerate() {
        let dst = op.dst();
        let name = pass_name(net, dst);
        if let Some(conv) = fused_into(dst) {
            g.cull(&name, format!("fused into {conv} (quality.denoiser_fused)"));
            continue;
        }
        let fusion = fused[i].as_ref().map(|(f, _)| *f);
        let reads = match fusion {
            Some(f) => vec![f.a, f.skip],
            None => op.srcs(),
        };
        // Ops run in order, and every op reads tensors made before it.
        let Some(srcs) = reads.iter().map(|s| tensors[s.0]).collect::<Option<Vec<Handle>>>() else {
            log::error!("denoiser: {name} reads a tensor no pass made");
            break;
        };
        let mut p = g.pass(&name, PassKind::Compute);
        let out = p.create("tensor", Meaning::Data, layout(dst), Access::StorageWrite);
        tensors[dst.0] = Some(out);
        let (ow, oh) = size(dst);
        match op {
            Op::Conv(c) => {
                let (a, b) = (reads[0], reads.get(1).copied());
                let kernel = scene.quality.denoiser_kernel;
                let key = p.pipeline(PipelineKey::new(conv_spec(kernel), &[(UPSAMPLE, fusion.is_some()), (CONCAT, fusion.is_some()), (F16, f16)]));
                let (aw, ah) = size(a);
                let a_handle = p.access(srcs[0], Access::StorageRead);
                let b_handle = srcs.get(1).map(|&h| p.access(h, Access::StorageRead));
                let overflow = f16.then(|| {
                    let o = p.create("overflow", Meaning::Data, TensorLayout::new(&[("count", 1)], Element::U32), Access::StorageWrite);
                    p.access(o, Access::CopyDst)
                });
                let u = LayerUniform {
                    width: ow,
                    height: oh,
                    a_width: aw,
                    a_height: ah,
                    a_blocks: channel_blocks(a),
                    b_blocks: b.map_or(0, channel_blocks),
                    out_blocks: channel_blocks(dst),
                    relu: c.relu.into(),
                };
                p.execute(schedule.wrap(move |ctx| {
                    let Some(weights) = ctx.scene.denoiser.as_ref().and_then(|d| d.conv(i)) else {
                        return no_weights(ctx);
                    };
                    let layer = ctx.uniform(bytemuck::bytes_of(&u));
                    let mut b = vec![
                        ("layer", layer.as_entire_binding()),
                        ("a", ctx.bind(a_handle)),
                        ("weights", weights.weights.as_entire_binding()),
                        ("bias", weights.bias.as_entire_binding()),
                        ("out", ctx.bind(out)),
                    ];
                    if let Some(h) = b_handle {
                        b.push(("b", ctx.bind(h)));
                    }
                    if let Some(o) = overflow {
                        // A frame buffer is reused from the last frame: count from zero.
                        ctx.encoder.clear_buffer(ctx.buffer(o), 0, None);
                        b.push(("overflow", ctx.bind(o)));
                    }
                    ctx.dispatch(&key, &b, conv_workgroups(kernel, ow, oh, u.out_blocks));
                }));
            }
            Op::Pool { src, .. } => {
                let key = p.pipeline(PipelineKey::new(&POOL, &[(F16, f16)]));
                let input = p.access(srcs[0], Access::StorageRead);
                let (iw, ih) = size(*src);
                let u = PoolUniform { width: iw, height: ih, blocks: channel_blocks(dst), pad: 0 };
                p.execute(schedule.wrap(move |ctx| {
                    let params = ctx.uniform(bytemuck::bytes_of(&u));
                    let b = [("pool", params.as_entire_binding()), ("input", ctx.bind(input)), ("out", ctx.bind(out))];
                    ctx.dispatch(&key, &b, [ow.div_ceil(TILE), oh.div_ceil(TILE), u.blocks]);
                }));
            }
            Op::Upsample { .. } => {
                let key = p.pipeline(PipelineKey::new(&UPSAMPLE_NEAREST, &[(F16, f16)]));
                let input = p.access(srcs[0], Access::StorageRead);
                let u = PoolUniform { width: ow, height: oh, blocks: channel_blocks(dst), pad: 0 };
                p.execute(schedule.wrap(move |ctx| {
                    let params = ctx.uniform(bytemuck::bytes_of(&u));
                    let b = [("upsample", params.as_entire_binding()), ("input", ctx.bind(input)), ("out", ctx.bind(out))];
                    ctx.dispatch(&key, &b, [ow.div_ceil(TILE), oh.div_ceil(TILE), u.blocks]);
                }));
            }
            Op::Concat { first, second, .. } => {
                let key = p.pipeline(PipelineKey::new(&CONCAT_CHANNELS, &[(F16, f16)]));
                let (a, b) = (p.access(srcs[0], Access::StorageRead), p.access(srcs[1], Access::StorageRead));
                let u = ConcatUniform { width: ow, height: oh, a_channels: net.tensor(*first).channels as u32, b_channels: net.tensor(*second).channels as u32 };
                let out_blocks = channel_blocks(dst);
                p.execute(schedule.wrap(move |ctx| {
                    let params = ctx.uniform(bytemuck::bytes_of(&u));
                    let b = [("concat", params.as_entire_binding()), ("a", ctx.bind(a)), ("b", ctx.bind(b)), ("out", ctx.bind(out))];
                    ctx.dispatch(&key, &b, [ow.div_ceil(TILE), oh.div_ceil(TILE), out_blocks]);
                }));
            }
        }
    }

    let Some(result) = tensors[net.output.0] else {
        g.cull("denoise", "the network's output was not made");
        return traced.color;
    };
    let mut p = g.pass("denoise", PassKind::Compute);
    p.one_invocation_per_pixel();
    let key = p.pipeline(PipelineKey::new(&OUTPUT, &defs));
    p.access(result, Access::StorageRead);
    if let Some(s) = scale {
        p.access(s, Access::StorageRead);
    }
    let denoised = p.create("color", Meaning::Color, TextureDesc::d2(COLOR, w, h), Access::StorageWrite);
    let params = [w, h, pw, given];
    p.execute(schedule.wrap(move |ctx| {
        let u = ctx.uniform(bytemuck::cast_slice(&params));
        let mut b = vec![("output_params", u.as_entire_binding()), ("network_output", ctx.bind(result)), ("denoised", ctx.bind(denoised))];
        if let Some(s) = scale {
            b.push(("scale", ctx.bind(s)));
        }
        ctx.dispatch(&key, &b, [w.div_ceil(TILE), h.div_ceil(TILE), 1]);
    }));
    denoised
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1 << 20)
}

/// OIDN's autoexposure over the colour: per bin of at most 16×16 pixels
/// its mean luminance (`bins`), then the input scale (`scale`).
fn autoexposure(g: &mut GraphBuilder, color: Handle, w: u32, h: u32, schedule: Schedule) -> Handle {
    let mut p = g.pass("denoise_autoexposure", PassKind::Compute);
    let bins_key = p.pipeline(PipelineKey::new(&AUTOEXPOSURE_BINS, &[]));
    let scale_key = p.pipeline(PipelineKey::new(&AUTOEXPOSURE_SCALE, &[]));
    p.sample(color);
    let (bw, bh) = (w.div_ceil(AUTOEXPOSURE_BIN), h.div_ceil(AUTOEXPOSURE_BIN));
    let bins = p.create("bins", Meaning::Data, TensorLayout::new(&[("y", bh), ("x", bw), ("luminance", 1)], Element::F32), Access::StorageWrite);
    let scale = p.create("scale", Meaning::Data, TensorLayout::new(&[("value", 1)], Element::F32), Access::StorageWrite);
    p.execute(schedule.wrap(move |ctx| {
        let b = [("color", ctx.bind(color)), ("bins", ctx.bind(bins)), ("scale", ctx.bind(scale))];
        ctx.dispatch(&bins_key, &b, [bw, bh, 1]);
        ctx.dispatch(&scale_key, &b, [1, 1, 1]);
    }));
    scale
}

#[cfg(test)]
mod tests;

/// A convolution whose weights the scene's GPU data lacks (the graph and
/// the data were built from different scenes): it draws nothing.
fn no_weights(ctx: &mut PassContext<'_>) {
    log::error!("pass `{}` has no weights on the GPU", ctx.pass);
    ctx.skipped = true;
}
