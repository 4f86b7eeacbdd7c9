//! The `loupe` binary: argument parsing, exit codes, and errors with
//! context. Everything else lives in the library.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use loupe::check::{self, CheckOptions, DeviceMode, format};
use loupe::offline;
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
    /// Compose, parse and validate every WGSL module, load every scene,
    /// and create every pipeline the renderer uses: a gate for CI.
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
    /// Render one frame without a server: every pass output as PNG and
    /// OpenEXR, plus `report.json` (passes, culled passes with reasons,
    /// timings, NaN report, statistics).
    ///
    /// Exit codes: 0 rendered, clean; 1 the scene or a shader has errors, or
    /// the frame holds NaN/Inf; 2 bad usage or unwritable output; 3 no GPU.
    Render(RenderArgs),
    /// Time each pass of a scene and the cost of captures (median over
    /// frames, captures none / final / all measured interleaved).
    Bench(BenchArgs),
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
    Denoise(DenoiseArgs),
}

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("range").required(true).args(["ldr", "hdr"])))]
struct DenoiseArgs {
    /// The weights: an OIDN .tza file whose network takes the inputs given
    /// [default: OIDN's network bundled with loupe for the range (--hdr or
    /// --ldr) and the inputs (colour, or colour, albedo and normal)].
    #[arg(long)]
    weights: Option<PathBuf>,
    /// The noisy colour.
    #[arg(long)]
    color: PathBuf,
    /// The albedo (first-hit surface colour), in [0, 1].
    #[arg(long)]
    albedo: Option<PathBuf>,
    /// The first-hit normal, in [-1, 1]; needs --albedo.
    #[arg(long, requires = "albedo")]
    normal: Option<PathBuf>,
    /// The colour is low dynamic range, in [0, 1].
    #[arg(long)]
    ldr: bool,
    /// The colour is high dynamic range: any magnitude.
    #[arg(long, conflicts_with = "srgb")]
    hdr: bool,
    /// The LDR colour (and output) are sRGB-encoded, not linear: the
    /// network sees them as they are.
    #[arg(long)]
    srgb: bool,
    /// Multiplies the colour before the network and divides the output
    /// [default: in HDR OIDN's autoexposure, else 1].
    #[arg(long, value_parser = parse_scale)]
    input_scale: Option<f32>,
    /// Storage of the tensors between layers (accumulation is f32 either way).
    #[arg(long, value_enum, default_value = "f32")]
    precision: loupe::denoise::Precision,
    /// The denoised image: .pfm, .exr or .png.
    #[arg(short = 'o', long)]
    output: PathBuf,
    /// Write every tensor of the network into this directory as
    /// `<name>.npy` (height, width, channels of the padded image; on the
    /// GPU per tile, `tile<i>/`, when it cut the image into tiles).
    #[arg(long, value_name = "DIR")]
    dump_tensors: Option<PathBuf>,
    /// Where the network runs.
    #[arg(short = 'd', long, value_enum, default_value = "gpu")]
    device: loupe::denoise::offline::Device,
    /// Project root: where shaders/ is (the GPU's).
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// The most memory one tile's tensors may take on the GPU, in MiB
    /// (OIDN's `--maxmem`): larger images are cut into tiles that overlap
    /// by the network's receptive radius.
    #[arg(long, default_value_t = 2048, value_parser = clap::value_parser!(u64).range(1..=1 << 20))]
    max_memory_mb: u64,
    /// The GPU's tile side in pixels instead of the largest that fits: a
    /// multiple of 16, more than twice the receptive radius (224 or more
    /// for OIDN's networks).
    #[arg(long, value_parser = parse_tile)]
    tile: Option<u32>,
}

fn parse_tile(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n) if n > 0 && n % 16 == 0 && n <= 16384 => Ok(n),
        _ => Err(format!("{s} is not a tile side: a multiple of 16 up to 16384")),
    }
}

fn parse_scale(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a positive number")),
    }
}

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
    set: Vec<(String, loupe::scene::overrides::Value)>,
    /// Project root: where shaders/ is.
    #[arg(long, default_value = ".")]
    root: PathBuf,
}

