//! How the Inspector first shows an output, by the meaning its pass
//! declares and by its format: the table the browser's inspector reads
//! too (`client/presets.json`), compiled in, so both choose alike.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use serde::Deserialize;

/// What the display pass shows of a texel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Rgb,
    R,
    G,
    B,
    A,
    Luminance,
}

impl Channel {
    /// Its name in the table and the browser (`texture.js` CHANNELS).
    pub fn name(self) -> &'static str {
        match self {
            Channel::Rgb => "rgb",
            Channel::R => "r",
            Channel::G => "g",
            Channel::B => "b",
            Channel::A => "a",
            Channel::Luminance => "luminance",
        }
    }

    fn named(name: &str) -> Option<Channel> {
        [Channel::Rgb, Channel::R, Channel::G, Channel::B, Channel::A, Channel::Luminance].into_iter().find(|c| c.name() == name)
    }

    /// Its index into a texel, for a single channel.
    pub fn single(self) -> Option<usize> {
        match self {
            Channel::R => Some(0),
            Channel::G => Some(1),
            Channel::B => Some(2),
            Channel::A => Some(3),
            Channel::Rgb | Channel::Luminance => None,
        }
    }
}

/// The planes depth reads as view distance through (`writes[].depth`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Planes {
    pub near: f32,
    pub far: f32,
    pub reversed: bool,
}

impl Planes {
    /// View distance of depth `d`.
    pub fn distance(self, d: f32) -> f32 {
        let Planes { near, far, reversed } = self;
        if reversed { near * far / (near + d * (far - near)) } else { near * far / (far - d * (far - near)) }
    }

    /// What a depth target is cleared to: no surface covered the pixel.
    pub fn clear(self) -> f32 {
        if self.reversed { 0.0 } else { 1.0 }
    }
}

/// How the display pass maps an output's values to the screen:
/// `(value · 2^exposure − min) / (max − min)`, clamped, then sRGB-encoded
/// or through the false-colour map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayOptions {
    pub channel: Channel,
    pub exposure: f32,
    pub min: f32,
    pub max: f32,
    pub srgb: bool,
    /// Depth shown as view distance through these planes.
    pub linearize: Option<Planes>,
    /// The channel (or luminance) through viridis instead of grey.
    pub false_colour: bool,
    /// NaN magenta, +Inf yellow, −Inf cyan (the browser's colours).
    pub overlay: bool,
}

/// What a format says about an output: its channels' names and whether
/// it holds integers or depth (as `presets.js` formatInfo reads it).
#[derive(Debug, Clone, PartialEq)]
pub struct FormatInfo {
    pub names: Vec<&'static str>,
    pub integer: bool,
    pub depth: bool,
}

pub fn format_info(format: &str) -> FormatInfo {
    if format.starts_with("Depth") || format.starts_with("Stencil") {
        return FormatInfo { names: vec!["depth"], integer: false, depth: true };
    }
    let integer = format.contains("Uint") || format.contains("Sint");
    let digit_after = |prefix: &str| format.strip_prefix(prefix).is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()));
    let names = if format.starts_with("Rg11b10") || format.starts_with("Rgb9e5") {
        vec!["R", "G", "B"]
    } else if ["Rgba", "Bgra", "Rgb10a2"].iter().any(|p| format.starts_with(p)) {
        vec!["R", "G", "B", "A"]
    } else if digit_after("Rg") {
        vec!["R", "G"]
    } else if digit_after("R") {
        vec!["R"]
    } else {
        vec!["R", "G", "B", "A"]
    };
    FormatInfo { names, integer, depth: false }
}

/// The channels a format can show, the composite first when it has
/// several (`presets.js` channelOptions).
pub fn channels(info: &FormatInfo) -> Vec<(Channel, String)> {
    if info.depth {
        return vec![(Channel::R, "depth".into())];
    }
    let singles = [Channel::R, Channel::G, Channel::B, Channel::A];
    let mut out: Vec<(Channel, String)> = info.names.iter().zip(singles).map(|(n, c)| (c, (*n).to_owned())).collect();
    if info.names.len() > 1 {
        out.insert(0, (Channel::Rgb, info.names.iter().take(3).copied().collect()));
        if info.names.len() >= 3 {
            out.push((Channel::Luminance, "luminance".into()));
        }
    }
    out
}

/// An output's automatic preset, and whether to fit its range to the
/// values once they are measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    pub options: DisplayOptions,
    pub fit: bool,
    /// The meaning it is shown by.
    pub meaning: String,
}

