//! The denoiser's passes on the device (lavapipe without a GPU), fed known
//! colour, albedo and normal images, against a plain CPU evaluation written
//! here from the definitions: OIDN's processing around the network (as the
//! CPU reference `denoise::process` states it) and the network's ops
//! (`denoise::network`'s walk), every tensor compared with the GPU's.

use std::sync::Arc;

use super::*;
use crate::denoise::network::Conv;
use crate::denoise::testing::{Rng, small_unet};
use crate::gpu::pipeline::HDR;
use crate::render::capture::CapturedTensor;
use crate::render::denoise_weights::BLOCK;
use crate::render::frame::FrameResult;
use crate::render::passes::path_trace::SAMPLES;
use crate::render::session::Session;

/// An image as the path tracer leaves it: RGB per pixel, row-major.
#[derive(Clone)]
struct Image {
    w: usize,
    h: usize,
    data: Vec<[f32; 3]>,
}

/// Channels-last with exact channels.
#[derive(Clone, Debug)]
struct Tensor {
    w: usize,
    h: usize,
    c: usize,
    data: Vec<f32>,
}

impl Tensor {
    fn zeros(w: usize, h: usize, c: usize) -> Tensor {
        Tensor { w, h, c, data: vec![0.0; w * h * c] }
    }

    fn at(&self, x: usize, y: usize, c: usize) -> f32 {
        self.data[(y * self.w + x) * self.c + c]
    }

    /// Every value rounded to the nearest f16, as an f16 store does.
    fn stored(mut self, f16: bool) -> Tensor {
        if f16 {
            self.data.iter_mut().for_each(|v| *v = half::f16::from_f32(*v).to_f32());
        }
        self
    }
}

// OIDN's processing (`denoise::process` of the CPU reference), written out.

fn sanitize(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_nan() { 0.0 } else { v.clamp(lo, hi) }
}

fn srgb_forward(y: f32) -> f32 {
    if y <= 0.0031308 { 12.92 * y } else { 1.055 * y.powf(1.0 / 2.4) - 0.055 }
}

fn srgb_inverse(x: f32) -> f32 {
    if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) }
}

// OIDN's constants as OIDN writes them (more digits than an f32 holds).
#[allow(clippy::excessive_precision)]
fn pu_forward(y: f32) -> f32 {
    if y <= 1.57945760e-06 {
        1.41283765e+03 * y
    } else if y <= 3.22087631e-02 {
        1.64593172e+00 * y.powf(4.31384981e-01) - 2.94139609e-03
    } else {
        1.92653254e-01 * (y + 6.26026094e-03).ln() + 9.98620152e-01
    }
}

#[allow(clippy::excessive_precision)]
fn pu_inverse(x: f32) -> f32 {
    if x <= 2.23151711e-03 {
        x / 1.41283765e+03
    } else if x <= 3.70974749e-01 {
        ((x + 2.94139609e-03) / 1.64593172e+00).powf(1.0 / 4.31384981e-01)
    } else {
        ((x - 9.98620152e-01) / 1.92653254e-01).exp() - 6.26026094e-03
    }
}

fn forward(hdr: bool, y: f32) -> f32 {
    if hdr { pu_forward(y) * (1.0 / pu_forward(65504.0)) } else { srgb_forward(y) }
}

fn inverse(hdr: bool, x: f32) -> f32 {
    if hdr { pu_inverse(x * pu_forward(65504.0)) } else { srgb_inverse(x) }
}

