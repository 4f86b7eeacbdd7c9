//! `/api/sources/…`: the source files diagnostics point into, for the UI's
//! excerpts. A path is first checked as text ([`safe_relative`]: no
//! absolute paths, no `..`, no double encoding), then its canonical form
//! must be a regular file inside a canonicalized source root.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use axum::extract::State;
use axum::http::{StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::guard::error;

/// The largest source file `/api/sources` serves.
const MAX_SOURCE_BYTES: u64 = 16 * 1024 * 1024;
/// Decodes `%XX` escapes once; `None` for a malformed escape or a result
/// that is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = |c: u8| (c as char).to_digit(16);
            let hi = hex(*b.get(i + 1)?)?;
            let lo = hex(*b.get(i + 2)?)?;
            out.push((hi * 16 + lo) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Turns the raw (still percent-encoded) tail of a URL path into a relative
/// path with only normal components, or refuses it: backslashes, `:` (drive
/// letters, streams), control characters, a `%` left after one decoding
/// (double encoding), a leading `/` (absolute), and empty, `.` or `..`
/// segments are all refused. This is the first line only; the canonical
/// path is checked against the roots after.
pub(super) fn safe_relative(raw: &str) -> Option<String> {
    if raw.contains('\\') {
        return None;
    }
    let decoded = percent_decode(raw)?;
    if decoded.is_empty() || decoded.starts_with('/') {
        return None;
    }
    if decoded.chars().any(|c| matches!(c, '%' | '\\' | ':') || c.is_control()) {
        return None;
    }
    if decoded.split('/').any(|seg| seg.is_empty() || seg == "." || seg == "..") {
        return None;
    }
    Some(decoded)
}

/// The canonical path of a regular file named by `rel` — relative to the
/// working directory (how diagnostics show paths), to a root, or to a
/// root's parent — that lies inside a canonicalized root; `None` otherwise.
fn resolve_source(roots: &[PathBuf], rel: &str) -> Option<PathBuf> {
    let canonical_roots: Vec<PathBuf> = roots.iter().filter_map(|r| r.canonicalize().ok()).collect();
    let mut bases: Vec<PathBuf> = Vec::new();
    if let Ok(cwd) = std::env::current_dir() {
        bases.push(cwd);
    }
    for (raw, canonical) in roots.iter().zip(roots.iter().map(|r| r.canonicalize().ok())) {
        bases.push(raw.clone());
        bases.extend(raw.parent().map(Path::to_owned));
        if let Some(c) = canonical {
            bases.extend(c.parent().map(Path::to_owned));
            bases.push(c);
        }
    }
    bases.into_iter().find_map(|base| {
        let found = base.join(rel).canonicalize().ok()?;
        let inside = canonical_roots.iter().any(|r| found.starts_with(r));
        (inside && found.is_file()).then_some(found)
    })
}

pub(super) async fn source(State(st): State<Arc<AppState>>, uri: Uri) -> Response {
    let raw = uri.path().strip_prefix("/api/sources/").unwrap_or("");
    let Some(rel) = safe_relative(raw) else {
        return error(StatusCode::FORBIDDEN, "path refused: only relative paths inside the source roots are served");
    };
    let roots = st.shared.source_roots.clone();
    let found = tokio::task::spawn_blocking(move || -> Result<Vec<u8>, (StatusCode, String)> {
        let not_found = || (StatusCode::NOT_FOUND, format!("no source file `{rel}`"));
        let path = resolve_source(&roots, &rel).ok_or_else(not_found)?;
        let len = std::fs::metadata(&path).map_err(|_| not_found())?.len();
        if len > MAX_SOURCE_BYTES {
            return Err((StatusCode::PAYLOAD_TOO_LARGE, format!("`{rel}` is larger than {MAX_SOURCE_BYTES} bytes")));
        }
        std::fs::read(&path).map_err(|_| not_found())
    })
    .await;
    match found {
        Ok(Ok(bytes)) => (StatusCode::OK, [(header::CONTENT_TYPE, "text/plain; charset=utf-8")], bytes).into_response(),
        Ok(Err((status, message))) => error(status, &message),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{get, request, start, temp_dir};
    use super::*;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn sources_are_served_only_from_inside_the_roots() {
        let base = temp_dir("sources");
        let root = base.join("root");
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::write(root.join("a.wgsl"), "legit shader").unwrap();
        std::fs::write(root.join("sub/b.wgsl"), "nested shader").unwrap();
        std::fs::write(base.join("secret.txt"), "TOPSECRET").unwrap();
        std::os::unix::fs::symlink(base.join("secret.txt"), root.join("link.wgsl")).unwrap();
        std::os::unix::fs::symlink(&base, root.join("dirlink")).unwrap();
        std::os::unix::fs::symlink(root.join("a.wgsl"), root.join("inner.wgsl")).unwrap();
        let s = start(vec![root.clone()]).await;

        for (path, want) in [
            ("/api/sources/a.wgsl", "legit shader"),
            ("/api/sources/sub/b.wgsl", "nested shader"),
            ("/api/sources/sub%2Fb.wgsl", "nested shader"),
            ("/api/sources/root/a.wgsl", "legit shader"),
            ("/api/sources/inner.wgsl", "legit shader"),
        ] {
            let r = get(s.addr, path).await;
            assert_eq!(r.status, 200, "{path}: {}", r.text());
            assert_eq!(r.text(), want, "{path}");
            assert_eq!(r.header("content-type").as_deref(), Some("text/plain; charset=utf-8"));
        }
        let r = request(s.addr, "HEAD", "/api/sources/a.wgsl", "").await;
        assert_eq!((r.status, r.body.len()), (200, 0));
        assert_eq!(r.header("content-length").as_deref(), Some("12"));

        let abs = base.join("secret.txt").display().to_string();
        let abs_inside = root.join("a.wgsl").display().to_string();
        // Refused as text, before the file system is touched (PROTOCOL.md:
        // 403), and refused after resolving, with the answer a missing
        // file gets, so nothing outside the roots can be probed (404).
        let refused = [
            "/api/sources/../secret.txt".to_owned(),
            "/api/sources/sub/../../secret.txt".to_owned(),
            "/api/sources/..%2fsecret.txt".to_owned(),
            "/api/sources/..%2Fsecret.txt".to_owned(),
            "/api/sources/%2e%2e/secret.txt".to_owned(),
            "/api/sources/%2E%2E%2Fsecret.txt".to_owned(),
            "/api/sources/.%2e/secret.txt".to_owned(),
            "/api/sources/%252e%252e%252fsecret.txt".to_owned(),
            "/api/sources/%252e%252e/secret.txt".to_owned(),
            "/api/sources/..%255csecret.txt".to_owned(),
            "/api/sources/..%5csecret.txt".to_owned(),
            "/api/sources/..%5Csecret.txt".to_owned(),
            "/api/sources/..\\secret.txt".to_owned(),
            "/api/sources/sub\\..\\..\\secret.txt".to_owned(),
            "/api/sources/..%c0%afsecret.txt".to_owned(),
            "/api/sources/a.wgsl%00".to_owned(),
            format!("/api/sources/{abs}"),
            format!("/api/sources//{abs}"),
            format!("/api/sources/{}", abs.replace('/', "%2f")),
            format!("/api/sources/{abs_inside}"),
            "/api/sources/%2fetc%2fpasswd".to_owned(),
            "/api/sources//etc/passwd".to_owned(),
            "/api/sources/C:%5cWindows%5cwin.ini".to_owned(),
            "/api/sources/./a.wgsl".to_owned(),
        ];
        let not_found = [
            "/api/sources/link.wgsl".to_owned(),
            "/api/sources/dirlink/secret.txt".to_owned(),
            "/api/sources/missing.wgsl".to_owned(),
            "/api/sources/sub".to_owned(),
            // No path at all, and a path that leaves `/api/sources`: no
            // such route.
            "/api/sources/".to_owned(),
            "/api/../secret.txt".to_owned(),
        ];
        for (path, status) in refused.iter().map(|p| (p, 403)).chain(not_found.iter().map(|p| (p, 404))) {
            let r = get(s.addr, path).await;
            assert_eq!(r.status, status, "{path}: {}", r.text());
            assert!(!r.text().contains("TOPSECRET"), "{path} leaked the secret");
            assert!(!r.text().contains("root:"), "{path} leaked /etc/passwd");
        }
        let _ = std::fs::remove_dir_all(&base);
    }

    #[test]
    fn safe_relative_refuses_every_escape() {
        assert_eq!(safe_relative("shaders/a.wgsl").as_deref(), Some("shaders/a.wgsl"));
        assert_eq!(safe_relative("a%20b.wgsl").as_deref(), Some("a b.wgsl"));
        for bad in [
            "",
            "..",
            "../x",
            "a/../x",
            "./a",
            "a//b",
            "a/",
            "/etc",
            "%2e%2e/x",
            "..%2fx",
            "%252e%252e",
            "a%5cb",
            "a\\b",
            "c:/x",
            "a%00",
            "%zz",
            "%2",
            "..%c0%af",
        ] {
            assert_eq!(safe_relative(bad), None, "{bad:?}");
        }
    }
}
