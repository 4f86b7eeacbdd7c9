//! The material tree: the compiler's IR, between the front end (`front`,
//! `*.mat` files and the scene's shorthand) and the back end (`back`, WGSL).
//!
//! A `Definition` is one material's code: its parameters, the tree of slabs
//! and operators, and the expressions feeding them. Parameters stay symbolic
//! here (MDL's "class compilation"): a material's instances — the scene's
//! `[[materials]]` naming it, each with its own parameter values — share the
//! definition's generated code and differ only in the values the renderer
//! uploads, so a slider in the browser changes a buffer, never a pipeline.
//! Functions, imports and calls of other materials are gone by the time a
//! tree exists: the front end inlines them, so a node or expression's span
//! may point into an imported file.
//!
//! Architecture Invariant: every node and expression carries the `Location`
//! it was written at, in the file the user wrote; the back end never needs
//! the source text.

use crate::diag::Location;

/// Index into `Definition::nodes`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(pub u32);

/// Index into `Definition::exprs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ExprId(pub u32);

/// One material's code.
#[derive(Debug, Clone, PartialEq)]
pub struct Definition {
    /// The material's name, unique among the definitions of a program
    /// (`file::material`, or `shorthand` for the scene file's own).
    pub name: String,
    /// Where `material NAME` is written.
    pub location: Location,
    /// The parameters an instance sets, in declaration order; each takes
    /// one `vec4<f32>` slot of the instance's block (a float in `.x`, a
    /// colour or vector in `.xyz`).
    pub params: Vec<Param>,
    /// Nodes in creation order; children come before their parents.
    pub nodes: Vec<Node>,
    pub exprs: Vec<Expr>,
    pub root: NodeId,
    /// Multiple-scattering energy compensation of the GGX lobes. On for
    /// materials from `*.mat` files, off for the scene file's shorthand (so
    /// today's scenes keep their look); `quality.energy_compensation` turns
    /// it off everywhere.
    pub energy_compensation: bool,
}

impl Definition {
    pub fn node(&self, id: NodeId) -> &Node {
        &self.nodes[id.0 as usize]
    }

    pub fn expr(&self, id: ExprId) -> &Expr {
        &self.exprs[id.0 as usize]
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub name: String,
    pub ty: Type,
    pub default: Value,
    /// Inclusive bounds an instance's value must lie in (each component of
    /// a colour or vector); `None`: any finite value.
    pub range: Option<(f32, f32)>,
    /// Shown beside the control (`mm`, `nm`, ...); informational.
    pub unit: Option<String>,
    /// The comment written above the parameter, if any.
    pub doc: Option<String>,
    pub location: Location,
}

/// The types of values. Colours are linear RGB.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Type {
    Float,
    Color,
    Vec3,
    /// An image sampled by UV (`sample`, `normal_map`); only a parameter
    /// of the material's own file has this type.
    Texture,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Float(f32),
    /// A colour or a vector (see the parameter's or expression's `Type`).
    Vec3([f32; 3]),
    /// A texture: an index into the `TextureSource` table of what holds
    /// the value (`front::Loaded::textures` for a file's defaults,
    /// `Program::textures` for a program's definitions and instances).
    Texture(u32),
}

/// An image file a texture value names.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureSource {
    /// Resolved against the file that names it.
    pub path: std::path::PathBuf,
    pub space: ColorSpace,
    /// Where the path is written.
    pub location: Location,
}

/// How a texture's values are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ColorSpace {
    /// sRGB-encoded colour, decoded to linear (8/16-bit PNG's default).
    Srgb,
    /// Linear values as stored (EXR's default; masks, roughness).
    Linear,
    /// A tangent-space normal map: linear, `rgb * 2 - 1`.
    Normal,
}

