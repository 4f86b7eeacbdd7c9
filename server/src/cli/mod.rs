//! The command layer: the clap `Cli` and `Command`, one module per command
//! holding its arguments and its `run`, and the small parsers and error
//! printing they share. Everything a command does beyond reading its flags
//! and printing its result lives in the library.

pub mod bench;
pub mod check;
pub mod denoise;
pub mod render;
pub mod serve;
pub mod tradeoffs;
pub mod view;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use loupe::check::format;
use loupe::offline::OfflineError;
use loupe::scene::settings::Value;
use loupe::serve::{ServeOptions, daemon::RenderMode};

/// Exit codes, the same for every subcommand.
pub mod exit {
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
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Compose, parse and validate every WGSL module, load every scene,
    /// and create every pipeline the renderer uses: a gate for CI.
    ///
    /// Exit codes: 0 clean; 1 errors (or warnings with --deny-warnings);
    /// 2 bad usage or unreadable input; 3 --device given and no GPU adapter.
    Check(check::Args),
    /// Watch shaders and scenes, render continuously, hot-reload on save
    /// (keeping the last good pipeline when a change fails), and serve the
    /// browser inspector.
    ///
    /// Exit codes: 0 after Ctrl-C; 2 bad usage; 3 no GPU adapter.
    Serve(serve::Args),
    /// Run the daemon of `serve` (the browser inspector stays on the port)
    /// and open a native window on its GPU device: the live frame, any
    /// pass output with the value under the cursor, the passes, the scene's
    /// controls, the pass times, and the problems (click one to open
    /// $VISUAL or $EDITOR at its line).
    ///
    /// Exit codes: 0 after the window closes or Ctrl-C; 2 bad usage or no
    /// display (`loupe serve` is the headless alternative); 3 no GPU adapter.
    View(view::Args),
    /// Render one frame without a server: every pass output as PNG and
    /// OpenEXR, plus `report.json` (passes, culled passes with reasons,
    /// timings, NaN report, statistics).
    ///
    /// Exit codes: 0 rendered, clean; 1 the scene or a shader has errors, or
    /// the frame holds NaN/Inf; 2 bad usage or unwritable output; 3 no GPU.
    Render(render::Args),
    /// Time each pass of a scene and the cost of captures (median over
    /// frames, captures none / final / all measured interleaved).
    Bench(bench::Args),
    /// Denoise an image with an OIDN U-Net, as OIDN's `oidnDenoise` does,
    /// on OIDN's weights files (.tza): on the GPU, with the frame's own
    /// denoiser passes (tiled when the image's tensors exceed the device's
    /// limits or --max-memory-mb), or on the CPU reference.
    ///
    /// Images: PFM, OpenEXR or PNG (by extension). PFM and EXR hold linear
    /// values; a PNG colour is sRGB-decoded and the output PNG encoded,
    /// unless --srgb; a PNG albedo is decoded; normals are read as stored.
    ///
    /// Exit codes: 0 denoised; 1 a malformed weights file or image, or
    /// images that do not fit the weights or each other; 2 bad usage, an
    /// unreadable input or an unwritable output.
    Denoise(denoise::Args),
}

impl Command {
    pub fn run(self) -> ExitCode {
        match self {
            Command::Check(args) => check::run(args),
            Command::Serve(args) => serve::run(args),
            Command::View(args) => view::run(args),
            Command::Render(args) => render::run(args),
            Command::Bench(args) => bench::run(args),
            Command::Denoise(args) => denoise::run(args),
        }
    }
}

/// `WIDTHxHEIGHT`, each side within the scene's limits.
pub use loupe::scene::parse_size;

/// `X,Y`: a pixel, from the top left (`--debug-pixel`).
pub fn parse_pixel(s: &str) -> Result<[u32; 2], String> {
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("`{s}` is not a pixel: X,Y with whole numbers from 0"));
    match s.split_once(',') {
        Some((x, y)) => Ok([parse(x)?, parse(y)?]),
        None => Err(format!("`{s}` is not a pixel: X,Y")),
    }
}

/// `PATH=VALUE`, the value typed as the browser's live controls type it.
pub fn parse_override(s: &str) -> Result<(String, Value), String> {
    let (path, v) = s.split_once('=').ok_or_else(|| format!("`{s}` is not PATH=VALUE"))?;
    let value = if let Ok(b) = v.parse::<bool>() {
        Value::Bool(b)
    } else if let Ok(i) = v.parse::<i64>() {
        Value::Int(i)
    } else if let Ok(f) = v.parse::<f64>() {
        Value::Float(f)
    } else {
        Value::Text(v.to_owned())
    };
    Ok((path.trim().to_owned(), value))
}

/// A path given relative to the project root, as every subcommand reads
/// `--scene` (absolute paths stand as they are).
pub fn under_root(root: &Path, path: &Path) -> PathBuf {
    if path.is_absolute() { path.to_owned() } else { root.join(path) }
}

/// What `loupe serve` and `loupe view` both take: the daemon's project,
/// scene and port.
#[derive(clap::Args)]
pub struct DaemonArgs {
    /// The scene to render.
    #[arg(long, default_value = "scenes/showcase.toml")]
    scene: PathBuf,
    /// Port of the browser inspector and the API (0 picks a free one).
    #[arg(long, default_value_t = 7878)]
    port: u16,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Enable the debug API for tests: `POST /api/debug/lose-device`
    /// destroys the GPU device to exercise recovery.
    #[arg(long)]
    debug_api: bool,
}

impl DaemonArgs {
    /// The daemon's options, or the usage exit after saying that the scene
    /// does not exist under the root (`command`: whose message it is).
    pub fn options(self, command: &str, bind: std::net::IpAddr, mode: RenderMode, max_fps: f64) -> Result<ServeOptions, ExitCode> {
        let scene = under_root(&self.root, &self.scene);
        if !scene.is_file() {
            eprintln!("loupe {command}: scene `{}` does not exist", scene.display());
            return Err(ExitCode::from(exit::USAGE));
        }
        Ok(ServeOptions { root: self.root, scene, bind, port: self.port, mode, max_fps, debug_api: self.debug_api })
    }
}

/// Logs at `warn` unless RUST_LOG says otherwise.
pub fn init_logging() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
}

/// Prints diagnostics on stderr the way `loupe check` prints them.
pub fn print_diagnostics(diags: &[loupe::diag::Diagnostic]) {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let _ = format::human::write_diagnostics(diags, color, &mut std::io::stderr().lock());
}

/// Prints input errors the way `loupe check` does and picks the exit code.
pub fn offline_failed(cmd: &str, e: OfflineError) -> ExitCode {
    match e {
        OfflineError::NoDevice(e) => {
            eprintln!("loupe {cmd}: {e}");
            ExitCode::from(exit::NO_DEVICE)
        }
        OfflineError::Input(diags) => {
            print_diagnostics(&diags);
            ExitCode::from(exit::ERRORS)
        }
        OfflineError::Io(e) | OfflineError::Usage(e) => {
            eprintln!("loupe {cmd}: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}
