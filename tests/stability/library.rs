//! The starter library (`scenes/materials/*.mat`) through the generated
//! `loupe::material` module, as the renderer compiles it (folded, pruned,
//! compensated): its directional albedo (the white furnace) and
//! `material_sample` against `material_pdf` (chi-square), on the device.
//!
//! Every definition of every library file goes into one module, so each
//! kernel is compiled once for the whole library (lavapipe takes seconds
//! per compile). The kernels always read instance 0: each case binds its
//! own two small buffers (its parameter values, and one instance header
//! naming the definition, compensation on as for any `.mat` material).
//!
//! The kernels read `input` as `sampling`'s do (`sampling::INPUT`), so
//! `sampling`'s quadrature, draw layout and chi-square fit serve them
//! unchanged.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::sampling::{self, Case, Density, Drawn};
use loupe::gpu::Gpu;
use loupe::gpu::testing::Kernel;
use loupe::material::back::{self, Bindings};
use loupe::material::tree::{Definition, Field, NodeKind, Type, Value};
use loupe::material::{Instance, Program, analysis};
use loupe::shader::SourceFile;
use wgpu::util::DeviceExt;

const PRELUDE: &str = r#"
#import loupe::material::{Surface, material_init_at, material_point, material_eval, material_pdf, material_sample}

// Instance 0 seen from v, its tangent along x (the views lie in the x-z
// plane): the direction an anisotropic lobe is stretched from.
fn surface(v: vec3<f32>) -> Surface {
    return material_init_at(0u, N, v, material_point(vec2(0.0), vec4(1.0, 0.0, 0.0, 1.0)));
}
"#;

/// Invocation i evaluates direction `input[2 + i].xyz`: (material_pdf,
/// material_eval).
const DENSITY: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let l = input[2u + id.x].xyz;
    let s = surface(view());
    output[id.x] = vec4(material_pdf(s, N, view(), l), material_eval(s, N, view(), l));
}
"#;

/// Invocation i draws with the uniform numbers `input[2 + i].xyz`:
/// (direction, pdf), (weight, 0), 0: `sampling::Drawn`, without the
/// pdf and eval of the direction recomputed (material_sample's weight is
/// material_eval / material_pdf as written; recomputing them would
/// double a kernel llvmpipe takes minutes to compile).
const SAMPLE: &str = r#"
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 3>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let v = view();
    let s = surface(v);
    let m = material_sample(s, N, v, input[2u + id.x].xyz);
    output[id.x] = array(vec4(m.l, m.pdf), vec4(m.weight, 0.0), vec4(0.0));
}
"#;

/// The library's kernels on the device both tests share: llvmpipe compiles
/// a kernel on its first dispatch, and over the material module that
/// takes minutes on two busy cores, so each is compiled once per run.
fn shared() -> &'static (Gpu, Library) {
    static SHARED: OnceLock<(Gpu, Library)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let gpu = loupe::gpu::testing::device();
        let library = Library::load(&gpu);
        (gpu, library)
    })
}

/// The library's definitions, compiled into one module, and its kernels.
pub struct Library {
    /// `file::material`, by definition id.
    pub names: Vec<String>,
    pub definitions: Vec<Definition>,
    density: Kernel,
    sample: Kernel,
}

/// A library material with parameter values: what one case binds.
pub struct Bound<'a> {
    pub name: &'a str,
    buffers: [wgpu::Buffer; 2],
    /// The narrowest GGX lobe's roughness (before a layer widens it): what
    /// the quadrature's and histogram's cells are sized from.
    pub roughness: f32,
}

impl Library {
    /// Every definition of `scenes/materials/*.mat`, analysed as the
    /// renderer's are.
    pub fn load(gpu: &Gpu) -> Library {
        let (mut names, mut definitions) = (Vec::new(), Vec::new());
        for path in files() {
            let loaded = loupe::material::front::load(&path).unwrap_or_else(|d| panic!("{}: {d:?}", path.display()));
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            // A textured material needs the texture array bound, which
            // these kernels do not have: `rust` is left out.
            for d in loaded.definitions.iter().filter(|d| d.params.iter().all(|p| p.ty != Type::Texture)) {
                let a = loupe::material::analysed(d).unwrap_or_else(|e| panic!("{}: {e:?}", d.name));
                assert!(a.def.energy_compensation, "{}: library materials are compensated", d.name);
                names.push(format!("{stem}::{}", d.name));
                definitions.push(a.def);
            }
        }
        let text = back::wgsl(&definitions, Bindings { group: 1, params: 0, instances: 1, textures: 2, sampler: 3 });
        let module = SourceFile::from_text(back::DISPLAY.into(), back::DISPLAY.into(), text.into());
        let kernel = |body: &str| {
            Kernel::with_modules(gpu, &format!("{}{PRELUDE}{body}", sampling::INPUT), "main", std::slice::from_ref(&module))
                .unwrap_or_else(|e| panic!("{e}"))
        };
        Library { density: kernel(DENSITY), sample: kernel(SAMPLE), names, definitions }
    }

