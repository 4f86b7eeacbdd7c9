//! A scene as the renderer takes it: the scene and its meshes, read by
//! `scene`, and the network its `[denoiser]` names, built from `denoise`.
//! Joining them here keeps the scene file's reader free of the denoiser.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::denoise::network::{Inputs, Network};
use crate::denoise::{bundled, tza};
use crate::diag::{Code, Diagnostic, Location, display_path};
use crate::material::report::Report;
use crate::material::texture;
use crate::material::tree::{Definition, TextureSource, Type, Value};
use crate::material::{Instance, Program};
use crate::mesh::MeshData;
use crate::scene::{self, Denoiser, MaterialSource, ParamValue, Scene, overrides::Overrides};

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
    /// The compile report of each of `materials`' definitions, in their
    /// order, with the size of its generated WGSL and its compile time.
    pub reports: Arc<Vec<Report>>,
    /// Every file this scene was read from (itself, its meshes, material
    /// files and weights), for the watcher's dependency graph.
    pub files: Vec<PathBuf>,
    /// What loading found but could render anyway: what glTF materials
    /// cannot represent (for `loupe check` and the browser's diagnostics).
    pub warnings: Vec<Diagnostic>,
}

/// Reads a scene file, every mesh it references (`scene::load`) and its
/// denoiser's weights.
pub fn load(path: &Path) -> Result<Loaded, Diagnostic> {
    load_with(path, &Overrides::new())
}

/// `load` with live overrides applied on top of the file's text.
pub fn load_with(path: &Path, overrides: &Overrides) -> Result<Loaded, Diagnostic> {
    load_keeping(path, overrides, None)
}

/// What a reload may keep from the scene it replaces: `previous`'s
/// meshes, texture layers and denoiser network, each when none of the
/// files it was read from is one `changed` names. A material edit or a
/// live override then costs the scene file and the material files, not
/// every mesh, image and weights file again.
pub struct Keep<'a> {
    pub previous: &'a Loaded,
    pub changed: &'a dyn Fn(&Path) -> bool,
}

/// `load_with`, keeping what `keep` allows from the previous load.
pub fn load_keeping(path: &Path, overrides: &Overrides, keep: Option<&Keep<'_>>) -> Result<Loaded, Diagnostic> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let unchanged = |files: &[PathBuf]| keep.filter(|k| !files.iter().any(|f| (k.changed)(f)));
    let kept_mesh = |mesh_path: &Path, own: &[PathBuf]| {
        unchanged(own)?.previous.meshes.iter().find(|(name, _)| dir.join(name) == mesh_path).map(|(_, m)| m.clone())
    };
    let scene::Read { mut scene, mut meshes, mut files } = scene::load_keeping(path, overrides, &kept_mesh)?;
    let (mut materials, mut reports) = materials(path, &scene, &mut files)?;
    let mut warnings = gltf_objects::split(dir, &mut scene, &mut meshes, &mut materials, &mut reports)?;
    simplify(&mut materials, &mut reports, &scene);
    let kept_layers = keep.and_then(|k| {
        let sources = |p: &Program| p.textures.iter().map(|t| (t.path.clone(), t.space)).collect::<Vec<_>>();
        let paths: Vec<PathBuf> = materials.textures.iter().map(|t| t.path.clone()).collect();
        (sources(&k.previous.materials) == sources(&materials) && unchanged(&paths).is_some()).then(|| k.previous.materials.layers.clone())
    });
    warnings.extend(read_textures(&mut materials, &mut files, kept_layers)?);
    let kept_network = |d: &Denoiser| {
        let k = keep?;
        let before = k.previous.scene.denoiser.as_ref()?;
        let weights: Vec<PathBuf> = d.weights.iter().map(|w| dir.join(w)).collect();
        (before.weights == d.weights && before.mode == d.mode && unchanged(&weights).is_some()).then(|| k.previous.denoiser.clone())?
    };
    let denoiser = match scene.denoiser.as_ref() {
        Some(d) => match kept_network(d) {
            Some(n) => {
                files.extend(d.weights.iter().map(|w| dir.join(w)));
                Some(n)
            }
            None => Some(Arc::new(network(dir, d, &mut files)?)),
        },
        None => None,
    };
    Ok(Loaded { scene, meshes, materials: Arc::new(materials), reports: Arc::new(reports), denoiser, files, warnings })
}

