//! `loupe view`: the daemon of `loupe serve` and a native window on its
//! device.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{daemon_scene, exit, init_logging};
use loupe::serve::viewer::{self, ViewError};
use loupe::serve::{ServeError, ServeOptions, daemon::RenderMode};

#[derive(clap::Args)]
pub struct Args {
    /// The scene to render.
    #[arg(long, default_value = "scenes/showcase.toml")]
    scene: PathBuf,
    /// Port of the browser inspector and the API, served beside the
    /// window on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 7878)]
    port: u16,
    /// Frame-rate cap.
    #[arg(long, default_value_t = 60.0)]
    fps: f64,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
}

pub fn run(args: Args) -> ExitCode {
    init_logging();
    let scene = match daemon_scene("view", &args.root, &args.scene) {
        Ok(scene) => scene,
        Err(code) => return code,
    };
    let opts = ServeOptions {
        root: args.root,
        scene,
        bind: std::net::Ipv4Addr::LOCALHOST.into(),
        port: args.port,
        mode: RenderMode::Continuous,
        max_fps: args.fps,
        debug_api: false,
    };
    match viewer::run(opts) {
        Ok(()) => ExitCode::from(exit::OK),
        Err(e) => {
            eprintln!("loupe view: {e}");
            ExitCode::from(match e {
                ViewError::Serve(ServeError::NoDevice(_)) => exit::NO_DEVICE,
                _ => exit::USAGE,
            })
        }
    }
}