/// OIDN's autoexposure: bins of at most 16×16 pixels, 0.18 over the
/// geometric mean of their mean luminances above 1e-8.
fn autoexposure(color: &Image) -> f32 {
    let (bh, bw) = (color.h.div_ceil(16), color.w.div_ceil(16));
    let (mut sum, mut count) = (0.0f64, 0);
    for i in 0..bh {
        for j in 0..bw {
            let (y0, y1, x0, x1) = (i * color.h / bh, (i + 1) * color.h / bh, j * color.w / bw, (j + 1) * color.w / bw);
            let mut l = 0.0f64;
            for y in y0..y1 {
                for x in x0..x1 {
                    let [r, g, b] = color.data[y * color.w + x].map(|v| sanitize(v, 0.0, f32::MAX));
                    l += f64::from(0.212671 * r + 0.715160 * g + 0.072169 * b);
                }
            }
            let l = l / ((y1 - y0) * (x1 - x0)) as f64;
            if l > 1e-8 {
                sum += l.log2();
                count += 1;
            }
        }
    }
    if count > 0 { (0.18 / (sum / f64::from(count)).exp2()) as f32 } else { 1.0 }
}

/// The network's input, zero-padded at the right and bottom to `align`.
fn process_input(images: &[Image; 3], channels: usize, hdr: bool, scale: f32, align: usize) -> Tensor {
    let [color, albedo, normal] = images;
    let mut t = Tensor::zeros(color.w.next_multiple_of(align), color.h.next_multiple_of(align), channels);
    let hi = if hdr { f32::MAX } else { 1.0 };
    for y in 0..color.h {
        for x in 0..color.w {
            let i = y * color.w + x;
            let mut v: Vec<f32> = color.data[i].iter().map(|c| forward(hdr, sanitize(c * scale, 0.0, hi))).collect();
            v.extend(albedo.data[i].map(|a| sanitize(a, 0.0, 1.0)));
            v.extend(normal.data[i].map(|n| sanitize(n, -1.0, 1.0) * 0.5 + 0.5));
            let at = (y * t.w + x) * channels;
            t.data[at..at + channels].copy_from_slice(&v[..channels]);
        }
    }
    t
}

/// The denoised colour from the network's output.
fn process_output(t: &Tensor, w: usize, h: usize, hdr: bool, scale: f32) -> Vec<[f32; 3]> {
    let out_scale = if scale != 0.0 { 1.0 / scale } else { 0.0 };
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            [0, 1, 2].map(|c| {
                let v = inverse(hdr, sanitize(t.at(x, y, c), 0.0, f32::MAX));
                (if hdr { v } else { v.min(1.0) }) * out_scale
            })
        })
        .collect()
}

// The network's ops, from their definitions.

fn conv(c: &Conv, src: &Tensor) -> Tensor {
    let mut out = Tensor::zeros(src.w, src.h, c.out_channels);
    for y in 0..src.h {
        for x in 0..src.w {
            for o in 0..c.out_channels {
                let mut sum = f64::from(c.bias[o]);
                for i in 0..c.in_channels {
                    for tap in 0..9 {
                        let (sx, sy) = (x as i64 + (tap % 3) as i64 - 1, y as i64 + (tap / 3) as i64 - 1);
                        if sx >= 0 && sy >= 0 && (sx as usize) < src.w && (sy as usize) < src.h {
                            sum += f64::from(c.weight[(o * c.in_channels + i) * 9 + tap]) * f64::from(src.at(sx as usize, sy as usize, i));
                        }
                    }
                }
                out.data[(y * src.w + x) * c.out_channels + o] = if c.relu { sum.max(0.0) as f32 } else { sum as f32 };
            }
        }
    }
    out
}

fn pool(src: &Tensor) -> Tensor {
    let mut out = Tensor::zeros(src.w / 2, src.h / 2, src.c);
    for y in 0..out.h {
        for x in 0..out.w {
            for c in 0..src.c {
                let m = [(0, 0), (1, 0), (0, 1), (1, 1)].iter().map(|(dx, dy)| src.at(2 * x + dx, 2 * y + dy, c)).fold(f32::NEG_INFINITY, f32::max);
                out.data[(y * out.w + x) * src.c + c] = m;
            }
        }
    }
    out
}

fn upsample(src: &Tensor) -> Tensor {
    let mut out = Tensor::zeros(src.w * 2, src.h * 2, src.c);
    for y in 0..out.h {
        for x in 0..out.w {
            for c in 0..src.c {
                out.data[(y * out.w + x) * src.c + c] = src.at(x / 2, y / 2, c);
            }
        }
    }
    out
}

