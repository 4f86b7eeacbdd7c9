//! The back end on the device: the scene file's shorthand, compiled through
//! the material module, evaluates, samples and weighs exactly as
//! `brdf.wgsl` does (what keeps the old scenes' images), and the module's
//! loops over several closures add up as the operators say.

use super::back::{self, Bindings};
use super::tree::{Definition, Expr, ExprId, ExprKind, Field, Node, NodeId, NodeKind, Slab, Type, Value};
use super::{Instance, Program, shorthand};
use crate::diag::Location;
use crate::gpu::testing::{Kernel, device};
use crate::shader::SourceFile;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    /// View direction (n = +z); w: the instance.
    v: [f32; 4],
    /// Light direction.
    l: [f32; 4],
    /// Three uniform numbers for the samplers.
    u: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Out {
    /// The material's eval (xyz) and pdf (w) of l.
    material: [f32; 4],
    /// brdf.wgsl's, for the instance's shorthand values.
    brdf: [f32; 4],
    /// The material's sample: direction and pdf, then weight.
    sample: [f32; 4],
    sample_weight: [f32; 4],
    /// brdf_sample's.
    brdf_sample: [f32; 4],
    brdf_sample_weight: [f32; 4],
}

const SHADER: &str = r#"
#import loupe::brdf::{brdf_cos, brdf_pdf, brdf_sample}
#import loupe::material::{material_init, material_eval, material_pdf, material_sample, material_params, material_instances}

struct Query { v: vec4<f32>, l: vec4<f32>, u: vec4<f32> }
struct Out { material: vec4<f32>, brdf: vec4<f32>, sample: vec4<f32>, sample_weight: vec4<f32>, brdf_sample: vec4<f32>, brdf_sample_weight: vec4<f32> }

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<Out>;

const N = vec3(0.0, 0.0, 1.0);

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    let instance = u32(q.v.w);
    let s = material_init(instance, N, q.v.xyz);
    // The shorthand's parameters, as the old materials buffer held them.
    let slot = material_instances[instance].y;
    let base = material_params[slot].xyz;
    let metallic = material_params[slot + 1u].x;
    let roughness = material_params[slot + 2u].x;
    let ms = material_sample(s, N, q.v.xyz, q.u.xyz);
    let bs = brdf_sample(N, q.v.xyz, q.u.xyz, base, metallic, roughness);
    output[id.x] = Out(
        vec4(material_eval(s, N, q.v.xyz, q.l.xyz), material_pdf(s, N, q.v.xyz, q.l.xyz)),
        vec4(brdf_cos(N, q.v.xyz, q.l.xyz, base, metallic, roughness), brdf_pdf(N, q.v.xyz, q.l.xyz, base, metallic, roughness)),
        vec4(ms.l, ms.pdf), vec4(ms.weight, 0.0),
        vec4(bs.l, bs.pdf), vec4(bs.weight, 0.0),
    );
}
"#;

/// The program's module, bound at group 1 where the test kernel binds
/// buffers, and its two buffers.
fn module(program: &Program) -> (SourceFile, [wgpu::Buffer; 2]) {
    let text = back::wgsl(&program.definitions, Bindings { group: 1, params: 0, instances: 1, textures: 2, sampler: 3 });
    let file = SourceFile::from_text(back::DISPLAY.into(), back::DISPLAY.into(), text.into());
    let (params, instances) = program.buffers();
    (file, [storage(bytemuck::cast_slice(&params)), storage(bytemuck::cast_slice(&instances))])
}

fn storage(bytes: &[u8]) -> wgpu::Buffer {
    let gpu = shared();
    wgpu::util::DeviceExt::create_buffer_init(
        &gpu.device,
        &wgpu::util::BufferInitDescriptor { label: Some("material test"), contents: bytes, usage: wgpu::BufferUsages::STORAGE },
    )
}

fn shared() -> &'static crate::gpu::Gpu {
    static GPU: std::sync::OnceLock<crate::gpu::Gpu> = std::sync::OnceLock::new();
    GPU.get_or_init(device)
}

