//! What the material fuzz targets share: a fuzz input as a small project
//! of material files, so imports, missing imports and import cycles are
//! exercised as well as one file's text.
//!
//! The input is cut at each `SEPARATOR` into at most `NAMES.len()` files,
//! written as `a.mat`, `b.mat`, ... into a directory of this process's own
//! (a later cut stays in the last file); `a.mat` is the root. A file the
//! input does not have is removed, so `import "c.mat"` is then a missing
//! import. Seeds join their files the same way (`fuzz/corpus/`).

use std::path::PathBuf;
use std::sync::OnceLock;

/// Where one file of the input ends and the next begins.
pub const SEPARATOR: &[u8] = b"\n//--- next file\n";

/// The files' names, the root first.
pub const NAMES: [&str; 4] = ["a.mat", "b.mat", "c.mat", "d.mat"];

/// Writes `data`'s files and returns the root's path.
pub fn project(data: &[u8]) -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("loupe-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a directory for the input's files");
        dir
    });
    let files = split(data);
    for (i, name) in NAMES.iter().enumerate() {
        let path = dir.join(name);
        match files.get(i) {
            Some(text) => std::fs::write(&path, text).expect("write an input file"),
            None => {
                let _ = std::fs::remove_file(&path);
            }
        }
    }
    dir.join(NAMES[0])
}

/// `data` cut into its files.
fn split(data: &[u8]) -> Vec<&[u8]> {
    let mut files = Vec::new();
    let mut rest = data;
    while files.len() + 1 < NAMES.len() {
        let Some(at) = rest.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) else { break };
        files.push(&rest[..at]);
        rest = &rest[at + SEPARATOR.len()..];
    }
    files.push(rest);
    files
}
