//! How diagnostics name files: a path as the user reads it, and as a URI.

use std::path::{Component, Path, PathBuf};

/// The path diagnostics show for `path`: relative to the working directory
/// when it lies under it, with forward slashes. A byte of the name that is
/// not UTF-8 shows as `\xHH`: no other `\` is left (they become `/`), so
/// two names never show alike and [`display_uri`] recovers the bytes.
pub fn display_path(path: &Path) -> String {
    let cwd = std::env::current_dir().ok();
    let shown = cwd.as_deref().and_then(|c| path.strip_prefix(c).ok()).unwrap_or(path);
    // `./shaders/x.wgsl` and `shaders/x.wgsl` are one file: drop `.` parts.
    let parts: Vec<_> = shown.components().filter(|c| !matches!(c, Component::CurDir)).collect();
    let shown: PathBuf = parts.iter().collect();
    let mut out = String::new();
    for chunk in os_bytes(&shown).utf8_chunks() {
        out.push_str(&chunk.valid().replace('\\', "/"));
        for b in chunk.invalid() {
            out.push_str(&format!("\\x{b:02X}"));
        }
    }
    out
}

/// A path's bytes as the file system holds them.
#[cfg(unix)]
fn os_bytes(path: &Path) -> Vec<u8> {
    std::os::unix::ffi::OsStrExt::as_bytes(path.as_os_str()).to_vec()
}

/// A path's bytes: UTF-16 names are not bytes, so any unpaired surrogate
/// shows as U+FFFD.
#[cfg(not(unix))]
fn os_bytes(path: &Path) -> Vec<u8> {
    path.to_string_lossy().into_owned().into_bytes()
}

/// A relative URI reference for a [`display_path`]: the file's real bytes
/// (a `\xHH` escape is the byte itself), percent-encoded where a URI path
/// may not hold them (`:` too, which would read as a scheme).
pub fn display_uri(display: &str) -> String {
    let mut bytes = Vec::with_capacity(display.len());
    let mut rest = display.as_bytes();
    while let Some((&b, tail)) = rest.split_first() {
        let escaped =
            tail.strip_prefix(b"x").and_then(|hex| std::str::from_utf8(hex.get(..2)?).ok()).and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b, escaped) {
            (b'\\', Some(byte)) => {
                bytes.push(byte);
                rest = &tail[3..];
            }
            _ => {
                bytes.push(b);
                rest = tail;
            }
        }
    }
    let mut uri = String::with_capacity(bytes.len());
    for b in bytes {
        if b.is_ascii_alphanumeric() || b"-._~/!$&'()*+,;=@".contains(&b) {
            uri.push(b as char);
        } else {
            uri.push_str(&format!("%{b:02X}"));
        }
    }
    uri
}
