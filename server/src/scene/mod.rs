//! Scenes: human-edited TOML, read with serde; every error is a diagnostic
//! at file:line:col. The renderer only ever sees a validated `Scene`.
//!
//! Reading is two steps: `parse` turns text into a `Scene` (pure, no file
//! system), and `load` reads the file and the meshes it references. The
//! denoiser's network is built above this module (`crate::loaded`): a scene
//! names its weights and settings, and knows nothing of the denoiser.

mod file;
pub mod overrides;
pub mod settings;
mod validate;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use file::{Camera, Environment, Noise, ParamValue, SdfShape, Vec3};
pub use settings::{DebugView, DenoiserKernel, Estimator, Post, Quality, Renderer, Tonemap, VolumeResolution};

use crate::denoise_options::{Mode, Precision};
use crate::diag::{Code, Diagnostic, LineIndex, Location};
use crate::mesh::MeshData;

/// The largest output side loupe renders; larger requests are an error, not
/// an out-of-memory.
pub const MAX_SIDE: u32 = 8192;

/// `WIDTHxHEIGHT`, each side in 1..=`MAX_SIDE`: `--size` and the image
/// cases' `size`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT"))?;
    let side = |v: &str| -> Result<u32, String> {
        let n: u32 = v.trim().parse().map_err(|_| format!("`{v}` is not a number"))?;
        if (1..=MAX_SIDE).contains(&n) { Ok(n) } else { Err(format!("{n} is outside 1..={MAX_SIDE}")) }
    };
    Ok((side(w)?, side(h)?))
}
/// Sizes the shaders' fixed loops and the GPU buffers are built for.
pub const MAX_LIGHTS: usize = 64;
pub const MAX_MEDIA: usize = 8;
pub const MAX_SHAPES: usize = 16;
pub const MAX_OBJECTS: usize = 4096;

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
    pub media: Vec<Medium>,
    pub environment: Environment,
    pub denoiser: Option<Denoiser>,
    pub post: Post,
    pub quality: Quality,
}

/// A `[[materials]]` entry, validated. The renderer takes it compiled
/// (`crate::loaded`, `crate::material`).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    pub source: MaterialSource,
}

#[derive(Debug, Clone, PartialEq)]
pub enum MaterialSource {
    /// `base_color`, `metallic`, `roughness`: one slab, as before
    /// materials were a language.
    Shorthand { base_color: Vec3, metallic: f32, roughness: f32 },
    /// A material of a `*.mat` file.
    File {
        /// As written, relative to the scene file.
        file: String,
        /// Which of the file's materials; `None`: its only one.
        material: Option<String>,
        /// Parameter values, each with where it is written.
        params: Vec<(String, ParamValue, Location)>,
        /// Where `file` is written.
        at: Location,
    },
}

/// `[denoiser]`: OIDN's U-Net run on the path tracer's output.
#[derive(Debug, Clone, PartialEq)]
pub struct Denoiser {
    /// The weights file as written, relative to the scene file; `None`:
    /// the network loupe bundles for `mode`, with albedo and normal.
    pub weights: Option<String>,
    /// Where `weights` is written (else the section), for diagnostics
    /// about the file.
    pub at: Location,
    pub precision: Precision,
    pub mode: Mode,
    /// `None`: OIDN's default (autoexposure in HDR, else 1).
    pub input_scale: Option<f32>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    pub name: String,
    pub geometry: Geometry,
    /// Index into `Scene::materials`: the material instance it is drawn
    /// with (`crate::loaded` appends instances past the scene's own for
    /// glTF materials).
    pub material: usize,
    /// The object names no material: it is drawn with its glTF's own, one
    /// per primitive. `crate::loaded` splits it into one object per glTF
    /// material before the renderer sees it.
    pub gltf_materials: bool,
    pub position: Vec3,
    pub rotation_deg: Vec3,
    pub scale: Vec3,
}

