//! `loupe bench tradeoffs`: what accuracy costs in time.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{exit, offline_failed, parse_override, parse_size, under_root};
use loupe::scene::settings::Value;
use loupe::tradeoffs::{self, report};

#[derive(clap::Args)]
pub struct Args {
    #[arg(long, default_value = "scenes/showcase.toml")]
    scene: PathBuf,
    /// Output size: WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "320x180")]
    size: (u32, u32),
    /// Output directory, under --root unless absolute (`loupe serve` shows
    /// `tradeoffs/`'s results in the browser).
    #[arg(long, default_value = "tradeoffs")]
    out: PathBuf,
    /// Timed frames per point, after 2 of warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeats: u32,
    /// Samples per pixel of path-traced references.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=65536))]
    reference_spp: u32,
    /// Where references are kept between runs [default: $XDG_CACHE_HOME/loupe/references, else ~/.cache/loupe/references].
    #[arg(long)]
    cache: Option<PathBuf>,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Override a scene value under every point, as `loupe render --set`
    /// does (e.g. `denoiser.weights=/path/rt_ldr_alb_nrm.tza` adds the
    /// denoiser's series to a scene without one).
    #[arg(long = "set", value_name = "PATH=VALUE", value_parser = parse_override)]
    set: Vec<(String, Value)>,
}

pub fn run(args: Args) -> ExitCode {
    let cache = args.cache.unwrap_or_else(|| {
        let base = std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")));
        base.unwrap_or_else(std::env::temp_dir).join("loupe/references")
    });
    let job = tradeoffs::Job {
        scene: under_root(&args.root, &args.scene),
        shader_root: args.root.join("shaders"),
        size: args.size,
        repeats: args.repeats,
        reference_spp: args.reference_spp,
        cache,
        overrides: args.set.into_iter().collect(),
    };
    let out = under_root(&args.root, &args.out);
    let report = match tradeoffs::run(&job, &out) {
        Ok(r) => r,
        Err(e) => return offline_failed("bench tradeoffs", e),
    };
    let files = [
        ("tradeoffs.json", serde_json::to_string_pretty(&report).unwrap_or_default()),
        ("tradeoffs.md", report::markdown(&report)),
        ("tradeoffs.svg", report::svg(&report)),
    ];
    for (name, text) in files {
        if let Err(e) = std::fs::write(out.join(name), text) {
            eprintln!("loupe bench tradeoffs: cannot write {name}: {e}");
            return ExitCode::from(exit::USAGE);
        }
    }
    print!("{}", report::markdown(&report));
    ExitCode::from(exit::OK)
}
