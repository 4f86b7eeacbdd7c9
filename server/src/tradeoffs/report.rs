//! The sweep's three files: `tradeoffs.json` (everything measured), a
//! Markdown table per series, and an SVG plot of error against time (both
//! axes logarithmic: settings span decades of both), one line per series.

use std::fmt::Write;

use super::Report;

pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Accuracy against time: {}\n", r.scene);
    let _ = writeln!(
        s,
        "{}×{}, {} ({} timing), median of {} frames after 2 of warm-up; a series that accumulates samples sums its frames.\n",
        r.width, r.height, r.adapter, r.timing, r.repeats
    );
    for series in &r.series {
        let _ = writeln!(s, "## {}\n", series.name);
        let _ = writeln!(s, "Reference: {}. Timed: {}.\n", series.reference, series.passes.join(", "));
        let lanes = series.points.iter().any(|p| p.helper_lanes.is_some());
        let _ = writeln!(
            s,
            "| value | time (ms) | range (ms) | × most accurate | relative MSE | PSNR (dB) | SSIM |{}",
            if lanes { " helper lanes |" } else { "" }
        );
        let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|{}", if lanes { "---:|" } else { "" });
        for p in &series.points {
            let psnr = if p.psnr_db.is_finite() { format!("{:.1}", p.psnr_db) } else { "∞".into() };
            let _ = write!(
                s,
                "| {} | {:.2} | {:.2}–{:.2} | {:.2} | {:.3e} | {psnr} | {:.4} |",
                p.value, p.time_ms, p.time_range_ms.0, p.time_range_ms.1, p.time_ratio, p.relative_mse, p.ssim
            );
            if let Some(h) = p.helper_lanes {
                let _ = write!(s, " {h} |");
            }
            s.push('\n');
        }
        s.push('\n');
    }
    s
}

const WIDTH: f64 = 920.0;
const HEIGHT: f64 = 520.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 340.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;
const COLORS: [&str; 12] =
    ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f", "#393b79", "#e7969c"];

/// Error (relative MSE) against time, log–log. A point equal to its
/// reference (no error to put on a log axis) sits hollow on the bottom
/// edge.
pub fn svg(r: &Report) -> String {
    let plotted: Vec<_> = r.series.iter().filter(|s| s.points.iter().any(|p| p.time_ms > 0.0)).collect();
    let points = || plotted.iter().flat_map(|s| s.points.iter()).filter(|p| p.time_ms > 0.0);
    let decades = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
        if lo > hi { (0.0, 1.0) } else { (lo.log10().floor(), hi.log10().ceil().max(lo.log10().floor() + 1.0)) }
    };
    let (x0, x1) = decades(&mut points().map(|p| p.time_ms));
    let (y0, y1) = decades(&mut points().map(|p| p.relative_mse).filter(|e| *e > 0.0));
    let error = |e: f64| if e > 0.0 { e } else { 10f64.powf(y0) };
    let (pw, ph) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
    let x = |t: f64| LEFT + (t.log10() - x0) / (x1 - x0) * pw;
    let y = |e: f64| TOP + (y1 - e.log10()) / (y1 - y0) * ph;

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{LEFT}" y="22" font-size="14">{} — {}×{}, {}</text>"#,
        escape(&r.scene),
        r.width,
        r.height,
        escape(&r.adapter)
    );
    for d in x0 as i32..=x1 as i32 {
        let px = x(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{px:.1}" y1="{TOP}" x2="{px:.1}" y2="{:.1}" stroke="#ddd"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">1e{d}</text>"##,
            TOP + ph,
            TOP + ph + 18.0
        );
    }
    for d in y0 as i32..=y1 as i32 {
        let py = y(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{LEFT}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">1e{d}</text>"##,
            LEFT + pw,
            LEFT - 6.0,
            py + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">time of the passes the setting affects (ms, {} timing)</text>"#,
        LEFT + pw / 2.0,
        HEIGHT - 16.0,
        r.timing
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18 {:.1}) rotate(-90)" text-anchor="middle">relative MSE against the reference</text>"#,
        TOP + ph / 2.0
    );
    for (i, series) in plotted.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let pts: Vec<_> = series.points.iter().filter(|p| p.time_ms > 0.0).collect();
        let line: Vec<String> = pts.iter().map(|p| format!("{:.1},{:.1}", x(p.time_ms), y(error(p.relative_mse)))).collect();
        let _ = writeln!(s, r#"<polyline fill="none" stroke="{color}" stroke-width="1.5" points="{}"/>"#, line.join(" "));
        for p in &pts {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{}" stroke="{color}"><title>{} = {}: {:.2} ms, relative MSE {:.3e}, SSIM {:.4}</title></circle>"#,
                x(p.time_ms),
                y(error(p.relative_mse)),
                if p.relative_mse > 0.0 { color } else { "white" },
                escape(&series.setting),
                escape(&p.value.to_string()),
                p.time_ms,
                p.relative_mse,
                p.ssim
            );
        }
        let ly = TOP + 14.0 + i as f64 * 18.0;
        let lx = LEFT + pw + 16.0;
        let _ = writeln!(
            s,
            r#"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{color}" stroke-width="2"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"#,
            lx + 18.0,
            lx + 24.0,
            ly + 4.0,
            escape(&series.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}
