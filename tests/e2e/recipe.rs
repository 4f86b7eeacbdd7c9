//! ARCHITECTURE.md's "How to add a pass", followed literally: its code
//! blocks (each naming where it goes in its info string: `file=PATH`, a
//! new file, or `file=PATH after=START`, inserted after the one line of
//! PATH that starts with START) applied to a copy of the workspace, which
//! must then build, pass `loupe check` and render the new pass. The recipe
//! is read from the document, so it cannot drift from what is tested.

use std::path::{Path, PathBuf};
use std::process::Command;

use loupe_tests::{Run, copy_dir, loupe_at, repo, run};
use serde_json::Value;

const SECTION: &str = "## How to add a pass";

/// One code block of the recipe and where it goes.
#[derive(Debug)]
struct Edit {
    file: String,
    /// The start of the line the block goes after; `None`: a new file.
    after: Option<String>,
    text: String,
}

/// The recipe's code blocks that say where they go, in order.
fn edits(doc: &str) -> Vec<Edit> {
    let section = doc.split_once(SECTION).unwrap_or_else(|| panic!("ARCHITECTURE.md has {SECTION:?}")).1;
    let section = section.split("\n## ").next().unwrap_or_default();
    let mut lines = section.lines();
    let mut out = vec![];
    while let Some(line) = lines.next() {
        let Some(info) = line.trim_start().strip_prefix("```") else { continue };
        // A block in a list item is indented as its fence is.
        let indent = line.len() - line.trim_start().len();
        let body: Vec<&str> = lines.by_ref().take_while(|l| l.trim() != "```").map(|l| l.get(indent..).unwrap_or(l.trim_start())).collect();
        let Some((_, place)) = info.split_once(" file=") else { continue };
        let (file, after) = match place.split_once(" after=") {
            Some((file, after)) => (file, Some(after.to_owned())),
            None => (place, None),
        };
        out.push(Edit { file: file.to_owned(), after, text: body.iter().map(|l| format!("{l}\n")).collect() });
    }
    out
}

/// Applies `e` under `root`; a block whose place is not there, or not one
/// line, fails the test at that step.
fn apply(root: &Path, e: &Edit) {
    let path = root.join(&e.file);
    let Some(after) = &e.after else {
        assert!(!path.exists(), "{} is a new file: {e:?}", e.file);
        std::fs::create_dir_all(path.parent().expect("a file in a folder")).expect("mkdir");
        std::fs::write(&path, &e.text).expect("write");
        return;
    };
    let text = std::fs::read_to_string(&path).unwrap_or_else(|err| panic!("{}: {err}: {e:?}", e.file));
    let at: Vec<usize> = text.lines().enumerate().filter(|(_, l)| l.trim_start().starts_with(after.as_str())).map(|(i, _)| i).collect();
    assert_eq!(at.len(), 1, "one line of {} starts with {after:?}: {e:?}", e.file);
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        out.push_str(line);
        out.push('\n');
        if i == at[0] {
            out.push_str(&e.text);
        }
    }
    std::fs::write(&path, out).expect("write");
}

/// A fresh copy of what `cargo build --workspace --bins` reads, at a fixed place
/// so that the loupe crate's incremental state is reused between runs.
fn copy_workspace(to: &Path) {
    let _ = std::fs::remove_dir_all(to);
    std::fs::create_dir_all(to).expect("mkdir");
    for file in ["Cargo.toml", "Cargo.lock"] {
        std::fs::copy(repo().join(file), to.join(file)).expect("copy");
    }
    // tests/ is a member of the workspace, and the lock file has its
    // dependencies: without it `--locked` refuses.
    for dir in ["server", "client", "shaders", "scenes", "tests"] {
        copy_dir(&repo().join(dir), &to.join(dir));
    }
}