    pub fn index(&self, name: &str) -> usize {
        self.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no library material {name}: {:?}", self.names))
    }

    /// Definition `index` at its defaults, with the parameters `set` names
    /// changed.
    pub fn bind(&self, gpu: &Gpu, index: usize, set: &[(&str, Value)]) -> Bound<'_> {
        let d = &self.definitions[index];
        let mut values: Vec<Value> = d.params.iter().map(|p| p.default).collect();
        for (name, value) in set {
            let i = d.params.iter().position(|p| p.name == *name).unwrap_or_else(|| panic!("{}: no param {name}", d.name));
            values[i] = *value;
        }
        let program = Program { instances: vec![Instance { definition: index as u32, values, compensated: true }], ..Program::default() };
        let (params, instances) = program.buffers();
        let storage = |bytes: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("library material"),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let roughness = narrowest(d, &program.instances[0].values);
        Bound {
            name: &self.names[index],
            buffers: [storage(bytemuck::cast_slice(&params)), storage(bytemuck::cast_slice(&instances))],
            roughness,
        }
    }

    /// (pdf, albedo) of a bound material seen at n·v = `cos_v`, over
    /// `cells` warped toward the mirror direction and sized for its
    /// narrowest lobe.
    pub fn density(&self, gpu: &Gpu, m: &Bound, cos_v: f64, cells: (usize, usize)) -> Density {
        let [a, b] = &m.buffers;
        sampling::quadrature_bound(gpu, &self.density, &case(m, cos_v), cells, &[a, b])
    }

    /// What `material_sample` draws from the uniform numbers `u`.
    pub fn draw(&self, gpu: &Gpu, m: &Bound, cos_v: f64, u: &[[f32; 3]]) -> Vec<Drawn> {
        let mut input = sampling::header(&case(m, cos_v)).to_vec();
        input.extend(u.iter().map(|u| [u[0], u[1], u[2], 0.0]));
        let [a, b] = &m.buffers;
        self.sample.run_bound(gpu, &input, u.len(), &[], &[a, b]).unwrap()
    }
}

/// The `sampling::Case` whose cells fit a bound material (its metallic is
/// not read by these kernels).
pub fn case(m: &Bound, cos_v: f64) -> Case {
    Case { cos_v, roughness: m.roughness, metallic: 0.0 }
}

/// The library's files, sorted.
fn files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "mat"))
        .collect();
    files.sort();
    files
}

/// The white furnace's parameters: every colour parameter white (base,
/// flake, specular and edge, fuzz, coat and emission colours), so the
/// material reflects all it can; emission stays at its default, which is
/// off in every library material (asserted by the caller through the
/// albedo: emission is not part of `material_eval`).
pub fn white(d: &Definition) -> Vec<(&str, Value)> {
    d.params.iter().filter(|p| p.ty == Type::Color).map(|p| (p.name.as_str(), Value::Vec3([1.0; 3]))).collect()
}

/// The smallest GGX roughness among the slabs' lobes (main and haze) at
/// these values; a lobe a layer widens is wider still, so the cells sized
/// from this resolve it too.
fn narrowest(d: &Definition, values: &[Value]) -> f32 {
    let mut least = 1.0f32;
    for node in &d.nodes {
        let NodeKind::Slab(slab) = &node.kind else { continue };
        let field = |f: Field| match slab.get(f).map(|e| analysis::eval(d, e, values)).unwrap_or(f.default()) {
            Value::Float(x) => x,
            Value::Vec3(c) => c[0],
            Value::Texture(_) => unreachable!("a texture is never a field's value"),
        };
        // An anisotropic lobe is narrowest across its direction:
        // α_b = (1 − a) α_t (brdf.wgsl's `alpha_aniso`), as a roughness.
        let a = field(Field::SpecularAnisotropy).clamp(0.0, 1.0);
        let across = (1.0 - a) * (2.0 / (1.0 + (1.0 - a) * (1.0 - a))).sqrt();
        least = least.min(field(Field::SpecularRoughness) * across.sqrt());
        if field(Field::HazeWeight) > 0.0 {
            least = least.min(field(Field::HazeRoughness));
        }
    }
    least.clamp(0.0, 1.0)
}