impl ColorSpace {
    pub const ALL: [(&'static str, ColorSpace); 3] =
        [("srgb", ColorSpace::Srgb), ("linear", ColorSpace::Linear), ("normal", ColorSpace::Normal)];
}

#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub kind: NodeKind,
    pub location: Location,
}

/// Substrate's operators over slabs.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeKind {
    Slab(Slab),
    /// Horizontal mix: `b` with weight `weight` (clamped to [0, 1]), `a`
    /// with `1 - weight`.
    Mix {
        a: NodeId,
        b: NodeId,
        weight: ExprId,
    },
    /// Vertical layering: `top` over `base`; the base is weighted by what
    /// the top lets through (`f = f_top + (1 - E_top) T f_base`), with the
    /// top's `thickness` and `transmission_color` giving `T`.
    Layer {
        top: NodeId,
        base: NodeId,
    },
    /// `a` covering a fraction `weight` of the pixel; the rest is empty
    /// (transmits).
    Coverage {
        a: NodeId,
        weight: ExprId,
    },
    /// `a + b`: not energy-conserving, and the report says so.
    Add {
        a: NodeId,
        b: NodeId,
    },
}

/// One slab of matter: an interface over a medium, with fuzz on top and
/// emission. Fields the material does not set take `Field::default`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Slab {
    /// At most one expression per field, in the order written.
    pub fields: Vec<(Field, ExprId)>,
}

impl Slab {
    pub fn get(&self, field: Field) -> Option<ExprId> {
        self.fields.iter().find(|(f, _)| *f == field).map(|&(_, e)| e)
    }
}

/// A slab's fields, named after OpenPBR Surface's parameters where the
/// concept maps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Field {
    /// Diffuse albedo of a dielectric; the specular colour (F0) of a metal.
    BaseColor,
    /// 0: dielectric, 1: metal (F0 = base_color, no diffuse).
    BaseMetalness,
    /// Scales the interface's specular reflection (and what it takes).
    SpecularWeight,
    /// Tints the dielectric's F0.
    SpecularColor,
    /// F90: the colour at grazing angles (white: Schlick's Fresnel).
    SpecularEdgeColor,
    /// The dielectric's index of refraction; F0 = ((ior - 1) / (ior + 1))².
    SpecularIor,
    SpecularRoughness,
    /// A second, wider specular lobe mixed into the first: its weight...
    HazeWeight,
    /// ...and its roughness.
    HazeRoughness,
    FuzzWeight,
    FuzzColor,
    FuzzRoughness,
    EmissionColor,
    /// Emitted radiance is `emission_color * emission_luminance`.
    EmissionLuminance,
    /// The colour light keeps after crossing a unit thickness of the slab's
    /// medium (white: clear). Used when the slab is the top of a layer.
    TransmissionColor,
    /// The slab's thickness, in the units of `transmission_color`.
    Thickness,
    /// The shading normal, world space (`normal_map(tex, strength)`);
    /// unset: the geometry's.
    Normal,
    /// OpenPBR `transmission_weight`: the share of a dielectric's base that
    /// transmits (refracts through the interface) instead of diffusing.
    /// The transmitted light keeps `transmission_color` per unit of
    /// distance inside a solid (Beer–Lambert), or once through a thin wall.
    TransmissionWeight,
    /// OpenPBR `geometry_thin_walled`: above 0.5 the surface is a thin
    /// shell, and light passes straight through it instead of refracting
    /// into a solid.
    ThinWalled,
    /// OpenPBR `thin_film_weight`: how much of the specular lobe's Fresnel
    /// is a thin film's (iridescence, Belcour & Barla 2017) instead of the
    /// bare interface's: `mix(F, F_film, weight)`.
    ThinFilmWeight,
    /// The film's thickness in micrometres (OpenPBR's unit; glTF's
    /// nanometres are converted on import).
    ThinFilmThickness,
    /// The film's index of refraction.
    ThinFilmIor,
    /// The medium's mean free path per channel, in scene units: light
    /// keeps `exp(-distance / mean_free_path)` of itself. When set it
    /// replaces `transmission_color` (which is then `exp(-1 / mfp)`, the
    /// colour kept over one unit); `transmittance_to_mfp(color, d)` gives
    /// the path that keeps `color` after `d`.
    MeanFreePath,
    /// OpenPBR `specular_roughness_anisotropy`: 0 an isotropic lobe, toward
    /// 1 a lobe stretched along the direction `specular_rotation` gives
    /// (α_t = r² √(2 / (1 + (1 − a)²)), α_b = (1 − a) α_t).
    SpecularAnisotropy,
    /// Standard Surface `specular_rotation`: the direction of the longer
    /// roughness, in turns (0..1) from the surface's tangent (growing u)
    /// toward its bitangent.
    SpecularRotation,
}

