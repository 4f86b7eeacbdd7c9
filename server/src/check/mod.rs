//! `loupe check`: the CI shader gate. Reads every WGSL file, composes and
//! validates each entry shader under every shader-def permutation the
//! renderer uses, loads every scene with the meshes it references, and,
//! with a device, creates every pipeline exactly as the renderer does.
//! Then, with a device, the image gate (`images`) renders loupe.toml's
//! image cases and compares them with their references.

pub mod capabilities;
pub mod format;
pub mod images;
pub mod project;
mod report;
pub mod spans;

pub use report::{CheckReport, ModuleKind, ModuleResult};

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use naga::valid::Capabilities;
use rayon::prelude::*;

use crate::diag::{Code, Diagnostic, Location, Severity, SourceFiles, display_path};
use crate::gpu::{
    self, Gpu,
    pipeline::{self, PipelineSpec},
};
use crate::loaded::Loaded;
use crate::material::Program;
use crate::material::tree::Definition;
use crate::shader::{Compose, Composed, Library, NagaOil, ShaderDefs, SourceFile, defs_key, library};

/// naga's parser and validator recurse on nested expressions; a worker stack
/// this large turns a 10,000-deep expression into work, not a crash.
const WORKER_STACK: usize = 512 << 20;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceMode {
    /// Create pipelines when an adapter exists; say so when none does.
    Auto,
    /// Never open a device.
    Off,
    /// Fail (exit 3) when no adapter exists.
    Required,
}

pub struct CheckOptions {
    pub paths: Vec<PathBuf>,
    /// The project's shader root: its files are always loaded so imports
    /// resolve, and pipeline specs name shaders relative to it.
    pub shader_root: PathBuf,
    pub device: DeviceMode,
    /// What sources are validated with. `None`: what the adapter supports,
    /// or without one `gpu::capabilities_without_device()`.
    pub capabilities: Option<Capabilities>,
    /// The image cases to render; `None` with `--no-images`.
    pub images: Option<images::Options>,
    /// Every `debugPrintf` call is an error (a CI that wants none merged).
    pub deny_debug_printf: bool,
}

/// A failure of the run itself rather than of a checked file.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error("{0}")]
    BadPath(String),
    #[error(transparent)]
    NoDevice(gpu::OpenError),
}

