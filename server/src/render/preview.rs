//! A material's preview: a unit sphere wearing one material instance,
//! under the scene's environment and its directional lights, rendered
//! raster or path traced at `SIZE`² by a session of its own. The preview
//! compiles the scene's own generated material module, so what it shows is
//! what the frame's lighting pass and path tracer run.
//!
//! Which definitions the sphere wears is the preview's [`Materials`]: as
//! the scene renders them, the full ones, or the ones simplified to a
//! budget (`quality.material_bytes`), so the browser can put the full
//! material beside the budget's, raster and path traced. The full and
//! simplified definitions of one budget are compiled into one module
//! ([`program`]): switching between them, or between materials, rebuilds
//! no pipeline; a new budget does.
//!
//! The scene's point and rect lights are left out: they sit where the
//! scene put them, not around the sphere. Auto exposure is off (one frame
//! cannot adapt); the scene's exposure compensation stays as the exposure.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::session::Session;
use crate::diag::Diagnostic;
use crate::gpu::Gpu;
use crate::loaded::Loaded;
use crate::material::{Program, simplify};
use crate::scene::{Camera, DebugView, Geometry, LightKind, Object, Renderer, Scene};
use crate::shader::Library;

/// Pixels per side of a preview.
pub const SIZE: u32 = 128;
/// Samples per pixel of a path-traced preview.
pub const PATH_SPP: u32 = 16;

/// A rendered preview: the final (tonemapped) image.
#[derive(Debug, Clone)]
pub struct Preview {
    pub png: Vec<u8>,
    /// Samples per pixel (1 for the raster).
    pub samples: u32,
    /// The adaptive G-buffer's bytes per pixel of the definition the
    /// sphere wore, as the compile report's `budget` counts them.
    pub material_bytes: u32,
}

/// Which definitions a preview's sphere wears.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Materials {
    /// As the scene renders them: the raster the definitions simplified to
    /// the scene's `quality.material_bytes`, the path tracer the full ones
    /// (simplified too under `quality.path_simplified_materials`).
    AsScene,
    /// The full definitions, in both renderers.
    Full,
    /// The definitions simplified to this many bytes per pixel, in both.
    Budget(u32),
}

#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error("no material {index}: the scene has {count}")]
    NoSuchMaterial { index: usize, count: usize },
    /// A pipeline the preview needs never built; the diagnostics say why.
    #[error("the preview's pipelines did not build")]
    Pipelines(Vec<Diagnostic>),
}

/// What a preview is rendered from: the daemon's device and sources, and
/// the scene as installed.
pub struct Source<'a> {
    pub gpu: &'a Gpu,
    /// Which device `gpu` is (a new one after a loss starts a new session).
    pub device: u32,
    pub lib: &'a Library,
    pub loaded: &'a Loaded,
}

/// The preview scene of instance `material` of `scene`.
pub fn scene(scene: &Scene, material: usize, renderer: Renderer) -> Scene {
    let directional = |l: &&crate::scene::Light| matches!(l.kind, LightKind::Directional { .. });
    let mut s = Scene {
        width: SIZE,
        height: SIZE,
        // About 4.8 units away with 30° of view: the unit sphere fills
        // four fifths of the frame, seen slightly from above.
        camera: Camera { position: [0.0, 1.2, 4.65], target: [0.0, 0.0, 0.0], fov_deg: 30.0, near: 0.05, far: 20.0, ..Camera::default() },
        materials: scene.materials.clone(),
        objects: vec![Object {
            name: "preview".to_owned(),
            geometry: Geometry::Shape("sphere".to_owned()),
            material,
            gltf_materials: false,
            position: [0.0; 3],
            rotation_deg: [0.0; 3],
            scale: [1.0; 3],
        }],
        lights: scene.lights.iter().filter(directional).cloned().collect(),
        media: Vec::new(),
        environment: scene.environment.clone(),
        denoiser: None,
        post: scene.post.clone(),
        quality: scene.quality.clone(),
    };
    s.post.auto_exposure = false;
    s.post.debug_view = DebugView::None;
    s.quality.renderer = renderer;
    s.quality.path_spp = PATH_SPP;
    s
}

/// Renders previews on one session, kept between calls: only the
/// pipelines whose sources changed since the last preview are rebuilt.
pub struct Previewer {
    shader_root: PathBuf,
    session: Option<(u32, Session)>,
}

impl Previewer {
    pub fn new(shader_root: &Path) -> Self {
        Previewer { shader_root: shader_root.to_owned(), session: None }
    }