fn at() -> Location {
    Location::file_start("test.mat")
}

/// Shorthand instances over the corners of their parameters' ranges.
fn shorthand_program() -> Program {
    let mut instances = Vec::new();
    for base in [[0.0, 0.0, 0.0], [0.9, 0.5, 0.1], [1.0, 1.0, 1.0]] {
        for metallic in [0.0, 0.3, 1.0] {
            for roughness in [0.0, 0.05, 0.4, 1.0] {
                instances.push(Instance {
                    definition: 0,
                    values: vec![Value::Vec3(base), Value::Float(metallic), Value::Float(roughness)],
                    compensated: false,
                });
            }
        }
    }
    Program { definitions: vec![shorthand(at())], instances, ..Program::default() }
}

fn queries(instances: usize) -> Vec<Query> {
    let dirs = |t: f32, p: f32| [t.sin() * p.cos(), t.sin() * p.sin(), t.cos(), 0.0];
    let mut out = Vec::new();
    for i in 0..instances {
        for (k, theta_v) in [0.0f32, 0.6, 1.2, 1.55].into_iter().enumerate() {
            for (j, theta_l) in [0.1f32, 0.7, 1.3, 1.6].into_iter().enumerate() {
                let mut v = dirs(theta_v, 0.3);
                v[3] = i as f32;
                let u = [(k * 4 + j) as f32 / 16.0 + 0.01, 0.37 + 0.03 * j as f32, 0.71 - 0.05 * k as f32, 0.0];
                out.push(Query { v, l: dirs(theta_l, 2.0), u });
            }
        }
    }
    out
}

#[test]
fn the_shorthand_is_brdf_wgsl_to_the_bit() {
    let program = shorthand_program();
    let (file, [params, instances]) = module(&program);
    let gpu = shared();
    let kernel = Kernel::with_modules(gpu, SHADER, "main", &[file]).unwrap();
    let q = queries(program.instances.len());
    let out: Vec<Out> = kernel.run_bound(gpu, &q, q.len(), &[], &[&params, &instances]).unwrap();
    let bits = |a: [f32; 4]| a.map(f32::to_bits);
    for (q, o) in q.iter().zip(&out) {
        let what = format!("{:?}: {:?}", q, program.instances[q.v[3] as usize].values);
        assert_eq!(bits(o.material), bits(o.brdf), "eval and pdf of {what}");
        assert_eq!(bits(o.sample), bits(o.brdf_sample), "sample of {what}");
        assert_eq!(bits(o.sample_weight), bits(o.brdf_sample_weight), "sample weight of {what}");
    }
}

/// A definition of one operator over two plain slabs of the given
/// roughness and colour.
fn two_slabs(op: impl FnOnce(NodeId, NodeId, ExprId) -> NodeKind, weight: f32) -> Definition {
    let c = |v: Value, ty| Expr { kind: ExprKind::Const(v), ty, location: at() };
    let exprs = vec![
        c(Value::Vec3([0.9, 0.2, 0.1]), Type::Color),
        c(Value::Float(0.3), Type::Float),
        c(Value::Vec3([0.1, 0.3, 0.8]), Type::Color),
        c(Value::Float(0.8), Type::Float),
        c(Value::Float(weight), Type::Float),
    ];
    let slab = |color: u32, rough: u32| Node {
        kind: NodeKind::Slab(Slab { fields: vec![(Field::BaseColor, ExprId(color)), (Field::SpecularRoughness, ExprId(rough))] }),
        location: at(),
    };
    let root = Node { kind: op(NodeId(0), NodeId(1), ExprId(4)), location: at() };
    Definition {
        name: "two".into(),
        location: at(),
        params: vec![],
        nodes: vec![slab(0, 1), slab(2, 3), root],
        exprs,
        root: NodeId(2),
        energy_compensation: false,
    }
}

