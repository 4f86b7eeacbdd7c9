//! `loupe denoise`: OIDN's `oidnDenoise` on loupe's network. Until the GPU
//! network lands it runs the CPU reference.
//!
//! Files are treated as `oidnDenoise` treats them (`apps/oidnDenoise.cpp`,
//! `apps/utils/image_io.cpp`): PFM and EXR hold linear values; a PNG colour
//! is sRGB-decoded on reading and the output PNG encoded on writing, unless
//! `--srgb` says the network is to see the encoded values; a PNG albedo is
//! always decoded; normals are read as stored.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::image::{self, Format, Image};
use super::network::{Inputs, Network};
use super::process::{self, Mode, Transfer};
use super::{Precision, cpu, tza};
use crate::diag::{Code, Diagnostic, Location};

pub struct Job {
    pub weights: PathBuf,
    pub color: PathBuf,
    pub albedo: Option<PathBuf>,
    pub normal: Option<PathBuf>,
    pub mode: Mode,
    /// `None`: OIDN's default (autoexposure in HDR, else 1).
    pub input_scale: Option<f32>,
    pub precision: Precision,
    pub output: PathBuf,
    /// Where every tensor of the network goes as `<name>.npy`.
    pub dump_tensors: Option<PathBuf>,
}

/// What was done, for the command's summary line.
#[derive(Debug)]
pub struct Report {
    pub width: usize,
    pub height: usize,
    pub inputs: Inputs,
    pub input_scale: f32,
    /// The network alone (pre- and post-processing excluded).
    pub network_seconds: f64,
    pub tensors_dumped: usize,
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

pub fn run(job: &Job) -> Result<Report, Diagnostic> {
    let weights = display(&job.weights);
    let archive = tza::read(&job.weights, &weights)?;
    let net = Network::from_archive(&archive).map_err(|e| e.diagnostic(&weights))?;
    let given = match (&job.albedo, &job.normal) {
        (None, None) => Inputs::Color,
        (Some(_), None) => Inputs::ColorAlbedo,
        (Some(_), Some(_)) => Inputs::ColorAlbedoNormal,
        (None, Some(normal)) => {
            let message = "a normal needs an albedo: OIDN's networks take colour, colour and albedo, or all three";
            return Err(Diagnostic::error(Code::Image, message).at(Location::file_start(&display(normal))));
        }
    };
    if given != net.inputs {
        return Err(Diagnostic::error(
            Code::Weights,
            format!("these weights take {}, but {} were given", net.inputs.describe(), given.describe()),
        )
        .at(Location::file_start(&weights)));
    }

    let color = read(&job.color, job.mode != Mode::LdrSrgb, None)?;
    let albedo = job.albedo.as_deref().map(|p| read(p, true, Some(&color))).transpose()?;
    let normal = job.normal.as_deref().map(|p| read(p, false, Some(&color))).transpose()?;

    let scale = process::input_scale(job.mode, job.input_scale, &color);
    let input = process::input(&color, albedo.as_ref(), normal.as_ref(), job.mode, scale, net.alignment());
    let start = Instant::now();
    let (out, tensors) = if job.dump_tensors.is_some() {
        let all = cpu::run_all(&net, input, job.precision);
        (all[net.output.0].clone(), all)
    } else {
        (cpu::run(&net, input, job.precision), Vec::new())
    };
    let network_seconds = start.elapsed().as_secs_f64();
    let mut denoised = process::output(&out, color.width, color.height, job.mode, scale);

    if job.mode != Mode::LdrSrgb && Format::of(&job.output) == Some(Format::Png) {
        denoised.data.iter_mut().for_each(|v| *v = Transfer::Srgb.forward(*v));
    }
    image::write(&job.output, &denoised)?;
    if let Some(dir) = &job.dump_tensors {
        dump(dir, &net, &tensors)?;
    }
    Ok(Report {
        width: color.width,
        height: color.height,
        inputs: net.inputs,
        input_scale: scale,
        network_seconds,
        tensors_dumped: tensors.len(),
    })
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

/// Every tensor as `<dir>/<name>.npy`, shaped (height, width, channels) of
/// the padded image.
fn dump(dir: &Path, net: &Network, tensors: &[cpu::Tensor]) -> Result<(), Diagnostic> {
    let io = |e: std::io::Error, path: &Path| {
        Diagnostic::error(Code::Io, format!("cannot write tensors: {e}")).at(Location::file_start(&display(path)))
    };
    std::fs::create_dir_all(dir).map_err(|e| io(e, dir))?;
    for (desc, t) in net.tensors.iter().zip(tensors) {
        let path = dir.join(format!("{}.npy", desc.name));
        std::fs::write(&path, crate::npy::encode(&[t.height, t.width, t.channels], &t.data)).map_err(|e| io(e, &path))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
