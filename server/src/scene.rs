//! Scenes: human-edited TOML, read with serde; every error is a diagnostic
//! at file:line:col. The full scene model (camera, lights, objects, media)
//! grows here; the renderer only ever sees a validated `Scene`.

use serde::Deserialize;
use toml::Spanned;

use crate::diag::{Code, Diagnostic, LineIndex};

/// The largest output side loupe renders; larger requests are an error, not
/// an out-of-memory.
pub const MAX_SIDE: u32 = 8192;

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub width: u32,
    pub height: u32,
    pub post: Post,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Post {
    /// Exposure in stops: the HDR image is multiplied by 2^EV.
    pub exposure_ev: f32,
    pub tonemap: Tonemap,
    /// Draw fullscreen passes as two triangles instead of one, to compare.
    pub two_triangles: bool,
}

impl Default for Post {
    fn default() -> Self {
        Post { exposure_ev: 0.0, tonemap: Tonemap::Aces, two_triangles: false }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tonemap {
    Aces,
    Reinhard,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    output: Output,
    #[serde(default)]
    post: Post,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Output {
    width: Spanned<i64>,
    height: Spanned<i64>,
}

impl Default for Output {
    fn default() -> Self {
        Output { width: Spanned::new(0..0, 1280), height: Spanned::new(0..0, 720) }
    }
}

/// Parses and validates a scene; `display` names the file in diagnostics.
pub fn parse(display: &str, text: &str) -> Result<Scene, Diagnostic> {
    let lines = LineIndex::new(text);
    let at = |span: std::ops::Range<usize>| lines.location(display, text, span);
    let file: File = toml::from_str(text).map_err(|e| {
        let d = Diagnostic::error(Code::Scene, e.message().to_owned());
        match e.span() {
            Some(span) => d.with_label(at(span), "here", true),
            None => d.at(crate::diag::Location::file_start(display)),
        }
    })?;
    let side = |v: &Spanned<i64>, what: &str| -> Result<u32, Diagnostic> {
        let n = *v.get_ref();
        if (1..=i64::from(MAX_SIDE)).contains(&n) {
            Ok(n as u32)
        } else {
            Err(Diagnostic::error(Code::Scene, format!("output {what} must be between 1 and {MAX_SIDE}, not {n}"))
                .with_label(at(v.span()), "out of range", true))
        }
    };
    let width = side(&file.output.width, "width")?;
    let height = side(&file.output.height, "height")?;
    if !file.post.exposure_ev.is_finite() {
        return Err(Diagnostic::error(Code::Scene, "post.exposure_ev must be a finite number")
            .at(crate::diag::Location::file_start(display)));
    }
    Ok(Scene { width, height, post: file.post })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_located() {
        let e = parse("s.toml", "[output]\nwidth = 0\nheight = 10\n").unwrap_err();
        let l = e.location.unwrap();
        assert_eq!((l.line, l.column), (2, 9));
        let e = parse("s.toml", "[post]\nexposure = 1\n").unwrap_err();
        assert_eq!(e.location.unwrap().line, 2, "unknown field");
        let e = parse("s.toml", "[output]\nwidth = 16384\nheight = 16384\n").unwrap_err();
        assert!(e.message.contains("8192"));
    }

    #[test]
    fn defaults_apply() {
        let s = parse("s.toml", "# nothing\n").unwrap();
        assert_eq!((s.width, s.height, s.post.tonemap), (1280, 720, Tonemap::Aces));
    }
}