impl Field {
    pub const ALL: [Field; 25] = [
        Field::BaseColor,
        Field::BaseMetalness,
        Field::SpecularWeight,
        Field::SpecularColor,
        Field::SpecularEdgeColor,
        Field::SpecularIor,
        Field::SpecularRoughness,
        Field::HazeWeight,
        Field::HazeRoughness,
        Field::FuzzWeight,
        Field::FuzzColor,
        Field::FuzzRoughness,
        Field::EmissionColor,
        Field::EmissionLuminance,
        Field::TransmissionColor,
        Field::Thickness,
        Field::Normal,
        Field::TransmissionWeight,
        Field::ThinWalled,
        Field::ThinFilmWeight,
        Field::ThinFilmThickness,
        Field::ThinFilmIor,
        Field::MeanFreePath,
        Field::SpecularAnisotropy,
        Field::SpecularRotation,
    ];

    /// The name written in material files.
    pub fn name(self) -> &'static str {
        match self {
            Field::BaseColor => "base_color",
            Field::BaseMetalness => "base_metalness",
            Field::SpecularWeight => "specular_weight",
            Field::SpecularColor => "specular_color",
            Field::SpecularEdgeColor => "specular_edge_color",
            Field::SpecularIor => "specular_ior",
            Field::SpecularRoughness => "specular_roughness",
            Field::HazeWeight => "haze_weight",
            Field::HazeRoughness => "haze_roughness",
            Field::FuzzWeight => "fuzz_weight",
            Field::FuzzColor => "fuzz_color",
            Field::FuzzRoughness => "fuzz_roughness",
            Field::EmissionColor => "emission_color",
            Field::EmissionLuminance => "emission_luminance",
            Field::TransmissionColor => "transmission_color",
            Field::Thickness => "thickness",
            Field::Normal => "normal",
            Field::TransmissionWeight => "transmission_weight",
            Field::ThinWalled => "thin_walled",
            Field::ThinFilmWeight => "thin_film_weight",
            Field::ThinFilmThickness => "thin_film_thickness",
            Field::ThinFilmIor => "thin_film_ior",
            Field::MeanFreePath => "mean_free_path",
            Field::SpecularAnisotropy => "specular_roughness_anisotropy",
            Field::SpecularRotation => "specular_rotation",
        }
    }

    pub fn from_name(name: &str) -> Option<Field> {
        Field::ALL.into_iter().find(|f| f.name() == name)
    }

    pub fn ty(self) -> Type {
        match self {
            Field::BaseColor
            | Field::SpecularColor
            | Field::SpecularEdgeColor
            | Field::FuzzColor
            | Field::EmissionColor
            | Field::TransmissionColor
            | Field::MeanFreePath => Type::Color,
            Field::Normal => Type::Vec3,
            _ => Type::Float,
        }
    }

    /// The value of a field the material does not set: together, a white
    /// rough plastic with IOR 1.5 (F0 = 0.04), no haze, fuzz or emission,
    /// and a clear, infinitely thin medium that transmits nothing.
    pub fn default(self) -> Value {
        match self {
            Field::BaseColor => Value::Vec3([0.8; 3]),
            Field::BaseMetalness => Value::Float(0.0),
            Field::SpecularWeight => Value::Float(1.0),
            Field::SpecularColor | Field::SpecularEdgeColor | Field::FuzzColor | Field::TransmissionColor => Value::Vec3([1.0; 3]),
            Field::SpecularIor => Value::Float(1.5),
            Field::SpecularRoughness => Value::Float(0.5),
            Field::HazeWeight | Field::FuzzWeight | Field::EmissionLuminance | Field::Thickness => Value::Float(0.0),
            Field::TransmissionWeight | Field::ThinWalled => Value::Float(0.0),
            Field::SpecularAnisotropy | Field::SpecularRotation => Value::Float(0.0),
            Field::HazeRoughness => Value::Float(0.7),
            Field::FuzzRoughness => Value::Float(0.5),
            Field::EmissionColor => Value::Vec3([1.0; 3]),
            // Never used as a value: an unset normal is the geometry's.
            Field::Normal => Value::Vec3([0.0, 0.0, 1.0]),
            Field::ThinFilmWeight => Value::Float(0.0),
            Field::ThinFilmThickness => Value::Float(0.5),
            Field::ThinFilmIor => Value::Float(1.5),
            // Clear: light crosses any distance whole.
            Field::MeanFreePath => Value::Vec3([f32::MAX; 3]),
        }
    }

    /// The range a constant value must lie in (`None`: any finite value).
    /// Parameters feeding a field are checked against it too.
    pub fn range(self) -> Option<(f32, f32)> {
        match self {
            Field::SpecularIor | Field::ThinFilmIor => Some((1.0, 5.0)),
            Field::EmissionLuminance | Field::Thickness | Field::ThinFilmThickness | Field::MeanFreePath => Some((0.0, f32::MAX)),
            Field::Normal => None,
            _ => Some((0.0, 1.0)),
        }
    }
}