#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum Geometry {
    Shape(String),
    /// A glTF file as written in the scene, relative to the scene file, and
    /// where it was written (for diagnostics about the mesh).
    Mesh {
        file: String,
        at: Location,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    pub color: Vec3,
    pub intensity: f32,
    pub shadows: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// `direction` points from the light into the scene, normalized.
    Directional {
        direction: Vec3,
    },
    Point {
        position: Vec3,
    },
    Spot {
        position: Vec3,
        direction: Vec3,
        inner_deg: f32,
        outer_deg: f32,
    },
    /// Emits from the side its `direction` points to (both with two_sided).
    Rect {
        position: Vec3,
        direction: Vec3,
        size: [f32; 2],
        two_sided: bool,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Medium {
    pub name: String,
    pub shapes: Vec<SdfShape>,
    pub blend: f32,
    pub edge: f32,
    pub absorption: Vec3,
    pub scattering: Vec3,
    pub emission: Vec3,
    pub noise: Option<Noise>,
}

impl Scene {
    pub fn has_rect_lights(&self) -> bool {
        self.lights.iter().any(|l| matches!(l.kind, LightKind::Rect { .. }))
    }

    /// Lights that get a shadow map this frame.
    pub fn shadow_casters(&self) -> impl Iterator<Item = (usize, &Light)> {
        let on = self.quality.shadows && !self.objects.is_empty();
        self.lights.iter().enumerate().filter(move |(_, l)| on && l.shadows)
    }

    /// True for a scene with nothing to draw: it shows the test pattern.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty() && self.media.is_empty() && self.lights.is_empty()
    }

    /// Mesh files the scene references, as written, deduplicated.
    pub fn mesh_files(&self) -> Vec<(&str, &Location)> {
        let mut seen = BTreeMap::new();
        for o in &self.objects {
            if let Geometry::Mesh { file, at } = &o.geometry {
                seen.entry(file.as_str()).or_insert(at);
            }
        }
        seen.into_iter().collect()
    }
}

/// Parses and validates a scene; `display` names the file in diagnostics.
pub fn parse(display: &str, text: &str) -> Result<Scene, Diagnostic> {
    let file: file::File = toml::from_str(text).map_err(|e| syntax_error(display, text, e.message(), e.span()))?;
    validate::scene(display, text, file)
}

/// A TOML parser's error, located where it points.
fn syntax_error(display: &str, text: &str, message: &str, span: Option<std::ops::Range<usize>>) -> Diagnostic {
    let d = Diagnostic::error(Code::Scene, message.trim().to_owned());
    match span {
        Some(span) => d.with_label(LineIndex::new(text).location(display, text, span), "here", true),
        None => d.at(Location::file_start(display)),
    }
}

/// A scene and the meshes it references, read from disk.
#[derive(Debug, Clone)]
pub struct Read {
    pub scene: Scene,
    /// Mesh data by the file name as written in the scene.
    pub meshes: BTreeMap<String, Arc<MeshData>>,
    /// Every file this scene was read from (itself and its meshes), for
    /// the watcher's dependency graph.
    pub files: Vec<PathBuf>,
}

/// Reads a scene file and every mesh it references. A mesh that fails to
/// load is an error located in the mesh file, with the scene line that
/// references it as a second label.
pub fn load(path: &Path) -> Result<Read, Diagnostic> {
    load_with(path, &overrides::Overrides::new())
}

/// `load` with live overrides applied on top of the file's text.
pub fn load_with(path: &Path, overrides: &overrides::Overrides) -> Result<Read, Diagnostic> {
    load_keeping(path, overrides, &|_, _| None)
}

/// A mesh a reload may keep instead of importing it again: `kept(path,
/// files)` gets the glTF's path and every file it is read from (itself
/// and its external buffers) and gives the mesh when none of them changed.
pub type KeptMesh<'a> = dyn Fn(&Path, &[PathBuf]) -> Option<Arc<MeshData>> + 'a;

/// `load_with`, taking unchanged meshes from `kept`.
pub fn load_keeping(path: &Path, overrides: &overrides::Overrides, kept: &KeptMesh<'_>) -> Result<Read, Diagnostic> {
    let display = crate::diag::display_path(path);
    let mut text = std::fs::read_to_string(path)
        .map_err(|e| Diagnostic::error(Code::Io, format!("cannot read scene: {e}")).at(Location::file_start(&display)))?;
    if !overrides.is_empty() {
        text = overrides::apply(&text, overrides)
            .map_err(|e| Diagnostic::error(Code::Scene, format!("cannot apply override: {e}")).at(Location::file_start(&display)))?;
    }
    let scene = parse(&display, &text)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut meshes = BTreeMap::new();
    let mut files = vec![path.to_owned()];
    for (name, at) in scene.mesh_files() {
        let mesh_path = dir.join(name);
        let mesh_display = crate::diag::display_path(&mesh_path);
        let mut own = vec![mesh_path.clone()];
        own.extend(crate::mesh::external_buffers(&mesh_path));
        files.extend(own.iter().cloned());
        if let Some(mesh) = kept(&mesh_path, &own) {
            meshes.insert(name.to_owned(), mesh);
            continue;
        }
        if !mesh_path.exists() {
            return Err(Diagnostic::error(Code::Scene, format!("mesh file `{mesh_display}` does not exist")).with_label(
                at.clone(),
                "referenced here",
                true,
            ));
        }
        let mesh = crate::mesh::load_gltf(&mesh_path, &mesh_display).map_err(|d| d.with_label(at.clone(), "referenced here", false))?;
        meshes.insert(name.to_owned(), Arc::new(mesh));
    }
    Ok(Read { scene, meshes, files })
}

#[cfg(test)]
mod docs_tests;
#[cfg(test)]
mod tests;