/// Views of the furnace: head-on to grazing.
const VIEWS: [f64; 4] = [1.0, 0.5, 0.1, 0.02];
/// The furnace's cells (cos θ × φ), a quarter of the chi-square's: the
/// albedo needs fewer than the histogram, and the library has 8 materials
/// × 2 colourings × 4 views to integrate.
const FURNACE_CELLS: (usize, usize) = (32, 64);
/// The library materials that lose no light when white: the metals. Their
/// one lobe (two for the hazy one) is GGX with Turquin's compensation, and
/// a metal has no diffuse part whose Fresnel weighting loses light. Every
/// other material has a dielectric part: its diffuse is weighted by
/// `(1 − f0)·t(n·l)·t(n·v)` (brdf.wgsl), which keeps less than the
/// specular leaves (a white dielectric keeps at most 0.988), or fuzz,
/// whose sheen is not energy-conserving downward.
const LOSSLESS: [&str; 3] = ["metal::rough_metal", "metal::polished_metal", "hazy_metal::hazy_metal"];
/// How far a lossless white material's albedo may sit from 1: the
/// compensation fit's 2e-3 and the quadrature's error (as `FURNACE`).
const WHITE: f64 = 5e-3;

/// The white furnace of every library material: each colour parameter
/// white (`white`), a lossless material's directional albedo is 1 within
/// `WHITE` and any other's at most 1 + `ALBEDO_SLACK`, at every view; and
/// at the library's own default colours, no material's albedo exceeds 1.
#[test]
fn every_library_material_reflects_at_most_the_light_it_gets() {
    let start = std::time::Instant::now();
    let (gpu, lib) = shared();
    let mut failures = Vec::new();
    for index in 0..lib.names.len() {
        let d = &lib.definitions[index];
        let lossless = LOSSLESS.contains(&lib.names[index].as_str());
        for (colours, set) in [("white", white(d)), ("default", vec![])] {
            let m = lib.bind(gpu, index, &set);
            let mut seen = Vec::new();
            for cos_v in VIEWS {
                let albedo = lib.density(gpu, &m, cos_v, FURNACE_CELLS).albedo;
                seen.push(format!("{:.5}", albedo.iter().fold(0.0f64, |a, b| a.max(*b))));
                for (c, a) in albedo.into_iter().enumerate() {
                    let what = format!("{}, {colours} colours, n·v {cos_v}, channel {c}: albedo", m.name);
                    if lossless && colours == "white" {
                        failures.extend(crate::at_most(&format!("{what} {a} against 1"), (a - 1.0).abs(), WHITE).err());
                    } else {
                        failures.extend(crate::at_most(&what, a, 1.0 + crate::ALBEDO_SLACK).err());
                    }
                }
            }
            eprintln!(
                "{} ({colours}, lobes from roughness {}): largest channel's albedo at n·v {VIEWS:?}: {} ({:.1} s in)",
                m.name,
                m.roughness,
                seen.join(", "),
                start.elapsed().as_secs_f64()
            );
        }
    }
    crate::all_pass(&failures);
}