fn concat(a: &Tensor, b: &Tensor) -> Tensor {
    let mut out = Tensor::zeros(a.w, a.h, a.c + b.c);
    for p in 0..a.w * a.h {
        out.data[p * out.c..p * out.c + a.c].copy_from_slice(&a.data[p * a.c..(p + 1) * a.c]);
        out.data[p * out.c + a.c..(p + 1) * out.c].copy_from_slice(&b.data[p * b.c..(p + 1) * b.c]);
    }
    out
}

/// Every tensor of the network, by id, each rounded to f16 when stored so.
fn run_network(net: &Network, input: Tensor, f16: bool) -> Vec<Tensor> {
    let mut tensors: Vec<Option<Tensor>> = vec![None; net.tensors.len()];
    tensors[net.input.0] = Some(input.stored(f16));
    for op in &net.ops {
        let get = |id: TensorId| tensors[id.0].as_ref().expect("made before");
        let t = match op {
            Op::Conv(c) => conv(c, get(c.src)),
            Op::Pool { src, .. } => pool(get(*src)),
            Op::Upsample { src, .. } => upsample(get(*src)),
            Op::Concat { first, second, .. } => concat(get(*first), get(*second)),
        };
        tensors[op.dst().0] = Some(t.stored(f16));
    }
    tensors.into_iter().map(|t| t.expect("every tensor is made")).collect()
}

// The GPU side: the passes in a frame of their own, after a copy pass that
// stands in for the path tracer.

/// What a test frame is made of.
struct Setup {
    hdr: bool,
    f16: bool,
    fused: bool,
}

fn scene(s: &Setup, w: usize, h: usize) -> Scene {
    let text = format!(
        "[output]\nwidth = {w}\nheight = {h}\n[quality]\nrenderer = \"path\"\ndenoiser_fused = {}\n\
         [denoiser]\nweights = \"w.tza\"\nprecision = \"{}\"\nmode = \"{}\"\n",
        s.fused,
        if s.f16 { "f16" } else { "f32" },
        if s.hdr { "hdr" } else { "ldr" },
    );
    crate::scene::parse("denoise.toml", &text).unwrap_or_else(|d| panic!("{d}"))
}

/// The path tracer's images: colour (`Rgba32Float`), albedo and normal
/// (`Rgba16Float`, so the values are rounded to f16 here already).
fn images(w: usize, h: usize, hdr: bool, seed: u64) -> [Image; 3] {
    let mut rng = Rng(seed);
    let mut color: Vec<[f32; 3]> = (0..w * h)
        .map(|_| [(); 3].map(|_| if hdr { (rng.signed() * 4.0).exp2() * 3.0 } else { rng.signed() * 0.6 + 0.55 }))
        .collect();
    // Bad values the input processing must sanitise: NaN to 0, and in LDR
    // Inf clamped to 1 (in HDR it would make the autoexposure's mean Inf).
    color[3] = [f32::NAN, 0.5, 0.5];
    if !hdr {
        color[5] = [f32::INFINITY, 0.5, 0.5];
    }
    let f16 = |v: f32| half::f16::from_f32(v).to_f32();
    let albedo = (0..w * h).map(|_| [(); 3].map(|_| f16(rng.signed() * 0.6 + 0.5))).collect();
    let normal = (0..w * h).map(|_| [(); 3].map(|_| f16(rng.signed() * 1.1))).collect();
    [Image { w, h, data: color }, Image { w, h, data: albedo }, Image { w, h, data: normal }]
}

fn texture(gpu: &crate::gpu::Gpu, format: wgpu::TextureFormat, image: &Image) -> Arc<wgpu::Texture> {
    let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test input"),
        size: wgpu::Extent3d { width: image.w as u32, height: image.h as u32, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let bytes: Vec<u8> = if format == COLOR {
        image.data.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).flat_map(f32::to_le_bytes).collect()
    } else {
        image.data.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).flat_map(|v| half::f16::from_f32(v).to_le_bytes()).collect()
    };
    let texel = if format == COLOR { 16 } else { 8 };
    gpu.queue.write_texture(
        t.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(image.w as u32 * texel), rows_per_image: Some(image.h as u32) },
        t.size(),
    );
    Arc::new(t)
}