/// Runs the check; the report holds every diagnostic and the source texts
/// they point into.
pub fn run(opts: &CheckOptions) -> Result<(CheckReport, SourceFiles), CheckError> {
    let start = Instant::now();
    let found = library::discover_with(&opts.paths, is_target).map_err(CheckError::BadPath)?;
    let (scenes, targets): (Vec<PathBuf>, Vec<PathBuf>) =
        found.into_iter().filter(|p| p.file_name().is_none_or(|n| n != project::FILE)).partition(|p| is_toml(p));
    let (materials, targets): (Vec<PathBuf>, Vec<PathBuf>) = targets.into_iter().partition(|p| is_material(p));
    let root_files = if opts.shader_root.is_dir() {
        library::discover(std::slice::from_ref(&opts.shader_root)).map_err(CheckError::BadPath)?
    } else {
        Vec::new()
    };
    let canon = |p: &Path| p.canonicalize().unwrap_or_else(|_| p.to_owned());
    let all: BTreeMap<PathBuf, PathBuf> = targets.iter().chain(root_files.iter()).map(|p| (canon(p), p.clone())).collect();
    let target_set: BTreeSet<PathBuf> = targets.iter().map(|p| canon(p)).collect();

    let pool = rayon::ThreadPoolBuilder::new().stack_size(WORKER_STACK).build().expect("a thread pool with default thread count");
    let _quiet = QuietPanics::install();

    let read: Vec<(PathBuf, Result<SourceFile, Diagnostic>)> =
        pool.install(|| all.par_iter().map(|(canon, shown)| (canon.clone(), SourceFile::read(shown, display_path(shown)))).collect());
    let mut files = SourceFiles::default();
    let mut unreadable: BTreeMap<String, Diagnostic> = BTreeMap::new();
    let mut sources = Vec::new();
    let mut target_displays = Vec::new();
    for (canon, r) in read {
        let is_target = target_set.contains(&canon);
        match r {
            Ok(f) => {
                files.insert(f.display.clone(), f.text.clone());
                if is_target {
                    target_displays.push(f.display.clone());
                }
                sources.push(f);
            }
            Err(d) if is_target => {
                let shown = d.file().unwrap_or_default().to_owned();
                target_displays.push(shown.clone());
                unreadable.insert(shown, d);
            }
            Err(_) => {}
        }
    }
    let mut lib = Library::new(sources);
    let shader_root = canon(&opts.shader_root);
    // Scenes and material files first: their materials make the
    // `loupe::material` module the renderer's shaders import, so every
    // material's generated code passes the gate.
    let scenes: Vec<(Checked, Option<Loaded>)> = pool.install(|| scenes.par_iter().with_max_len(1).map(|p| check_scene(p)).collect());
    let materials: Vec<(Checked, Vec<Definition>)> =
        pool.install(|| materials.par_iter().with_max_len(1).map(|p| check_material(p)).collect());
    let definitions = scenes
        .iter()
        .filter_map(|(_, l)| l.as_ref())
        .flat_map(|l| l.materials.definitions.iter())
        .chain(materials.iter().flat_map(|(_, d)| d.iter()));
    // Only a tree that imports the module gets it: someone else's WGSL is
    // checked as it is.
    let material_paths = [crate::material::back::IMPORT_PATH, crate::material::back::PATH_IMPORT_PATH];
    if lib.files().any(|f| f.imports.iter().any(|i| material_paths.contains(&i.module.as_str()))) {
        crate::render::session::material_module(&mut lib, &opts.shader_root, &project_materials(definitions));
    }
    let specs_by_file = specs_by_display(&lib, &shader_root);

    // The device first: without a capability list, sources are judged by
    // what its adapter supports. Pipelines are created on it at the end.
    let mut device_note = None;
    let gpu = match opts.device {
        DeviceMode::Off => None,
        mode => match gpu::open() {
            Ok(gpu) => Some(gpu),
            Err(e) if mode == DeviceMode::Required => return Err(CheckError::NoDevice(e)),
            Err(e) => {
                device_note = Some(Diagnostic {
                    severity: Severity::Note,
                    ..Diagnostic::error(Code::DeviceMissing, format!("pipelines were not created: {e}"))
                });
                None
            }
        },
    };
    let caps = opts.capabilities.unwrap_or_else(|| gpu.as_ref().map_or_else(gpu::capabilities_without_device, Gpu::adapter_capabilities));

    // Compose every target under each of its permutations, in parallel,
    // one file per task and largest first: rayon otherwise hands each thread
    // a contiguous chunk up front, and the chunk holding the big files keeps
    // one core busy while the other idles.
    let size = |d: &String| lib.get(d).map_or(0, |f| f.text.len());
    target_displays.sort_by_key(|d| std::cmp::Reverse(size(d)));
    let mut checked: Vec<Checked> = pool.install(|| {
        target_displays
            .par_iter()
            .with_max_len(1)
            .map(|display| match unreadable.get(display) {
                Some(d) => Checked::uncompiled(display, ModuleKind::Entry, [d.clone()]),
                None => check_file(&lib, &lib.get(display).expect("read above").clone(), &specs_by_file, caps),
            })
            .collect()
    });
    for c in scenes.into_iter().map(|(c, _)| c).chain(materials.into_iter().map(|(c, _)| c)) {
        format::human::read_sources(&c.diagnostics, &mut files);
        checked.push(c);
    }

    let mut report = CheckReport::default();
    let mut seen = BTreeSet::new();
    let mut modules: BTreeMap<String, ModuleResult> = BTreeMap::new();
    for c in &checked {
        modules.insert(
            c.display.clone(),
            ModuleResult {
                file: c.display.clone(),
                kind: c.kind,
                permutations: c.permutations.iter().map(defs_key).collect(),
                pipelines: 0,
                diagnostics: Vec::new(),
                duration: c.duration,
            },
        );
    }
    let mut place = |owner: &str, d: Diagnostic, modules: &mut BTreeMap<String, ModuleResult>| {
        if !seen.insert(d.to_string()) {
            return; // the same error reached through another importer
        }
        let home = d.file().filter(|f| modules.contains_key(*f)).unwrap_or(owner).to_owned();
        if let Some(m) = modules.get_mut(&home) {
            m.diagnostics.push(d);
        }
    };
    for d in lib.diagnostics.iter().cloned() {
        let owner = d.file().unwrap_or_default().to_owned();
        place(&owner, d, &mut modules);
    }
    for c in &checked {
        for d in c.diagnostics.iter().cloned() {
            place(&c.display, d, &mut modules);
        }
    }
    if opts.deny_debug_printf {
        for file in target_displays.iter().filter_map(|d| lib.get(d)) {
            for site in &file.prints.sites {
                let at = file.location(site.call.clone());
                let d = Diagnostic::error(Code::PrintfDenied, "`debugPrintf` is denied in this check")
                    .with_label(at, "printed here", true)
                    .with_note("denied by --deny-debug-printf (or `deny_debug_printf = true` in loupe.toml)");
                place(&file.display, d, &mut modules);
            }
        }
    }
    // A shader tree that holds some of the renderer's shaders must hold all
    // of them; a tree with none is someone else's WGSL, checked as sources.
    let renderer_tree = !specs_by_file.is_empty() && opts.paths.iter().any(|p| canon(p) == shader_root);
    for spec in crate::render::passes::specs() {
        if renderer_tree && !specs_by_file.values().flatten().any(|s| s.name == spec.name) {
            let wanted = opts.shader_root.join(spec.shader);
            report.general.push(
                pipeline::missing_shader(spec.name, &display_path(&wanted)).with_note("the renderer builds this pipeline from that file"),
            );
        }
    }

    // Create every pipeline on the device, on this thread.
    report.general.extend(device_note);
    if let Some(gpu) = &gpu {
        report.adapter = Some(gpu.adapter_name());
        for c in &checked {
            for (spec, defs, composed) in &c.composed {
                let result = crate::shader::guard::guarded(&c.display, "wgpu", || {
                    pipeline::create(&gpu.device, spec, defs, composed, &lib, &c.display, None).map(|_| ())
                });
                match result {
                    Ok(()) => modules.get_mut(&c.display).expect("inserted").pipelines += 1,
                    Err(ds) => {
                        for d in ds {
                            let d = d.with_note(format!("permutation: [{}]", defs_key(defs)));
                            place(&c.display, d, &mut modules);
                        }
                    }
                }
            }
        }
    }

    report.modules = modules.into_values().collect();
    if let Some(io) = &opts.images {
        report.images = match &gpu {
            None if opts.device == DeviceMode::Off => images::skipped(io, "--no-device"),
            _ => image_cases(io, gpu.as_ref(), &opts.shader_root, &mut report),
        };
        // Their failures point into loupe.toml: the excerpts need its text.
        for c in &report.images {
            format::human::read_sources(&c.diagnostics, &mut files);
        }
    }
    report.duration = start.elapsed();
    Ok((report, files))
}

