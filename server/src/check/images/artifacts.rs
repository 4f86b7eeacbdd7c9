//! What a failed case leaves for a reviewer, under `--artifacts` (default
//! `target/loupe-images/`): per output the actual image, the reference,
//! FLIP's map in magma and the three side by side, as PNG (an HDR output
//! also as the OpenEXR a bless would write), and one `report.html` that
//! shows every failed case with its images and figures, linking them
//! relatively so the folder can be uploaded as it is.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::compare::Image;
use super::report::{CaseResult, Verdict};
use crate::flip::{ErrorMap, encode_srgb8};

pub const DEFAULT_DIR: &str = "target/loupe-images";

/// The pictures of one output, in the report's order.
const KINDS: [(&str, &str); 4] =
    [("reference", "reference"), ("actual", "actual"), ("flip", "FLIP error"), ("side-by-side", "side by side")];

/// `<case>/<pass>.<output>.<kind>.png`, relative to the artifacts folder.
fn relative(case: &str, output: &str, kind: &str) -> String {
    format!("{case}/{}.{kind}.png", output.replace('/', "."))
}

/// Writes an output's images; `exr`: the actual image as the float
/// reference a bless would write, for an HDR output.
pub fn write_output(
    dir: &Path,
    case: &str,
    output: &str,
    actual: &Image,
    exr: Option<&[u8]>,
    reference: Option<&Image>,
    map: Option<&ErrorMap>,
) -> Result<(), String> {
    let path = |kind: &str| dir.join(relative(case, output, kind));
    let folder = dir.join(case);
    std::fs::create_dir_all(&folder).map_err(|e| format!("cannot create {}: {e}", folder.display()))?;
    let write = |p: PathBuf, bytes: Vec<u8>| std::fs::write(&p, bytes).map_err(|e| format!("cannot write {}: {e}", p.display()));
    let (w, h) = (actual.width, actual.height);
    let actual_rgb = encode_srgb8(&actual.rgba);
    write(path("actual"), png(w, h, &actual_rgb))?;
    if let Some(exr) = exr {
        write(folder.join(format!("{}.actual.exr", output.replace('/', "."))), exr.to_vec())?;
    }
    let (Some(reference), Some(map)) = (reference, map) else {
        return Ok(());
    };
    let reference_rgb = encode_srgb8(&reference.rgba);
    let magma = map.magma_rgb8();
    write(path("reference"), png(w, h, &reference_rgb))?;
    write(path("flip"), map.magma_png())?;
    write(path("side-by-side"), side_by_side(w, h, &[&reference_rgb, &actual_rgb, &magma]))
}

/// Images of one size left to right, 4 black pixels apart.
fn side_by_side(w: u32, h: u32, images: &[&[u8]]) -> Vec<u8> {
    const GAP: u32 = 4;
    let n = images.len() as u32;
    let total = n * w + (n - 1) * GAP;
    let mut rgb = vec![0u8; (total * h * 3) as usize];
    for (i, image) in images.iter().enumerate() {
        let x0 = i as u32 * (w + GAP);
        for y in 0..h {
            let src = &image[(y * w * 3) as usize..((y + 1) * w * 3) as usize];
            let at = ((y * total + x0) * 3) as usize;
            rgb[at..at + src.len()].copy_from_slice(src);
        }
    }
    png(total, h, &rgb)
}

/// RGB8 bytes as a PNG file.
pub fn png(w: u32, h: u32, rgb: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(encoder, rgb, w, h, image::ExtendedColorType::Rgb8)
        .expect("an in-memory PNG of matching size cannot fail");
    out
}

/// Writes `report.html` for the failed cases, or removes a stale one when
/// none failed. Returns the report's path when written.
pub fn write_report(dir: &Path, cases: &[CaseResult], adapter: &str) -> Result<Option<PathBuf>, String> {
    let path = dir.join("report.html");
    let failed: Vec<&CaseResult> = cases.iter().filter(|c| c.verdict == Verdict::Failed).collect();
    if failed.is_empty() {
        let _ = std::fs::remove_file(&path);
        return Ok(None);
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut html = String::from(concat!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>loupe check: image cases</title>\n",
        "<style>body{font:14px sans-serif;margin:2em;background:#fafafa}figure{display:inline-block;margin:0 1em 1em 0}",
        "img{image-rendering:pixelated;min-width:320px;border:1px solid #ccc}pre{background:#eee;padding:.5em;white-space:pre-wrap}",
        "td,th{padding:.2em .8em;text-align:left}</style></head><body>\n"
    ));
    let _ = writeln!(html, "<h1>{} of {} image cases failed</h1>\n<p>On {}.</p>", failed.len(), cases.len(), escape(adapter));
    for case in failed {
        let t = case.threshold;
        let _ = writeln!(
            html,
            "<h2 id=\"{0}\">{0}</h2>\n<p>{1} ({2}:{3})</p>",
            escape(&case.name),
            escape(&case.scene),
            escape(&case.at.file),
            case.at.line
        );
        for d in &case.diagnostics {
            let mut text = d.to_string();
            for note in &d.notes {
                let _ = write!(text, "\n  = {note}");
            }
            let _ = writeln!(html, "<pre>{}</pre>", escape(&text));
        }
        for o in &case.outputs {
            let _ = writeln!(html, "<h3>{}</h3>\n<table><tr><th></th><th>measured</th><th>allowed</th></tr>", escape(&o.output));
            if let Some(f) = o.flip {
                let _ = writeln!(html, "<tr><td>FLIP mean</td><td>{:.5}</td><td>{}</td></tr>", f.mean, t.flip_mean);
                let _ = writeln!(html, "<tr><td>FLIP 99th percentile</td><td>{:.5}</td><td>{}</td></tr>", f.p99, t.flip_p99);
                let _ = writeln!(html, "<tr><td>FLIP weighted median</td><td>{:.5}</td><td></td></tr>", f.weighted_median);
            }
            if let Some(m) = o.relative_mse {
                let _ = writeln!(html, "<tr><td>relMSE</td><td>{m:.3e}</td><td></td></tr>");
            }
            let _ = writeln!(html, "<tr><td>reference</td><td colspan=2>{}</td></tr></table>", escape(&o.reference));
            for (kind, caption) in KINDS {
                let rel = relative(&case.name, &o.output, kind);
                if dir.join(&rel).exists() {
                    let _ =
                        writeln!(html, "<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1}</figcaption></figure>", escape(&rel), caption);
                }
            }
        }
    }
    html.push_str("</body></html>\n");
    std::fs::write(&path, html).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(Some(path))
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}