impl Loaded {
    /// This load under `scene` (the same files, other settings): the
    /// materials brought to its budget and its energy compensation again,
    /// the parts of a load its settings decide.
    pub fn with_scene(&self, scene: Scene) -> Loaded {
        let mut materials = (*self.materials).clone();
        let mut reports = (*self.reports).clone();
        for i in &mut materials.instances {
            i.compensated = compensated(&scene, &materials.definitions[i.definition as usize]);
        }
        simplify(&mut materials, &mut reports, &scene);
        Loaded { scene, materials: Arc::new(materials), reports: Arc::new(reports), ..self.clone() }
    }
}

/// Whether an instance of `d` compensates its GGX lobes for multiple
/// scattering under `scene`'s settings.
fn compensated(scene: &Scene, d: &Definition) -> bool {
    scene.quality.energy_compensation && d.energy_compensation
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
    let (mut program, mut reports) = materials(Path::new("scene.toml"), scene, &mut Vec::new()).unwrap_or_else(|d| panic!("{d}"));
    simplify(&mut program, &mut reports, scene);
    read_textures(&mut program, &mut Vec::new(), None).unwrap_or_else(|d| panic!("{d}"));
    Arc::new(program)
}

/// The scene's materials compiled: the shorthand's one definition (when
/// any entry uses it) and each material file's, once each. A material file
/// and its imports join the scene's dependencies; a bad one is its own
/// diagnostic with the scene line that names it as a second label. Each
/// definition's report comes with it (`compiled`). Textures are indexed,
/// not read yet (`read_textures`).
fn materials(path: &Path, scene: &Scene, files: &mut Vec<PathBuf>) -> Result<(Program, Vec<Report>), Diagnostic> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut program = Program::default();
    let mut reports = Vec::new();
    // Definition index by (material file, material name); each file read
    // once, however many entries name it, with how long parsing took.
    let mut known: BTreeMap<(PathBuf, String), u32> = BTreeMap::new();
    let mut read: BTreeMap<PathBuf, (crate::material::front::Loaded, f64)> = BTreeMap::new();
    let mut shorthand = None;
    for m in &scene.materials {
        let instance = match &m.source {
            MaterialSource::Shorthand { base_color, metallic, roughness } => {
                let definition = *shorthand.get_or_insert_with(|| {
                    let start = Instant::now();
                    let def = crate::material::shorthand(Location::file_start(&display_path(path)));
                    // The module keeps the shorthand as written (it renders
                    // what loupe rendered before materials); the report is
                    // of its analysis, which finds nothing to fold.
                    reports.push(compiled(crate::material::analysis::analyse(&def), start, 0.0).1);
                    program.definitions.push(def);
                    program.definitions.len() as u32 - 1
                });
                Instance {
                    definition,
                    values: vec![Value::Vec3(*base_color), Value::Float(*metallic), Value::Float(*roughness)],
                    compensated: false,
                }
            }
            MaterialSource::File { file, material, params, at } => {
                let file_path = dir.join(file);
                if !read.contains_key(&file_path) {
                    let start = Instant::now();
                    let mut loaded = material_file(&file_path, at, files)?;
                    for d in &mut loaded.definitions {
                        index_textures(&mut program, d, &loaded.textures);
                    }
                    read.insert(file_path.clone(), (loaded, start.elapsed().as_secs_f64() * 1e3));
                }
                let (loaded, parse_ms) = &read[&file_path];
                let chosen = match material {
                    Some(name) => loaded.definitions.iter().find(|d| &d.name == name),
                    None if loaded.definitions.len() == 1 => loaded.definitions.first(),
                    None => None,
                };
                let names: Vec<&str> = loaded.definitions.iter().map(|d| d.name.as_str()).collect();
                let Some(d) = chosen else {
                    let shown = display_path(&file_path);
                    let message = match material {
                        Some(name) => format!("`{shown}` defines no material `{name}` (it defines: {})", names.join(", ")),
                        None => format!("`{shown}` defines {} materials: name one with `material` ({})", names.len(), names.join(", ")),
                    };
                    return Err(Diagnostic::error(Code::Scene, message).with_label(at.clone(), "this file", true));
                };
                let values = param_values(d, params, &m.name)?;
                let key = (file_path.clone(), d.name.clone());
                let definition = match known.get(&key) {
                    Some(&i) => i,
                    None => {
                        let start = Instant::now();
                        let analysed = crate::material::analysed(d).map_err(|ds| first_of(ds, at))?;
                        let (def, report) = compiled(analysed, start, *parse_ms);
                        program.definitions.push(def);
                        reports.push(report);
                        let i = program.definitions.len() as u32 - 1;
                        known.insert(key, i);
                        i
                    }
                };
                Instance { definition, values, compensated: compensated(scene, &program.definitions[definition as usize]) }
            }
        };
        program.instances.push(instance);
    }
    Ok((program, reports))
}

