//! `loupe check`: the gate for CI.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use super::{exit, print_diagnostics};
use loupe::check::{self, CheckOptions, DeviceMode, format, images};

#[derive(clap::Args)]
pub struct Args {
    /// Files or directories to check: directories are searched for *.wgsl,
    /// and for *.toml scenes inside a directory named `scenes`; a file
    /// named here is a scene when it ends in .toml, else WGSL.
    /// Default: `paths` in loupe.toml, else the project's shaders/ and scenes/.
    paths: Vec<PathBuf>,
    /// Output format [default: `format` in loupe.toml, else human].
    #[arg(long, value_enum)]
    format: Option<format::Format>,
    /// Skip pipeline creation: check sources only, never open a device.
    #[arg(long, conflicts_with = "device")]
    no_device: bool,
    /// Require a device: exit 3 when no GPU adapter exists.
    #[arg(long)]
    device: bool,
    /// Treat warnings as errors for the exit code; `--deny-warnings=false`
    /// overrides loupe.toml's `deny_warnings = true`.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    deny_warnings: Option<bool>,
    /// Make every `debugPrintf` call an error; `--deny-debug-printf=false`
    /// overrides loupe.toml's `deny_debug_printf = true`.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    deny_debug_printf: Option<bool>,
    /// Shader capabilities to validate with, comma-separated naga names
    /// (`float64,shader-int64,shader-float16`) or `all`; what every WebGPU
    /// device has is always allowed. Default: `capabilities` in loupe.toml,
    /// else with a device what its adapter supports, and without one
    /// `primitive-index,subgroup,subgroup-barrier,shader-float16` (what
    /// loupe can request).
    #[arg(long, value_name = "LIST", value_parser = check::capabilities::parse_arg)]
    capabilities: Option<naga::valid::Capabilities>,
    /// Colour in the human format.
    #[arg(long, value_enum, default_value_t = Color::Auto)]
    color: Color,
    /// Leave timings out of the human summary, for reproducible logs.
    #[arg(long)]
    no_timings: bool,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Require the image cases (loupe.toml's [[images]]): exit 3 when no
    /// GPU adapter exists. Without it they run when a device exists and
    /// are reported skipped when none does.
    #[arg(long, conflicts_with_all = ["no_device", "no_images"])]
    images: bool,
    /// Skip the image cases.
    #[arg(long)]
    no_images: bool,
    /// Render the named image cases (all when none is named) and write
    /// them as their references, saying what changed; takes the names that
    /// follow it. A plain check never writes a reference.
    #[arg(long, value_name = "CASE", num_args = 0.., conflicts_with_all = ["no_device", "no_images"])]
    bless: Option<Vec<String>>,
    /// Where a failed image case's images and report.html go
    /// [default: ROOT/target/loupe-images].
    #[arg(long, value_name = "DIR")]
    artifacts: Option<PathBuf>,
    /// Image cases rendered at once, each job on a session of its own.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64))]
    jobs: u16,
    /// Run only every N-th image case from the K-th (1-based), to split
    /// the cases across CI machines; the shards' reports concatenate.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    shard: Option<images::Shard>,
}

fn parse_shard(s: &str) -> Result<images::Shard, String> {
    s.parse()
}

#[derive(Clone, Copy, ValueEnum)]
enum Color {
    Auto,
    Always,
    Never,
}

pub fn run(args: Args) -> ExitCode {
    // loupe.toml's defaults, then the flags over them.
    let defaults = match check::project::read(&args.root) {
        Ok(d) => d,
        Err(d) => {
            print_diagnostics(&[d]);
            return ExitCode::from(exit::USAGE);
        }
    };
    let shader_root = args.root.join("shaders");
    let paths = if !args.paths.is_empty() {
        args.paths.clone()
    } else if let Some(paths) = defaults.paths {
        paths
    } else {
        [shader_root.clone(), args.root.join("scenes")].into_iter().filter(|p| p.exists()).collect()
    };
    if paths.is_empty() {
        eprintln!("loupe check: nothing to check: no paths given and no shaders/ or scenes/ under {}", args.root.display());
        return ExitCode::from(exit::USAGE);
    }
    let device = match (args.no_device, args.device || args.images || args.bless.is_some()) {
        (true, _) => DeviceMode::Off,
        (false, true) => DeviceMode::Required,
        (false, false) => DeviceMode::Auto,
    };
    let capabilities = args.capabilities.or(defaults.capabilities);
    let images = (!args.no_images && !defaults.images.is_empty()).then(|| images::Options {
        cases: defaults.images,
        references: defaults.references.unwrap_or_else(|| args.root.join(check::project::DEFAULT_REFERENCES)),
        artifacts: args.artifacts.clone().unwrap_or_else(|| args.root.join(images::artifacts::DEFAULT_DIR)),
        bless: args.bless.clone(),
        jobs: usize::from(args.jobs),
        shard: args.shard.unwrap_or(images::Shard::ALL),
    });
    if let Some(unknown) = images.as_ref().map(images::Options::unknown_names).filter(|u| !u.is_empty()) {
        let known: Vec<&str> = images.iter().flat_map(|o| o.cases.iter().map(|c| c.name.as_str())).collect();
        eprintln!("loupe check: no image case named {}; the cases: {}", unknown.join(", "), known.join(", "));
        return ExitCode::from(exit::USAGE);
    }
    if args.bless.is_some() && images.is_none() {
        eprintln!("loupe check: --bless: {} has no [[images]] cases", args.root.join(check::project::FILE).display());
        return ExitCode::from(exit::USAGE);
    }
    let deny_debug_printf = args.deny_debug_printf.or(defaults.deny_debug_printf).unwrap_or(false);
    let (mut report, files) = match check::run(&CheckOptions { paths, shader_root, device, capabilities, images, deny_debug_printf }) {
        Ok(r) => r,
        Err(check::CheckError::BadPath(e)) => {
            eprintln!("loupe check: cannot read input: {e}");
            return ExitCode::from(exit::USAGE);
        }
        Err(check::CheckError::NoDevice(e)) => {
            eprintln!("loupe check: {e}");
            return ExitCode::from(exit::NO_DEVICE);
        }
    };
    // Denied warnings are errors in every format, not only in the exit code.
    if args.deny_warnings.or(defaults.deny_warnings).unwrap_or(false) {
        report.deny_warnings();
    }
    let color = match args.color {
        Color::Always => true,
        Color::Never => false,
        Color::Auto => std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    };
    let opts = format::Options { color, timings: !args.no_timings };
    let mut out = std::io::stdout().lock();
    let format = args.format.or(defaults.format).unwrap_or(format::Format::Human);
    // A reader that stops early (`| head`) is no failure.
    if let Err(e) = format::write(format, &report, &files, &opts, &mut out)
        && e.kind() != std::io::ErrorKind::BrokenPipe
    {
        eprintln!("loupe check: cannot write output: {e}");
        return ExitCode::from(exit::USAGE);
    }
    match report.exit_code() {
        0 => ExitCode::from(exit::OK),
        _ => ExitCode::from(exit::ERRORS),
    }
}
