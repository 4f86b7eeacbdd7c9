//! Every command that needs a GPU, run where there is none: exit 3 and
//! advice the user can follow — no flag the command it names does not take.

use std::collections::BTreeSet;
use std::path::Path;

use loupe_tests::{Project, Run, loupe, loupe_with_env, repo};

use super::denoise::{fixture, weights};

/// Runs `loupe args` in `dir` with the Vulkan loader pointed at no driver
/// at all: a machine with no GPU and no lavapipe. A display is named (none
/// is reached) so that `view` gets as far as looking for an adapter.
pub fn without_adapter(dir: &Path, args: &[&str]) -> Run {
    loupe_with_env(dir, args, &[("VK_ICD_FILENAMES", "/nonexistent.json"), ("VK_DRIVER_FILES", "/nonexistent.json"), ("DISPLAY", ":0")])
}

/// The `--flags` words of `text`, cut where the name ends (`=value`,
/// `[=<BOOL>]`, punctuation).
fn flags(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| c.is_whitespace() || c == '(' || c == ',').filter(|w| w.starts_with("--") && w.len() > 2).map(|w| {
        let end = w[2..].find(|c: char| !(c.is_ascii_alphanumeric() || c == '-')).map_or(w.len(), |i| i + 2);
        &w[..end]
    })
}

/// The flags `loupe <command> --help` lists as options.
fn accepted(command: &str) -> BTreeSet<String> {
    let help = loupe(&repo(), &[command, "--help"]);
    help.code(0);
    let options =
        help.stdout.lines().map(|l| l.trim_start()).map(|l| if l.starts_with("-") && l.get(2..4) == Some(", ") { &l[4..] } else { l });
    options.filter(|l| l.starts_with("--")).filter_map(|l| flags(l).next()).map(str::to_owned).collect()
}

/// Every flag `advice` names is one the command it names takes: inside a
/// quoted `loupe <other> …` that command, elsewhere `command` itself.
fn assert_takes_every_flag(command: &str, advice: &str) {
    for (i, part) in advice.split('`').enumerate() {
        let quoted = i % 2 == 1;
        let named = match part.strip_prefix("loupe ") {
            Some(rest) if quoted => rest.split_whitespace().next().unwrap_or(command),
            // Another program's command line (`apt-get install …`).
            _ if quoted => continue,
            _ => command,
        };
        let takes = accepted(named);
        for flag in flags(part) {
            assert!(
                takes.contains(flag),
                "`loupe {command}` without an adapter suggests `{flag}`, which `loupe {named}` does not take: {advice}"
            );
        }
    }
}

#[test]
fn every_command_without_an_adapter_gives_advice_that_works() {
    let p = Project::empty("no-adapter-advice");
    let root = repo().display().to_string();
    let out = p.path("out").display().to_string();
    let (w, color) = (weights("rt_ldr.tza"), fixture("color.pfm"));
    let denoised = p.path("denoised.pfm").display().to_string();
    let runs: [(&str, Vec<&str>); 5] = [
        ("serve", vec!["serve", "--root", &root, "--port", "0"]),
        ("view", vec!["view", "--root", &root, "--port", "0"]),
        ("render", vec!["render", "--root", &root, "--size", "32x18", "--out", &out]),
        ("denoise", vec!["denoise", "--root", &root, "--weights", &w, "--color", &color, "--ldr", "-o", &denoised]),
        // `check` requires its device only when asked to, and says how not to.
        ("check", vec!["check", "--root", &root, "--device"]),
    ];
    for (command, args) in runs {
        let run = without_adapter(p.root.as_path(), &args);
        run.code(3).stderr_has("mesa-vulkan-drivers").stderr_has("`loupe check --no-device`");
        assert_takes_every_flag(command, &run.stderr);
    }
}