#[test]
fn a_mix_evaluates_as_its_weights_say() {
    // mix(a, b, 0.25) = 0.75 a + 0.25 b, against each slab alone.
    let mix = two_slabs(|a, b, weight| NodeKind::Mix { a, b, weight }, 0.25);
    let only = |mix: &Definition, keep: u32| {
        let mut d = mix.clone();
        d.root = NodeId(keep);
        d.nodes.truncate(2);
        d
    };
    let program = Program {
        definitions: vec![only(&mix, 0), only(&mix, 1), mix],
        instances: (0..3).map(|definition| Instance { definition, values: vec![], compensated: false }).collect(),
        ..Program::default()
    };
    let (file, [params, instances]) = module(&program);
    let gpu = shared();
    let kernel = Kernel::with_modules(gpu, SHADER, "main", &[file]).unwrap();
    let per = queries(1);
    let q: Vec<Query> = (0..3).flat_map(|i| per.iter().map(move |q| Query { v: [q.v[0], q.v[1], q.v[2], i as f32], ..*q })).collect();
    let out: Vec<Out> = kernel.run_bound(gpu, &q, q.len(), &[], &[&params, &instances]).unwrap();
    let n = per.len();
    for k in 0..n {
        let (a, b, m) = (out[k].material, out[n + k].material, out[2 * n + k].material);
        for c in 0..3 {
            let want = 0.75 * a[c] + 0.25 * b[c];
            assert!((m[c] - want).abs() <= 1e-5 * want.abs().max(1.0), "channel {c} of {:?}: {} against {want}", per[k], m[c]);
        }
    }
}

#[test]
fn a_program_without_materials_links() {
    // Media alone: the module still composes, and a surface has no closures.
    let (file, [params, instances]) = module(&Program::default());
    let gpu = shared();
    let kernel = Kernel::with_modules(gpu, SHADER, "main", &[file]).unwrap();
    let q = queries(1);
    let out: Vec<Out> = kernel.run_bound(gpu, &q, q.len(), &[], &[&params, &instances]).unwrap();
    assert!(out.iter().all(|o| o.material == [0.0; 4]), "no closures reflect nothing");
}

