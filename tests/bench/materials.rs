//! `bench-materials`: the compile time of every material of the starter
//! library (`scenes/materials/*.mat`), parse → tree → analysis → WGSL, as
//! a scene's load compiles it (the compile report's `compile_ms`: the
//! file and its imports read and parsed, then the definition analysed and
//! its module written), and apart from it the naga validation of that
//! module composed with the shader library it imports (what `loupe check`
//! and the renderer's pipelines add, not part of the goal).
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-materials [-- --runs 200]
//! ```
//!
//! Prints one row per material: the generated WGSL's bytes, the compile's
//! p50, p95 and max over `--runs` (default 200, after 5 unmeasured), and
//! the validation's p50 over a tenth as many. The goal is judged at p95:
//! on a loaded machine the max is whichever run the scheduler preempted.
//! Exits 1 when a material fails to compile or validate.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use loupe::material::tree::Definition;
use loupe::material::{Program, back, front};
use loupe::shader::{ShaderDefs, compose, library};
use loupe_tests::reload::percentile;
use loupe_tests::{machine, repo};

/// What compiling one material takes, as `loupe::loaded` does it.
fn compile(path: &Path, name: &str) -> Result<(Definition, String), String> {
    let loaded = front::load(path).map_err(|d| format!("{d:?}"))?;
    let def = loaded.definitions.iter().find(|d| d.name == name).ok_or(format!("no material `{name}`"))?;
    let analysed = loupe::material::analysed(def).map_err(|d| format!("{d:?}"))?;
    let wgsl = back::wgsl(std::slice::from_ref(&analysed.def), back::Bindings::RENDERER);
    Ok((analysed.def, wgsl))
}

/// Milliseconds of each of `runs` calls of `f`, after 5 unmeasured.
fn timed<T>(runs: usize, mut f: impl FnMut() -> T) -> Vec<f64> {
    for _ in 0..5 {
        std::hint::black_box(f());
    }
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect()
}

fn main() -> ExitCode {
    let runs = match std::env::args().skip(1).collect::<Vec<_>>().as_slice() {
        [] => 200,
        [flag, n] if flag == "--runs" && n.parse::<usize>().is_ok_and(|n| n > 0) => n.parse().expect("checked"),
        _ => {
            eprintln!("bench-materials: usage: bench-materials [--runs N]");
            return ExitCode::from(2);
        }
    };
    let shaders = repo().join("shaders");
    let lib = match library::read_tree(&shaders) {
        Ok(lib) => lib,
        Err(e) => {
            eprintln!("bench-materials: {e}");
            return ExitCode::FAILURE;
        }
    };
    let caps = loupe::gpu::capabilities_without_device();
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("scenes/materials"))
        .expect("scenes/materials/ is readable")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "mat"))
        .collect();
    files.sort();
    let profile = if cfg!(debug_assertions) { "debug build: not a figure to quote" } else { "release build" };
    println!("bench-materials: {runs} compiles per material (validation: {}), {profile}, {}", (runs / 10).max(1), machine());
    println!("{:<24} {:>10} {:>12} {:>12} {:>12} {:>16}", "material", "WGSL bytes", "compile p50", "p95", "max", "naga p50 (apart)");
    let mut ok = true;
    let mut worst: f64 = 0.0;
    for path in files {
        let names: Vec<String> = match front::load(&path) {
            Ok(l) => l.definitions.iter().map(|d| d.name.clone()).collect(),
            Err(d) => {
                eprintln!("{}: {d:?}", path.display());
                ok = false;
                continue;
            }
        };
        let stem = path.file_stem().unwrap_or_default().to_string_lossy().into_owned();
        for name in names {
            let label = if name == stem { stem.clone() } else { format!("{stem}: {name}") };
            let (def, wgsl) = match compile(&path, &name) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("{label}: {e}");
                    ok = false;
                    continue;
                }
            };
            let times = timed(runs, || compile(&path, &name));
            // The module as the renderer binds it, among the shaders, then
            // composed with its imports and validated (a fresh composer each
            // time, as `loupe check` does).
            let mut with_module = lib.clone();
            let program = Program { definitions: vec![def], ..Program::default() };
            loupe::render::session::material_module(&mut with_module, &shaders, &program);
            let module = with_module.get(back::DISPLAY).expect("just added").clone();
            let validate = || compose::check_library(&with_module, &module, &ShaderDefs::new(), caps);
            if let Err(ds) = validate() {
                eprintln!("{label}: the generated module does not validate: {ds:?}");
                ok = false;
                continue;
            }
            let naga = timed((runs / 10).max(1), validate);
            let max = times.iter().copied().fold(0.0, f64::max);
            let p95 = percentile(&times, 0.95);
            worst = worst.max(p95);
            println!(
                "{label:<24} {:>10} {:>9.3} ms {:>9.3} ms {:>9.3} ms {:>13.2} ms",
                wgsl.len(),
                percentile(&times, 0.5),
                p95,
                max,
                percentile(&naga, 0.5)
            );
        }
    }
    println!(
        "goal (each compile under 5 ms, at p95): the slowest material's p95 {worst:.3} ms, {}",
        if worst < 5.0 { "met" } else { "NOT met" }
    );
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