/// A session rendering only the denoiser's passes over `images`, and the
/// culled passes with their reasons.
fn gpu_session(net: Network, s: &Setup, images: &[Image; 3]) -> (Session, Vec<(String, String)>) {
    let (w, h) = (images[0].w, images[0].h);
    let scene = scene(s, w, h);
    let network = Arc::new(net);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let lib = crate::shader::library::read_tree(&root).unwrap();
    let loaded = crate::scene::Loaded { scene: scene.clone(), meshes: Default::default(), denoiser: Some(network.clone()), files: vec![] };
    let gpu = crate::gpu::testing::device();
    let sources = [texture(&gpu, COLOR, &images[0]), texture(&gpu, HDR, &images[1]), texture(&gpu, HDR, &images[2])];
    let mut session = Session::new(gpu, &root, lib, &loaded);

    let mut g = GraphBuilder::new();
    let mut p = g.pass("source", PassKind::Copy);
    let (w32, h32) = (w as u32, h as u32);
    let color = p.create("color", TextureDesc::d2(COLOR, w32, h32), Access::CopyDst);
    let albedo = p.create("albedo", TextureDesc::d2(HDR, w32, h32), Access::CopyDst);
    let normal = p.create("normal", TextureDesc::d2(HDR, w32, h32), Access::CopyDst);
    let samples = p.create("samples", TextureDesc::d2(SAMPLES, w32, h32), Access::CopyDst);
    p.execute(move |ctx| {
        for (from, to) in sources.iter().zip([color, albedo, normal]) {
            ctx.encoder.copy_texture_to_texture(from.as_image_copy(), ctx.texture(to).as_image_copy(), from.size());
        }
    });
    let traced = Traced { color, albedo, normal, samples };
    let out = denoise(&mut g, &scene, Some(&network), &traced);
    g.output(out);
    let graph = g.build();
    let culled = graph.culled.iter().map(|c| (c.name.clone(), c.reason.clone())).collect();
    session.use_graph(graph);
    assert_eq!(session.install_missing(), vec![], "the denoiser's shaders build");
    (session, culled)
}

/// One frame, everything captured.
fn frame(session: &mut Session) -> FrameResult {
    let pending = session.submit(None, 1.0 / 30.0);
    let r = session.wait(pending);
    assert_eq!(session.take_uncaptured(), Vec::<String>::new());
    assert_eq!(r.skipped, Vec::<String>::new(), "every pass ran");
    r
}

fn captured<'r>(r: &'r FrameResult, key: &str) -> &'r CapturedTensor {
    r.tensors.iter().find(|t| t.key() == key).unwrap_or_else(|| panic!("{key} is not captured: {:?}", r.tensors.iter().map(|t| t.key()).collect::<Vec<_>>()))
}

/// The GPU's padded tensor against the CPU's: its padding lanes are 0; the
/// largest difference relative to the CPU tensor's largest magnitude.
fn difference(gpu: &CapturedTensor, cpu: &Tensor, what: &str) -> f32 {
    let dims: Vec<u32> = gpu.layout.dims.iter().map(|(_, n)| *n).collect();
    let padded = blocks(cpu.c) * BLOCK;
    assert_eq!(dims, [cpu.h as u32, cpu.w as u32, padded as u32], "{what}: shape");
    let (mut worst, mut peak) = (0.0f32, 1e-6f32);
    for p in 0..cpu.w * cpu.h {
        for c in 0..padded {
            let got = gpu.data[p * padded + c];
            if c >= cpu.c {
                assert_eq!(got, 0.0, "{what}: padding lane {c} of pixel {p}");
                continue;
            }
            let want = cpu.data[p * cpu.c + c];
            assert!(got.is_finite() == want.is_finite(), "{what}: pixel {p} channel {c}: {got} against {want}");
            if want.is_finite() {
                worst = worst.max((got - want).abs());
                peak = peak.max(want.abs());
            }
        }
    }
    worst / peak
}

