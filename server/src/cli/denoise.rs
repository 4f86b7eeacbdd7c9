//! `loupe denoise`: OIDN's `oidnDenoise` on loupe's network.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{exit, print_diagnostics};
use loupe::denoise::process::Mode;
use loupe::diag::Code;
use loupe::offline::denoise::{self, Device, Job};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("range").required(true).args(["ldr", "hdr"])))]
pub struct Args {
    /// The weights: an OIDN .tza file whose network takes the inputs given
    /// [default: OIDN's network bundled with loupe for the range (--hdr or
    /// --ldr) and the inputs (colour, or colour, albedo and normal)].
    #[arg(long)]
    weights: Option<PathBuf>,
    /// The noisy colour.
    #[arg(long)]
    color: PathBuf,
    /// The albedo (first-hit surface colour), in [0, 1].
    #[arg(long)]
    albedo: Option<PathBuf>,
    /// The first-hit normal, in [-1, 1]; needs --albedo.
    #[arg(long, requires = "albedo")]
    normal: Option<PathBuf>,
    /// The colour is low dynamic range, in [0, 1].
    #[arg(long)]
    ldr: bool,
    /// The colour is high dynamic range: any magnitude.
    #[arg(long, conflicts_with = "srgb")]
    hdr: bool,
    /// The LDR colour (and output) are sRGB-encoded, not linear: the
    /// network sees them as they are.
    #[arg(long)]
    srgb: bool,
    /// Multiplies the colour before the network and divides the output
    /// [default: in HDR OIDN's autoexposure, else 1].
    #[arg(long, value_parser = parse_scale)]
    input_scale: Option<f32>,
    /// Storage of the tensors between layers (accumulation is f32 either way).
    #[arg(long, value_enum, default_value = "f32")]
    precision: loupe::denoise::Precision,
    /// The denoised image: .pfm, .exr or .png.
    #[arg(short = 'o', long)]
    output: PathBuf,
    /// Write every tensor of the network into this directory as
    /// `<name>.npy` (height, width, channels of the padded image; on the
    /// GPU per tile, `tile<i>/`, when it cut the image into tiles).
    #[arg(long, value_name = "DIR")]
    dump_tensors: Option<PathBuf>,
    /// Where the network runs.
    #[arg(short = 'd', long, value_enum, default_value = "gpu")]
    device: Device,
    /// Project root: where shaders/ is (the GPU's).
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// The most memory one tile's tensors may take on the GPU, in MiB
    /// (OIDN's `--maxmem`): larger images are cut into tiles that overlap
    /// by the network's receptive radius.
    #[arg(long, default_value_t = 2048, value_parser = clap::value_parser!(u64).range(1..=1 << 20))]
    max_memory_mb: u64,
    /// The GPU's tile side in pixels instead of the largest that fits: a
    /// multiple of 16, more than twice the receptive radius (224 or more
    /// for OIDN's networks).
    #[arg(long, value_parser = parse_tile)]
    tile: Option<u32>,
}

fn parse_tile(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n) if n > 0 && n % 16 == 0 && n <= 16384 => Ok(n),
        _ => Err(format!("{s} is not a tile side: a multiple of 16 up to 16384")),
    }
}

fn parse_scale(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a positive number")),
    }
}

pub fn run(args: Args) -> ExitCode {
    let mode = match (args.hdr, args.srgb) {
        (true, _) => Mode::Hdr,
        (false, true) => Mode::LdrSrgb,
        (false, false) => Mode::Ldr,
    };
    let job = Job {
        weights: args.weights,
        color: args.color,
        albedo: args.albedo,
        normal: args.normal,
        mode,
        input_scale: args.input_scale,
        precision: args.precision,
        output: args.output,
        dump_tensors: args.dump_tensors,
        device: args.device,
        shader_root: args.root.join("shaders"),
        max_memory_mb: args.max_memory_mb,
        tile: args.tile,
    };
    match denoise::run(&job) {
        Ok(r) => {
            let dumped = match &job.dump_tensors {
                Some(dir) => format!(", {} tensors in {}", r.tensors_dumped, dir.display()),
                None => String::new(),
            };
            let tiles = match r.window {
                Some(side) if r.tiles > 1 => format!(" in {} tiles of {side}x{side}", r.tiles),
                _ => String::new(),
            };
            println!(
                "{}: {}x{}, {}, input scale {}, network {:.3} s on {}{tiles}{dumped}",
                job.output.display(),
                r.width,
                r.height,
                r.inputs.describe(),
                r.input_scale,
                r.network_seconds,
                r.device
            );
            ExitCode::from(exit::OK)
        }
        Err(d) => {
            print_diagnostics(std::slice::from_ref(&d));
            ExitCode::from(match d.code {
                Code::Io | Code::FileTooLarge => exit::USAGE,
                Code::DeviceMissing => exit::NO_DEVICE,
                _ => exit::ERRORS,
            })
        }
    }
}