/// The preset for an output of `format` whose pass declares `meaning`
/// (`None`: a depth format's is depth, else colour); `planes`: its depth
/// planes where known.
pub fn choose(format: &str, meaning: Option<&str>, planes: Option<Planes>) -> Preset {
    let info = format_info(format);
    let meaning = match meaning {
        Some(m) if !m.is_empty() => m.to_owned(),
        _ if info.depth => "depth".to_owned(),
        _ => "color".to_owned(),
    };
    let t = table();
    let entry = t.meanings.get(&meaning).or_else(|| t.meanings.get(&t.unknown_meaning)).expect("presets.json: unknown_meaning is listed");
    let channel = entry.channel.as_deref().and_then(Channel::named).unwrap_or(channels(&info)[0].0);
    let mut options = DisplayOptions {
        channel,
        exposure: 0.0,
        min: entry.min,
        max: entry.max,
        srgb: entry.srgb,
        linearize: planes.filter(|p| entry.linearize && p.far > p.near && p.near > 0.0),
        false_colour: false,
        overlay: true,
    };
    let mut fit = entry.fit;
    if info.integer {
        options.srgb = t.integer.srgb;
        fit = t.integer.fit;
    }
    Preset { options, fit, meaning }
}

/// The false-colour map's polynomial, lowest power first, RGB.
pub fn viridis() -> &'static [[f64; 3]] {
    &table().viridis
}

