//! A scene as the renderer takes it: the scene and its meshes, read by
//! `scene`, and the network its `[denoiser]` names, built from `denoise`.
//! Joining them here keeps the scene file's reader free of the denoiser.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::denoise::network::{Inputs, Network};
use crate::denoise::{bundled, tza};
use crate::diag::{Code, Diagnostic};
use crate::material::tree::Value;
use crate::material::{Instance, Program};
use crate::mesh::MeshData;
use crate::scene::{self, Denoiser, MaterialSource, Scene, overrides::Overrides};

/// A scene and the meshes and weights it references, read from disk.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub scene: Scene,
    /// Mesh data by the file name as written in the scene.
    pub meshes: BTreeMap<String, Arc<MeshData>>,
    /// The network `[denoiser]` names (or the bundled one), built from its
    /// weights.
    pub denoiser: Option<Arc<Network>>,
    /// The scene's materials compiled: the definitions its
    /// `[[materials]]` use and one instance per entry.
    pub materials: Arc<Program>,
    /// Every file this scene was read from (itself, its meshes, material
    /// files and weights), for the watcher's dependency graph.
    pub files: Vec<PathBuf>,
}

/// Reads a scene file, every mesh it references (`scene::load`) and its
/// denoiser's weights.
pub fn load(path: &Path) -> Result<Loaded, Diagnostic> {
    load_with(path, &Overrides::new())
}

/// `load` with live overrides applied on top of the file's text.
pub fn load_with(path: &Path, overrides: &Overrides) -> Result<Loaded, Diagnostic> {
    let scene::Read { scene, meshes, mut files } = scene::load_with(path, overrides)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let materials = Arc::new(materials(path, &scene, &mut files)?);
    let denoiser = scene.denoiser.as_ref().map(|d| network(dir, d, &mut files)).transpose()?.map(Arc::new);
    Ok(Loaded { scene, meshes, materials, denoiser, files })
}

/// The network of `[denoiser]`: without `weights`, the bundled one for its
/// mode that takes the colour, albedo and normal the path tracer writes.
/// Else the file's: a missing file is an error at `weights`; a malformed
/// one is the weights file's own diagnostic, with `weights` as a second
/// label.
fn network(dir: &Path, d: &Denoiser, files: &mut Vec<PathBuf>) -> Result<Network, Diagnostic> {
    let Some(weights) = &d.weights else {
        return bundled::weights(d.mode, Inputs::ColorAlbedoNormal)
            .and_then(bundled::Bundled::network)
            .map_err(|e| e.with_label(d.at.clone(), "the denoiser without weights", true));
    };
    let path = dir.join(weights);
    let display = crate::diag::display_path(&path);
    files.push(path.clone());
    if !path.is_file() {
        return Err(Diagnostic::error(Code::Scene, format!("weights file `{display}` does not exist")).with_label(
            d.at.clone(),
            "named here",
            true,
        ));
    }
    let archive = tza::read(&path, &display).map_err(|e| e.with_label(d.at.clone(), "named here", false))?;
    Network::from_archive(&archive).map_err(|e| e.diagnostic(&display).with_label(d.at.clone(), "named here", false))
}

/// The materials of a scene parsed from text, for tests: material files
/// relative to the working directory; a failure panics.
#[cfg(any(test, feature = "testing"))]
pub fn materials_of(scene: &Scene) -> Arc<Program> {
    Arc::new(materials(Path::new("scene.toml"), scene, &mut Vec::new()).unwrap_or_else(|d| panic!("{d}")))
}

/// The scene's materials compiled: the shorthand's one definition (when
/// any entry uses it) and each material file's, once each.
fn materials(path: &Path, scene: &Scene, files: &mut Vec<PathBuf>) -> Result<Program, Diagnostic> {
    let _ = files;
    let mut program = Program { definitions: Vec::new(), instances: Vec::new() };
    let mut shorthand = None;
    for m in &scene.materials {
        let instance = match &m.source {
            MaterialSource::Shorthand { base_color, metallic, roughness } => {
                let definition = *shorthand.get_or_insert_with(|| {
                    let at = crate::diag::Location::file_start(&crate::diag::display_path(path));
                    program.definitions.push(crate::material::shorthand(at));
                    program.definitions.len() as u32 - 1
                });
                Instance { definition, values: vec![Value::Vec3(*base_color), Value::Float(*metallic), Value::Float(*roughness)] }
            }
            MaterialSource::File { at, .. } => {
                return Err(Diagnostic::error(Code::Scene, "material files are not read yet").with_label(at.clone(), "here", true));
            }
        };
        program.instances.push(instance);
    }
    Ok(program)
}

#[cfg(test)]
mod tests;