/// Reads and decodes the program's textures into its layers (or takes
/// `kept`, the previous load's layers of the same unchanged files); each
/// texture file joins `files`. A texture of another size than the scene's
/// largest is resampled to it (the layers of one array share a size): a
/// warning at the param naming it, since its texels are not the file's.
fn read_textures(
    program: &mut Program,
    files: &mut Vec<PathBuf>,
    kept: Option<Arc<texture::Layers>>,
) -> Result<Vec<Diagnostic>, Diagnostic> {
    // Watched before they are read, so a fix is seen after a failure.
    files.extend(program.textures.iter().map(|t| t.path.clone()));
    let layers = match kept {
        Some(layers) => layers,
        None => Arc::new(texture::Layers::of(program.textures.iter().map(texture::read).collect::<Result<Vec<_>, _>>()?)),
    };
    let warnings = layers
        .resampled()
        .map(|i| {
            let source = &program.textures[i];
            let (w, h) = layers.sources[i];
            Diagnostic::warning(
                Code::Material,
                format!(
                    "texture `{}` is {w}×{h}: resampled to {}×{}, the size of the scene's textures",
                    display_path(&source.path),
                    layers.width,
                    layers.height
                ),
            )
            .with_label(source.location.clone(), "this image", true)
            .with_note(format!(
                "a scene's textures share one size (the largest, at most {} a side): make them alike to keep every texel",
                texture::MAX_SIZE
            ))
        })
        .collect();
    program.layers = layers;
    Ok(warnings)
}

/// Brings the program to the scene's `quality.material_bytes` and puts
/// what that did in each definition's report.
fn simplify(program: &mut Program, reports: &mut [Report], scene: &Scene) {
    program.simplify(scene.quality.material_bytes, scene.quality.path_simplified_materials);
    for (report, s) in reports.iter_mut().zip(&program.simplified) {
        report.budget = Some(crate::material::report::Budget::of(s));
    }
}

/// An analysed definition and its report, whose WGSL size is that of the
/// module generated for it alone (its `init` with the shared loops) and
/// whose compile time runs from `start` (before the analysis) through the
/// back end, plus `parse_ms`, the time its file took to parse.
fn compiled(analysis: crate::material::analysis::Analysis, start: Instant, parse_ms: f64) -> (Definition, Report) {
    let mut report = Report::new(&analysis);
    let wgsl = crate::material::back::wgsl(std::slice::from_ref(&analysis.def), crate::material::back::Bindings::RENDERER);
    report.wgsl_bytes = Some(wgsl.len());
    report.compile_ms = Some(parse_ms + start.elapsed().as_secs_f64() * 1e3);
    (analysis.def, report)
}