/// Peak signal to noise ratio of `a` against the reference `b`, in dB; the
/// peak is 1, or the reference's largest value where that is larger (HDR).
fn psnr(a: &[f32], b: &[f32]) -> f64 {
    let mse = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>() / a.len() as f64;
    let peak = b.iter().fold(1.0f32, |m, v| m.max(v.abs()));
    10.0 * (f64::from(peak).powi(2) / mse).log10()
}

/// Runs `net` on the GPU and on the CPU over the same images; checks every
/// tensor the GPU stored and the denoised colour; returns the GPU's colour
/// and the CPU's (RGB).
fn compare(net: Network, s: &Setup, images: &[Image; 3], tolerance: f32) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (images[0].w, images[0].h);
    let (mut session, culled) = gpu_session(net.clone(), s, images);
    let r = frame(&mut session);
    let scale = if s.hdr { autoexposure(&images[0]) } else { 1.0 };
    if s.hdr {
        let gpu_scale = captured(&r, "denoise_autoexposure/scale").data[0];
        assert!((gpu_scale - scale).abs() <= 1e-4 * scale, "input scale {gpu_scale}, expected {scale}");
    }
    let input = process_input(images, net.tensor(net.input).channels, s.hdr, scale, net.alignment());
    let cpu = run_network(&net, input, s.f16);
    for (id, t) in net.tensors.iter().enumerate() {
        let pass = if id == net.input.0 { "denoise_input".to_owned() } else { format!("denoise.{}", t.name) };
        let stored = r.tensors.iter().find(|c| c.key() == format!("{pass}/tensor"));
        if s.fused && (t.name.starts_with("upsample") || t.name.starts_with("concat")) {
            assert!(stored.is_none(), "{pass} is fused: its tensor is never stored");
            let reason = culled.iter().find(|(n, _)| *n == pass).map(|(_, r)| r.as_str()).unwrap_or_default();
            assert!(reason.starts_with("fused into denoise.dec_conv") && reason.ends_with("(quality.denoiser_fused)"), "{pass}: {reason:?}");
            continue;
        }
        let gpu = stored.unwrap_or_else(|| panic!("{pass}/tensor is captured"));
        let d = difference(gpu, &cpu[id], &pass);
        assert!(d <= tolerance, "{pass}: the GPU differs from the CPU by {d} of the tensor's largest value (tolerance {tolerance})");
    }
    let want = process_output(&cpu[net.output.0], w, h, s.hdr, scale);
    let got = r.captures.iter().find(|c| c.key() == "denoise/color").expect("the denoised colour is captured");
    assert_eq!((got.width as usize, got.height as usize), (w, h), "cropped to the image");
    let got_rgb: Vec<f32> = (0..w * h).flat_map(|i| got.data[i * 4..i * 4 + 3].to_vec()).collect();
    let want_rgb: Vec<f32> = want.iter().flatten().copied().collect();
    assert!(got.data.chunks(4).all(|p| p[3] == 1.0), "alpha is 1");
    (got_rgb, want_rgb)
}

/// OIDN's base U-Net's layers at small, distinct widths, random weights;
/// a size that is not a multiple of 16 (padded 48×32). Every tensor, the
/// input scale and the denoised colour match the CPU, whether upsample
/// and concatenation are fused into the convolution or stored, in HDR and
/// LDR, with f32 and f16 storage.
#[test]
fn the_network_on_the_gpu_matches_the_cpu_tensor_by_tensor() {
    let net = crate::denoise::testing::network(&small_unet(9), 7);
    for (hdr, f16, fused) in [(true, false, true), (true, false, false), (false, false, true), (false, true, false), (true, true, true)] {
        let s = Setup { hdr, f16, fused };
        let images = images(37, 21, hdr, 11);
        // f32: sums in another order than the CPU's f64. f16: a value on
        // the other side of a rounding boundary moves by an f16 ulp and
        // carries through the layers after it.
        let tolerance = if f16 { 5e-3 } else { 1e-5 };
        let (gpu, cpu) = compare(net.clone(), &s, &images, tolerance);
        let db = psnr(&gpu, &cpu);
        let floor = if f16 { 40.0 } else { 80.0 };
        assert!(db >= floor, "hdr {hdr}, f16 {f16}, fused {fused}: the denoised colour is {db:.1} dB from the CPU's");
    }
}

