//! The `[post]` and `[quality]` settings, each declared once in `settings!`
//! below: its typed field (what the renderer reads), default, type and
//! range, label, the render passes it affects and when its control shows.
//! Reading and checking the file (`super::validate`), overrides
//! (`super::overrides::apply`) and the browser's controls
//! (`super::overrides::controls`) all come from this one table, so they
//! cannot disagree.

use serde::{Deserialize, Serialize};

use super::Scene;

/// A value a control can set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Value {
    Bool(bool),
    Int(i64),
    Float(f64),
    Text(String),
    /// A colour or vector: a material parameter's `[r, g, b]`.
    List(Vec<f64>),
}

/// As TOML writes it (`true`, `2`, `1.5`, `"aces"`), for messages.
impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => write!(f, "{x:?}"),
            Value::Text(t) => write!(f, "{t:?}"),
            Value::List(l) => write!(f, "[{}]", l.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ")),
        }
    }
}

/// A setting's type and the values it accepts. Ranges are inclusive; `step`
/// is the browser slider's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    Toggle,
    Int {
        min: i64,
        max: i64,
        step: i64,
    },
    Float {
        min: f64,
        max: f64,
        step: f64,
    },
    /// The option names as written in the file.
    Choice(&'static [&'static str]),
}

/// One entry of the table.
pub struct Setting {
    /// As written in the file: `post.exposure_ev`.
    pub path: &'static str,
    pub label: &'static str,
    /// The field's doc comment, its lines joined ("" when it has none).
    pub doc: &'static str,
    pub kind: Kind,
    /// The render passes whose output changes with this setting, by name
    /// or by a group the renderer expands (`FULLSCREEN`):
    /// `render::passes::affected` gives the names.
    pub affects: &'static [&'static str],
    /// Whether the browser shows a control for it in this scene.
    pub shown_when: fn(&Scene) -> bool,
    /// The typed field's value.
    pub get: fn(&Scene) -> Value,
    /// Sets the typed field; false when `Value` is not of its type.
    assign: fn(&mut Scene, &Value) -> bool,
}

impl Setting {
    /// The table (`post`) and key (`exposure_ev`).
    pub fn split(&self) -> (&'static str, &'static str) {
        self.path.split_once('.').unwrap_or(("", self.path))
    }

    /// Checks `v` against the entry's type and range, then sets the typed
    /// field. The message is written to follow the path (`post.x: …`).
    pub fn set(&self, scene: &mut Scene, v: &Value) -> Result<(), String> {
        self.check(v)?;
        if (self.assign)(scene, v) { Ok(()) } else { Err(self.expected(&v.to_string())) }
    }

    /// Type and range, as the file and overrides both need.
    pub fn check(&self, v: &Value) -> Result<(), String> {
        match (self.kind, v) {
            (Kind::Toggle, Value::Bool(_)) => Ok(()),
            (Kind::Int { min, max, .. }, Value::Int(i)) => {
                if (min..=max).contains(i) {
                    Ok(())
                } else {
                    Err(format!("must be between {min} and {max}, not {i}"))
                }
            }
            (Kind::Float { min, max, .. }, Value::Int(_) | Value::Float(_)) => {
                let f = number(v).unwrap_or(f64::NAN);
                if !f.is_finite() {
                    Err(format!("must be a finite number, not {f}"))
                } else if (min..=max).contains(&f) {
                    Ok(())
                } else {
                    Err(format!("must be between {min} and {max}, not {}", shown(f)))
                }
            }
            (Kind::Choice(options), Value::Text(t)) => {
                if options.contains(&t.as_str()) {
                    Ok(())
                } else {
                    Err(format!("must be one of {}, not {t:?}", quoted(options)))
                }
            }
            _ => Err(self.expected(&v.to_string())),
        }
    }

    /// The message for a value of the wrong type, `found` as the user wrote
    /// it (`"high"`, `1.5`, `an array`).
    pub fn expected(&self, found: &str) -> String {
        let want = match self.kind {
            Kind::Toggle => "true or false".to_owned(),
            Kind::Int { .. } => "a whole number".to_owned(),
            Kind::Float { .. } => "a number".to_owned(),
            Kind::Choice(options) => format!("one of {}", quoted(options)),
        };
        format!("must be {want}, not {found}")
    }
}

