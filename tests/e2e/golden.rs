//! Golden tests in naga's manner: each directory under tests/golden/ is a
//! tiny project of bad shaders or scenes, checked with `loupe check --no-device`; its
//! human-format output must equal the checked-in `expected.txt` exactly.
//!
//! Regenerate after an intended change with:
//!     LOUPE_BLESS=1 cargo test -p loupe-tests --test e2e golden
//! and review the diff.

use loupe_tests::{loupe, repo};

#[test]
fn golden_diagnostics() {
    let root = repo().join("tests/golden");
    let bless = std::env::var_os("LOUPE_BLESS").is_some();
    let mut cases: Vec<_> = std::fs::read_dir(&root).expect("tests/golden").flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
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
