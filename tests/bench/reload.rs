//! `bench-reload`: save-to-frame latency and the edit/break/fix soak of the
//! release `loupe serve`, on a temporary copy of the repository's project.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-reload               # both
//! cargo run --release -p loupe-tests --bin bench-reload -- latency --edits 50
//! cargo run --release -p loupe-tests --bin bench-reload -- soak --cycles 1000
//! ```
//!
//! Latency: two series side by side on one server, serving `minimal.toml`
//! with its material from a `.mat` file, their saves alternating: the
//! tonemap shader with a new constant colour, and the material file with a
//! new colour (a value edit). Each is saved as an editor does (temporary
//! file renamed over it) and timed from the write to the arrival of the
//! `frame` event that carries its reload. The split comes from that
//! reload's `reload_succeeded` timings; `send` is the rest (the write to
//! the first file event, queues between threads, the events' way to this
//! client, and for a material edit the scene's reload, which no timing
//! covers: its load alone is measured in this process on the same files).
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

use std::process::ExitCode;

use loupe_tests::reload::{self, Driver, Split};
use loupe_tests::{Project, Server, machine, release_bin};

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

fn start(bin: &std::path::Path, name: &str, extra: &[&str]) -> (Project, Server) {
    let project = Project::copy_of_repo(name);
    reload::material_scene(&project);
    let server = Server::start_with(bin, &project.root, 0, extra);
    (project, server)
}

/// Milliseconds of the project's material scene loaded as the daemon
/// reloads it after a material edit (`loupe::loaded::load_keeping`: the
/// previous load's meshes, textures and network kept, the material file
/// read again), and of a whole load (`load_with`), `n` times each: the part
/// of a material edit's reload that no timing of `reload_succeeded` covers
/// (installing it on the device is not in it).
fn scene_loads(project: &Project, n: usize) -> (Vec<f64>, Vec<f64>) {
    let scene = project.path(reload::MATERIAL_SCENE);
    let timed = |f: &dyn Fn()| {
        let start = std::time::Instant::now();
        f();
        start.elapsed().as_secs_f64() * 1e3
    };
    let overrides = Default::default();
    let load = || loupe::loaded::load_with(&scene, &overrides).expect("the material scene loads");
    let previous = load();
    let material = |p: &std::path::Path| p.extension().is_some_and(|e| e == "mat");
    let keep = loupe::loaded::Keep { previous: &previous, changed: &material };
    let kept = (0..n)
        .map(|_| timed(&|| drop(loupe::loaded::load_keeping(&scene, &overrides, Some(&keep)).expect("the material scene loads"))))
        .collect();
    let whole = (0..n).map(|_| timed(&|| drop(load()))).collect();
    (kept, whole)
}

/// One figure of a save's split.
type Column = fn(&Split) -> f64;

fn latency(bin: &std::path::Path, o: &Options) -> bool {
    let (project, server) = start(bin, "bench-latency", &["--render", &o.render, "--scene", reload::MATERIAL_SCENE]);
    let mut driver = Driver::new(&project, &server);
    let series = [reload::Edits::shader(&project), reload::Edits::material()];
    let samples = reload::latency(&mut driver, o.warmup, o.edits, &series);
    let adapter = server.get_json("/api/status")["adapter"].as_str().unwrap_or("?").to_owned();
    println!(
        "save-to-frame latency: {} edits of each series, alternating (after {} warm-up rounds), --render {}, scene {}",
        o.edits,
        o.warmup,
        o.render,
        reload::MATERIAL_SCENE
    );
    println!("  adapter {adapter}; {}", machine());
    println!("  {:<30} {:>12} {:>12} {:>12} {:>12}", "ms", "shader p50", "p95", "material p50", "p95");
    let rows: [(&str, Column); 6] = [
        ("total (write -> frame event)", |s| s.total),
        ("watch + debounce", |s| s.watch),
        ("compose + validate", |s| s.compose),
        ("pipeline creation", |s| s.pipeline),
        ("render (first frame)", |s| s.render),
        ("send (the rest)", |s| s.send),
    ];
    let column = |series: &[Split], f: Column| series.iter().map(f).collect::<Vec<f64>>();
    let [shader, material] = [&samples[0], &samples[1]];
    for (name, f) in rows {
        let (a, b) = (column(shader, f), column(material, f));
        let p = |v: &[f64], q| reload::percentile(v, q);
        println!("  {name:<30} {:>12.1} {:>12.1} {:>12.1} {:>12.1}", p(&a, 0.5), p(&a, 0.95), p(&b, 0.5), p(&b, 0.95));
    }
    let (kept, whole) = scene_loads(&project, o.edits);
    for (name, v) in [("  of which the scene's load", kept), ("    (a whole load, for scale)", whole)] {
        let p = |q| reload::percentile(&v, q);
        println!("  {name:<30} {:>12} {:>12} {:>12.1} {:>12.1}", "-", "-", p(0.5), p(0.95));
    }
    // loupe's own time: everything but pipeline creation and rendering,
    // which are the driver's (lavapipe compiles shaders at the first draw).
    let own = |s: &Split| s.watch + s.compose + s.send;
    for (name, series) in [("shader", shader), ("material", material)] {
        let v = column(series, own);
        let (p50, p95) = (reload::percentile(&v, 0.5), reload::percentile(&v, 0.95));
        println!(
            "  {name}: watch + compose + send (loupe's own time) {p50:.1} ms at p50, {p95:.1} ms at p95; goal under 10 ms at p95: {}",
            if p95 < 10.0 { "met" } else { "NOT met" }
        );
    }
    println!("  dropped: {} events, {} frames", driver.dropped_events, driver.dropped_frames);
    driver.dropped_events == 0
}

fn soak(bin: &std::path::Path, o: &Options) -> bool {
    let (project, server) = start(bin, "bench-soak", &["--render", &o.render, "--scene", "scenes/pattern.toml"]);
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
    let bin = release_bin();
    let mut ok = true;
    if o.latency {
        ok &= latency(&bin, &o);
    }
    if o.soak {
        ok &= soak(&bin, &o);
    }
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