/// The image gate, once the sources are checked: skipped, never passed,
/// without a device or when a shader or scene has errors (its frames
/// could not be what the project means).
fn image_cases(io: &images::Options, gpu: Option<&Gpu>, shader_root: &Path, report: &mut CheckReport) -> Vec<images::CaseResult> {
    let Some(gpu) = gpu else {
        return images::skipped(io, "no device: the image cases need one");
    };
    if report.count(Severity::Error) > 0 {
        return images::skipped(io, "the shaders or scenes have errors");
    }
    match library::read_tree(shader_root) {
        Ok(lib) => {
            let (cases, general) = images::run(io, gpu, shader_root, &lib);
            report.general.extend(general);
            cases
        }
        Err(e) => {
            report.general.push(Diagnostic::error(Code::Io, format!("the image cases cannot read the shaders: {e}")));
            images::skipped(io, "the shaders could not be read")
        }
    }
}

/// Whether a file found under `root` is checked: every `*.wgsl` and
/// `*.mat`, and a `*.toml` inside a directory named `scenes` (the search
/// root counts).
/// Files named on the command line are always checked, by extension.
fn is_target(root: &Path, path: &Path) -> bool {
    if path.extension().is_some_and(|e| e == "wgsl") || is_material(path) {
        return true;
    }
    let scenes = |c: &std::ffi::OsStr| c == "scenes";
    let root_name = root.canonicalize().ok().and_then(|r| r.file_name().map(ToOwned::to_owned));
    let inside = path.strip_prefix(root).ok().and_then(Path::parent).is_some_and(|dir| dir.iter().any(scenes));
    is_toml(path) && (root_name.as_deref().is_some_and(scenes) || inside)
}

