//! The denoiser's passes on the device (lavapipe without a GPU), fed known
//! colour, albedo and normal images, against the CPU reference
//! (`denoise::process` around `denoise::cpu`), every tensor compared.

use std::sync::Arc;

use super::*;
use crate::scene::settings::DenoiseAt;
use crate::denoise::cpu::{self, Tensor};
use crate::denoise::image::Image;
use crate::denoise::process::{self, Mode};
use crate::denoise::testing::{Rng, small_unet};
use crate::gpu::pipeline::HDR;
use crate::render::capture::CapturedTensor;
use crate::render::denoise_weights::BLOCK;
use crate::render::frame::FrameResult;
use crate::render::session::Session;
use crate::scene::DenoiserKernel;

// The GPU side: the passes in a frame of their own, after a copy pass that
// stands in for the path tracer.

/// What a test frame is made of.
struct Setup {
    hdr: bool,
    f16: bool,
    fused: bool,
    /// `quality.denoiser_kernel`.
    kernel: &'static str,
}

fn scene(s: &Setup, w: usize, h: usize) -> Scene {
    let text = format!(
        "[output]\nwidth = {w}\nheight = {h}\n[quality]\nrenderer = \"path\"\ndenoiser_fused = {}\ndenoiser_kernel = \"{}\"\n\
         [denoiser]\nweights = \"w.tza\"\nprecision = \"{}\"\nmode = \"{}\"\n",
        s.fused,
        s.kernel,
        if s.f16 { "f16" } else { "f32" },
        if s.hdr { "hdr" } else { "ldr" },
    );
    crate::scene::parse("denoise.toml", &text).unwrap_or_else(|d| panic!("{d}"))
}

/// The path tracer's images: colour (`Rgba32Float`), albedo and normal
/// (`Rgba16Float`, so the values are rounded to f16 here already).
fn images(w: usize, h: usize, hdr: bool, seed: u64) -> [Image; 3] {
    let mut rng = Rng(seed);
    let mut color: Vec<f32> = (0..w * h * 3).map(|_| if hdr { (rng.signed() * 4.0).exp2() * 3.0 } else { rng.signed() * 0.6 + 0.55 }).collect();
    // Bad values the input processing must sanitise: NaN to 0, and in LDR
    // Inf clamped to 1 (in HDR it would make the autoexposure's mean Inf).
    color[9] = f32::NAN;
    if !hdr {
        color[15] = f32::INFINITY;
    }
    let f16 = |v: f32| half::f16::from_f32(v).to_f32();
    let albedo = (0..w * h * 3).map(|_| f16(rng.signed() * 0.6 + 0.5)).collect();
    let normal = (0..w * h * 3).map(|_| f16(rng.signed() * 1.1)).collect();
    [color, albedo, normal].map(|data| Image { width: w, height: h, data })
}

fn texture(gpu: &crate::gpu::Gpu, format: wgpu::TextureFormat, image: &Image) -> Arc<wgpu::Texture> {
    let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test input"),
        size: wgpu::Extent3d { width: image.width as u32, height: image.height as u32, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let rgba = image.data.chunks(3).flat_map(|p| [p[0], p[1], p[2], 1.0]);
    let bytes: Vec<u8> = if format == COLOR { rgba.flat_map(f32::to_le_bytes).collect() } else { rgba.flat_map(|v| half::f16::from_f32(v).to_le_bytes()).collect() };
    let texel = if format == COLOR { 16 } else { 8 };
    gpu.queue.write_texture(
        t.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(image.width as u32 * texel), rows_per_image: Some(image.height as u32) },
        t.size(),
    );
    Arc::new(t)
}

/// A session rendering only the denoiser's passes over `images`, and the
/// culled passes with their reasons.
fn gpu_session(net: Network, s: &Setup, images: &[Image; 3]) -> (Session, Vec<(String, String)>) {
    let (w, h) = (images[0].width, images[0].height);
    gpu_session_with(net, scene(s, w, h), std::slice::from_ref(images))
}