/// A path given relative to the project root, as every subcommand reads
/// `--scene` (absolute paths stand as they are).
fn under_root(root: &std::path::Path, path: &std::path::Path) -> PathBuf {
    if path.is_absolute() { path.to_owned() } else { root.join(path) }
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
struct RenderArgs {
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
}

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
struct BenchArgs {
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
}

#[derive(clap::Subcommand)]
enum BenchCommand {
    /// What accuracy costs in time: sweep each quality setting the scene
    /// calls for, time the passes it affects and compare each image with
    /// a reference (relative MSE; PSNR and SSIM of the tonemapped image).
    /// Writes tradeoffs.json, tradeoffs.md, tradeoffs.svg and each point's
    /// image into --out.
    Tradeoffs(TradeoffsArgs),
}

#[derive(clap::Args)]
struct TradeoffsArgs {
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
    set: Vec<(String, loupe::scene::overrides::Value)>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT"))?;
    let side = |v: &str| -> Result<u32, String> {
        let n: u32 = v.trim().parse().map_err(|_| format!("`{v}` is not a number"))?;
        if (1..=loupe::scene::MAX_SIDE).contains(&n) { Ok(n) } else { Err(format!("{n} is outside 1..={}", loupe::scene::MAX_SIDE)) }
    };
    Ok((side(w)?, side(h)?))
}

fn parse_override(s: &str) -> Result<(String, loupe::scene::overrides::Value), String> {
    use loupe::scene::overrides::Value;
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

#[derive(clap::Args)]
struct ServeArgs {
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

#[derive(clap::Args)]
struct CheckArgs {
    /// Files or directories to check: directories are searched for *.wgsl,
    /// and for *.toml scenes inside a directory named `scenes`; a file
    /// named here is a scene when it ends in .toml, else WGSL.
    /// Default: `paths` in loupe.toml, else the project's shaders/ and scenes/.
    paths: Vec<PathBuf>,
    /// Output format [default: `format` in loupe.toml, else human].
    #[arg(long, value_enum)]
    format: Option<format::Format>,
    /// Skip pipeline creation: check sources only, never open a device.
    #[arg(long, conflicts_with = "device")]
    no_device: bool,
    /// Require a device: exit 3 when no GPU adapter exists.
    #[arg(long)]
    device: bool,
    /// Treat warnings as errors for the exit code; `--deny-warnings=false`
    /// overrides loupe.toml's `deny_warnings = true`.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    deny_warnings: Option<bool>,
    /// Shader capabilities to validate with, comma-separated naga names
    /// (`float64,shader-int64,shader-float16`) or `all`; what every WebGPU
    /// device has is always allowed. Default: `capabilities` in loupe.toml,
    /// else with a device what its adapter supports, and without one
    /// `primitive-index,subgroup,subgroup-barrier,shader-float16` (what
    /// loupe can request).
    #[arg(long, value_name = "LIST", value_parser = check::capabilities::parse_arg)]
    capabilities: Option<naga::valid::Capabilities>,
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
    // SAFETY: the first thing the process does, before any thread exists.
    unsafe { loupe::gpu::provide_runtime_dir() };
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => run_check(args),
        Command::Serve(args) => run_serve(args),
        Command::Render(args) => run_render(args),
        Command::Bench(args) => run_bench(args),
        Command::Denoise(args) => run_denoise(args),
    }
}

/// Prints diagnostics on stderr the way `loupe check` prints them.
fn print_diagnostics(diags: &[loupe::diag::Diagnostic]) {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let _ = format::human::write_diagnostics(diags, color, &mut std::io::stderr().lock());
}

/// Prints input errors the way `loupe check` does and picks the exit code.
fn offline_failed(cmd: &str, e: offline::OfflineError) -> ExitCode {
    match e {
        offline::OfflineError::NoDevice(e) => {
            eprintln!("loupe {cmd}: {e}");
            ExitCode::from(exit::NO_DEVICE)
        }
        offline::OfflineError::Input(diags) => {
            print_diagnostics(&diags);
            ExitCode::from(exit::ERRORS)
        }
        offline::OfflineError::Io(e) => {
            eprintln!("loupe {cmd}: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}

fn run_render(args: RenderArgs) -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let mut job = args.scene.job();
    use loupe::scene::overrides::Value;
    if let Some(r) = &args.renderer {
        job.overrides.insert("quality.renderer".into(), Value::Text(r.clone()));
    }
    if let Some(n) = args.spp {
        job.overrides.insert("quality.path_spp".into(), Value::Int(n));
    }
    let report = match offline::render(&job, &args.out) {
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

fn run_denoise(args: DenoiseArgs) -> ExitCode {
    use loupe::denoise::{offline, process::Mode};
    let mode = match (args.hdr, args.srgb) {
        (true, _) => Mode::Hdr,
        (false, true) => Mode::LdrSrgb,
        (false, false) => Mode::Ldr,
    };
    let job = offline::Job {
        weights: args.weights,
        color: args.color,
        albedo: args.albedo,
        normal: args.normal,
        mode,
        input_scale: args.input_scale,
        precision: args.precision,
        output: args.output,
        dump_tensors: args.dump_tensors,
        device: args.device,
        shader_root: args.root.join("shaders"),
        max_memory_mb: args.max_memory_mb,
        tile: args.tile,
    };
    match offline::run(&job) {
        Ok(r) => {
            let dumped = match &job.dump_tensors {
                Some(dir) => format!(", {} tensors in {}", r.tensors_dumped, dir.display()),
                None => String::new(),
            };
            let tiles = match r.window {
                Some(side) if r.tiles > 1 => format!(" in {} tiles of {side}x{side}", r.tiles),
                _ => String::new(),
            };
            println!(
                "{}: {}x{}, {}, input scale {}, network {:.3} s on {}{tiles}{dumped}",
                job.output.display(),
                r.width,
                r.height,
                r.inputs.describe(),
                r.input_scale,
                r.network_seconds,
                r.device
            );
            ExitCode::from(exit::OK)
        }
        Err(d) => {
            use loupe::diag::Code;
            print_diagnostics(std::slice::from_ref(&d));
            ExitCode::from(match d.code {
                Code::Io | Code::FileTooLarge => exit::USAGE,
                Code::DeviceMissing => exit::NO_DEVICE,
                _ => exit::ERRORS,
            })
        }
    }
}

fn run_tradeoffs(args: TradeoffsArgs) -> ExitCode {
    let cache = args.cache.unwrap_or_else(|| {
        let base = std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")));
        base.unwrap_or_else(std::env::temp_dir).join("loupe/references")
    });
    let job = loupe::tradeoffs::Job {
        scene: under_root(&args.root, &args.scene),
        shader_root: args.root.join("shaders"),
        size: args.size,
        repeats: args.repeats,
        reference_spp: args.reference_spp,
        cache,
        overrides: args.set.into_iter().collect(),
    };
    let out = under_root(&args.root, &args.out);
    let report = match loupe::tradeoffs::run(&job, &out) {
        Ok(r) => r,
        Err(e) => return offline_failed("bench tradeoffs", e),
    };
    use loupe::tradeoffs::report;
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

fn run_bench(args: BenchArgs) -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    if let Some(BenchCommand::Tradeoffs(t)) = args.what {
        return run_tradeoffs(t);
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
        use loupe::scene::overrides::Value;
        let mut overrides = loupe::scene::overrides::Overrides::from([("quality.renderer".to_owned(), Value::Text(args.renderer.clone()))]);
        if args.renderer == "path" {
            overrides.insert("quality.path_spp".into(), Value::Int(65536));
        }
        if let Some(b) = args.bounces {
            overrides.insert("quality.path_bounces".into(), Value::Int(b));
        }
        let job = offline::Job { scene, shader_root: args.root.join("shaders"), size: Some(args.size), overrides };
        let r = match offline::bench(&job, args.frames, args.serial) {
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

fn run_serve(args: ServeArgs) -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let scene = under_root(&args.root, &args.scene);
    if !scene.is_file() {
        eprintln!("loupe serve: scene `{}` does not exist", scene.display());
        return ExitCode::from(exit::USAGE);
    }
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

fn run_check(args: CheckArgs) -> ExitCode {
    // loupe.toml's defaults, then the flags over them.
    let defaults = match check::project::read(&args.root) {
        Ok(d) => d,
        Err(d) => {
            print_diagnostics(&[d]);
            return ExitCode::from(exit::USAGE);
        }
    };
    let shader_root = args.root.join("shaders");
    let paths = if !args.paths.is_empty() {
        args.paths.clone()
    } else if let Some(paths) = defaults.paths {
        paths
    } else {
        [shader_root.clone(), args.root.join("scenes")].into_iter().filter(|p| p.exists()).collect()
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
    let capabilities = args.capabilities.or(defaults.capabilities);
    let (report, files) = match check::run(&CheckOptions { paths, shader_root, device, capabilities }) {
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
    let format = args.format.or(defaults.format).unwrap_or(format::Format::Human);
    if let Err(e) = format::write(format, &report, &files, &opts, &mut out) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("loupe check: cannot write output: {e}");
            return ExitCode::from(exit::USAGE);
        }
    }
    match report.exit_code(args.deny_warnings.or(defaults.deny_warnings).unwrap_or(false)) {
        0 => ExitCode::from(exit::OK),
        _ => ExitCode::from(exit::ERRORS),
    }
}
