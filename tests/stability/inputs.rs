//! Inputs that break renderers, through brdf.wgsl's functions on the
//! device: zero-length and NaN normals, normals along the tangent frame's
//! helper axis (±z for `basis`) and next to it, back-facing and grazing
//! views, random numbers exactly 0 and 1 − 2⁻²⁴ (the largest
//! `random_f32` makes), and roughness 0.
//!
//! The bounds:
//! - every output of the BRDF's functions is finite, always, and
//!   `basis`'s for any unit normal;
//! - `basis(n)` of a unit normal is orthonormal with n as its third
//!   column, within `FRAME`;
//! - a zero or NaN normal reflects nothing: brdf_cos 0, brdf_pdf 0, and
//!   the sample has pdf 0 (no direction);
//! - a sample with pdf > 0 has a unit direction (within 1e-5) above the
//!   surface, and a weight in [0, `crate::MAX_WEIGHT`].

use loupe::gpu::testing::Kernel;

/// Invocation i: `basis` of n (three columns), brdf_cos of (n, v, l) with
/// brdf_pdf in w, and a sample with u: (l, pdf), (weight, 0).
const SHADER: &str = r#"
#import loupe::brdf::{basis, brdf_cos, brdf_pdf, brdf_sample}

// n; v, w: roughness; l, w: metallic; u.
struct Query { n: vec4<f32>, v: vec4<f32>, l: vec4<f32>, u: vec4<f32> }

@group(0) @binding(0) var<storage, read> input: array<Query>;
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 6>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let q = input[id.x];
    let n = q.n.xyz;
    let frame = basis(n);
    let base = vec3(1.0);
    let f = brdf_cos(n, q.v.xyz, q.l.xyz, base, q.l.w, q.v.w);
    let pdf = brdf_pdf(n, q.v.xyz, q.l.xyz, base, q.l.w, q.v.w);
    let s = brdf_sample(n, q.v.xyz, q.u.xyz, base, q.l.w, q.v.w);
    output[id.x] = array(vec4(frame[0], 0.0), vec4(frame[1], 0.0), vec4(frame[2], 0.0), vec4(f, pdf), vec4(s.l, s.pdf), vec4(s.weight, 0.0));
}
"#;

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    n: [f32; 4],
    v: [f32; 4],
    l: [f32; 4],
    u: [f32; 4],
}

/// How far `basis`'s columns may be from orthonormal: a few f32 roundings.
const FRAME: f64 = 1e-6;

type V3 = [f64; 3];

