//! `loupe bench`: per-pass times and the cost of captures, scene by scene;
//! `loupe bench tradeoffs` is its subcommand.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{exit, init_logging, offline_failed, parse_pixel, parse_size, tradeoffs, under_root};
use loupe::offline;
use loupe::scene::overrides::Overrides;
use loupe::scene::settings::Value;

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    #[command(subcommand)]
    what: Option<BenchCommand>,
    /// Scenes to measure; default: every scene in scenes/.
    scenes: Vec<PathBuf>,
    /// Output size for every scene: WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "1280x720")]
    size: (u32, u32),
    /// Frames per capture setting.
    #[arg(long, default_value_t = 20)]
    frames: u32,
    /// Project root: where shaders/ and scenes/ are.
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// The renderer to time; `path` also reports paths per second (every
    /// frame traces: the sample budget is set beyond the frames).
    #[arg(long, value_parser = ["raster", "path"], default_value = "raster")]
    renderer: String,
    /// Indirect bounces when path tracing, as `quality.path_bounces`.
    #[arg(long)]
    bounces: Option<i64>,
    /// Time each pass by the wall clock, submitting it alone and waiting
    /// for it, in an extra frame per round: for adapters whose timestamps
    /// do not bracket compute work (llvmpipe).
    #[arg(long)]
    serial: bool,
    /// Also time frames with pixel X,Y selected for `debugPrintf`
    /// (docs/printf.md), after the others.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    debug_pixel: Option<[u32; 2]>,
}

#[derive(clap::Subcommand)]
enum BenchCommand {
    /// What accuracy costs in time: sweep each quality setting the scene
    /// calls for, time the passes it affects and compare each image with
    /// a reference (relative MSE; PSNR and SSIM of the tonemapped image).
    /// Writes tradeoffs.json, tradeoffs.md, tradeoffs.svg and each point's
    /// image into --out.
    Tradeoffs(tradeoffs::Args),
}

pub fn run(args: Args) -> ExitCode {
    init_logging();
    if let Some(BenchCommand::Tradeoffs(t)) = args.what {
        return tradeoffs::run(t);
    }
    let scenes = if args.scenes.is_empty() {
        let mut v: Vec<PathBuf> = std::fs::read_dir(args.root.join("scenes"))
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect())
            .unwrap_or_default();
        v.sort();
        v
    } else {
        args.scenes.iter().map(|s| under_root(&args.root, s)).collect()
    };
    for scene in scenes {
        let mut overrides = Overrides::from([("quality.renderer".to_owned(), Value::Text(args.renderer.clone()))]);
        if args.renderer == "path" {
            overrides.insert("quality.path_spp".into(), Value::Int(65536));
        }
        if let Some(b) = args.bounces {
            overrides.insert("quality.path_bounces".into(), Value::Int(b));
        }
        let job = offline::Job { scene, shader_root: args.root.join("shaders"), size: Some(args.size), overrides };
        let r = match offline::bench::run(&job, args.frames, args.serial, args.debug_pixel) {
            Ok(r) => r,
            Err(e) => return offline_failed("bench", e),
        };
        println!("## {} at {}x{}, {} frames, {} timing, {}", r.scene, r.width, r.height, r.frames, r.timing, r.adapter);
        let total: f64 = r.passes.iter().map(|(_, t)| t).sum();
        for (name, t) in &r.passes {
            println!("  {name:<20} {t:>9.3} ms  {:>5.1} %", if total > 0.0 { t / total * 100.0 } else { 0.0 });
        }
        let over = |x: f64| (x / r.frame_ms_no_capture - 1.0) * 100.0;
        println!(
            "  frame (submit to readback): no capture {:.2} ms; final only {:.2} ms ({:+.1} %); every output {:.2} ms ({:+.1} %)",
            r.frame_ms_no_capture,
            r.frame_ms_final_capture,
            over(r.frame_ms_final_capture),
            r.frame_ms_all_captures,
            over(r.frame_ms_all_captures)
        );
        println!(
            "  conversion and statistics (serve: on its own thread): final only {:.2} ms; every output {:.2} ms",
            r.convert_ms_final_capture, r.convert_ms_all_captures
        );
        println!(
            "  quad statistics: frame {:.2} ms ({:+.1} %), model {:.2} ms ({:.2}x the frame without)",
            r.frame_ms_quads,
            over(r.frame_ms_quads),
            r.convert_ms_quads,
            r.convert_ms_quads / r.frame_ms_no_capture
        );
        if let (Some(on), Some(off)) = (r.frame_ms_debug_pixel, r.frame_ms_debug_pixel_off) {
            println!(
                "  a pixel selected (prints and history): frame {on:.2} ms, {off:.2} ms without, interleaved ({:+.1} %)",
                (on / off - 1.0) * 100.0
            );
        }
        if let Some(ms) = r.first_history_ms {
            println!("  from selecting the pixel to its first history: {ms:.0} ms");
        }
        if let Some((_, ms)) = r.passes.iter().find(|(n, _)| n == "path_trace") {
            let paths = f64::from(r.width) * f64::from(r.height);
            // llvmpipe's timestamps around a compute dispatch do not
            // bracket its work: the frame's wall time is the honest figure there.
            println!(
                "  path tracer (one path per pixel per frame): {:.3} M paths/s by the pass's timestamps ({ms:.2} ms), {:.3} M paths/s by the whole frame's wall time",
                paths / ms / 1e3,
                paths / r.frame_ms_no_capture / 1e3
            );
        }
    }
    ExitCode::from(exit::OK)
}