/// The entry for `path`, if it is a table setting.
pub fn find(path: &str) -> Option<&'static Setting> {
    SETTINGS.iter().find(|s| s.path == path)
}

/// Pairs of settings where the first must be less than the second; a
/// violation is reported at the second.
pub const ORDERED: &[(&str, &str)] = &[("post.auto_exposure_min_ev", "post.auto_exposure_max_ev")];

pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Int(i) => Some(*i as f64),
        Value::Float(f) => Some(*f),
        _ => None,
    }
}

fn quoted(options: &[&str]) -> String {
    options.iter().map(|o| format!("{o:?}")).collect::<Vec<_>>().join(", ")
}

/// A field type a setting can have: converts to and from the value a file,
/// an override or a control carries.
trait Typed: Sized {
    fn to_value(&self) -> Value;
    fn from_value(v: &Value) -> Option<Self>;
}

impl Typed for bool {
    fn to_value(&self) -> Value {
        Value::Bool(*self)
    }
    fn from_value(v: &Value) -> Option<Self> {
        if let Value::Bool(b) = v { Some(*b) } else { None }
    }
}

impl Typed for u32 {
    fn to_value(&self) -> Value {
        Value::Int(i64::from(*self))
    }
    fn from_value(v: &Value) -> Option<Self> {
        if let Value::Int(i) = v { u32::try_from(*i).ok() } else { None }
    }
}

/// A number for a message: as written for everyday sizes, in exponent
/// form past them (`1e308`, not 309 digits).
pub fn shown(f: f64) -> String {
    if f == 0.0 || (1e-6..1e16).contains(&f.abs()) { f.to_string() } else { format!("{f:e}") }
}

/// The shortest decimal that reads back as `f`, so a control shows 0.1 as
/// written, not 0.10000000149011612.
pub fn float(f: f32) -> Value {
    Value::Float(f.to_string().parse().unwrap_or(f64::from(f)))
}

impl Typed for f32 {
    fn to_value(&self) -> Value {
        float(*self)
    }
    fn from_value(v: &Value) -> Option<Self> {
        number(v).map(|f| f as f32)
    }
}

