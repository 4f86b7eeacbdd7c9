//! Golden tests in naga's manner: each directory under tests/golden/ is a
//! tiny project of bad shaders or scenes, checked with `loupe check --no-device`; its
//! human-format output must equal the checked-in `expected.txt` exactly.
//! `tests/golden/materials/` is a corpus of bad material files instead:
//! each `NAME.mat` is checked alone and its output is `NAME.expected.txt`
//! (files under `imports/` are only imported); cases too large to keep are
//! written by the test into a temporary folder and checked there.
//!
//! Regenerate after an intended change with:
//!     LOUPE_BLESS=1 cargo test -p loupe-tests --test e2e golden
//! and review the diff.

use std::path::Path;

use loupe_tests::{Project, loupe, repo};

#[test]
fn golden_diagnostics() {
    let root = repo().join("tests/golden");
    let bless = std::env::var_os("LOUPE_BLESS").is_some();
    let mut cases: Vec<_> = std::fs::read_dir(&root).expect("tests/golden").flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
    // Not shader cases: the material corpus (its own test) and the
    // reference images (`materials::the_bundled_scenes_…`).
    cases.retain(|c| !c.ends_with("materials") && !c.ends_with("images"));
    cases.sort();
    assert!(cases.len() >= 10, "expected the golden cases to be present");
    let mut failures = Vec::new();
    for case in &cases {
        let run = loupe(case, &["check", "--no-device", "--no-timings", "--color", "never"]);
        let actual = format!("exit code: {}\n{}", run.code, run.stdout);
        let expected_path = case.join("expected.txt");
        if bless {
            std::fs::write(&expected_path, &actual).expect("write expected.txt");
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if expected != actual {
            failures.push(format!(
                "=== {} ===\n--- expected ---\n{expected}\n--- actual ---\n{actual}\n--- stderr ---\n{}",
                case.file_name().unwrap().to_string_lossy(),
                run.stderr
            ));
        }
    }
    assert!(failures.is_empty(), "golden output differs (LOUPE_BLESS=1 to regenerate):\n{}", failures.join("\n"));
}

#[test]
fn golden_material_diagnostics() {
    let root = repo().join("tests/golden/materials");
    let mut failures = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(&root).expect("tests/golden/materials").flatten().map(|e| e.path()).collect();
    files.retain(|p| p.extension().is_some_and(|e| e == "mat"));
    files.sort();
    assert!(files.len() >= 10, "expected the material cases to be present");
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        compare(&root, &root, &name, &mut failures);
    }
    // Over the size cap: a sparse file, never checked in.
    let generated = Project::empty("golden-materials");
    let huge = std::fs::File::create(generated.path("huge.mat")).expect("create huge.mat");
    huge.set_len(loupe::shader::library::MAX_FILE_BYTES + 1).expect("a sparse file");
    compare(&root, &generated.root, "huge.mat", &mut failures);
    assert!(failures.is_empty(), "golden output differs (LOUPE_BLESS=1 to regenerate):\n{}", failures.join("\n"));
}

/// Checks `dir/name` from `dir` and compares with `root/STEM.expected.txt`.
fn compare(root: &Path, dir: &Path, name: &str, failures: &mut Vec<String>) {
    let run = loupe(dir, &["check", "--no-device", "--no-timings", "--color", "never", name]);
    let actual = format!("exit code: {}\n{}", run.code, run.stdout);
    let expected_path = root.join(format!("{}.expected.txt", name.trim_end_matches(".mat")));
    if std::env::var_os("LOUPE_BLESS").is_some() {
        std::fs::write(&expected_path, &actual).expect("write the expected output");
        return;
    }
    let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
    if expected != actual {
        failures.push(format!("=== {name} ===\n--- expected ---\n{expected}\n--- actual ---\n{actual}\n--- stderr ---\n{}", run.stderr));
    }
}