/// The same for `scene`, the frame's images the sets of `sets` in turn
/// (frame 1 the first).
fn gpu_session_with(net: Network, scene: Scene, sets: &[[Image; 3]]) -> (Session, Vec<(String, String)>) {
    let (w, h) = (sets[0][0].width, sets[0][0].height);
    let network = Arc::new(net);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let lib = crate::shader::library::read_tree(&root).unwrap();
    let loaded = crate::loaded::Loaded { scene: scene.clone(), meshes: Default::default(), materials: crate::loaded::materials_of(&scene), denoiser: Some(network.clone()), files: vec![], reports: Default::default(), warnings: vec![] };
    let gpu = crate::gpu::testing::device();
    let sources: Vec<[Arc<wgpu::Texture>; 3]> = sets.iter().map(|i| [texture(&gpu, COLOR, &i[0]), texture(&gpu, HDR, &i[1]), texture(&gpu, HDR, &i[2])]).collect();
    let mut session = Session::new(gpu, &root, lib, &loaded);

    let mut g = GraphBuilder::new();
    let mut p = g.pass("source", PassKind::Copy);
    let (w32, h32) = (w as u32, h as u32);
    let color = p.create("color", Meaning::Color, TextureDesc::d2(COLOR, w32, h32), Access::CopyDst);
    let albedo = p.create("albedo", Meaning::Color, TextureDesc::d2(HDR, w32, h32), Access::CopyDst);
    let normal = p.create("normal", Meaning::Normal, TextureDesc::d2(HDR, w32, h32), Access::CopyDst);
    p.execute(move |ctx| {
        let set = &sources[(ctx.frame as usize - 1) % sources.len()];
        for (from, to) in set.iter().zip([color, albedo, normal]) {
            ctx.encoder.copy_texture_to_texture(from.as_image_copy(), ctx.texture(to).as_image_copy(), from.size());
        }
    });
    let traced = Noisy { color, albedo, normal };
    let out = denoise(&mut g, &scene, Some(&network), &traced, None);
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
    let padded = blocks(cpu.channels) * BLOCK;
    assert_eq!(dims, [cpu.height as u32, cpu.width as u32, padded as u32], "{what}: shape");
    let (mut worst, mut peak) = (0.0f32, 1e-6f32);
    for p in 0..cpu.width * cpu.height {
        for c in 0..padded {
            let got = gpu.data[p * padded + c];
            if c >= cpu.channels {
                assert_eq!(got, 0.0, "{what}: padding lane {c} of pixel {p}");
                continue;
            }
            let want = cpu.data[p * cpu.channels + c];
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
    let (w, h) = (images[0].width, images[0].height);
    let (mut session, culled) = gpu_session(net.clone(), s, images);
    let r = frame(&mut session);
    let mode = if s.hdr { Mode::Hdr } else { Mode::Ldr };
    let scale = process::input_scale(mode, None, &images[0]);
    if s.hdr {
        let gpu_scale = captured(&r, "denoise_autoexposure/scale").data[0];
        assert!((gpu_scale - scale).abs() <= 1e-4 * scale, "input scale {gpu_scale}, expected {scale}");
    }
    let input = process::input(&images[0], Some(&images[1]), Some(&images[2]), mode, scale, net.alignment());
    let cpu = cpu::run_all(&net, input, if s.f16 { Precision::F16 } else { Precision::F32 });
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
    let want = process::output(&cpu[net.output.0], w, h, mode, scale);
    let got = r.captures.iter().find(|c| c.key() == "denoise/color").expect("the denoised colour is captured");
    assert_eq!((got.width as usize, got.height as usize), (w, h), "cropped to the image");
    let got_rgb: Vec<f32> = (0..w * h).flat_map(|i| got.data[i * 4..i * 4 + 3].to_vec()).collect();
    assert!(got.data.chunks(4).all(|p| p[3] == 1.0), "alpha is 1");
    (got_rgb, want.data)
}

/// Every setup: each convolution kernel, HDR and LDR, f32 and f16
/// storage, upsample and concatenation fused or stored.
fn setups() -> impl Iterator<Item = Setup> {
    DenoiserKernel::NAMES.iter().flat_map(|&kernel| (0..8).map(move |i| Setup { hdr: i & 1 != 0, f16: i & 2 != 0, fused: i & 4 != 0, kernel }))
}

/// OIDN's base U-Net's layers at small, distinct widths, random weights;
/// a size that is not a multiple of 16 (padded 48×32). Every tensor, the
/// input scale and the denoised colour match the CPU in every setup.
#[test]
fn the_network_on_the_gpu_matches_the_cpu_tensor_by_tensor() {
    let net = crate::denoise::testing::network(&small_unet(9), 7);
    for s in setups() {
        let Setup { hdr, f16, fused, kernel } = s;
        let images = images(37, 21, hdr, 11);
        // f32: sums in another order than the CPU's f64. f16: a value on
        // the other side of a rounding boundary moves by an f16 ulp and
        // carries through the layers after it.
        let tolerance = if f16 { 5e-3 } else { 1e-5 };
        let (gpu, cpu) = compare(net.clone(), &s, &images, tolerance);
        let db = psnr(&gpu, &cpu);
        let floor = if f16 { 40.0 } else { 80.0 };
        assert!(db >= floor, "{kernel}, hdr {hdr}, f16 {f16}, fused {fused}: the denoised colour is {db:.1} dB from the CPU's");
    }
}

/// OIDN's own weights (its base U-Net for LDR colour, albedo and normal),
/// with each convolution kernel: the denoised colour at least 60 dB from
/// the CPU's with f32 tensors; with f16 tensors every layer within 1 % of
/// the CPU's f16 evaluation, and the colour's distance to the f32 result
/// is reported.
#[test]
fn oidn_weights_on_the_gpu_match_the_cpu() {
    let path = crate::denoise::testing::weights("rt_ldr_alb_nrm.tza");
    let archive = crate::denoise::tza::read(&path, "rt_ldr_alb_nrm.tza").unwrap_or_else(|d| panic!("{d}"));
    let net = Network::from_archive(&archive).unwrap();
    let images = images(40, 24, false, 5);
    for &kernel in DenoiserKernel::NAMES {
        let (gpu, cpu) = compare(net.clone(), &Setup { hdr: false, f16: false, fused: true, kernel }, &images, 1e-5);
        let db = psnr(&gpu, &cpu);
        assert!(db >= 60.0, "{kernel}, f32: {db:.1} dB");
        let (gpu16, cpu16) = compare(net.clone(), &Setup { hdr: false, f16: true, fused: true, kernel }, &images, 1e-2);
        let (db16, db16_f32) = (psnr(&gpu16, &cpu16), psnr(&gpu16, &cpu));
        eprintln!("rt_ldr_alb_nrm at 40×24, {kernel} kernel, GPU against CPU: f32 {db:.1} dB; f16 {db16:.1} dB against the CPU's f16, {db16_f32:.1} dB against its f32");
        assert!(db16 >= 40.0 && db16_f32 >= 40.0, "{kernel}, f16: {db16:.1} dB, {db16_f32:.1} dB");
    }
}

/// With f16 storage a convolution counts the values beyond 65504 before
/// the store, every frame from zero, and stores them as Inf; f32 storage
/// has nothing to count. Each convolution kernel.
#[test]
fn f16_overflow_is_counted_per_layer_and_stored_as_inf() {
    let mut net = crate::denoise::testing::network(&small_unet(9), 7);
    let Op::Conv(first) = &mut net.ops[0] else { panic!("the network starts with a convolution") };
    assert_eq!(first.name, "enc_conv0");
    // Channel 0 of every pixel, padding included, is about 1e5.
    first.bias[0] = 1e5;
    let images = images(37, 21, false, 3);
    let padded = 48 * 32;
    for &kernel in DenoiserKernel::NAMES {
        let (mut session, _) = gpu_session(net.clone(), &Setup { hdr: false, f16: true, fused: true, kernel }, &images);
        for _ in 0..2 {
            let r = frame(&mut session);
            assert_eq!(captured(&r, "denoise.enc_conv0/overflow").data, [padded as f32], "{kernel}: one per padded pixel, counted again each frame");
            let t = captured(&r, "denoise.enc_conv0/tensor");
            assert_eq!((t.stats.inf, t.stats.nan), (padded, 0), "{kernel}: channel 0 is stored as Inf, the others as they are");
            assert!(r.tensors.iter().all(|t| t.key() != "denoise.pool1/overflow"), "a pool makes no new values: nothing to count");
        }
        let (mut session, _) = gpu_session(net.clone(), &Setup { hdr: false, f16: false, fused: true, kernel }, &images);
        let r = frame(&mut session);
        assert!(r.tensors.iter().all(|t| t.output != "overflow"), "f32 storage counts nothing");
        let t = captured(&r, "denoise.enc_conv0/tensor");
        assert_eq!(t.stats.inf, 0);
        assert!(t.stats.max[0] > 9e4, "{kernel}: {:?}", t.stats.max);
    }
}

/// A frame whose largest tensor the device cannot bind in one buffer is
/// not denoised, and every denoiser pass says why, naming the tensor; a
/// larger limit denoises it.
#[test]
fn a_tensor_larger_than_the_device_binds_culls_the_denoiser_with_the_reason() {
    let net = crate::denoise::testing::network(&small_unet(9), 7);
    let scene = scene(&Setup { hdr: true, f16: false, fused: true, kernel: "direct" }, 64, 48);
    // The largest tensor made: the input, 9 channels padded to 12, f32.
    let input = 64 * 48 * 12 * 4;
    for (limit, denoised) in [(input - 4, false), (input, true)] {
        let mut g = GraphBuilder::new();
        let mut p = g.pass("source", PassKind::Copy);
        let [color, albedo, normal] = [("color", Meaning::Color), ("albedo", Meaning::Color), ("normal", Meaning::Normal)].map(|(n, m)| p.create(n, m, TextureDesc::d2(COLOR, 64, 48), Access::CopyDst));
        p.execute(|_| {});
        let out = denoise(&mut g, &scene, Some(&net), &Noisy { color, albedo, normal }, Some(limit));
        assert_eq!(out != color, denoised, "limit {limit}");
        g.output(out);
        let graph = g.build();
        let live: Vec<&str> = graph.passes.iter().map(|p| p.name.as_str()).filter(|n| n.starts_with("denoise")).collect();
        assert_eq!(live.is_empty(), !denoised, "{live:?}");
        if !denoised {
            for pass in PASSES {
                let reason = &graph.culled.iter().find(|c| c.name == pass).expect("culled").reason;
                assert!(reason.starts_with("the denoiser's tensor input would take 0.1 MiB at 64×48, more than the device binds in one buffer"), "{pass}: {reason}");
            }
        }
    }
}

/// `quality.denoise` off: the noisy colour goes on, every denoiser pass
/// culled with the reason.
#[test]
fn the_denoise_switch_culls_the_denoiser_with_the_reason() {
    let net = crate::denoise::testing::network(&small_unet(9), 7);
    let mut scene = scene(&Setup { hdr: true, f16: false, fused: true, kernel: "direct" }, 64, 48);
    for on in [true, false] {
        scene.quality.denoise = on;
        let mut g = GraphBuilder::new();
        let mut p = g.pass("source", PassKind::Copy);
        let [color, albedo, normal] = [("color", Meaning::Color), ("albedo", Meaning::Color), ("normal", Meaning::Normal)].map(|(n, m)| p.create(n, m, TextureDesc::d2(COLOR, 64, 48), Access::CopyDst));
        p.execute(|_| {});
        let out = denoise(&mut g, &scene, Some(&net), &Noisy { color, albedo, normal }, None);
        assert_eq!(out == color, !on);
        g.output(out);
        let graph = g.build();
        let culled = graph.culled.iter().filter(|c| c.reason == "quality.denoise is off").count();
        assert_eq!(culled, if on { 0 } else { PASSES.len() });
    }
}

/// `quality.denoise_at`: at doublings the denoiser runs at 1, 2, 4, …
/// samples, and on the frames between its output keeps the newest
/// denoised image; at every sample it runs each frame. The images change
/// every frame (A, B, A), so the third frame's output tells which.
#[test]
fn the_denoiser_runs_at_doublings_of_the_samples_and_keeps_its_image_between() {
    let net = crate::denoise::testing::network(&small_unet(9), 7);
    let (w, h) = (24, 16);
    let sets = [images(w, h, false, 1), images(w, h, false, 2)];
    for (at, between) in [(DenoiseAt::Doublings, 1), (DenoiseAt::Every, 0)] {
        let mut scene = scene(&Setup { hdr: false, f16: false, fused: true, kernel: "direct" }, w, h);
        scene.quality.denoise_at = at;
        let (mut session, _) = gpu_session_with(net.clone(), scene, &sets);
        assert_eq!(session.install_missing(), vec![]);
        let outputs: Vec<Vec<f32>> = (0..3).map(|_| frame(&mut session).captures.into_iter().find(|c| c.key() == "denoise/color").expect("captured").data).collect();
        assert!(outputs[0] != outputs[1], "images A and B denoise differently");
        assert!(outputs[2] == outputs[between], "{at:?}: the third frame (3 samples) does not show frame {}'s image", between + 1);
    }
}
