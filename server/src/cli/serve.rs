//! `loupe serve`: the daemon and the browser inspector.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{daemon_scene, exit, init_logging};
use loupe::serve::{self, ServeError, ServeOptions, daemon::RenderMode};

#[derive(clap::Args)]
pub struct Args {
    /// The scene to render.
    #[arg(long, default_value = "scenes/showcase.toml")]
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

pub fn run(args: Args) -> ExitCode {
    init_logging();
    let scene = match daemon_scene("serve", &args.root, &args.scene) {
        Ok(scene) => scene,
        Err(code) => return code,
    };
    let opts = ServeOptions {
        root: args.root,
        scene,
        bind: args.bind,
        port: args.port,
        mode: args.render,
        max_fps: args.fps,
        debug_api: args.debug_api,
    };
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
