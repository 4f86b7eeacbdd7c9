//! `bench-reload`: save-to-frame latency and the edit/break/fix soak of the
//! release `loupe serve`, on a temporary copy of the repository's project.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-reload               # both
//! cargo run --release -p loupe-tests --bin bench-reload -- latency --edits 50
//! cargo run --release -p loupe-tests --bin bench-reload -- soak --cycles 1000
//! ```
//!
//! Latency: each edit saves the tonemap shader as an editor does (temporary
//! file renamed over it) with a new constant colour, and is timed from the
//! write to the arrival of the `frame` event that carries its reload. The
//! split comes from that reload's `reload_succeeded` timings; `send` is the
//! rest (the write to the first file event, queues between threads, and
//! the events' way to this client).
//!
//! Soak: cycles of edit / break / fix; every save must produce its
//! `reload_succeeded` / `reload_failed`, the server's VmRSS must stay under
//! the bound, and the final frame must show the final file's colour.
//!
//! Options: `--edits N` (50), `--warmup N` (5), `--cycles N` (1000),
//! `--render continuous|on-change` (continuous, the default of `loupe
//! serve`), `--rss-bound-mib N` (256). `LOUPE_BIN` picks the binary;
//! otherwise `cargo build --release -p loupe` is run first. Exits 1 when a
//! check fails.

use std::path::PathBuf;
use std::process::{Command, ExitCode};

use loupe_tests::reload::{self, Driver, Split};
use loupe_tests::{Project, Server, machine, repo};

struct Options {
    latency: bool,
    soak: bool,
    edits: usize,
    warmup: usize,
    cycles: usize,
    render: String,
    rss_bound_mib: u64,
}

fn parse() -> Result<Options, String> {
    let mut o = Options { latency: true, soak: true, edits: 50, warmup: 5, cycles: 1000, render: "continuous".into(), rss_bound_mib: 256 };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        let number = |v: String| v.parse::<usize>().map_err(|e| format!("`{v}`: {e}"));
        match a.as_str() {
            "latency" => (o.latency, o.soak) = (true, false),
            "soak" => (o.latency, o.soak) = (false, true),
            "all" => (o.latency, o.soak) = (true, true),
            "--edits" => o.edits = number(value("--edits")?)?,
            "--warmup" => o.warmup = number(value("--warmup")?)?,
            "--cycles" => o.cycles = number(value("--cycles")?)?,
            "--render" => o.render = value("--render")?,
            "--rss-bound-mib" => o.rss_bound_mib = number(value("--rss-bound-mib")?)? as u64,
            other => return Err(format!("unknown argument `{other}` (see the top of tests/bench/reload.rs)")),
        }
    }
    Ok(o)
}

/// `LOUPE_BIN`, else the release build (built now if needed).
fn release_binary() -> PathBuf {
    if let Some(p) = std::env::var_os("LOUPE_BIN") {
        return p.into();
    }
    let status = Command::new(env!("CARGO"))
        .args(["build", "--release", "-p", "loupe", "--bin", "loupe"])
        .current_dir(repo())
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building the release loupe failed");
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| repo().join("target"));
    target.join("release/loupe")
}

fn start(bin: &std::path::Path, name: &str, render: &str) -> (Project, Server) {
    let project = Project::copy_of_repo(name);
    let server = Server::start_with(bin, &project.root, 0, &["--render", render]);
    (project, server)
}