fn unit(v: V3) -> V3 {
    let len = dot(v, v).sqrt();
    v.map(|x| x / len)
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Unit normals: the axes (±z is `basis`'s helper axis, where its
/// branchless form switches sign), next to ±z by one f32 step and by
/// 1e-4, and a few in general position.
fn unit_normals() -> Vec<V3> {
    let step = f64::from(f32::EPSILON);
    let mut out = vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
    for z in [1.0, -1.0] {
        for e in [step, 1e-4, -step, -1e-4] {
            out.push(unit([e, 0.0, z]));
            out.push(unit([0.0, e, z]));
            out.push(unit([e, e, z]));
        }
    }
    out.extend([[0.3, -0.5, 0.8], [-0.7, 0.1, -0.2], [0.0, 0.6, -0.8]].map(unit));
    out
}

/// Views and lights about normal `n`: along it, 45°, grazing (n·v = 0
/// and 1e-6) and below it (back-facing), in a tangent direction `t`.
fn directions(n: V3) -> Vec<V3> {
    let helper = if n[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let t = unit(cross(n, helper));
    let at = |c: f64| {
        let s = (1.0 - c * c).sqrt();
        [0, 1, 2].map(|k| c * n[k] + s * t[k])
    };
    [1.0, 0.7, 1e-6, 0.0, -0.3, -1.0].into_iter().map(at).collect()
}

fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// The extremes of a uniform number, and the middle.
const U: [f32; 3] = [0.0, 0.5, 1.0 - 1.0 / 16_777_216.0];

fn queries(normals: &[[f32; 3]], views: impl Fn(usize) -> Vec<V3>) -> Vec<Query> {
    let mut out = Vec::new();
    for (i, n) in normals.iter().enumerate() {
        let dirs = views(i);
        for v in &dirs {
            for l in &dirs {
                for (roughness, metallic) in [(0.0, 0.0), (0.045, 1.0), (1.0, 0.0)] {
                    for ux in U {
                        for uy in U {
                            for uz in U {
                                let f = |d: &V3, w: f32| [d[0] as f32, d[1] as f32, d[2] as f32, w];
                                out.push(Query { n: [n[0], n[1], n[2], 0.0], v: f(v, roughness), l: f(l, metallic), u: [ux, uy, uz, 0.0] });
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// Checks one result against the bounds; `degenerate` when n is zero or
/// NaN. Returns what failed.
fn check(q: &Query, o: &[[f32; 4]; 6], degenerate: bool) -> Vec<String> {
    let mut failures = Vec::new();
    let what = format!("n {:?}, v {:?}, l {:?}, u {:?}", q.n, q.v, q.l, q.u);
    // `basis` is for unit normals (its callers normalize); the BRDF's
    // functions take whatever normal comes.
    let checked = if degenerate { &o[3..] } else { &o[..] };
    if checked.iter().flatten().any(|x| !x.is_finite()) {
        return vec![format!("{what}: a NaN or Inf in {o:?}")];
    }
    let g = |x: [f32; 4]| [x[0], x[1], x[2]].map(f64::from);
    if degenerate {
        let reflected = o[3].iter().any(|x| *x != 0.0) || o[4][3] != 0.0 || o[5].iter().any(|x| *x != 0.0);
        if reflected {
            failures.push(format!(
                "{what}: a degenerate normal reflects light: brdf_cos, pdf {:?}, sample {:?}, weight {:?}",
                o[3], o[4], o[5]
            ));
        }
        return failures;
    }
    let n = g(q.n);
    let columns = [g(o[0]), g(o[1]), g(o[2])];
    let mut frame_error = (0..3).map(|k| (columns[2][k] - n[k]).abs()).fold(0.0, f64::max);
    for i in 0..3 {
        for j in 0..3 {
            frame_error = frame_error.max((dot(columns[i], columns[j]) - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    failures.extend(crate::at_most(&format!("{what}: basis off orthonormal"), frame_error, FRAME).err());
    let (l, pdf, weight) = (g(o[4]), f64::from(o[4][3]), g(o[5]));
    if pdf < 0.0 || o[3][3] < 0.0 {
        failures.push(format!("{what}: a negative pdf: {pdf}, {}", o[3][3]));
    }
    if pdf > 0.0 {
        failures.extend(crate::at_most(&format!("{what}: |l| - 1"), (dot(l, l).sqrt() - 1.0).abs(), 1e-5).err());
        if dot(l, n) <= 0.0 {
            failures.push(format!("{what}: a sample below the surface, n·l = {}", dot(l, n)));
        }
        for w in weight {
            failures.extend(crate::at_most(&format!("{what}: weight"), w, crate::MAX_WEIGHT).err());
            failures.extend(crate::at_most(&format!("{what}: negative weight"), -w, 0.0).err());
        }
    }
    failures
}

/// Runs every query and returns the failures and how many ran.
pub fn run(gpu: &loupe::gpu::Gpu) -> (Vec<String>, usize) {
    let kernel = Kernel::new(gpu, SHADER, "main").unwrap_or_else(|e| panic!("{e}"));
    let normals: Vec<V3> = unit_normals();
    let unit_f32: Vec<[f32; 3]> = normals.iter().map(|n| n.map(|x| x as f32)).collect();
    let mut all = queries(&unit_f32, |i| directions(normals[i]));
    let sane = all.len();
    // Zero and NaN normals, with the views of +z.
    let up = directions([0.0, 0.0, 1.0]);
    all.extend(queries(&[[0.0; 3], [f32::NAN; 3], [f32::NAN, 0.0, 1.0]], |_| up.clone()));
    let out: Vec<[[f32; 4]; 6]> = kernel.run(gpu, &all, all.len(), &[]).unwrap();
    let failures = all.iter().zip(&out).enumerate().flat_map(|(i, (q, o))| check(q, o, i >= sane)).collect();
    (failures, all.len())
}

/// A camera and a point light inside a closed sphere, with a mirror ball
/// inside too: every ray hits the sphere from within (its geometric
/// normal flipped to face the ray, the shading normal after it), and no
/// path escapes. The environment is black, so a path that leaks out
/// through the wall brings no light. Rendered with the path tracer's NaN
/// guard taken out.
pub const INSIDE: &str = "[output]\nwidth = 32\nheight = 24\n\
    [camera]\nposition = [0.0, 0.0, 0.0]\ntarget = [0.0, -0.2, -1.0]\n\
    [[materials]]\nname = \"wall\"\nbase_color = [0.8, 0.8, 0.8]\nroughness = 0.5\n\
    [[materials]]\nname = \"mirror\"\nbase_color = [0.9, 0.9, 0.9]\nmetallic = 1.0\nroughness = 0.0\n\
    [[objects]]\nshape = \"sphere\"\nmaterial = \"wall\"\nscale = 3.0\n\
    [[objects]]\nshape = \"sphere\"\nmaterial = \"mirror\"\nposition = [0.5, -0.5, -1.5]\nscale = 0.4\n\
    [[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 10.0\n\
    [environment]\nintensity = 0.0\n\
    [quality]\nrenderer = \"path\"\npath_spp = 8\npath_bounces = 4\n";
