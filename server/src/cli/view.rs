//! `loupe view`: the daemon of `loupe serve` and a native window on its
//! device.

use std::process::ExitCode;

use super::{DaemonArgs, exit, init_logging};
use loupe::serve::viewer::{self, ViewError};
use loupe::serve::{ServeError, daemon::RenderMode};

/// The port is bound on 127.0.0.1: the window is a local tool.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    daemon: DaemonArgs,
    /// Frame-rate cap.
    #[arg(long, default_value_t = 60.0)]
    fps: f64,
}

pub fn run(args: Args) -> ExitCode {
    init_logging();
    let opts = match args.daemon.options("view", std::net::Ipv4Addr::LOCALHOST.into(), RenderMode::Continuous, args.fps) {
        Ok(opts) => opts,
        Err(code) => return code,
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
