//! `loupe check`: the gate for CI.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use super::{exit, print_diagnostics};
use loupe::check::{self, CheckOptions, DeviceMode, format};

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
    let device = match (args.no_device, args.device) {
        (true, _) => DeviceMode::Off,
        (false, true) => DeviceMode::Required,
        (false, false) => DeviceMode::Auto,
    };
    let capabilities = args.capabilities.or(defaults.capabilities);
    let deny_debug_printf = args.deny_debug_printf.or(defaults.deny_debug_printf).unwrap_or(false);
    let (mut report, files) = match check::run(&CheckOptions { paths, shader_root, device, capabilities, deny_debug_printf }) {
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
