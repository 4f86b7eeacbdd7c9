//! The scene file's shape as serde reads it: every table denies unknown
//! fields, so a typo is an error at its line, never a silently ignored key.
//! Values are checked afterwards (`super::validate`), where each problem is
//! located by its path in the document. `[post]` and `[quality]` are read
//! through the settings table instead (`super::settings`).

use std::collections::BTreeMap;

use serde::Deserialize;
use serde::de::IgnoredAny;

use crate::denoise_options::{Mode, Precision};

pub type Vec3 = [f32; 3];

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct File {
    #[serde(default)]
    pub output: Output,
    #[serde(default)]
    pub camera: Camera,
    #[serde(default)]
    pub materials: Vec<Material>,
    #[serde(default)]
    pub objects: Vec<Object>,
    #[serde(default)]
    pub lights: Vec<Light>,
    #[serde(default)]
    pub media: Vec<Medium>,
    #[serde(default)]
    pub environment: Environment,
    #[serde(default)]
    pub denoiser: Option<Denoiser>,
    /// Accepted here, read through the settings table from the document,
    /// where each key and value keeps its span.
    #[serde(default, rename = "post")]
    _post: IgnoredAny,
    #[serde(default, rename = "quality")]
    _quality: IgnoredAny,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    pub width: i64,
    pub height: i64,
}

impl Default for Output {
    fn default() -> Self {
        Output { width: 1280, height: 720 }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
    pub near: f32,
    pub far: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera { position: [0.0, 1.5, 5.0], target: [0.0, 0.5, 0.0], up: [0.0, 1.0, 0.0], fov_deg: 45.0, near: 0.05, far: 200.0 }
    }
}

/// `[environment]`: the light arriving from infinitely far away in every
/// direction, a vertical gradient. Radiance from the unit direction `d` is
/// `intensity * mix(bottom, top, d.y * 0.5 + 0.5)`; the raster shows it as
/// the background and lights surfaces with it (`shaders/lib/environment.wgsl`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Environment {
    /// Linear RGB radiance straight up (before `intensity`).
    pub top: Vec3,
    /// Linear RGB radiance straight down (before `intensity`).
    pub bottom: Vec3,
    pub intensity: f32,
}

/// The sky loupe drew before the environment was part of the scene, so
/// scenes without `[environment]` keep their background.
impl Default for Environment {
    fn default() -> Self {
        Environment { top: [0.10, 0.16, 0.28], bottom: [0.02, 0.022, 0.025], intensity: 1.0 }
    }
}

/// `[denoiser]`: OIDN's U-Net run on the path tracer's output.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Denoiser {
    /// An OIDN weights file (.tza), relative to the scene file; `None`:
    /// the network loupe bundles for `mode`, with albedo and normal.
    pub weights: Option<String>,
    /// How tensors are stored between layers; accumulation is f32 either way.
    #[serde(default)]
    pub precision: Precision,
    #[serde(default)]
    pub mode: Mode,
    /// Multiplies the colour before the network and divides the output
    /// (OIDN's `inputScale`); by default OIDN's autoexposure in HDR, else 1.
    pub input_scale: Option<f32>,
}

/// A `[[materials]]` entry as written: the shorthand (`base_color`,
/// `metallic`, `roughness`) or a material file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    #[serde(default)]
    pub base_color: Option<Vec3>,
    #[serde(default)]
    pub metallic: Option<f32>,
    #[serde(default)]
    pub roughness: Option<f32>,
    /// A material file (`*.mat`), relative to the scene file.
    #[serde(default)]
    pub file: Option<String>,
    /// Which material of `file`; may be left out when the file defines one.
    #[serde(default)]
    pub material: Option<String>,
    /// Values for the material's parameters, by name: numbers, or arrays
    /// of three for colours and vectors.
    #[serde(default)]
    pub params: BTreeMap<String, ParamValue>,
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum ParamValue {
    Float(f32),
    Vec3(Vec3),
}

fn half() -> f32 {
    0.5
}

fn one() -> f32 {
    1.0
}

fn white() -> Vec3 {
    [1.0; 3]
}

fn yes() -> bool {
    true
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    #[serde(default)]
    pub name: Option<String>,
    /// A built-in shape: `sphere`, `cube`, `plane`. Exactly one of `shape`
    /// and `mesh`.
    #[serde(default)]
    pub shape: Option<String>,
    /// A glTF 2.0 file (.gltf or .glb), relative to the scene file.
    #[serde(default)]
    pub mesh: Option<String>,
    /// Required for a shape; a mesh without one takes its glTF materials.
    #[serde(default)]
    pub material: Option<String>,
    #[serde(default)]
    pub position: Vec3,
    /// Euler angles in degrees, applied in Y, X, Z order (yaw, pitch, roll).
    #[serde(default)]
    pub rotation_deg: Vec3,
    #[serde(default = "unit_scale")]
    pub scale: Scale,
}

fn unit_scale() -> Scale {
    Scale::Uniform(1.0)
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    Axes(Vec3),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    #[serde(rename = "type")]
    pub kind: LightType,
    #[serde(default = "white")]
    pub color: Vec3,
    #[serde(default = "one")]
    pub intensity: f32,
    #[serde(default)]
    pub position: Option<Vec3>,
    #[serde(default)]
    pub direction: Option<Vec3>,
    /// Spot cone: full intensity inside `inner_deg`, none outside `outer_deg`
    /// (half-angles).
    #[serde(default)]
    pub inner_deg: Option<f32>,
    #[serde(default)]
    pub outer_deg: Option<f32>,
    /// Rect light: width and height in scene units.
    #[serde(default)]
    pub size: Option<[f32; 2]>,
    #[serde(default)]
    pub two_sided: bool,
    #[serde(default = "yes")]
    pub shadows: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    Directional,
    Point,
    Spot,
    Rect,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Medium {
    #[serde(default)]
    pub name: Option<String>,
    pub shapes: Vec<SdfShape>,
    /// Smooth-union radius between the shapes; 0 is a hard union.
    #[serde(default)]
    pub blend: f32,
    /// Width of the soft edge, in scene units, over which density fades in
    /// from the SDF surface inward.
    #[serde(default = "edge")]
    pub edge: f32,
    /// Per-unit-length coefficients, per RGB channel.
    pub absorption: Vec3,
    pub scattering: Vec3,
    #[serde(default)]
    pub emission: Vec3,
    #[serde(default)]
    pub noise: Option<Noise>,
}

fn edge() -> f32 {
    0.1
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum SdfShape {
    Sphere {
        center: Vec3,
        radius: f32,
    },
    Box {
        center: Vec3,
        half_extents: Vec3,
    },
    /// The half-space below the plane `dot(p, normal) = offset`.
    Plane {
        normal: Vec3,
        offset: f32,
    },
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    #[serde(default = "octaves")]
    pub octaves: i64,
    #[serde(default = "one")]
    pub frequency: f32,
    /// How much of the density the noise may remove, 0..=1.
    #[serde(default = "half")]
    pub amplitude: f32,
}

fn octaves() -> i64 {
    4
}