    /// Renders instance `material` of `source`'s scene wearing `materials`,
    /// waiting for it.
    pub fn render(
        &mut self,
        source: Source<'_>,
        material: usize,
        renderer: Renderer,
        materials: Materials,
    ) -> Result<Preview, PreviewError> {
        let scene_program = &source.loaded.materials;
        let count = scene_program.instances.len();
        if material >= count {
            return Err(PreviewError::NoSuchMaterial { index: material, count });
        }
        let quality = &source.loaded.scene.quality;
        let (budget, simplified) = match materials {
            Materials::AsScene => (quality.material_bytes, renderer == Renderer::Raster || quality.path_simplified_materials),
            Materials::Full => (quality.material_bytes, false),
            Materials::Budget(bytes) => (bytes, true),
        };
        let (program, bytes) = program(scene_program, budget);
        let instance = if simplified { count + material } else { material };
        // As the compile report counts them.
        let (before, after) = bytes[scene_program.instances[material].definition as usize];
        let material_bytes = if simplified { after } else { before };
        let mut lib = source.lib.clone();
        super::session::material_module(&mut lib, &self.shader_root, &program);
        let loaded = Loaded {
            scene: scene(&source.loaded.scene, instance, renderer),
            meshes: BTreeMap::new(),
            denoiser: None,
            materials: Arc::new(program),
            reports: Arc::default(),
            files: Vec::new(),
            warnings: Vec::new(),
        };
        let session = match &mut self.session {
            Some((device, session)) if *device == source.device => {
                let mut changed = changed_files(session.library(), &lib);
                session.apply_sources(lib);
                changed.extend(session.set_scene(&loaded));
                let stale = session.built_from(&changed);
                session.install_now(stale);
                session
            }
            slot => {
                let session = Session::new(source.gpu.clone(), &self.shader_root, lib, &loaded);
                &mut slot.insert((source.device, session)).1
            }
        };
        session.install_missing();
        let live = session.pipelines().live();
        if !session.wanted().iter().all(|k| live.contains_key(k)) {
            return Err(PreviewError::Pipelines(session.pipeline_diagnostics()));
        }
        let samples = if renderer == Renderer::Path { PATH_SPP } else { 1 };
        let final_name = session.graph().final_name();
        let mut png = Vec::new();
        for i in 1..=samples {
            let capture: BTreeSet<String> = final_name.iter().filter(|_| i == samples).cloned().collect();
            // No pass of the preview adapts over time (auto exposure is off).
            let pending = session.submit(Some(&capture), 0.0);
            let result = session.wait(pending);
            if let Some(c) = result.captures.iter().find(|c| Some(format!("{}/{}", c.pass, c.output)) == final_name) {
                png = c.to_png();
            }
        }
        Ok(Preview { png, samples, material_bytes })
    }
}

/// The preview's program for `budget`: the scene's full definitions and
/// instances, then one instance per scene instance (instance `count + i`
/// for instance `i`) wearing its definition simplified to `budget`, a new
/// definition only where simplification changed it. Both renderers
/// compile every definition as it stands (nothing left to simplify), so
/// one module serves the full and the budget previews of every material.
/// With it, each scene definition's bytes per pixel before and after.
pub fn program(scene: &Program, budget: u32) -> (Program, Vec<(u32, u32)>) {
    let mut out = Program { simplified: Vec::new(), path_simplified: false, ..scene.clone() };
    let mut at_budget = Vec::with_capacity(scene.definitions.len());
    let mut bytes = Vec::with_capacity(scene.definitions.len());
    for (k, d) in scene.definitions.iter().enumerate() {
        let s = simplify::simplify(d, budget);
        bytes.push((s.bytes_before, s.bytes_after));
        at_budget.push(if s.simplified() {
            out.definitions.push(s.def);
            (out.definitions.len() - 1) as u32
        } else {
            k as u32
        });
    }
    let copies: Vec<_> =
        scene.instances.iter().map(|i| crate::material::Instance { definition: at_budget[i.definition as usize], ..i.clone() }).collect();
    out.instances.extend(copies);
    (out, bytes)
}

