//! `loupe render`: one frame of a scene, every pass output on disk.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{exit, init_logging, offline_failed, parse_override, parse_pixel, parse_size, under_root};
use loupe::offline;
use loupe::scene::settings::Value;

/// The scene and how it is changed, as `loupe render` takes them.
#[derive(clap::Args)]
struct SceneArgs {
    /// The scene to render.
    #[arg(long, default_value = "scenes/showcase.toml")]
    scene: PathBuf,
    /// Output size, replacing the scene's: WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Override a scene value, as the browser's live controls do:
    /// `--set post.exposure_ev=1.5 --set lights[0].intensity=3`.
    #[arg(long = "set", value_parser = parse_override)]
    set: Vec<(String, Value)>,
    /// Project root: where shaders/ is.
    #[arg(long, default_value = ".")]
    root: PathBuf,
}

impl SceneArgs {
    fn job(&self) -> offline::Job {
        offline::Job {
            scene: under_root(&self.root, &self.scene),
            shader_root: self.root.join("shaders"),
            size: self.size,
            overrides: self.set.iter().cloned().collect(),
        }
    }
}

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    /// Directory for the images and report.json (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// The renderer, as `--set quality.renderer=…`: `path` accumulates
    /// `quality.path_spp` samples (one a frame) before writing.
    #[arg(long, value_parser = ["raster", "path"])]
    renderer: Option<String>,
    /// Samples per pixel for the path tracer, as `--set quality.path_spp=N`.
    #[arg(long)]
    spp: Option<i64>,
    /// Collect the `debugPrintf`s and the history of pixel X,Y (from the
    /// top left) into report.json's `prints` and `history`
    /// (docs/printf.md, docs/pixel-history.md).
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    debug_pixel: Option<[u32; 2]>,
}

pub fn run(args: Args) -> ExitCode {
    init_logging();
    let mut job = args.scene.job();
    if let Some(r) = &args.renderer {
        job.overrides.insert("quality.renderer".into(), Value::Text(r.clone()));
    }
    if let Some(n) = args.spp {
        job.overrides.insert("quality.path_spp".into(), Value::Int(n));
    }
    let report = match offline::render::run(&job, &args.out, args.debug_pixel) {
        Ok(r) => r,
        Err(e) => return offline_failed("render", e),
    };
    let json = serde_json::to_string_pretty(&report).expect("the report is plain data");
    if let Err(e) = std::fs::write(args.out.join("report.json"), json + "\n") {
        eprintln!("loupe render: cannot write report.json: {e}");
        return ExitCode::from(exit::USAGE);
    }
    let outputs: usize = report.passes.iter().map(|p| p.outputs.len()).sum();
    println!(
        "{}: {} passes ({} culled), {outputs} outputs written to {} [{}]",
        report.scene,
        report.passes.len(),
        report.culled.len(),
        args.out.display(),
        report.adapter
    );
    for e in &report.gpu_errors {
        eprintln!("loupe render: GPU error: {e}");
    }
    match &report.nan {
        Some(n) => {
            eprintln!(
                "loupe render: NaN/Inf first made by pass `{}` ({}/{}) at pixel ({}, {}): {:?}",
                n.pass, n.pass, n.output, n.pixel[0], n.pixel[1], n.value
            );
            ExitCode::from(exit::ERRORS)
        }
        None if !report.gpu_errors.is_empty() => ExitCode::from(exit::ERRORS),
        None => ExitCode::from(exit::OK),
    }
}
