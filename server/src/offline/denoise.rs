//! `loupe denoise`: OIDN's `oidnDenoise` on loupe's network, on the GPU
//! (the frame's own denoiser passes, `on_gpu`) or on the CPU reference.
//!
//! Files are treated as `oidnDenoise` treats them (`apps/oidnDenoise.cpp`,
//! `apps/utils/image_io.cpp`): PFM and EXR hold linear values; a PNG colour
//! is sRGB-decoded on reading and the output PNG encoded on writing, unless
//! `--srgb` says the network is to see the encoded values; a PNG albedo is
//! always decoded; normals are read as stored.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::denoise::image::{self, Format, Image};
use crate::denoise::network::{Inputs, Network};
use crate::denoise::process::{self, Mode, Transfer};
use crate::denoise::{Precision, bundled, cpu, tza};
use crate::diag::{Code, Diagnostic, Location};
use crate::render::passes::images::TileImages;

mod on_gpu;

/// Where the network runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Device {
    /// The denoiser's WGSL passes, on the GPU wgpu opens (lavapipe when
    /// there is none).
    Gpu,
    /// The plain-Rust reference (`denoise::cpu`).
    Cpu,
}

pub struct Job {
    /// An OIDN .tza; `None`: the bundled network for `mode` that takes the
    /// inputs given (`bundled`).
    pub weights: Option<PathBuf>,
    pub color: PathBuf,
    pub albedo: Option<PathBuf>,
    pub normal: Option<PathBuf>,
    pub mode: Mode,
    /// `None`: OIDN's default (autoexposure in HDR, else 1).
    pub input_scale: Option<f32>,
    pub precision: Precision,
    pub output: PathBuf,
    /// Where every tensor of the network goes as `<name>.npy` (per tile,
    /// `tile<i>/<name>.npy`, when the GPU cut the image into tiles).
    pub dump_tensors: Option<PathBuf>,
    pub device: Device,
    /// The GPU's shaders (`shaders/` of the project).
    pub shader_root: PathBuf,
    /// The most memory one tile's tensors may take on the GPU.
    pub max_memory_mb: u64,
    /// The GPU's tile side instead of the largest that fits.
    pub tile: Option<u32>,
}

