//! The repository's Markdown stays navigable and sourced: README.md stays
//! short; every relative link in README.md, PROTOCOL.md, ARCHITECTURE.md
//! and docs/*.md names a file that exists and, with a `#anchor`, a heading
//! that file has; every table of figures in docs/benchmarks.md comes with
//! the command that made it. Tests of the docs, not of the crate: they
//! live here because this crate's unit tests are the ones every run builds.

use std::path::{Path, PathBuf};

/// About 200 lines, as the README's brief says, with some slack.
const README_MAX_LINES: usize = 220;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The Markdown files whose links are checked.
fn documents() -> Vec<PathBuf> {
    let root = repo();
    let mut files: Vec<PathBuf> = ["README.md", "PROTOCOL.md", "ARCHITECTURE.md"].iter().map(|f| root.join(f)).collect();
    let docs = std::fs::read_dir(root.join("docs")).expect("docs/ exists");
    files.extend(docs.map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|x| x == "md")));
    files
}

/// The lines outside fenced code blocks: a `](` inside one is code.
fn prose(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|line| {
            if line.trim_start().starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// Every link target of the form `[text](target)` or `![alt](target)`.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose(text) {
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            rest = &rest[at + 2..];
            let end = rest.find([')', ' ']).unwrap_or(rest.len());
            out.push(rest[..end].to_owned());
        }
    }
    out
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces
/// to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(text: &str) -> Vec<String> {
    prose(text).iter().filter(|l| l.starts_with('#')).map(|l| slug(l.trim_start_matches('#'))).collect()
}

/// What is wrong with one link of `file`, if anything.
fn broken(file: &Path, target: &str) -> Option<String> {
    if target.contains("://") || target.starts_with("mailto:") {
        return None;
    }
    let (path, anchor) = target.split_once('#').unwrap_or((target, ""));
    let linked = if path.is_empty() { file.to_path_buf() } else { file.parent().unwrap().join(path) };
    if !linked.exists() {
        return Some(format!("{target}: no file {}", linked.display()));
    }
    if anchor.is_empty() || linked.extension().is_none_or(|x| x != "md") {
        return None;
    }
    let text = std::fs::read_to_string(&linked).unwrap();
    if anchors(&text).iter().any(|a| a == anchor) { None } else { Some(format!("{target}: no heading #{anchor} in {}", linked.display())) }
}

#[test]
fn the_readme_is_short() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(lines <= README_MAX_LINES, "README.md has {lines} lines, more than {README_MAX_LINES}: move the detail into docs/");
}

#[test]
fn every_relative_link_in_the_docs_resolves() {
    let mut failures = Vec::new();
    for file in documents() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(repo()).unwrap_or(&file).display().to_string();
        failures.extend(links(&text).iter().filter_map(|t| broken(&file, t)).map(|e| format!("{name}: {e}")));
    }
    assert!(failures.is_empty(), "broken links:\n{}", failures.join("\n"));
}

/// Each section of docs/benchmarks.md that holds a table also says how
/// to make it again: a `- Command:` line, or a paragraph marked
/// **Historical** naming the commit and the command.
#[test]
fn every_benchmark_table_names_its_command() {
    let text = std::fs::read_to_string(repo().join("docs/benchmarks.md")).unwrap();
    let mut sections: Vec<Vec<&str>> = vec![Vec::new()];
    for line in prose(&text) {
        if line.starts_with('#') {
            sections.push(Vec::new());
        }
        sections.last_mut().unwrap().push(line);
    }
    let unsourced: Vec<&str> = sections
        .iter()
        .filter(|s| s.iter().any(|l| l.starts_with('|')))
        .filter(|s| !s.iter().any(|l| l.starts_with("- Command: ") || l.contains("**Historical**")))
        .map(|s| s[0])
        .collect();
    assert!(unsourced.is_empty(), "docs/benchmarks.md: tables without their command under {unsourced:?}");
}

#[test]
fn slugs_are_githubs() {
    assert_eq!(slug(" `loupe.toml`"), "loupetoml");
    assert_eq!(slug(" The CPU reference's time"), "the-cpu-references-time");
    assert_eq!(slug(" `loupe check` against naga-cli"), "loupe-check-against-naga-cli");
}
