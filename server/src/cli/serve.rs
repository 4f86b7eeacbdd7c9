//! `loupe serve`: the daemon and the browser inspector.

use std::process::ExitCode;

use super::{DaemonArgs, exit, init_logging};
use loupe::serve::{self, ServeError, daemon::RenderMode};

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    daemon: DaemonArgs,
    /// Address to listen on. Anything but loopback is reachable from other
    /// machines, and loupe has no authentication.
    #[arg(long, default_value = "127.0.0.1")]
    bind: std::net::IpAddr,
    /// Render continuously, or only when something changed.
    #[arg(long, value_enum, default_value_t = RenderMode::Continuous)]
    render: RenderMode,
    /// Frame-rate cap in continuous mode.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
}

pub fn run(args: Args) -> ExitCode {
    init_logging();
    let opts = match args.daemon.options("serve", args.bind, args.render, args.fps) {
        Ok(opts) => opts,
        Err(code) => return code,
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