/// The generated WGSL of each file of the starter library, as the renderer
/// binds it, against `tests/golden/materials/generated/FILE.wgsl`;
/// `LOUPE_BLESS=1` rewrites them.
#[test]
fn the_starter_library_generates_its_golden_wgsl() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let golden = root.join("tests/golden/materials/generated");
    let bless = std::env::var_os("LOUPE_BLESS").is_some();
    let mut files: Vec<_> = std::fs::read_dir(root.join("scenes/materials"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mat"))
        .collect();
    files.sort();
    assert!(files.len() >= 7, "{files:?}");
    for path in files {
        let loaded = super::front::load(&path).unwrap_or_else(|d| panic!("{d:?}"));
        let definitions: Vec<Definition> = loaded.definitions.iter().map(|d| super::analysed(d).unwrap().def).collect();
        // (Locations in the header are relative to the crate's directory,
        // where cargo runs its tests.)
        let text = back::wgsl(&definitions, Bindings::RENDERER);
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let expected = golden.join(format!("{stem}.wgsl"));
        if bless {
            std::fs::create_dir_all(&golden).unwrap();
            std::fs::write(&expected, &text).unwrap();
            continue;
        }
        let want = std::fs::read_to_string(&expected).unwrap_or_else(|e| panic!("{}: {e} (LOUPE_BLESS=1 writes it)", expected.display()));
        assert!(
            want == text,
            "{stem}: the generated WGSL changed; LOUPE_BLESS=1 cargo test -p loupe --lib material:: rewrites {}",
            expected.display()
        );
    }
}

/// The car paint (a coat over a mix) simplified to the smallest budget:
/// one slab, its flag set (`tests/golden/materials/generated/car_paint_24.wgsl`).
#[test]
fn a_simplified_library_material_generates_its_golden_wgsl() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let loaded = super::front::load(&root.join("scenes/materials/car_paint.mat")).unwrap_or_else(|d| panic!("{d:?}"));
    let s = super::simplify::simplify(&super::analysed(&loaded.definitions[0]).unwrap().def, super::layout::MIN_BYTES);
    let text = back::module(std::slice::from_ref(&s.def), Bindings::RENDERER, back::IMPORT_PATH, &[s.simplified()]);
    let expected = root.join("tests/golden/materials/generated/car_paint_24.wgsl");
    if std::env::var_os("LOUPE_BLESS").is_some() {
        std::fs::write(&expected, &text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&expected).unwrap_or_else(|e| panic!("{}: {e} (LOUPE_BLESS=1 writes it)", expected.display()));
    assert!(want == text, "the simplified car paint's WGSL changed; LOUPE_BLESS=1 cargo test -p loupe --lib material:: rewrites it");
}

/// `mean_free_path: transmittance_to_mfp(C, d)` keeps what a transmission
/// colour of C^(1/d) per unit did: through a layer's top (absorption) and
/// through a thin wall (transmission), the same evaluation either way.
#[test]
fn a_mean_free_path_keeps_what_the_transmission_colour_kept() {
    let (kept, d) = ([0.3f32, 0.6, 0.9], 2.5f32);
    let definition = |path: bool| {
        let mut b = super::build::Build::new("medium");
        let medium = if path {
            let (colour, distance) = (b.rgb(kept), b.float(d));
            (Field::MeanFreePath, b.call(super::tree::Builtin::TransmittanceToMfp, &[colour, distance]))
        } else {
            (Field::TransmissionColor, b.rgb(kept.map(|k| k.powf(1.0 / d))))
        };
        let (thick, one) = (b.float(0.4), b.float(1.0));
        // A coat 0.4 thick over a plain slab, beside a thin wall.
        let coat = b.slab(&[medium, (Field::Thickness, thick)]);
        let base = b.slab(&[]);
        let layer = b.layer(coat, base);
        let wall = b.slab(&[medium, (Field::TransmissionWeight, one), (Field::ThinWalled, one)]);
        let root = b.add(layer, wall);
        b.finish(root)
    };
    let program = Program {
        definitions: vec![definition(false), definition(true)],
        instances: (0..2).map(|definition| Instance { definition, values: vec![], compensated: false }).collect(),
        ..Program::default()
    };
    let (file, [params, instances]) = module(&program);
    let gpu = shared();
    let kernel = Kernel::with_modules(gpu, SHADER, "main", &[file]).unwrap();
    // Light from above and, through the wall, from below.
    let mut per = queries(1);
    per.extend(queries(1).into_iter().map(|q| Query { l: [q.l[0], q.l[1], -q.l[2], 0.0], ..q }));
    let q: Vec<Query> = (0..2).flat_map(|i| per.iter().map(move |q| Query { v: [q.v[0], q.v[1], q.v[2], i as f32], ..*q })).collect();
    let out: Vec<Out> = kernel.run_bound(gpu, &q, q.len(), &[], &[&params, &instances]).unwrap();
    let n = per.len();
    let below = (n / 2..n).filter(|&k| out[k].material[..3].iter().any(|x| *x > 0.0)).count();
    assert!(below > 0, "the wall lets light through from below");
    for k in 0..n {
        let (colour, path) = (out[k].material, out[n + k].material);
        for c in 0..3 {
            let tolerance = 1e-5 * colour[c].abs().max(1e-3);
            assert!((path[c] - colour[c]).abs() <= tolerance, "channel {c} of {:?}: {} against {}", per[k], path[c], colour[c]);
        }
    }
}

const ALBEDO: &str = r#"
#import loupe::material::{material_init, material_sample}

@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

const N = vec3(0.0, 0.0, 1.0);
const SIDE = 32u;

// The directional albedo toward v (x: the view's angle from n, y: the
// instance): the mean sample weight over a stratified grid of u.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    let v = vec3(sin(q.x), 0.0, cos(q.x));
    let s = material_init(u32(q.y), N, v);
    var sum = vec3(0.0);
    for (var i = 0u; i < SIDE; i++) {
        for (var j = 0u; j < SIDE; j++) {
            let u = vec3((f32(i) + 0.5) / f32(SIDE), (f32(j) + 0.5) / f32(SIDE), fract(f32(i * SIDE + j) * 0.6180339 + 0.1));
            let b = material_sample(s, N, v, u);
            if b.pdf > 0.0 && all(b.weight == b.weight) {
                sum += b.weight;
            }
        }
    }
    output[id.x] = vec4(sum / f32(SIDE * SIDE), 0.0);
}
"#;