/// Parameter values by name, over a definition's defaults.
type Params = Vec<(&'static str, Value)>;

/// Samples per chi-square case.
const SAMPLES: usize = 1 << 18;

/// The chi-square cases: a layered material (car paint: a clear coat over
/// a mix of pigment and flakes), a mixed one (OpenPBR with its coat on
/// half the surface: a mix of the base and the base under a coat), a hazy
/// one (two GGX lobes) and a fuzz one (fabric: sheen over a rough
/// dielectric) and an anisotropic one (brushed metal at anisotropy 0.6,
/// its direction an eighth of a turn off the plane of incidence; at 1 its
/// lobe at roughness 1 spans α 1.41 one way and 0.002 the other, which
/// cells sized for either cannot resolve), each
/// with its roughness parameter swept from below the module's clamp
/// (0.045) to 1. (material, its parameters, the one swept.)
fn chi2_materials() -> [(&'static str, Params, &'static str); 5] {
    [
        ("car_paint::car_paint", vec![], "coat_roughness"),
        ("openpbr::openpbr", vec![("coat_weight", Value::Float(0.5))], "coat_roughness"),
        ("hazy_metal::hazy_metal", vec![], "specular_roughness"),
        ("fabric::fabric", vec![], "fuzz_roughness"),
        ("brushed_metal::brushed_metal", vec![("anisotropy", Value::Float(0.6)), ("rotation", Value::Float(0.125))], "specular_roughness"),
    ]
}

const CHI2_VIEWS: [f64; 2] = [1.0, 0.001];
/// The ends of the range: below the module's clamp (0.045), and 1. (0.3
/// passed too, but each case costs about a minute on two busy cores.)
const CHI2_ROUGHNESS: [f32; 2] = [0.001, 1.0];
/// The histogram's cells (cos θ × φ): 2^18 samples put 128 in a cell on
/// average, and its 2,048 cells are integrated 4 times faster than the
/// `sampling` cases' 8,192.
const CHI2_CELLS: (usize, usize) = (32, 64);

/// `material_sample` draws from `material_pdf` (chi-square at the suite's
/// significance, Šidák-corrected over the cases); each weight is at most
/// `MAX_WEIGHT`; the mean
/// weight (an importance-sampled albedo) equals the quadrature's within 4
/// standard errors + `GRAZING`: what measures the quadrature's error on
/// materials of several lobes.
#[test]
fn library_material_sample_draws_from_material_pdf() {
    let start = std::time::Instant::now();
    let (gpu, lib) = shared();
    let cases = chi2_materials().len() * CHI2_VIEWS.len() * CHI2_ROUGHNESS.len();
    let threshold = crate::chi2::sidak(crate::SIGNIFICANCE, cases);
    let u = loupe::testing::uniforms(SAMPLES);
    let mut failures = Vec::new();
    let (mut worst_p, mut largest_weight, mut worst_albedo) = (1.0f64, 0.0f64, 0.0f64);
    for (name, set, swept) in chi2_materials() {
        for roughness in CHI2_ROUGHNESS {
            let mut set = set.clone();
            set.push((swept, Value::Float(roughness)));
            let m = lib.bind(gpu, lib.index(name), &set);
            for cos_v in CHI2_VIEWS {
                let what = format!("{name}, {swept} {roughness}, n·v {cos_v}");
                let density = lib.density(gpu, &m, cos_v, CHI2_CELLS);
                let drawn = lib.draw(gpu, &m, cos_v, &u);
                let bad = drawn.iter().filter(|d| d.iter().flatten().any(|x| !x.is_finite())).count();
                failures.extend((bad > 0).then(|| format!("{what}: {bad} samples hold a NaN or Inf")));
                let fit = sampling::fit_in(&case(&m, cos_v), CHI2_CELLS, &drawn, &density);
                let largest = drawn.iter().flat_map(|d| d[1][..3].iter()).fold(0.0f64, |a, w| a.max(f64::from(*w)));
                let mean = sampling::mean_weight(&drawn);
                eprintln!(
                    "{what}: chi² {:.0} over {} dof, p = {:.3e}; largest weight {largest:.3}; albedo {:.5} (sampled {:.5} ± {:.1e})",
                    fit.statistic, fit.dof, fit.p_value, density.albedo[0], mean[0].0, mean[0].1
                );
                if fit.p_value < threshold {
                    failures
                        .push(format!("{what}: chi-square p = {:e} < {threshold:e}: the samples do not follow material_pdf", fit.p_value));
                }
                failures.extend(crate::at_most(&format!("{what}: largest weight"), largest, crate::MAX_WEIGHT).err());
                for (c, (a, (s, se))) in density.albedo.into_iter().zip(mean).enumerate() {
                    let off = (s - a).abs();
                    failures.extend(
                        crate::at_most(
                            &format!("{what}, channel {c}: sampled albedo {s} against quadrature {a}"),
                            off,
                            4.0 * se + crate::GRAZING,
                        )
                        .err(),
                    );
                    worst_albedo = worst_albedo.max(off);
                }
                worst_p = worst_p.min(fit.p_value);
                largest_weight = largest_weight.max(largest);
            }
        }
    }
    eprintln!(
        "{cases} library cases in {:.0} s: worst p {worst_p:.3e} (threshold {threshold:.3e}), largest weight {largest_weight:.3}, sampled albedo off the quadrature by at most {worst_albedo:.1e}",
        start.elapsed().as_secs_f64()
    );
    crate::all_pass(&failures);
}