/// The files whose text differs between two versions of the sources.
fn changed_files(old: &Library, new: &Library) -> BTreeSet<String> {
    let hashes = |lib: &Library| -> BTreeMap<String, blake3::Hash> { lib.files().map(|f| (f.display.clone(), f.hash)).collect() };
    let (old, new) = (hashes(old), hashes(new));
    let mut changed: BTreeSet<String> = new.iter().filter(|(d, t)| old.get(*d) != Some(t)).map(|(d, _)| d.clone()).collect();
    changed.extend(old.keys().filter(|d| !new.contains_key(*d)).cloned());
    changed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::layout;
    use crate::shader::library;

    const MAT: &str = "param tint: color = rgb(0.1, 0.6, 0.1)\nmaterial paint = slab { base_color: tint }\n";
    const SCENE: &str = "[output]\nwidth = 32\nheight = 32\n\n[[materials]]\nname = \"paint\"\nfile = \"paint.mat\"\n\n\
        [[objects]]\nshape = \"cube\"\nmaterial = \"paint\"\n\n[[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, -0.4]\nintensity = 3.0\n";

    fn centre(png: &[u8]) -> [u8; 3] {
        let img = image::load_from_memory(png).expect("a PNG").to_rgb8();
        assert_eq!(img.dimensions(), (SIZE, SIZE));
        img.get_pixel(SIZE / 2, SIZE / 2).0
    }

    /// The preview keeps what lights the sphere from afar (sky, sun) and
    /// leaves what sits in the scene (its objects, point lights, media,
    /// the denoiser) and what takes frames to settle (auto exposure).
    #[test]
    fn the_preview_scene_is_one_sphere_under_the_sky_and_the_sun() {
        let text = format!(
            "{SCENE}\n[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\n\n[environment]\ntop = [0.5, 0.6, 0.9]\n\n\
             [post]\nauto_exposure = true\nexposure_ev = 1.5\n\n[[media]]\nname = \"fog\"\nshapes = [{{ type = \"box\", center = [0.0, 0.0, 0.0], half_extents = [1.0, 1.0, 1.0] }}]\n\
             scattering = [0.5, 0.5, 0.5]\nabsorption = [0.1, 0.1, 0.1]\n\n[denoiser]\nmode = \"hdr\"\n"
        );
        let full = crate::scene::parse("scene.toml", &text).unwrap_or_else(|d| panic!("{d}"));
        assert_eq!((full.lights.len(), full.media.len(), full.denoiser.is_some()), (2, 1, true));
        let p = scene(&full, 0, Renderer::Path);
        assert_eq!(p.objects.len(), 1);
        assert_eq!((&p.objects[0].geometry, p.objects[0].material), (&Geometry::Shape("sphere".into()), 0));
        assert!(p.lights.len() == 1 && matches!(p.lights[0].kind, LightKind::Directional { .. }), "{:?}", p.lights);
        assert!(p.media.is_empty() && p.denoiser.is_none());
        assert_eq!(p.environment, full.environment);
        assert!(!p.post.auto_exposure && p.post.exposure_ev == 1.5);
        assert_eq!((p.quality.renderer, p.quality.path_spp, p.width, p.height), (Renderer::Path, PATH_SPP, SIZE, SIZE));
    }

    /// The preview's program holds the full definitions and, after them,
    /// those the budget simplified (only those): at 40 B the showcase's car
    /// paint (56 B), rust (48 B) and the glTF crate's wood (44 B) get a
    /// simplified copy that fits, its other materials wear their own definition either way; at 256 B
    /// nothing is added. One instance per scene instance and budget.
    #[test]
    fn the_preview_program_holds_the_full_and_the_budget_definitions() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/showcase.toml");
        let loaded = crate::loaded::load(&path).unwrap_or_else(|d| panic!("{d}"));
        let full = &loaded.materials;
        let (n, count) = (full.definitions.len(), full.instances.len());
        let (p, _) = program(full, 40);
        assert_eq!(p.definitions[..n], full.definitions[..]);
        assert_eq!(p.definitions.len(), n + 3, "the car paint, the rust and the crate's wood");
        assert!(p.simplified.is_empty() && !p.path_simplified, "both renderers compile the definitions as they stand");
        assert_eq!(p.instances.len(), 2 * count);
        for i in 0..count {
            let (whole, budget) = (&p.instances[i], &p.instances[count + i]);
            let name = &full.definitions[whole.definition as usize].name;
            assert_eq!((whole, &budget.values), (&full.instances[i], &whole.values), "{name}");
            let bytes = layout::bytes(&crate::material::analysed(&p.definitions[budget.definition as usize]).unwrap());
            assert!(bytes <= 40, "{name}: {bytes} B");
            let simplified = ["car_paint", "rust"].contains(&name.as_str()) || name.ends_with("::wood");
            assert_eq!(budget.definition as usize >= n, simplified, "{name}");
        }
        assert_eq!(program(full, 256).0.definitions.len(), n);
    }

    /// An edit to the material file is new generated code: the preview
    /// session rebuilds the pipelines built from it.
    #[test]
    fn a_preview_follows_an_edit_of_its_material() {
        let dir = tempfile::tempdir().unwrap();
        let (scene, mat) = (dir.path().join("scene.toml"), dir.path().join("paint.mat"));
        std::fs::write(&scene, SCENE).unwrap();
        std::fs::write(&mat, MAT).unwrap();
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let gpu = crate::gpu::testing::device();
        let mut previewer = Previewer::new(&root);
        let mut render = |loaded: &Loaded| {
            let mut lib = library::read_tree(&root).unwrap();
            super::super::session::material_module(&mut lib, &root, &loaded.materials);
            let source = Source { gpu: &gpu, device: 0, lib: &lib, loaded };
            centre(&previewer.render(source, 0, Renderer::Raster, Materials::AsScene).unwrap_or_else(|e| panic!("{e:?}")).png)
        };
        let [r, g, b] = render(&crate::loaded::load(&scene).unwrap());
        assert!(g > r + 20 && g > b + 20, "green: {:?}", [r, g, b]);
        std::fs::write(&mat, MAT.replace("base_color: tint", "base_color: rgb(0.1, 0.1, 0.7)")).unwrap();
        let [r, g, b] = render(&crate::loaded::load(&scene).unwrap());
        assert!(b > r + 20 && b > g + 20, "blue: {:?}", [r, g, b]);
    }
}
