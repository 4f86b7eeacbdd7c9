//! `loupe denoise` on the GPU: the frame's own denoiser passes
//! (`render::passes::denoise`) in a session of their own, fed the images
//! a tile at a time (`render::denoise_graph`). Tiles are as large as the
//! device's buffer limits and the memory budget allow (`tiles`): one for
//! most images, several for very large ones, each window's pixels
//! uploaded, denoised and its inner pixels kept.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use crate::denoise::Precision;
use crate::denoise::image::Image;
use crate::denoise::network::Network;
use crate::denoise::process::Mode;
use crate::denoise::tiles::{self, Rect, Tile};
use crate::diag::{Code, Diagnostic, Location};
use crate::gpu::Gpu;
use crate::loaded::Loaded;
use crate::render::capture::CapturedTensor;
use crate::render::passes::images::TileImages;
use crate::render::session::Session;
use crate::scene::settings::DenoiseAt;
use crate::scene::{Denoiser, Renderer};

/// How the network runs, beyond the images.
pub struct Settings {
    pub mode: Mode,
    /// The whole image's input scale: every tile uses the same.
    pub input_scale: f32,
    pub precision: Precision,
    /// The most bytes one tile's tensors may take together.
    pub budget: u64,
    /// A window side to use instead of the largest that fits (a multiple
    /// of the network's alignment): to test the seams.
    pub window: Option<u32>,
    /// Keep every tensor, per tile: upsamples and concatenations are then
    /// separate passes, so that each is made.
    pub keep_tensors: bool,
}

/// The denoised image, and what it took.
pub struct Denoised {
    pub image: Image,
    /// Per tile, its window and every tensor (when `keep_tensors`).
    pub tiles: Vec<(Tile, Vec<CapturedTensor>)>,
    /// The window side the tiles were cut with.
    pub window: u32,
    pub adapter: String,
    /// From the first submission to the last readback.
    pub seconds: f64,
}

pub fn denoise(gpu: Gpu, shader_root: &Path, net: Arc<Network>, images: &TileImages, s: &Settings) -> Result<Denoised, Diagnostic> {
    let (w, h) = (images.color.width as u32, images.color.height as u32);
    let side = window(&net, &gpu.device.limits(), s)?;
    let overlap = tiles::overlap(&net);
    let plan = tiles::plan(w, h, side, overlap, net.alignment() as u32);

    let lib = crate::shader::library::read_tree(shader_root).map_err(|e| {
        Diagnostic::error(Code::Io, format!("cannot read the shaders: {e}")).at(Location::file_start(&shader_root.display().to_string()))
    })?;
    let mut scene = crate::scene::parse("loupe denoise", "").expect("the empty scene is valid");
    // The renderer the denoiser follows in a frame: its weights go to the GPU.
    scene.quality.renderer = Renderer::Path;
    scene.quality.denoiser_fused = !s.keep_tensors;
    // Every tile is a frame of its own, each to be denoised.
    scene.quality.denoise_at = DenoiseAt::Every;
    scene.denoiser = Some(Denoiser {
        weights: None,
        at: Location::file_start("loupe denoise"),
        precision: s.precision,
        mode: s.mode,
        input_scale: Some(s.input_scale),
    });
    let loaded = Loaded {
        scene: scene.clone(),
        meshes: Default::default(),
        materials: Default::default(),
        reports: Default::default(),
        denoiser: Some(net.clone()),
        files: vec![],
        warnings: vec![],
    };
    let adapter = gpu.adapter_name();
    let mut session = Session::new(gpu, shader_root, lib, &loaded);

    let mut out = Image { width: w as usize, height: h as usize, data: vec![0.0; (w * h * 3) as usize] };
    let mut kept = Vec::new();
    let wanted = ["denoise/color".to_owned()].into();
    let start = Instant::now();
    for tile in plan {
        let win = tile.window;
        let crop = |image: &Image| crop(image, win);
        let tile_images =
            TileImages { color: crop(&images.color), albedo: images.albedo.as_ref().map(crop), normal: images.normal.as_ref().map(crop) };
        (scene.width, scene.height) = (win.width, win.height);
        session.use_graph(crate::render::denoise_graph(&scene, &net, Arc::new(tile_images)));
        let errors = session.install_missing();
        if let Some(first) = errors.into_iter().next() {
            return Err(first);
        }
        let pending = session.submit((!s.keep_tensors).then_some(&wanted), 0.0);
        let r = session.wait(pending);
        if let Some(e) = session.take_uncaptured().into_iter().next().or(r.skipped.first().map(|p| format!("pass {p} did not run"))) {
            return Err(Diagnostic::error(Code::Gpu, format!("the device failed the denoiser: {e}")));
        }
        let color = r.captures.iter().find(|c| c.key() == "denoise/color").expect("the denoised colour is captured");
        let inner = tile.inner;
        for y in inner.y..inner.y + inner.height {
            for x in inner.x..inner.x + inner.width {
                let from = (((y - win.y) * win.width + (x - win.x)) * 4) as usize;
                let to = ((y * w + x) * 3) as usize;
                out.data[to..to + 3].copy_from_slice(&color.data[from..from + 3]);
            }
        }
        kept.push((tile, if s.keep_tensors { r.tensors } else { Vec::new() }));
    }
    Ok(Denoised { image: out, tiles: kept, window: side, adapter, seconds: start.elapsed().as_secs_f64() })
}