/// Expressions over parameters and constants. Arithmetic on a float and a
/// colour broadcasts the float.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub ty: Type,
    pub location: Location,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    Const(Value),
    /// The instance's value of `Definition::params[i]`.
    Param(u32),
    Neg(ExprId),
    Binary(BinOp, ExprId, ExprId),
    Call(Builtin, Vec<ExprId>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
}

/// Functions on values, the same in every material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Builtin {
    /// `rgb(r, g, b)`: a colour from three floats.
    Rgb,
    /// `grey(x)`: `rgb(x, x, x)`.
    Grey,
    /// `lerp(a, b, t)`.
    Lerp,
    Clamp,
    Saturate,
    Min,
    Max,
    Pow,
    Sqrt,
    Abs,
    /// `luminance(c)`: Rec. 709 luminance of a linear colour.
    Luminance,
    /// `srgb(c)`: an sRGB-encoded colour (as colour pickers give) to linear.
    Srgb,
    /// `ior_to_f0(ior)`: `((ior - 1) / (ior + 1))²`.
    IorToF0,
    /// `transmittance_to_mfp(color, distance)`: the mean free path that keeps
    /// `color` of the light after `distance`.
    TransmittanceToMfp,
    /// `sample(tex)`: the texture's colour at the surface's UV.
    Sample,
    /// `normal_map(tex, strength)`: the world normal a tangent-space
    /// normal map gives, its tilt scaled by `strength`.
    NormalMap,
}

impl Builtin {
    pub const ALL: [Builtin; 16] = [
        Builtin::Rgb,
        Builtin::Grey,
        Builtin::Lerp,
        Builtin::Clamp,
        Builtin::Saturate,
        Builtin::Min,
        Builtin::Max,
        Builtin::Pow,
        Builtin::Sqrt,
        Builtin::Abs,
        Builtin::Luminance,
        Builtin::Srgb,
        Builtin::IorToF0,
        Builtin::TransmittanceToMfp,
        Builtin::Sample,
        Builtin::NormalMap,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Builtin::Rgb => "rgb",
            Builtin::Grey => "grey",
            Builtin::Lerp => "lerp",
            Builtin::Clamp => "clamp",
            Builtin::Saturate => "saturate",
            Builtin::Min => "min",
            Builtin::Max => "max",
            Builtin::Pow => "pow",
            Builtin::Sqrt => "sqrt",
            Builtin::Abs => "abs",
            Builtin::Luminance => "luminance",
            Builtin::Srgb => "srgb",
            Builtin::IorToF0 => "ior_to_f0",
            Builtin::TransmittanceToMfp => "transmittance_to_mfp",
            Builtin::Sample => "sample",
            Builtin::NormalMap => "normal_map",
        }
    }

    pub fn from_name(name: &str) -> Option<Builtin> {
        Builtin::ALL.into_iter().find(|b| b.name() == name)
    }
}
