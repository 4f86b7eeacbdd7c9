//! `bench-view`: what `loupe view`'s window costs the daemon's frame rate,
//! against `loupe serve` rendering alone and against the browser's live
//! view of the same frames; and the README's screenshot of the window.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-view                  # the comparison
//! cargo run --release -p loupe-tests --bin bench-view -- --seconds 20 --rounds 3 --size 320x180
//! cargo run --release -p loupe-tests --bin bench-view -- screenshot docs/view.png
//! ```
//!
//! The comparison: three setups on the same scene (`--scene`, the showcase
//! by default, its output resized to `--size`), each a process of its own,
//! taken in turn round after round so that drift in the machine's speed
//! falls on all three alike:
//! - `serve`: `loupe serve` with no client;
//! - `view`: `loupe view` in a virtual display (Xvfb), its window showing
//!   the Frame tab, no browser;
//! - `serve + browser`: `loupe serve` with one WebSocket client reading
//!   every message, as the browser's live view does (each frame's final
//!   output read back, PNG-encoded and sent).
//!
//! Each renders as fast as it can (`--fps 1000`); after `--warmup` seconds
//! (the first pipelines compile) the frames rendered over `--seconds` are
//! counted from `GET /api/status` (not over the WebSocket, which would make
//! a client of the `serve` setup). A frame's time is the window's length
//! over its frames. On a CPU adapter (lavapipe) the window's own drawing
//! and Xvfb share the CPU with the renderer, which a GPU does not.
//!
//! `screenshot PATH`: `loupe view` on the scene at its own size in a
//! 1280×800 virtual display; once frames render, the screen is saved as a
//! PNG.
//!
//! `LOUPE_BIN` picks the binary; otherwise the release build is built
//! first. Needs Xvfb and xwd (`tests/run` installs them).

use std::process::ExitCode;
use std::time::{Duration, Instant};

use loupe_tests::ws::{Msg, Ws};
use loupe_tests::xvfb::Xvfb;
use loupe_tests::{Project, Server, machine, release_bin};

struct Options {
    screenshot: Option<String>,
    scene: String,
    size: Option<(u32, u32)>,
    seconds: f64,
    warmup: f64,
    rounds: usize,
}

fn parse() -> Result<Options, String> {
    let mut o =
        Options { screenshot: None, scene: "scenes/showcase.toml".into(), size: Some((320, 180)), seconds: 20.0, warmup: 15.0, rounds: 3 };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        let number = |v: String| v.parse::<f64>().map_err(|e| format!("`{v}`: {e}"));
        match a.as_str() {
            "screenshot" => {
                o.screenshot = Some(value("screenshot")?);
                o.size = None;
            }
            "--scene" => o.scene = value("--scene")?,
            "--size" => {
                let v = value("--size")?;
                let (w, h) = v.split_once('x').ok_or(format!("--size `{v}`: WIDTHxHEIGHT"))?;
                o.size = Some((w.parse().map_err(|e| format!("`{w}`: {e}"))?, h.parse().map_err(|e| format!("`{h}`: {e}"))?));
            }
            "--seconds" => o.seconds = number(value("--seconds")?)?,
            "--warmup" => o.warmup = number(value("--warmup")?)?,
            "--rounds" => o.rounds = number(value("--rounds")?)? as usize,
            other => return Err(format!("unknown argument `{other}` (see the top of tests/bench/view.rs)")),
        }
    }
    Ok(o)
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Setup {
    Serve,
    View,
    Browser,
}

impl Setup {
    fn name(self) -> &'static str {
        match self {
            Setup::Serve => "serve",
            Setup::View => "view",
            Setup::Browser => "serve + browser",
        }
    }
}

/// A copy of the project whose scene renders at `size` (its own without):
/// the `width` and `height` lines of its `[output]` table replaced.
fn project(o: &Options) -> Project {
    let p = Project::copy_of_repo("bench-view");
    if let Some((w, h)) = o.size {
        let mut table = String::new();
        let lines: Vec<String> = p
            .read(&o.scene)
            .lines()
            .map(|line| {
                if line.starts_with('[') {
                    table = line.trim().to_owned();
                }
                match (table.as_str(), line.split('=').next().map(str::trim)) {
                    ("[output]", Some("width")) => format!("width = {w}"),
                    ("[output]", Some("height")) => format!("height = {h}"),
                    _ => line.to_owned(),
                }
            })
            .collect();
        p.write(&o.scene, lines.join("\n") + "\n");
    }
    p
}

fn frame(server: &Server) -> u64 {
    server.get_json("/api/status")["frame"].as_u64().unwrap_or(0)
}