/// An enum whose variants are a setting's options, with their names as
/// written in the file.
macro_rules! choice {
    ($(#[$m:meta])* $name:ident { $($(#[$vm:meta])* $variant:ident = $text:literal,)* }) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $name { $($(#[$vm])* $variant,)* }

        impl $name {
            pub const NAMES: &[&str] = &[$($text),*];
        }

        impl Typed for $name {
            fn to_value(&self) -> Value {
                Value::Text(match self { $(Self::$variant => $text,)* }.to_owned())
            }
            fn from_value(v: &Value) -> Option<Self> {
                match v {
                    $(Value::Text(t) if t == $text => Some(Self::$variant),)*
                    _ => None,
                }
            }
        }
    };
}

choice!(Tonemap {
    Aces = "aces",
    Reinhard = "reinhard",
});

choice!(
    /// What the debug-view pass shows instead of the lit frame.
    DebugView {
        None = "none",
        Normal = "normal",
        Albedo = "albedo",
        Roughness = "roughness",
        Metallic = "metallic",
        /// The G-buffer's UV, its fractional part in red and green.
        Uv = "uv",
        Depth = "depth",
        /// Each 8×8 tile by its class (tile classification): empty grey,
        /// simple green, single yellow, complex red.
        TileClass = "tile_class",
        /// Per pixel, its closures: 1 green, 2 yellow, 3 or more red.
        Closures = "closures",
        /// Per pixel, its material bytes, white at the scene's most.
        Bytes = "bytes",
    }
);

choice!(
    /// How each ray-march step integrates in-scattered light.
    Estimator {
        /// Scattered light × step length × transmittance at the step start:
        /// biased, brightens as steps grow.
        Constant = "constant",
        /// The exact integral of in-scattering times transmittance over the
        /// step for constant coefficients: energy-conserving at any step count.
        Analytic = "analytic",
    }
);

choice!(
    /// How the raster integrates a rect light's light over its area.
    RectLights {
        /// Linearly transformed cosines: closed form, fitted tables.
        Ltc = "ltc",
        /// 16 × 16 stratified points over the rectangle through the BRDF
        /// itself: the reference LTC approximates, at 256 evaluations.
        Sampled = "sampled",
    }
);

choice!(
    /// Which of the path tracer's frames the denoiser runs on.
    DenoiseAt {
        /// At 1, 2, 4, 8, … samples and at the last: the others show the
        /// newest denoised image, at a fraction of the cost.
        Doublings = "doublings",
        Every = "every_sample",
    }
);

choice!(
    /// How many of the frame's pixels share one volume march.
    VolumeResolution {
        Full = "full",
        Half = "half",
        Quarter = "quarter",
    }
);

impl VolumeResolution {
    /// Pixels per side of the block one march serves.
    pub fn scale(self) -> u32 {
        match self {
            Self::Full => 1,
            Self::Half => 2,
            Self::Quarter => 4,
        }
    }
}

choice!(
    /// Which renderer makes the frame's HDR image.
    Renderer {
        /// Rasterized G-buffer, deferred lighting and the volume pass.
        Raster = "raster",
        /// The progressive path tracer (`path_trace`), the reference.
        Path = "path",
    }
);

choice!(
    /// Which kernel runs the denoiser's convolutions
    /// (`render::passes::denoise::kernels`); the result is the same.
    DenoiserKernel {
        /// One invocation per output pixel and 4 output blocks, reading its
        /// inputs and weights from the storage buffers itself.
        Direct = "direct",
        /// Workgroup-tiled (implicit GEMM): each workgroup copies its tile's
        /// input patch and the weights to workgroup memory once per chunk of
        /// input channels.
        Tiled = "tiled",
    }
);

macro_rules! or_always {
    () => {
        always
    };
    ($f:expr) => {
        $f
    };
}

/// Declares each table's struct (a field per setting, `Default` from the
/// settings' defaults) and `SETTINGS`, the table every other use reads.
macro_rules! settings {
    ($(
        $(#[$tm:meta])*
        $table:ident: $Struct:ident {
            $(
                $(#[doc = $doc:literal])*
                $field:ident: $ty:ty = $default:expr, $kind:expr, $label:literal, affects $affects:expr $(, shown_when $shown:expr)?;
            )*
        }
    )*) => {
        $(
            $(#[$tm])*
            #[derive(Debug, Clone, PartialEq)]
            pub struct $Struct {
                $($(#[doc = $doc])* pub $field: $ty,)*
            }

            impl Default for $Struct {
                fn default() -> Self {
                    $Struct { $($field: $default,)* }
                }
            }
        )*

        /// Every setting, in the order the browser shows them.
        pub static SETTINGS: &[Setting] = &[$($(
            Setting {
                path: concat!(stringify!($table), ".", stringify!($field)),
                label: $label,
                doc: concat!($($doc),*),
                kind: $kind,
                affects: &$affects,
                shown_when: or_always!($($shown)?),
                get: |s| Typed::to_value(&s.$table.$field),
                assign: |s, v| match <$ty as Typed>::from_value(v) {
                    Some(x) => {
                        s.$table.$field = x;
                        true
                    }
                    None => false,
                },
            },
        )*)*];
    };
}

fn always(_: &Scene) -> bool {
    true
}

fn has_media(s: &Scene) -> bool {
    !s.media.is_empty()
}

fn path_traced(s: &Scene) -> bool {
    s.quality.renderer == Renderer::Path
}

fn rastered(s: &Scene) -> bool {
    !path_traced(s)
}

fn raster_media(s: &Scene) -> bool {
    has_media(s) && rastered(s)
}

fn raster_rect(s: &Scene) -> bool {
    s.has_rect_lights() && rastered(s)
}

fn denoised(s: &Scene) -> bool {
    path_traced(s) && s.denoiser.is_some()
}

fn auto_exposure(s: &Scene) -> bool {
    s.post.auto_exposure
}

/// Every pass that makes the HDR image, raster or path traced (the path
/// tracer last).
pub(crate) const RENDERED: [&str; 13] = [
    "shadows",
    "depth_prepass",
    "gbuffer",
    "classify",
    "ltc_tables",
    "lighting",
    "lighting_simple",
    "lighting_single",
    "lighting_complex",
    "volume_shadows",
    "volume_march",
    "volumes",
    "path_trace",
];

/// In `affects`: every pass drawn as a fullscreen triangle. The passes are
/// declared by the renderer, above the scene, so the table names the group
/// and `render::passes::affected` expands it from the pass specs.
pub const FULLSCREEN: &str = "@fullscreen";

use Kind::{Choice, Float, Int, Toggle};

settings! {
    /// `[post]`: exposure, tonemapping and the debug view.
    post: Post {
        /// Exposure in stops: the HDR image is multiplied by 2^EV. With auto
        /// exposure on, the compensation added to the metered exposure.
        exposure_ev: f32 = 0.0, Float { min: -24.0, max: 24.0, step: 0.1 },
            "Exposure (EV; compensation with auto exposure)", affects ["exposure"];
        /// Meter the frame and adapt the exposure over time.
        auto_exposure: bool = false, Toggle, "Auto exposure", affects ["exposure_histogram", "exposure_adapt", "exposure"];
        /// How fast the adapted exposure follows the metered one.
        auto_exposure_speed: f32 = 3.0, Float { min: 0.1, max: 30.0, step: 0.1 },
            "Adaptation speed (EV/s)", affects ["exposure_adapt"], shown_when auto_exposure;
        /// The luminance range the meter considers, in EV.
        auto_exposure_min_ev: f32 = -8.0, Float { min: -16.0, max: 16.0, step: 0.5 },
            "Metering range min (EV)", affects ["exposure_histogram", "exposure_adapt"], shown_when auto_exposure;
        /// The top of the metering range, in EV.
        auto_exposure_max_ev: f32 = 8.0, Float { min: -16.0, max: 16.0, step: 0.5 },
            "Metering range max (EV)", affects ["exposure_histogram", "exposure_adapt"], shown_when auto_exposure;
        /// The curve from HDR to the display.
        tonemap: Tonemap = Tonemap::Aces, Choice(Tonemap::NAMES), "Tonemap", affects ["tonemap"];
        /// A G-buffer channel shown instead of the lit frame, or `none`.
        debug_view: DebugView = DebugView::None, Choice(DebugView::NAMES), "Debug view", affects ["debug_view"];
        /// Draw fullscreen passes as two triangles instead of one, to compare.
        two_triangles: bool = false, Toggle, "Fullscreen as two triangles", affects [FULLSCREEN];
    }

    /// `[quality]`: the renderer, and shadow, ray-march and path costs.
    quality: Quality {
        /// Which renderer makes the HDR image: the raster frame, or the
        /// progressive path tracer, its reference.
        renderer: Renderer = Renderer::Raster, Choice(Renderer::NAMES), "Renderer", affects RENDERED;
        /// Samples per pixel the path tracer accumulates to, one a frame.
        path_spp: u32 = 256, Int { min: 1, max: 65536, step: 1 }, "Path samples per pixel", affects ["path_trace"], shown_when path_traced;
        /// Indirect bounces; 0 is direct light only.
        path_bounces: u32 = 4, Int { min: 0, max: 64, step: 1 }, "Path bounces", affects ["path_trace"], shown_when path_traced;
        /// The raster's shadow maps, for the lights that cast shadows.
        shadows: bool = true, Toggle, "Shadows", affects ["shadows", "lighting", "volume_march", "volumes"], shown_when rastered;
        /// Texels per side of each shadow-map layer.
        shadow_map_size: u32 = 1024, Int { min: 64, max: 4096, step: 64 }, "Shadow map size", affects ["shadows"], shown_when rastered;
        /// The shadow maps' percentage-closer filter: (2r + 1)² taps.
        shadow_filter: u32 = 1, Int { min: 0, max: 4, step: 1 }, "Shadow filter radius (texels; 1 is 3×3 PCF)", affects ["lighting"], shown_when rastered;
        /// How the raster integrates a rect light: linearly transformed
        /// cosines, or 16 × 16 points through the BRDF (the reference).
        rect_lights: RectLights = RectLights::Ltc, Choice(RectLights::NAMES), "Rect lights", affects ["ltc_tables", "lighting"], shown_when raster_rect;
        /// Scale each GGX lobe by Turquin's factor for the light it loses to
        /// multiple scattering (`shaders/lib/multiscatter.wgsl`), so a white
        /// rough metal stays white. On, it applies to the materials of
        /// `.mat` files only, never to the scene file's shorthand materials
        /// (today's scenes keep their look); off, it applies nowhere.
        energy_compensation: bool = true, Toggle, "Energy compensation (multiple scattering)", affects ["lighting", "path_trace"];
        /// Bytes per pixel a material's closures may take in the adaptive
        /// G-buffer (`material::layout`). A material that needs more is
        /// simplified to fit (`material::simplify`): the raster renders the
        /// simplified tree, the path tracer the full one. 80 is Substrate's
        /// desktop default, and every library material but `openpbr`
        /// (108) fits it; 24 is one closure without features, the least any
        /// material can be made to take.
        material_bytes: u32 = 80, Int { min: 24, max: 256, step: 4 }, "Material budget (bytes per pixel)",
            affects ["gbuffer", "lighting", "path_trace"];
        /// The path tracer renders the materials simplified to
        /// `material_bytes` too, instead of the full ones (the reference
        /// the budget's error is measured against).
        path_simplified_materials: bool = false, Toggle, "Path tracer: simplified materials", affects ["path_trace"],
            shown_when path_traced;
        /// Classify 8×8 tiles by the dearest material class among their
        /// pixels and light each class with its own pipeline over its
        /// tiles only; off, every tile goes through the complex pipeline.
        tile_classification: bool = true, Toggle, "Tile classification", affects ["classify", "lighting"], shown_when rastered;
        /// Ray-march steps per pixel through the media.
        volume_steps: u32 = 48, Int { min: 1, max: 1024, step: 1 }, "Volume steps", affects ["volume_march", "volumes"], shown_when raster_media;
        /// Steps of the march toward each light (self-shadowing), from each
        /// point of the volume grid and from each lit surface.
        volume_shadow_steps: u32 = 6, Int { min: 1, max: 64, step: 1 },
            "Volume shadow steps", affects ["lighting", "volume_shadows", "volume_march", "volumes"], shown_when raster_media;
        /// Points of the volume grid (transmittance toward each light) along
        /// the longest side of the box around the media.
        volume_grid: u32 = 32, Int { min: 8, max: 256, step: 8 },
            "Volume shadow grid (points, longest side)", affects ["volume_shadows", "volume_march", "volumes"], shown_when raster_media;
        /// The march's resolution: one march per pixel, per 2×2 or per 4×4
        /// pixels, brought back to the frame by a depth-aware upsample.
        volume_resolution: VolumeResolution = VolumeResolution::Full, Choice(VolumeResolution::NAMES),
            "Volume march resolution", affects ["volume_march", "volumes"], shown_when raster_media;
        /// How each march step integrates in-scattered light: constant
        /// (biased), or analytic (exact for constant coefficients).
        volume_estimator: Estimator = Estimator::Analytic, Choice(Estimator::NAMES),
            "In-scattering estimator", affects ["volume_march", "volumes"], shown_when raster_media;
        /// Denoise the path-traced image with the scene's `[denoiser]`; off,
        /// its passes are culled and the noisy image is shown.
        denoise: bool = true, Toggle, "Denoise", affects ["denoise"], shown_when denoised;
        /// Which frames of the accumulation are denoised.
        denoise_at: DenoiseAt = DenoiseAt::Doublings, Choice(DenoiseAt::NAMES), "Denoise at (samples)", affects ["denoise"], shown_when denoised;
        /// Run each decoder level's 2× upsample and concatenation inside the
        /// convolution that reads them (the `upsample<L>` and `concat<L>`
        /// tensors are never stored); off, each is a pass of its own whose
        /// tensor can be inspected. The denoised image is the same.
        denoiser_fused: bool = true, Toggle, "Denoiser: fuse upsample + concat into the convolution",
            affects ["denoise"], shown_when denoised;
        /// Which kernel runs the convolutions: one invocation per pixel
        /// (`direct`) or workgroup-tiled; the denoised image is the same.
        denoiser_kernel: DenoiserKernel = DenoiserKernel::Direct, Choice(DenoiserKernel::NAMES), "Denoiser: convolution kernel",
            affects ["denoise"], shown_when denoised;
    }
}