/// What was done, for the command's summary line.
#[derive(Debug)]
pub struct Report {
    pub width: usize,
    pub height: usize,
    pub inputs: Inputs,
    pub input_scale: f32,
    /// The network: on the CPU alone; on the GPU with its pre- and
    /// post-processing passes and the uploads and readbacks of its tiles.
    pub network_seconds: f64,
    pub tensors_dumped: usize,
    /// "the CPU reference", or the adapter.
    pub device: String,
    /// The GPU's tiles (1 on the CPU) and their window side.
    pub tiles: usize,
    pub window: Option<u32>,
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

pub fn run(job: &Job) -> Result<Report, Diagnostic> {
    let given = match (&job.albedo, &job.normal) {
        (None, None) => Inputs::Color,
        (Some(_), None) => Inputs::ColorAlbedo,
        (Some(_), Some(_)) => Inputs::ColorAlbedoNormal,
        (None, Some(normal)) => {
            let message = "a normal needs an albedo: OIDN's networks take colour, colour and albedo, or all three";
            return Err(Diagnostic::error(Code::Image, message).at(Location::file_start(&display(normal))));
        }
    };
    let (weights, net) = match &job.weights {
        Some(path) => {
            let weights = display(path);
            let net = Network::from_archive(&tza::read(path, &weights)?).map_err(|e| e.diagnostic(&weights))?;
            if given != net.inputs {
                return Err(Diagnostic::error(
                    Code::Weights,
                    format!("these weights take {}, but {} were given", net.inputs.describe(), given.describe()),
                )
                .at(Location::file_start(&weights)));
            }
            (weights, net)
        }
        None => {
            // Only colour with albedo alone has no bundled network: the albedo is what does not fit.
            let at = job.albedo.as_deref().map_or_else(|| display(&job.color), display);
            let b = bundled::weights(job.mode, given).map_err(|d| d.at(Location::file_start(&at)))?;
            (b.display(), b.network()?)
        }
    };

    let color = read(&job.color, job.mode != Mode::LdrSrgb, None)?;
    let albedo = job.albedo.as_deref().map(|p| read(p, true, Some(&color))).transpose()?;
    let normal = job.normal.as_deref().map(|p| read(p, false, Some(&color))).transpose()?;

    let scale = process::input_scale(job.mode, job.input_scale, &color);
    let mut report = Report {
        width: color.width,
        height: color.height,
        inputs: net.inputs,
        input_scale: scale,
        network_seconds: 0.0,
        tensors_dumped: 0,
        device: "the CPU reference".into(),
        tiles: 1,
        window: None,
    };
    let mut denoised = match job.device {
        Device::Cpu => {
            let input = process::input(&color, albedo.as_ref(), normal.as_ref(), job.mode, scale, net.alignment());
            let start = Instant::now();
            let (out, tensors) = if job.dump_tensors.is_some() {
                let all = cpu::run_all(&net, input, job.precision);
                (all[net.output.0].clone(), all)
            } else {
                (cpu::run(&net, input, job.precision), Vec::new())
            };
            report.network_seconds = start.elapsed().as_secs_f64();
            if let Some(dir) = &job.dump_tensors {
                let named =
                    net.tensors.iter().zip(&tensors).map(|(d, t)| (d.name.as_str(), [t.height, t.width, t.channels], t.data.clone()));
                report.tensors_dumped = dump(dir, named)?;
            }
            process::output(&out, color.width, color.height, job.mode, scale)
        }
        Device::Gpu => {
            let gpu = crate::gpu::open()
                .map_err(|e| Diagnostic::error(Code::DeviceMissing, format!("{e} (--device cpu runs the CPU reference)")))?;
            let settings = on_gpu::Settings {
                mode: job.mode,
                input_scale: scale,
                precision: job.precision,
                budget: job.max_memory_mb << 20,
                window: job.tile,
                keep_tensors: job.dump_tensors.is_some(),
            };
            let images = TileImages { color, albedo, normal };
            let done = on_gpu::denoise(gpu, &job.shader_root, Arc::new(net.clone()), &images, &settings)
                .map_err(|d| if d.code == Code::Weights { d.at(Location::file_start(&weights)) } else { d })?;
            (report.network_seconds, report.device, report.tiles, report.window) =
                (done.seconds, done.adapter, done.tiles.len(), Some(done.window));
            if let Some(dir) = &job.dump_tensors {
                let tiled = done.tiles.len() > 1;
                for (i, (_, tensors)) in done.tiles.iter().enumerate() {
                    let dir = if tiled { dir.join(format!("tile{i}")) } else { dir.clone() };
                    report.tensors_dumped += dump(&dir, tensors.iter().filter_map(|t| unpadded(&net, t)))?;
                }
            }
            done.image
        }
    };

    if job.mode != Mode::LdrSrgb && Format::of(&job.output) == Some(Format::Png) {
        denoised.data.iter_mut().for_each(|v| *v = Transfer::Srgb.forward(*v));
    }
    image::write(&job.output, &denoised)?;
    Ok(report)
}

/// A captured tensor of the network as (name, shape, values): its
/// channels without the padding to blocks of 4.
fn unpadded<'t>(net: &'t Network, t: &crate::render::capture::CapturedTensor) -> Option<(&'t str, [usize; 3], Vec<f32>)> {
    let name = if t.pass == "denoise_input" {
        &net.tensor(net.input).name
    } else {
        &net.tensors.iter().find(|d| Some(d.name.as_str()) == t.pass.strip_prefix("denoise."))?.name
    };
    let desc = net.tensors.iter().find(|d| d.name == *name)?;
    let [h, w, padded] = [0, 1, 2].map(|i| t.layout.dims.get(i).map_or(0, |d| d.1 as usize));
    if t.output != "tensor" || padded < desc.channels {
        return None;
    }
    let data = t.data.chunks(padded).flat_map(|px| px[..desc.channels].iter().copied()).collect();
    Some((name.as_str(), [h, w, desc.channels], data))
}

/// Reads an input image: a PNG sRGB-decoded when `decode_png`, and the
/// size checked against the colour's when `like` is given.
fn read(path: &Path, decode_png: bool, like: Option<&Image>) -> Result<Image, Diagnostic> {
    let name = display(path);
    let mut img = image::read(path, &name)?;
    if decode_png && Format::of(path) == Some(Format::Png) {
        img.data.iter_mut().for_each(|v| *v = Transfer::Srgb.inverse(*v));
    }
    if let Some(c) = like.filter(|c| (c.width, c.height) != (img.width, img.height)) {
        let message = format!("the image is {}×{}, but the colour is {}×{}", img.width, img.height, c.width, c.height);
        return Err(Diagnostic::error(Code::Image, message).at(Location::file_start(&name)));
    }
    Ok(img)
}

/// Every (name, shape, values) as `<dir>/<name>.npy`; how many.
fn dump<'a>(dir: &Path, tensors: impl Iterator<Item = (&'a str, [usize; 3], Vec<f32>)>) -> Result<usize, Diagnostic> {
    let io = |e: std::io::Error, path: &Path| {
        Diagnostic::error(Code::Io, format!("cannot write tensors: {e}")).at(Location::file_start(&display(path)))
    };
    std::fs::create_dir_all(dir).map_err(|e| io(e, dir))?;
    let mut n = 0;
    for (name, shape, data) in tensors {
        let path = dir.join(format!("{name}.npy"));
        std::fs::write(&path, crate::npy::encode(&shape, &data)).map_err(|e| io(e, &path))?;
        n += 1;
    }
    Ok(n)
}

#[cfg(test)]
mod tests;