fn is_toml(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "toml")
}

fn is_material(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "mat")
}

/// Loads a material file and its imports, as the front end does for
/// `loupe serve`: its errors, or its warnings and its definitions (whose
/// generated code the renderer's shaders are then checked with).
fn check_material(path: &Path) -> (Checked, Vec<Definition>) {
    let start = Instant::now();
    let display = display_path(path);
    let compiled = guarded(&display, "the material compiler", || {
        let loaded = crate::material::front::load(path)?;
        let analysed = loaded.definitions.iter().map(crate::material::analysed).collect::<Result<Vec<_>, _>>()?;
        // Its textures are read as a scene's are: a missing or undecodable
        // image is an error here too.
        let bad: Vec<_> = loaded.textures.iter().filter_map(|t| crate::material::texture::read(t).err()).collect();
        if !bad.is_empty() {
            return Err(bad);
        }
        Ok((loaded.warnings, analysed.into_iter().map(|a| a.def).collect()))
    });
    let (diagnostics, definitions) = compiled.unwrap_or_else(|errors| (errors, Vec::new()));
    (Checked { duration: start.elapsed(), ..Checked::uncompiled(&display, ModuleKind::Material, diagnostics) }, definitions)
}

/// Loads a scene as `loupe serve` does: the file, then every glTF and
/// material file it references.
fn check_scene(path: &Path) -> (Checked, Option<Loaded>) {
    let start = Instant::now();
    let display = display_path(path);
    let (loaded, diagnostics) = match guarded(&display, "the scene loader", || crate::loaded::load(path).map_err(|d| vec![d])) {
        Ok(l) => {
            let warnings = l.warnings.clone();
            (Some(l), warnings)
        }
        Err(ds) => (None, ds),
    };
    (Checked { duration: start.elapsed(), ..Checked::uncompiled(&display, ModuleKind::Scene, diagnostics) }, loaded)
}

/// Every material definition of the checked scenes and material files,
/// each once, and the
/// shorthand's always: the renderer's shaders compile against it even in
/// a project without scenes.
fn project_materials<'a>(definitions: impl Iterator<Item = &'a Definition>) -> Program {
    let mut program =
        Program { definitions: vec![crate::material::shorthand(Location::file_start("scene shorthand"))], ..Program::default() };
    for d in definitions {
        if !program.definitions.iter().any(|x| x.nodes == d.nodes && x.exprs == d.exprs && x.params == d.params) {
            program.definitions.push(d.clone());
        }
    }
    // The raster's module holds them simplified at the default budget, so
    // the gate sees the simplification's code too.
    program.simplify(crate::scene::settings::Quality::default().material_bytes, false);
    program
}

/// Pipeline specs by the display path of the shader file they build from.
fn specs_by_display(lib: &Library, shader_root: &Path) -> BTreeMap<String, Vec<&'static PipelineSpec>> {
    let mut out: BTreeMap<String, Vec<&'static PipelineSpec>> = BTreeMap::new();
    for f in lib.files() {
        let canon = f.path.canonicalize().unwrap_or_else(|_| f.path.clone());
        let Ok(rel) = canon.strip_prefix(shader_root) else { continue };
        let rel = rel.to_string_lossy().replace('\\', "/");
        for spec in crate::render::passes::specs().filter(|s| s.shader == rel) {
            out.entry(f.display.clone()).or_default().push(spec);
        }
    }
    out
}