/// The library's untextured materials at the smallest budget
/// (`layout::MIN_BYTES`, where every one is a single slab), against the
/// full ones: the directional albedo of the simplified stays ≤ 1 and
/// within each material's documented distance (docs/materials.md "Budget
/// and simplification") of the full one, at four views.
#[test]
fn a_simplified_library_material_keeps_its_albedo_near_the_full_one() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials");
    let mut files: Vec<_> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "mat")).collect();
    files.sort();
    let full: Vec<Definition> = files
        .iter()
        .flat_map(|p| super::front::load(p).unwrap_or_else(|d| panic!("{d:?}")).definitions)
        .map(|d| super::analysed(&d).unwrap().def)
        .filter(|d| !d.params.iter().any(|p| p.ty == Type::Texture))
        .map(|d| (super::simplify::simplify(&d, super::layout::MIN_BYTES), d))
        .filter(|(s, _)| s.simplified())
        .map(|(_, d)| d)
        .collect();
    let simplified: Vec<Definition> = full.iter().map(|d| super::simplify::simplify(d, super::layout::MIN_BYTES).def).collect();
    let definitions: Vec<Definition> = full.iter().chain(&simplified).cloned().collect();
    let instances = definitions
        .iter()
        .enumerate()
        .map(|(i, d)| Instance {
            definition: i as u32,
            values: d.params.iter().map(|p| p.default).collect(),
            compensated: d.energy_compensation,
        })
        .collect();
    let program = Program { definitions, instances, ..Program::default() };
    let (file, [params, instances]) = module(&program);
    let gpu = shared();
    let kernel = Kernel::with_modules(gpu, ALBEDO, "main", &[file]).unwrap();
    const VIEWS: [f32; 4] = [0.0, 0.6, 1.2, 1.5];
    let q: Vec<[f32; 4]> = (0..program.instances.len()).flat_map(|i| VIEWS.map(|theta| [theta, i as f32, 0.0, 0.0])).collect();
    let out: Vec<[f32; 4]> = kernel.run_bound(gpu, &q, q.len(), &[], &[&params, &instances]).unwrap();
    let luminance = |c: [f32; 4]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    // The largest luminance difference over the views, as measured (with
    // room for another device's rounding); docs/materials.md quotes these.
    let bound = |name: &str| match name {
        "brushed_metal" | "openpbr" => 0.01,
        "hazy_metal" => 0.02,
        "polished_metal" => 0.12,
        "skin" => 0.16,
        "thin_glass" => 0.2,
        "solid_glass" => 0.25,
        "fabric" => 0.34,
        "anodized_metal" => 0.36,
        "car_paint" => 0.39,
        other => panic!("no documented distance for {other}"),
    };
    let mut report = Vec::new();
    for (k, d) in full.iter().enumerate() {
        let row = |i: usize| &out[i * VIEWS.len()..(i + 1) * VIEWS.len()];
        let (f, s) = (row(k), row(k + full.len()));
        let worst = s.iter().flat_map(|a| a[..3].iter().copied()).fold(0.0f32, f32::max);
        let distance = f.iter().zip(s).map(|(a, b)| (luminance(*a) - luminance(*b)).abs()).fold(0.0f32, f32::max);
        report.push((d.name.clone(), distance, worst, format!("{f:?} against {s:?}")));
    }
    eprintln!("albedo distance at {} B: {report:#?}", super::layout::MIN_BYTES);
    for (name, distance, worst, values) in report {
        assert!(worst <= 1.02, "{name}: the simplified albedo reaches {worst}: {values}");
        assert!(distance <= bound(&name), "{name}: {distance} from the full albedo: {values}");
    }
}
