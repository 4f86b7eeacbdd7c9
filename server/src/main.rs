//! The `loupe` binary: argument parsing, exit codes, and errors with
//! context. Everything else lives in the library.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use loupe::check::{self, CheckOptions, DeviceMode, format};
use loupe::serve::{self, ServeError, ServeOptions, daemon::RenderMode};

/// Exit codes, the same for every subcommand.
mod exit {
    pub const OK: u8 = 0;
    /// The input has errors (or warnings, when denied).
    pub const ERRORS: u8 = 1;
    /// Bad usage or unreadable input (clap uses 2 for usage errors too).
    pub const USAGE: u8 = 2;
    /// A GPU device was required and none exists.
    pub const NO_DEVICE: u8 = 3;
}

#[derive(Parser)]
#[command(name = "loupe", version, about = "Shader hot-reload server and frame debugger for WGSL on wgpu")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compose, parse and validate every WGSL module and create every
    /// pipeline the renderer uses: a shader gate for CI.
    ///
    /// Exit codes: 0 clean; 1 errors (or warnings with --deny-warnings);
    /// 2 bad usage or unreadable input; 3 --device given and no GPU adapter.
    Check(CheckArgs),
    /// Watch shaders and scenes, render continuously, hot-reload on save
    /// (keeping the last good pipeline when a change fails), and serve the
    /// browser inspector.
    ///
    /// Exit codes: 0 after Ctrl-C; 2 bad usage; 3 no GPU adapter.
    Serve(ServeArgs),
}

#[derive(clap::Args)]
struct ServeArgs {
    /// The scene to render.
    #[arg(long, default_value = "scenes/default.toml")]
    scene: PathBuf,
    /// Address to listen on. Anything but loopback is reachable from other
    /// machines, and loupe has no authentication.
    #[arg(long, default_value = "127.0.0.1")]
    bind: std::net::IpAddr,
    /// Port to listen on (0 picks a free one).
    #[arg(long, default_value_t = 7878)]
    port: u16,
    /// Render continuously, or only when something changed.
    #[arg(long, value_enum, default_value_t = RenderMode::Continuous)]
    render: RenderMode,
    /// Frame-rate cap in continuous mode.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Enable the debug API for tests: `POST /api/debug/lose-device`
    /// destroys the GPU device to exercise recovery.
    #[arg(long)]
    debug_api: bool,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// Files or directories to check (directories are searched for *.wgsl).
    /// Default: the project's shaders/ and scenes/.
    paths: Vec<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = format::Format::Human)]
    format: format::Format,
    /// Skip pipeline creation: check sources only, never open a device.
    #[arg(long, conflicts_with = "device")]
    no_device: bool,
    /// Require a device: exit 3 when no GPU adapter exists.
    #[arg(long)]
    device: bool,
    /// Treat warnings as errors for the exit code.
    #[arg(long)]
    deny_warnings: bool,
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => run_check(args),
        Command::Serve(args) => run_serve(args),
    }
}

fn run_serve(args: ServeArgs) -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let scene = if args.scene.is_absolute() { args.scene.clone() } else { args.root.join(&args.scene) };
    if !scene.is_file() {
        eprintln!("loupe serve: scene `{}` does not exist", scene.display());
        return ExitCode::from(exit::USAGE);
    }
    let opts = ServeOptions { root: args.root, scene, bind: args.bind, port: args.port, mode: args.render, max_fps: args.fps, debug_api: args.debug_api };
    match serve::run(opts) {
        Ok(()) => ExitCode::from(exit::OK),
        Err(ServeError::NoDevice(e)) => {
            eprintln!("loupe serve: {e}");
            ExitCode::from(exit::NO_DEVICE)
        }
        Err(e) => {
            eprintln!("loupe serve: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}

fn run_check(args: CheckArgs) -> ExitCode {
    let shader_root = args.root.join("shaders");
    let paths = if args.paths.is_empty() {
        [shader_root.clone(), args.root.join("scenes")].into_iter().filter(|p| p.exists()).collect()
    } else {
        args.paths.clone()
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
    let (report, files) = match check::run(&CheckOptions { paths, shader_root, device }) {
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
    let color = match args.color {
        Color::Always => true,
        Color::Never => false,
        Color::Auto => std::io::stdout().is_terminal() && std::env::var_os("NO_COLOR").is_none(),
    };
    let opts = format::Options { color, timings: !args.no_timings };
    let mut out = std::io::stdout().lock();
    if let Err(e) = format::write(args.format, &report, &files, &opts, &mut out) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("loupe check: cannot write output: {e}");
            return ExitCode::from(exit::USAGE);
        }
    }
    match report.exit_code(args.deny_warnings) {
        0 => ExitCode::from(exit::OK),
        _ => ExitCode::from(exit::ERRORS),
    }
}