/// Frames per second of one run of `setup`, and the bytes per frame a
/// browser received (`Browser` only).
fn measure(bin: &std::path::Path, p: &Project, o: &Options, setup: Setup, xvfb: &Xvfb) -> (f64, Option<f64>) {
    let args = ["--scene", o.scene.as_str(), "--fps", "1000"];
    let command = if setup == Setup::View { "view" } else { "serve" };
    let server = Server::start_command(bin, &p.root, command, 0, &args, &[("DISPLAY", &xvfb.display)]);
    let mut browser = (setup == Setup::Browser).then(|| Ws::connect(&server.addr).expect("the browser connects"));
    // The browser reads every message as it comes, in its own thread, as
    // a page does; the bytes it got are counted.
    let received = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = browser.take().map(|mut ws| {
        let (received, stop) = (received.clone(), stop.clone());
        std::thread::spawn(move || {
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                if let Some(Msg::Image(_, bytes)) = ws.next_before(Instant::now() + Duration::from_millis(200)) {
                    received.fetch_add(bytes.len() as u64, std::sync::atomic::Ordering::Relaxed);
                }
            }
        })
    });
    std::thread::sleep(Duration::from_secs_f64(o.warmup));
    let (start, bytes_start, at) = (frame(&server), received.load(std::sync::atomic::Ordering::Relaxed), Instant::now());
    std::thread::sleep(Duration::from_secs_f64(o.seconds));
    let (end, bytes_end, took) = (frame(&server), received.load(std::sync::atomic::Ordering::Relaxed), at.elapsed().as_secs_f64());
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    if let Some(r) = reader {
        let _ = r.join();
    }
    server.kill();
    let frames = end.saturating_sub(start);
    let per_frame = reader_bytes(setup, bytes_end - bytes_start, frames);
    (frames as f64 / took, per_frame)
}

fn reader_bytes(setup: Setup, bytes: u64, frames: u64) -> Option<f64> {
    (setup == Setup::Browser && frames > 0).then(|| bytes as f64 / frames as f64)
}

fn compare(bin: &std::path::Path, o: &Options) -> bool {
    let p = project(o);
    let xvfb = Xvfb::start(1280, 800);
    let setups = [Setup::Serve, Setup::View, Setup::Browser];
    let mut rates: Vec<Vec<f64>> = vec![Vec::new(); setups.len()];
    let mut bytes = Vec::new();
    for round in 0..o.rounds {
        for (i, setup) in setups.into_iter().enumerate() {
            let (rate, per_frame) = measure(bin, &p, o, setup, &xvfb);
            eprintln!("round {}: {:<16} {rate:.2} frames/s", round + 1, setup.name());
            rates[i].push(rate);
            bytes.extend(per_frame);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let size = o.size.map_or("its own size".into(), |(w, h)| format!("{w}x{h}"));
    println!(
        "loupe view against loupe serve: {} at {size}, {} rounds of {} s (after {} s warm-up), --fps 1000",
        o.scene, o.rounds, o.seconds, o.warmup
    );
    println!("  {}", machine());
    println!("  {:<16} {:>10} {:>14} {:>16}", "setup", "frames/s", "ms per frame", "against serve");
    let base = mean(&rates[0]);
    for (setup, r) in setups.iter().zip(&rates) {
        let m = mean(r);
        println!("  {:<16} {:>10.2} {:>14.1} {:>15.1}%", setup.name(), m, 1e3 / m, (base / m - 1.0) * 100.0);
    }
    if !bytes.is_empty() {
        println!("  the browser received {:.0} KiB per frame", mean(&bytes) / 1024.0);
    }
    rates.iter().all(|r| r.iter().all(|&x| x > 0.0))
}

fn screenshot(bin: &std::path::Path, o: &Options, path: &str) -> bool {
    let p = project(o);
    let xvfb = Xvfb::start(1280, 800);
    let server = Server::start_command(bin, &p.root, "view", 0, &["--scene", &o.scene], &[("DISPLAY", &xvfb.display)]);
    server.wait_for("frames", Duration::from_secs(600), || (frame(&server) >= 10).then_some(()));
    // The window shows the newest frame a moment after it lands.
    std::thread::sleep(Duration::from_secs(3));
    let shot = xvfb.screenshot();
    server.kill();
    match shot.save(path) {
        Ok(()) => {
            println!("wrote {path} ({}x{})", shot.width(), shot.height());
            true
        }
        Err(e) => {
            eprintln!("bench-view: cannot write {path}: {e}");
            false
        }
    }
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("bench-view: {e}");
            return ExitCode::from(2);
        }
    };
    let bin = release_bin();
    let ok = match &o.screenshot {
        Some(path) => screenshot(&bin, &o, path),
        None => compare(&bin, &o),
    };
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