/// Makes `d`'s texture defaults, which index `textures` (its front end's
/// table), index the program's table instead.
fn index_textures(program: &mut Program, d: &mut Definition, textures: &[TextureSource]) {
    for p in &mut d.params {
        if let Value::Texture(k) = p.default {
            p.default = Value::Texture(texture_index(program, &textures[k as usize]));
        }
    }
}

/// `source`'s index in the program's texture table, added if new.
fn texture_index(program: &mut Program, source: &TextureSource) -> u32 {
    let position = program.textures.iter().position(|t| t.path == source.path && t.space == source.space);
    position.unwrap_or_else(|| {
        program.textures.push(source.clone());
        program.textures.len() - 1
    }) as u32
}

/// A material file and its imports, read and lowered; every file read
/// joins `files` (so a fix is seen even after a failure).
fn material_file(path: &Path, at: &Location, files: &mut Vec<PathBuf>) -> Result<crate::material::front::Loaded, Diagnostic> {
    files.push(path.to_owned());
    if !path.is_file() {
        let message = format!("material file `{}` does not exist", display_path(path));
        return Err(Diagnostic::error(Code::Scene, message).with_label(at.clone(), "named here", true));
    }
    match crate::material::front::load(path) {
        Ok(loaded) => {
            files.extend(loaded.files.iter().skip(1).cloned());
            Ok(loaded)
        }
        Err(errors) => Err(first_of(errors, at)),
    }
}

/// The first of a material file's errors, saying how many more there are,
/// with the scene line that names the file.
fn first_of(errors: Vec<Diagnostic>, at: &Location) -> Diagnostic {
    let more = errors.len().saturating_sub(1);
    let mut first = errors.into_iter().next().expect("a failure has a diagnostic");
    if more > 0 {
        first = first.with_note(format!("and {more} more error{} in the material files", if more == 1 { "" } else { "s" }));
    }
    first.with_label(at.clone(), "material file named here", false)
}

/// An instance's values: each parameter's default, replaced by the scene's
/// `params` (checked against the parameter's type and range).
fn param_values(d: &Definition, params: &[(String, ParamValue, Location)], material: &str) -> Result<Vec<Value>, Diagnostic> {
    let mut values: Vec<Value> = d.params.iter().map(|p| p.default).collect();
    for (name, value, at) in params {
        let error = |message: String| {
            Diagnostic::error(Code::Scene, format!("materials `{material}`: {message}")).with_label(at.clone(), "here", true)
        };
        let Some(i) = d.params.iter().position(|p| &p.name == name) else {
            let known: Vec<&str> = d.params.iter().map(|p| p.name.as_str()).collect();
            let known = if known.is_empty() { "none".to_owned() } else { known.join(", ") };
            return Err(error(format!("material `{}` has no parameter `{name}` (it has: {known})", d.name)));
        };
        let p = &d.params[i];
        let v = match (p.ty, *value) {
            (Type::Float, ParamValue::Float(x)) => Value::Float(x),
            (Type::Color | Type::Vec3, ParamValue::Vec3(c)) => Value::Vec3(c),
            (Type::Float, _) => return Err(error(format!("`{name}` is a number"))),
            (Type::Texture, _) => return Err(error(format!("`{name}` is a texture: scenes cannot set one yet"))),
            (_, _) => return Err(error(format!("`{name}` is a colour: three numbers, [r, g, b]"))),
        };
        let parts = crate::material::analysis::channels(v);
        if let Some(bad) = parts.iter().find(|x| !x.is_finite()) {
            return Err(error(format!("`{name}` must be finite, not {bad}")));
        }
        if let Some((lo, hi)) = p.range
            && let Some(bad) = parts.iter().find(|x| **x < lo || **x > hi)
        {
            return Err(error(format!("`{name}` must lie in [{lo}, {hi}], not {bad}")));
        }
        values[i] = v;
    }
    Ok(values)
}

mod gltf_objects;
#[cfg(test)]
mod tests;