fn latency(bin: &std::path::Path, o: &Options) -> bool {
    let (project, server) = start(bin, "bench-latency", &o.render);
    let mut driver = Driver::new(&project, &server);
    let samples = reload::latency(&mut driver, o.warmup, o.edits);
    let adapter = server.get_json("/api/status")["adapter"].as_str().unwrap_or("?").to_owned();
    println!("save-to-frame latency: {} edits (after {} warm-up), --render {}", samples.len(), o.warmup, o.render);
    println!("  adapter {adapter}; {}", machine());
    println!("  {:<26} {:>9} {:>9}", "ms", "p50", "p95");
    let column = |f: fn(&Split) -> f64| samples.iter().map(f).collect::<Vec<f64>>();
    let rows: [(&str, Vec<f64>); 6] = [
        ("total (write -> frame event)", column(|s| s.total)),
        ("watch + debounce", column(|s| s.watch)),
        ("compose + validate", column(|s| s.compose)),
        ("pipeline creation", column(|s| s.pipeline)),
        ("render (first frame)", column(|s| s.render)),
        ("send (the rest)", column(|s| s.send)),
    ];
    for (name, v) in &rows {
        println!("  {name:<26} {:>9.1} {:>9.1}", reload::percentile(v, 0.5), reload::percentile(v, 0.95));
    }
    let p50 = |i: usize| reload::percentile(&rows[i].1, 0.5);
    let own = p50(1) + p50(2) + p50(5);
    println!(
        "  goal (watch + compose + send, loupe's own time, under 10 ms at p50): {own:.1} ms, {}",
        if own < 10.0 { "met" } else { "NOT met" }
    );
    println!("  dropped: {} events, {} frames", driver.dropped_events, driver.dropped_frames);
    driver.dropped_events == 0
}

fn soak(bin: &std::path::Path, o: &Options) -> bool {
    let (project, server) = start(bin, "bench-soak", &o.render);
    let mut driver = Driver::new(&project, &server);
    let started = std::time::Instant::now();
    let report = reload::soak(&server, &mut driver, o.cycles, 10, |r| {
        if r.done % 100 == 0 {
            let kib = r.rss.last().map_or(0, |x| x.1);
            eprintln!("  {} cycles: VmRSS {:.1} MiB, {} outcomes, {} lost", r.done, kib as f64 / 1024.0, r.outcomes, r.lost.len());
        }
    });
    let mib = |k: u64| k as f64 / 1024.0;
    let first = report.rss.first().map_or(0, |r| r.1);
    let last = report.rss.last().map_or(0, |r| r.1);
    println!(
        "soak: {} edit/break/fix cycles ({} saves), --render {}, {:.0} s",
        report.cycles,
        report.cycles * 3,
        o.render,
        started.elapsed().as_secs_f64()
    );
    println!("  {}", machine());
    println!("  outcomes as expected: {} of {}; lost: {}", report.outcomes, report.cycles * 3, report.lost.len());
    for l in report.lost.iter().take(10) {
        println!("    {l}");
    }
    println!("  dropped by the server for this client: {} events, {} frames", report.dropped_events, report.dropped_frames);
    println!(
        "  VmRSS: after cycle 0 {:.1} MiB, max {:.1} MiB, at the end {:.1} MiB (bound {} MiB)",
        mib(first),
        mib(report.rss_max_kib()),
        mib(last),
        o.rss_bound_mib
    );
    let [r, g, b] = report.final_colour.map(reload::srgb);
    let p = report.final_pixel;
    println!(
        "  final frame {}: pixel ({:.4}, {:.4}, {:.4}), file's colour sRGB-encoded ({r:.4}, {g:.4}, {b:.4}): {}",
        report.final_frame,
        p[0],
        p[1],
        p[2],
        if report.final_matches() { "match" } else { "MISMATCH" }
    );
    let ok =
        report.lost.is_empty() && report.dropped_events == 0 && report.final_matches() && report.rss_max_kib() <= o.rss_bound_mib * 1024;
    println!("  soak {}", if ok { "passed" } else { "FAILED" });
    ok
}

fn main() -> ExitCode {
    let o = match parse() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("bench-reload: {e}");
            return ExitCode::from(2);
        }
    };
    let bin = release_binary();
    let mut ok = true;
    if o.latency {
        ok &= latency(&bin, &o);
    }
    if o.soak {
        ok &= soak(&bin, &o);
    }
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