/// `t` (0 … 1) through the false-colour map as 8-bit RGB, as the
/// browser's tensor view paints it (`presets.js` `viridis`).
pub fn viridis_rgb(t: f64) -> [u8; 3] {
    let c = viridis();
    std::array::from_fn(|k| (c.iter().rev().fold(0.0, |v, p| v * t + p[k]) * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// A quad statistics map laid over a raster pass's output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QuadOverlay {
    /// Quads launched over each pixel's 2×2 block.
    Overdraw,
    /// Times each pixel ran as a helper lane.
    Helpers,
}

impl QuadOverlay {
    pub fn name(self) -> &'static str {
        match self {
            QuadOverlay::Overdraw => "quad overdraw",
            QuadOverlay::Helpers => "helper lanes",
        }
    }

    /// The count from which the map hatches ("5+").
    pub fn top(self) -> u32 {
        let top = &table().quad_maps.top;
        match self {
            QuadOverlay::Overdraw => top.overdraw,
            QuadOverlay::Helpers => top.helpers,
        }
    }

    /// The overlay's RGBA8 colour of count `n` at image pixel (x, y), as
    /// the browser paints it (`quads.js` `paintMap`); `None` (transparent)
    /// for 0 and what is not a count.
    pub fn colour(self, n: f32, x: u32, y: u32) -> Option<[u8; 4]> {
        let q = &table().quad_maps;
        if n.is_nan() || n < 1.0 {
            return None;
        }
        let [r, g, b] = if (n as u32) < self.top() { q.steps[n as usize - 1] } else { q.hatch[((x + y) / q.stripe) as usize % 2] };
        Some([r, g, b, q.alpha])
    }

    pub fn legend(self) -> Legend {
        let q = &table().quad_maps;
        let steps = q.steps.iter().take(self.top() as usize - 1).enumerate().map(|(i, c)| (*c, (i + 1).to_string())).collect();
        Legend { steps, hatch: q.hatch, top: format!("{}+", self.top()) }
    }
}

/// A quad map's legend: each solid step's colour and count, then the
/// hatch's two colours and its label ("5+").
pub struct Legend {
    pub steps: Vec<([u8; 3], String)>,
    pub hatch: [[u8; 3]; 2],
    pub top: String,
}

#[derive(Deserialize)]
struct Table {
    meanings: BTreeMap<String, Entry>,
    unknown_meaning: String,
    integer: Integer,
    viridis: Vec<[f64; 3]>,
    quad_maps: QuadMaps,
}

#[derive(Deserialize)]
struct QuadMaps {
    steps: Vec<[u8; 3]>,
    hatch: [[u8; 3]; 2],
    top: Tops,
    stripe: u32,
    alpha: u8,
}

#[derive(Deserialize)]
struct Tops {
    overdraw: u32,
    helpers: u32,
}

#[derive(Deserialize)]
struct Entry {
    srgb: bool,
    min: f32,
    max: f32,
    fit: bool,
    linearize: bool,
    channel: Option<String>,
}

#[derive(Deserialize)]
struct Integer {
    srgb: bool,
    fit: bool,
}

fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| serde_json::from_str(include_str!("../../presets.json")).expect("client/presets.json is the presets table"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAMERA: Planes = Planes { near: 0.05, far: 200.0, reversed: false };

    #[test]
    fn quad_maps_step_through_plasma_and_hatch_from_their_top_count() {
        let o = QuadOverlay::Overdraw;
        assert_eq!(o.colour(0.0, 0, 0), None, "no quad: transparent");
        assert_eq!(o.colour(f32::NAN, 0, 0), None);
        assert_eq!(o.colour(1.0, 7, 3), Some([76, 2, 161, 190]));
        assert_eq!(o.colour(4.0, 7, 3), Some([253, 197, 39, 190]));
        // 5+ alternates stripes two pixels wide along x + y.
        assert_eq!(o.colour(5.0, 0, 0), Some([240, 249, 33, 190]));
        assert_eq!(o.colour(9.0, 1, 1), Some([13, 8, 135, 190]));
        assert_eq!(o.colour(9.0, 3, 1), Some([240, 249, 33, 190]));
        // Helper lanes hatch from 3; the same count has the same colour.
        assert_eq!(QuadOverlay::Helpers.colour(2.0, 0, 0), o.colour(2.0, 0, 0));
        assert_eq!(QuadOverlay::Helpers.colour(3.0, 0, 0), Some([240, 249, 33, 190]));
        let legend = QuadOverlay::Helpers.legend();
        assert_eq!((legend.steps.len(), legend.top.as_str()), (2, "3+"));
    }

    #[test]
    fn each_meaning_opens_as_the_table_says() {
        let colour = choose("Rgba16Float", Some("color"), None);
        assert_eq!(
            (colour.options.channel, colour.options.srgb, colour.options.min, colour.options.max, colour.fit),
            (Channel::Rgb, true, 0.0, 1.0, false)
        );
        let normal = choose("Rgba16Float", Some("normal"), None);
        assert_eq!((normal.options.srgb, normal.options.min, normal.options.max, normal.fit), (false, -1.0, 1.0, false));
        let depth = choose("Depth32Float", Some("depth"), Some(CAMERA));
        assert_eq!(
            (depth.options.channel, depth.options.srgb, depth.options.linearize, depth.fit),
            (Channel::R, false, Some(CAMERA), true)
        );
        let light = choose("Depth32Float", Some("depth"), None);
        assert_eq!(light.options.linearize, None, "a light's depth has no planes");
        // Ids are not in the table: shown as its unknown meaning (data).
        let id = choose("R32Float", Some("id"), None);
        assert_eq!((id.options.srgb, id.fit, id.meaning.as_str()), (false, true, "id"));
        assert_eq!(choose("Depth32Float", None, None).meaning, "depth");
        assert!(choose("R32Uint", Some("color"), None).fit, "integers are fitted");
    }

    #[test]
    fn a_format_offers_only_its_own_channels() {
        let labels = |f: &str| channels(&format_info(f)).into_iter().map(|(_, l)| l).collect::<Vec<_>>();
        assert_eq!(labels("Depth32Float"), ["depth"]);
        assert_eq!(labels("R32Float"), ["R"]);
        assert_eq!(labels("Rg16Float"), ["RG", "R", "G"]);
        assert_eq!(labels("Rgba8UnormSrgb"), ["RGB", "R", "G", "B", "A", "luminance"]);
        assert_eq!(format_info("Rg11b10Ufloat").names, ["R", "G", "B"]);
    }

    #[test]
    fn viridis_runs_from_purple_to_yellow() {
        // matplotlib's viridis at its ends is #440154 and #fde725; the
        // polynomial is within a few levels of both.
        let near = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(a, b)| a.abs_diff(b) <= 4);
        assert!(near(viridis_rgb(0.0), [0x44, 0x01, 0x54]), "{:?}", viridis_rgb(0.0));
        assert!(near(viridis_rgb(1.0), [0xfd, 0xe7, 0x25]), "{:?}", viridis_rgb(1.0));
    }

    #[test]
    fn depth_reads_as_distance_from_near_to_far() {
        let planes = Planes { near: 1.0, far: 3.0, reversed: false };
        assert_eq!([0.0, 0.75, 1.0].map(|d| planes.distance(d)), [1.0, 2.0, 3.0]);
        assert_eq!(planes.clear(), 1.0);
        let reversed = Planes { reversed: true, ..planes };
        assert_eq!([1.0, 0.0].map(|d| reversed.distance(d)), [1.0, 3.0]);
        assert_eq!(reversed.clear(), 0.0);
    }
}
