//! The pinned pixel's events (PROTOCOL.md's `pixel_history` and `prints`),
//! read as far as the Pixel panel shows them, and the mapping between an
//! inspected image's texels and the frame's pixels.

use serde::Deserialize;

/// A pixel's history through one frame (the `pixel_history` event).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PixelHistory {
    pub frame: u64,
    pub pixel: [u32; 2],
    /// Every pass that wrote or read the pixel, in frame order.
    pub passes: Vec<PassHistory>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PassHistory {
    pub pass: String,
    /// `raster`, `compute` or `copy`.
    pub kind: String,
    pub outputs: Vec<TexelChange>,
    /// The images it read at the pixel (`pass/output`).
    pub inputs: Vec<String>,
    pub tensors: Vec<TensorAtPixel>,
    /// A raster pass's draws that launched a fragment at the pixel, in
    /// submission order; `None` for other passes (and raster passes the
    /// model could not replay).
    pub draws: Option<Vec<DrawTrace>>,
    /// A raster pass's fragment whose output its images hold there.
    pub survivor: Option<Survivor>,
    /// The global id of a per-pixel compute pass's invocation there.
    pub invocation: Option<[u32; 3]>,
}

/// A fragment named by its draw and primitive.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Survivor {
    pub draw: String,
    pub primitive: u32,
}

impl Survivor {
    /// Whether `f` of draw `draw` is this fragment (a helper lane never is).
    pub fn is(&self, draw: &str, f: &Fragment) -> bool {
        !f.helper && self.draw == draw && self.primitive == f.primitive
    }
}

/// RGBA as the protocol sends it: JSON has no NaN or infinity, so a
/// channel that is not finite arrives as `null`.
pub type Rgba = [Option<f32>; 4];

/// An output at the pixel, before and after the pass.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct TexelChange {
    /// `pass/output`.
    pub output: String,
    /// The texel the pixel falls on: x, y, layer.
    pub texel: [u32; 3],
    /// `cleared`, `read`, `undefined` or `unread`.
    pub origin: String,
    pub before: Option<Rgba>,
    /// `None` when its readback failed.
    pub after: Option<Rgba>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct DrawTrace {
    pub name: String,
    pub fragments: Vec<Fragment>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Fragment {
    pub primitive: u32,
    /// As the depth test saw it; `None` without a depth test.
    pub depth: Option<f32>,
    /// `passed`, `failed_depth`, `not_tested` or `culled`.
    pub verdict: String,
    /// The lane ran only as a helper of its 2×2 quad.
    pub helper: bool,
}

/// A tensor laid over the image, at the element under the pixel.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct TensorAtPixel {
    /// `pass/output`.
    pub output: String,
    pub at: [u32; 2],
    /// Channel → value (`None`: not finite).
    pub channels: Vec<Option<f32>>,
}

/// What a frame's `debugPrintf`s printed at the pixel (the `prints` event).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Prints {
    pub frame: u64,
    pub pixel: [u32; 2],
    /// In the order the GPU ran them.
    pub lines: Vec<PrintLine>,
    /// Prints that did not fit the frame's buffer.
    pub dropped: u32,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PrintLine {
    pub pass: String,
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub text: String,
}

/// The lines a call (`file:line:column`) printed.
#[derive(Debug, Clone, PartialEq)]
pub struct Call<'a> {
    pub file: &'a str,
    pub line: u32,
    pub column: u32,
    pub texts: Vec<&'a str>,
}

/// Lines grouped by pass, then by call, both in the order first printed
/// (client/prints.js `groupPrints`).
pub fn group(lines: &[PrintLine]) -> Vec<(&str, Vec<Call<'_>>)> {
    let mut passes: Vec<(&str, Vec<Call>)> = Vec::new();
    for l in lines {
        let i = passes.iter().position(|(p, _)| *p == l.pass).unwrap_or_else(|| {
            passes.push((&l.pass, Vec::new()));
            passes.len() - 1
        });
        let calls = &mut passes[i].1;
        match calls.iter_mut().find(|c| (c.file, c.line, c.column) == (l.file.as_str(), l.line, l.column)) {
            Some(call) => call.texts.push(&l.text),
            None => calls.push(Call { file: &l.file, line: l.line, column: l.column, texts: vec![&l.text] }),
        }
    }
    passes
}

/// The frame's pixel under texel `t` of an image of `size`, for a frame
/// of `frame` size: a pass may render at another size than the frame
/// (client/prints.js `framePixel`).
pub fn frame_pixel(t: [u32; 2], size: [u32; 2], frame: [u32; 2]) -> [u32; 2] {
    [0, 1].map(|i| {
        let at = (f64::from(t[i]) + 0.5) * f64::from(frame[i]) / f64::from(size[i].max(1));
        (at as u32).min(frame[i].saturating_sub(1))
    })
}

/// The texel of an image of `size` that frame pixel `p` falls on: the
/// inverse of [`frame_pixel`].
pub fn texel_of(p: [u32; 2], frame: [u32; 2], size: [u32; 2]) -> [u32; 2] {
    frame_pixel(p, frame, size)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_survivor_is_its_draws_fragment_and_never_a_helper_lane() {
        let s = Survivor { draw: "knot".into(), primitive: 7 };
        let f = |primitive, helper| Fragment { primitive, depth: None, verdict: "passed".into(), helper };
        assert!(s.is("knot", &f(7, false)));
        assert!(!s.is("knot", &f(7, true)), "a helper lane writes nothing");
        assert!(!s.is("floor", &f(7, false)));
        assert!(!s.is("knot", &f(8, false)));
    }

    #[test]
    fn a_texel_of_a_smaller_image_maps_to_the_frame_pixel_under_its_centre_and_back() {
        assert_eq!(frame_pixel([7, 4], [64, 36], [64, 36]), [7, 4], "the frame's own size");
        assert_eq!(frame_pixel([7, 4], [32, 18], [64, 36]), [15, 9], "half the size");
        assert_eq!(texel_of([15, 9], [64, 36], [32, 18]), [7, 4]);
        assert_eq!(texel_of([14, 8], [64, 36], [32, 18]), [7, 4], "both pixels of a half-size texel");
        assert_eq!(frame_pixel([31, 17], [32, 18], [63, 35]), [62, 34], "never past the frame's edge");
    }

    fn line(pass: &str, line: u32, text: &str) -> PrintLine {
        PrintLine { pass: pass.into(), file: "shaders/a.wgsl".into(), line, column: 5, text: text.into() }
    }

    #[test]
    fn prints_group_by_pass_then_call_in_the_order_first_printed() {
        let lines = [line("lighting", 9, "a"), line("tonemap", 3, "b"), line("lighting", 12, "c"), line("lighting", 9, "d")];
        let groups = group(&lines);
        let shape: Vec<String> =
            groups.iter().flat_map(|(p, calls)| calls.iter().map(move |c| format!("{p}:{} {}", c.line, c.texts.join(" ")))).collect();
        assert_eq!(shape, ["lighting:9 a d", "lighting:12 c", "tonemap:3 b"]);
        assert_eq!(groups.len(), 2, "one group per pass");
    }
}