/// Builds the copy's `loupe` in `target/recipe`, a target folder of its
/// own, so that the workspace's `target/debug/loupe`, which the other tests
/// run, is left alone. The first time, it starts from a copy of the
/// workspace's compiled dependencies (mtimes kept, so cargo finds them
/// fresh), and builds what `tests/run` builds, so that features unify alike
/// and only the copy's own crates compile.
fn build(root: &Path, target: &Path) -> (Run, PathBuf) {
    let debug = target.join("debug");
    if !debug.exists() {
        std::fs::create_dir_all(&debug).expect("mkdir");
        for dir in [".fingerprint", "build", "deps"] {
            let from = repo().join("target/debug").join(dir);
            if from.exists() {
                let ok = Command::new("cp").arg("-a").arg(&from).arg(&debug).status().is_ok_and(|s| s.success());
                assert!(ok, "cp -a {} {}", from.display(), debug.display());
            }
        }
    }
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let args = ["build", "--workspace", "--bins", "--offline", "--locked"];
    let mut cmd = Command::new(cargo);
    cmd.args(args).current_dir(root).env("CARGO_TARGET_DIR", target);
    let shown = format!("(cd {} && CARGO_TARGET_DIR={} cargo {})", root.display(), target.display(), args.join(" "));
    (run(cmd, shown), debug.join("loupe"))
}

fn pass<'a>(report: &'a Value, name: &str) -> Option<&'a Value> {
    report["passes"].as_array().expect("passes").iter().find(|p| p["name"] == name)
}

/// The sum of an RGBA8 image's color channels.
fn brightness(path: &Path) -> u64 {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
    img.pixels().map(|p| p.0[..3].iter().map(|&c| u64::from(c)).sum::<u64>()).sum()
}

/// `loupe render` of the minimal scene into `out`, with `set`; the report.
fn render(bin: &Path, root: &Path, out: &str, set: &str) -> Value {
    let run = loupe_at(bin, root, &["render", "--scene", "scenes/minimal.toml", "--out", out, "--size", "96x54", "--set", set]);
    run.code(0);
    let text = std::fs::read_to_string(root.join(out).join("report.json")).expect("report.json written");
    serde_json::from_str(&text).expect("report.json is JSON")
}

/// Slow: it compiles the loupe crate (and, the first time, its
/// dependencies into `target/recipe`).
#[test]
fn adding_a_pass_by_the_recipe_builds_and_renders_it() {
    let doc = std::fs::read_to_string(repo().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let edits = edits(&doc);
    assert!(edits.len() >= 5, "the recipe's blocks say where they go: {edits:?}");
    let target = repo().join("target/recipe");
    let root = target.join("workspace");
    copy_workspace(&root);
    for e in &edits {
        apply(&root, e);
    }

    let (built, bin) = build(&root, &target);
    built.code(0);
    let check = loupe_at(&bin, &root, &["check", "--no-device", "--format", "junit"]);
    check.code(0);
    check.check(check.stdout.contains("name=\"shaders/post/vignette.wgsl\""), "the new shader was checked");

    let off = render(&bin, &root, "off", "post.vignette=0");
    let culled = off["culled"].as_array().expect("culled").iter().find(|c| c["name"] == "vignette");
    assert!(
        culled.is_some_and(|c| c["reason"].as_str().is_some_and(|r| r.contains("post.vignette is 0"))),
        "culled with its reason: {off}"
    );
    let on = render(&bin, &root, "on", "post.vignette=1");
    let vignette = pass(&on, "vignette").unwrap_or_else(|| panic!("the vignette pass runs: {on}"));
    assert_eq!(vignette["pipelines"], serde_json::json!(["post.vignette"]), "{vignette}");
    // Its output is captured, and tonemapping reads it: the frame darkens
    // everywhere but at its very center.
    assert_eq!(vignette["outputs"].as_array().map(Vec::len), Some(1), "{vignette}");
    let final_png = |report: &Value, out: &str| {
        root.join(out).join(pass(report, "tonemap").expect("tonemap")["outputs"][0]["png"].as_str().expect("png"))
    };
    let (dark, lit) = (brightness(&final_png(&on, "on")), brightness(&final_png(&off, "off")));
    assert!(dark < lit, "the frame darkens with the vignette on: {dark} against {lit}");
    let _ = std::fs::remove_dir_all(&root);
}