/// The tiles' window side: the one asked for, or the largest whose
/// tensors fit the device's buffer limits and the budget. Problems are
/// the weights' (their receptive field): the caller says where they are.
fn window(net: &Network, limits: &wgpu::Limits, s: &Settings) -> Result<u32, Diagnostic> {
    let overlap = tiles::overlap(net);
    let element = if s.precision == Precision::F16 { 2 } else { 4 };
    let max_binding = crate::gpu::largest_binding(limits);
    let fitting = tiles::window_side(net, element, max_binding, s.budget).map(|side| side.min(limits.max_texture_dimension_2d / 16 * 16));
    let Some(side) = s.window.or(fitting) else {
        let message = format!(
            "no tile fits the device: these weights see {overlap} pixels around each pixel, and a window of {} pixels a side needs more than the device's {} MiB per buffer or the {} MiB budget",
            2 * overlap + 16,
            max_binding >> 20,
            s.budget >> 20
        );
        return Err(Diagnostic::error(Code::Weights, message));
    };
    if side <= 2 * overlap {
        let message = format!(
            "a tile of {side} pixels is too small for these weights: they see {overlap} pixels around each pixel, so a tile must be more than {}",
            2 * overlap
        );
        return Err(Diagnostic::error(Code::Weights, message));
    }
    Ok(side)
}

fn crop(image: &Image, r: Rect) -> Image {
    let (x0, y0, w) = (r.x as usize, r.y as usize, r.width as usize);
    let data = (y0..y0 + r.height as usize).flat_map(|y| image.data[(y * image.width + x0) * 3..][..w * 3].iter().copied()).collect();
    Image { width: w, height: r.height as usize, data }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At 4096×4096 the tensors of OIDN's base network exceed what one
    /// buffer of this device or the default 2 GiB may hold, in f32 and in
    /// f16: the image is cut into tiles, each of whose tensors fit.
    #[test]
    fn a_4096_square_image_is_cut_into_tiles_that_fit_the_device() {
        let gpu = crate::gpu::testing::device();
        let path = crate::denoise::testing::weights("rt_ldr_alb_nrm.tza");
        let net = Network::from_archive(&crate::denoise::tza::read(&path, "w").unwrap()).unwrap();
        let limits = gpu.device.limits();
        let max_binding = crate::gpu::largest_binding(&limits);
        for precision in [Precision::F32, Precision::F16] {
            let s = Settings { mode: Mode::Hdr, input_scale: 1.0, precision, budget: 2048 << 20, window: None, keep_tensors: false };
            let element = if precision == Precision::F16 { 2 } else { 4 };
            let (all, largest) = tiles::window_bytes(&net, 4096, element);
            assert!(largest > max_binding || all > s.budget, "{precision:?}: 4096² fits whole ({all} bytes, {largest} the largest)");
            let side = window(&net, &limits, &s).unwrap();
            let (all, largest) = tiles::window_bytes(&net, side, element);
            assert!(largest <= max_binding && all <= s.budget);
            let plan = tiles::plan(4096, 4096, side, tiles::overlap(&net), 16);
            eprintln!(
                "{precision:?}: {} tiles of {side}² ({} MiB of tensors, the largest {} MiB; the device's limit {} MiB)",
                plan.len(),
                all >> 20,
                largest >> 20,
                max_binding >> 20
            );
            assert!(plan.len() > 1);
        }
    }
}