/// What checking one file produced.
struct Checked {
    display: String,
    kind: ModuleKind,
    permutations: Vec<ShaderDefs>,
    diagnostics: Vec<Diagnostic>,
    /// Modules that composed, with the spec they are for, for the device pass.
    composed: Vec<(&'static PipelineSpec, ShaderDefs, Composed)>,
    duration: std::time::Duration,
}

impl Checked {
    /// A file with nothing composed: unreadable WGSL, or a scene.
    fn uncompiled(display: &str, kind: ModuleKind, diagnostics: impl IntoIterator<Item = Diagnostic>) -> Self {
        Checked {
            display: display.to_owned(),
            kind,
            permutations: Vec::new(),
            diagnostics: diagnostics.into_iter().collect(),
            composed: Vec::new(),
            duration: Default::default(),
        }
    }
}

fn check_file(
    lib: &Library,
    file: &Arc<SourceFile>,
    specs: &BTreeMap<String, Vec<&'static PipelineSpec>>,
    caps: naga::valid::Capabilities,
) -> Checked {
    let start = Instant::now();
    let own_specs = specs.get(&file.display).cloned().unwrap_or_default();
    let kind = if file.import_path.is_some() { ModuleKind::Library } else { ModuleKind::Entry };
    let mut permutations: Vec<ShaderDefs> = own_specs.iter().flat_map(|s| s.permutations()).collect();
    permutations.sort();
    permutations.dedup();
    if permutations.is_empty() {
        permutations.push(ShaderDefs::new());
    }
    let mut diagnostics: Vec<Diagnostic> = Vec::new();
    let mut composed = Vec::new();
    for defs in &permutations {
        let result = match kind {
            ModuleKind::Library => {
                guarded(&file.display, "the WGSL compiler", || crate::shader::compose::check_library(lib, file, defs, caps).map(|_| None))
            }
            _ => guarded(&file.display, "the WGSL compiler", || NagaOil.compose(lib, file, defs, caps).map(Some)),
        };
        match result {
            Ok(Some(c)) if c.module.entry_points.is_empty() && !diagnostics.iter().any(|d| d.code == Code::UnusedModule) => {
                diagnostics.push(
                    Diagnostic::warning(Code::UnusedModule, "no entry point and no `#define_import_path`: nothing can use this file")
                        .at(Location::file_start(&file.display))
                        .with_note(
                            "add `#define_import_path some::name` to make it importable, or an @vertex/@fragment/@compute entry point",
                        ),
                );
            }
            Ok(Some(c)) => {
                for spec in own_specs.iter().filter(|s| s.permutations().contains(defs)) {
                    composed.push((*spec, defs.clone(), c.clone()));
                }
            }
            Ok(None) => {}
            Err(ds) => {
                // The shader, then what it imports: where a capability
                // error without a span is looked for.
                let sources: Vec<Arc<SourceFile>> =
                    std::iter::once(file.clone()).chain(lib.dependencies(file).unwrap_or_default()).collect();
                for d in ds {
                    let d = capabilities::explain(d, caps, &sources);
                    let d = if permutations.len() > 1 { d.with_note(format!("permutation: [{}]", defs_key(defs))) } else { d };
                    if !diagnostics.iter().any(|x| x.to_string() == d.to_string()) {
                        diagnostics.push(d);
                    }
                }
            }
        }
    }
    Checked { display: file.display.clone(), kind, permutations, diagnostics, composed, duration: start.elapsed() }
}

/// Runs one step of `who` (naga, naga_oil, the scene loader), turning a
/// panic into a diagnostic so the other files are still checked.
fn guarded<T>(display: &str, who: &str, f: impl FnOnce() -> Result<T, Vec<Diagnostic>>) -> Result<T, Vec<Diagnostic>> {
    crate::shader::guard::guarded(display, who, f)
}

/// Silences the default panic message while compile steps run: a panic
/// there is reported as a diagnostic, not as a backtrace on stderr.
struct QuietPanics(Option<PanicHook>);

/// A panic hook, as `std::panic::take_hook` returns it.
type PanicHook = Box<dyn Fn(&std::panic::PanicHookInfo<'_>) + Sync + Send + 'static>;

impl QuietPanics {
    fn install() -> Self {
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        QuietPanics(Some(prev))
    }
}

impl Drop for QuietPanics {
    fn drop(&mut self) {
        if let Some(prev) = self.0.take() {
            std::panic::set_hook(prev);
        }
    }
}
