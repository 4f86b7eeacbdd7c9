//! The `loupe` binary: parse the command line and dispatch. Each command's
//! arguments and run are in `cli/`; everything else lives in the library.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // SAFETY: the first thing the process does, before any thread exists.
    unsafe { loupe::gpu::provide_runtime_dir() };
    cli::Cli::parse().command.run()
}