/// OIDN's own weights (its base U-Net for LDR colour, albedo and normal):
/// the denoised colour at least 60 dB from the CPU's with f32 tensors;
/// with f16 tensors every layer within 1 % of the CPU's f16 evaluation,
/// and the colour's distance to the f32 result is reported.
#[test]
fn oidn_weights_on_the_gpu_match_the_cpu() {
    let path = crate::denoise::testing::weights("rt_ldr_alb_nrm.tza");
    let archive = crate::denoise::tza::read(&path, "rt_ldr_alb_nrm.tza").unwrap_or_else(|d| panic!("{d}"));
    let net = Network::from_archive(&archive).unwrap();
    let images = images(40, 24, false, 5);
    let (gpu, cpu) = compare(net.clone(), &Setup { hdr: false, f16: false, fused: true }, &images, 1e-5);
    let db = psnr(&gpu, &cpu);
    assert!(db >= 60.0, "f32: {db:.1} dB");
    let (gpu16, cpu16) = compare(net, &Setup { hdr: false, f16: true, fused: true }, &images, 1e-2);
    let (db16, db16_f32) = (psnr(&gpu16, &cpu16), psnr(&gpu16, &cpu));
    eprintln!("rt_ldr_alb_nrm at 40×24, GPU against CPU: f32 {db:.1} dB; f16 {db16:.1} dB against the CPU's f16, {db16_f32:.1} dB against its f32");
    assert!(db16 >= 40.0 && db16_f32 >= 40.0, "f16: {db16:.1} dB, {db16_f32:.1} dB");
}

/// With f16 storage a convolution counts the values beyond 65504 before
/// the store, every frame from zero, and stores them as Inf; f32 storage
/// has nothing to count.
#[test]
fn f16_overflow_is_counted_per_layer_and_stored_as_inf() {
    let mut net = crate::denoise::testing::network(&small_unet(9), 7);
    let Op::Conv(first) = &mut net.ops[0] else { panic!("the network starts with a convolution") };
    assert_eq!(first.name, "enc_conv0");
    // Channel 0 of every pixel, padding included, is about 1e5.
    first.bias[0] = 1e5;
    let images = images(37, 21, false, 3);
    let padded = 48 * 32;
    let (mut session, _) = gpu_session(net.clone(), &Setup { hdr: false, f16: true, fused: true }, &images);
    for _ in 0..2 {
        let r = frame(&mut session);
        assert_eq!(captured(&r, "denoise.enc_conv0/overflow").data, [padded as f32], "one per padded pixel, counted again each frame");
        let t = captured(&r, "denoise.enc_conv0/tensor");
        assert_eq!((t.stats.inf, t.stats.nan), (padded, 0), "channel 0 is stored as Inf, the others as they are");
        assert!(r.tensors.iter().all(|t| t.key() != "denoise.pool1/overflow"), "a pool makes no new values: nothing to count");
    }
    let (mut session, _) = gpu_session(net, &Setup { hdr: false, f16: false, fused: true }, &images);
    let r = frame(&mut session);
    assert!(r.tensors.iter().all(|t| t.output != "overflow"), "f32 storage counts nothing");
    let t = captured(&r, "denoise.enc_conv0/tensor");
    assert_eq!(t.stats.inf, 0);
    assert!(t.stats.max[0] > 9e4, "{:?}", t.stats.max);
}
