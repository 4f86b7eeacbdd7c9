//! The packing on the device: closures with random and extreme values
//! (zero, one, denormal-small, past rgb9e5's range) through
//! `material_pack` and `material_unpack`, each field within its bound
//! (the table in docs/materials.md "Storage classes"), none NaN or Inf,
//! and no pixel writing more words than its definition's `words`.

use super::{SIMPLE_WORDS, program_words, words};
use crate::gpu::testing::{Kernel, device};
use crate::material::back::{self, Bindings};
use crate::material::front;
use crate::shader::SourceFile;

/// Every optional part in two closures (definition 0), and one plain
/// slab (definition 1). Parameters, not constants, so no feature folds
/// away.
const MATERIALS: &str = "
param c: color = rgb(0.5, 0.5, 0.5) in [0, 1]
param x: float = 0.5 in [0, 1]
param d: vec3 = rgb(0, 0, 1)
material full = mix(
    slab { base_color: c, base_metalness: x, specular_roughness: x, specular_edge_color: c, haze_weight: x, haze_roughness: x,
           fuzz_weight: x, fuzz_color: c, emission_luminance: x, emission_color: c, normal: d,
           specular_roughness_anisotropy: x, specular_rotation: x, transmission_weight: x, thin_film_weight: x },
    slab { base_color: c, base_metalness: x, specular_roughness: x, specular_edge_color: c, haze_weight: x, haze_roughness: x,
           fuzz_weight: x, fuzz_color: c, emission_luminance: x, emission_color: c, normal: d,
           specular_roughness_anisotropy: x, specular_rotation: x, transmission_weight: x, thin_film_weight: x },
    x)
material plain = slab { base_color: c, base_metalness: x, specular_roughness: x }
";

/// One closure's fields in, the unpacked ones out, as vec4s:
/// weight+metallic, base+roughness, F0+haze share, F90+haze roughness,
/// fuzz+roughness, emission+anisotropy, own normal+transmission,
/// tangent+eta, tint+thin, film Fresnel+film, geometry normal+pixel,
/// (closures, definition, words written, class).
const FIELDS: usize = 12;
type Case = [[f32; 4]; FIELDS];

const KERNEL: &str = r#"
#import loupe::material::{Surface, Closure, make_closure, material_pack, material_unpack}

@group(0) @binding(0) var<storage, read> input: array<array<vec4<f32>, 12>>;
@group(0) @binding(1) var<storage, read_write> output: array<array<vec4<f32>, 12>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) { return; }
    let i = input[id.x];
    var c = make_closure(i[1].xyz, i[0].w, i[2].xyz, i[1].w);
    c.weight = i[0].xyz;
    c.haze = vec2(i[2].w, i[3].w);
    c.edge = i[3].xyz;
    c.fuzz_color = i[4].xyz;
    c.fuzz_roughness = i[4].w;
    c.emission = i[5].xyz;
    c.anisotropy = i[5].w;
    c.normal = i[6].xyz;
    c.transmission = i[6].w;
    c.tangent = i[7].xyz;
    c.eta = i[7].w;
    c.tint = i[8].xyz;
    c.thin = i[8].w;
    c.film_fresnel = i[9].xyz;
    c.film = i[9].w;
    var s: Surface;
    s.count = u32(i[11].x);
    for (var k = 0u; k < s.count; k++) {
        s.closures[k] = c;
    }
    let n = i[10].xyz;
    let pixel = u32(i[10].w);
    let p = material_pack(s, n, u32(i[11].y), false, false, vec2(pixel % 64u, pixel / 64u));
    let u = material_unpack(p.words, n);
    // The last closure: every closure's words went before it.
    let o = u.surface.closures[max(u.surface.count, 1u) - 1u];
    output[id.x] = array(
        vec4(o.weight, o.metallic), vec4(o.base_color, o.roughness), vec4(o.reflectance, o.haze.x), vec4(o.edge, o.haze.y),
        vec4(o.fuzz_color, o.fuzz_roughness), vec4(o.emission, o.anisotropy), vec4(o.normal, o.transmission), vec4(o.tangent, o.eta),
        vec4(o.tint, o.thin), vec4(o.film_fresnel, o.film), vec4(u.normal, 0.0), vec4(f32(u.surface.count), 0.0, f32(p.count), f32(p.words[0] & 3u)),
    );
}
"#;

/// A small deterministic generator (the cases must not change between runs).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn unit(&mut self) -> [f32; 3] {
        loop {
            let v = [self.next() * 2.0 - 1.0, self.next() * 2.0 - 1.0, self.next() * 2.0 - 1.0];
            let l = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            if l > 0.1 && l < 1.0 {
                return v.map(|x| x / l);
            }
        }
    }
}

/// A closure whose every [0, 1] field is `unit()` and whose weight and
/// emission are `big()`, with random unit normals.
fn case(r: &mut Lcg, unit: &mut dyn FnMut(&mut Lcg) -> f32, big: &mut dyn FnMut(&mut Lcg) -> f32, pixel: usize) -> Case {
    let v3 = |r: &mut Lcg, f: &mut dyn FnMut(&mut Lcg) -> f32| [f(r), f(r), f(r)];
    let [w, b, f0, f90, fuzz, em, tint, film] = [0, 1, 2, 3, 4, 5, 6, 7].map(|k| if k == 0 || k == 5 { v3(r, big) } else { v3(r, unit) });
    let (normal, tangent, n) = (r.unit(), r.unit(), r.unit());
    let mut s = || unit(r);
    let [metallic, rough, haze, haze_rough, fuzz_rough, aniso, transmission, film_w] = [(); 8].map(|_| s());
    let eta = 1.0 + 2.0 * r.next();
    let thin = if r.next() < 0.5 { 0.0 } else { 1.0 };
    let x = |c: [f32; 3], w: f32| [c[0], c[1], c[2], w];
    [
        x(w, metallic),
        x(b, rough),
        x(f0, haze),
        x(f90, haze_rough),
        x(fuzz, fuzz_rough),
        x(em, aniso),
        x(normal, transmission),
        x(tangent, eta),
        x(tint, thin),
        x(film, film_w),
        x(n, pixel as f32),
        [0.0; 4],
    ]
}

/// The same closure made simple: weight 1, the shorthand's F0 (base
/// colour and metallic in range, as `init` leaves them), no optional field.
fn simple(mut c: Case) -> Case {
    let m = c[0][3].clamp(0.0, 1.0);
    c[0] = [1.0, 1.0, 1.0, m];
    c[1] = c[1].map(|x| x.clamp(0.0, 1.0));
    let f0 = |x: f32| 0.04 + (x - 0.04) * m;
    c[2] = [f0(c[1][0]), f0(c[1][1]), f0(c[1][2]), 0.0];
    c[3] = [1.0, 1.0, 1.0, c[3][3]];
    c[4] = [0.0, 0.0, 0.0, c[4][3]];
    c[5] = [0.0, 0.0, 0.0, 0.0];
    c[6] = [0.0, 0.0, 0.0, 0.0];
    c[9][3] = 0.0;
    c
}

fn cases() -> Vec<Case> {
    let mut r = Lcg(23);
    let mut out = Vec::new();
    let mut unit_random = |r: &mut Lcg| r.next();
    let mut big_random = |r: &mut Lcg| r.next() * r.next() * 40.0;
    let extremes: [(f32, f32); 5] = [(0.0, 0.0), (1.0, 1.0), (1e-40, 1e-40), (1.0, 1e6), (1e-7, 65408.0)];
    for pixel in 0..256 {
        let c = match pixel % 8 {
            0..4 => case(&mut r, &mut unit_random, &mut big_random, pixel),
            k => {
                let (u, b) = extremes[(pixel / 8 + k) % extremes.len()];
                case(&mut r, &mut |_: &mut Lcg| u, &mut |_: &mut Lcg| b, pixel)
            }
        };
        // One closure and two of definition 0, and simple ones of definition 1.
        for (closures, definition, c) in [(1.0, 0.0, c), (2.0, 0.0, c), (1.0, 1.0, simple(c))] {
            let mut c = c;
            c[11] = [closures, definition, 0.0, 0.0];
            out.push(c);
        }
    }
    out
}

/// The angle between two directions, by atan2 (acos of an f32 dot
/// product cannot resolve 1e-4 rad).
fn angle(a: [f32; 4], b: [f32; 4]) -> f64 {
    let [a, b] = [a, b].map(|v| [0, 1, 2].map(|i| f64::from(v[i])));
    let dot: f64 = (0..3).map(|i| a[i] * b[i]).sum();
    let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    cross.iter().map(|x| x * x).sum::<f64>().sqrt().atan2(dot)
}

/// Channel `i` of field `f`: out against in, within `bound`.
fn check(errors: &mut Vec<String>, case: usize, name: &str, got: f32, want: f32, bound: f64) {
    let err = (f64::from(got) - f64::from(want)).abs();
    if !got.is_finite() || err > bound + 1e-6 {
        errors.push(format!("case {case}: {name} {got} for {want}: error {err:e} > {bound:e}"));
    }
}

/// rgb9e5's bound: half a step of the shared exponent's scale, at most
/// 2^-9 of the largest channel (after clamping to its range).
fn rgb9e5(errors: &mut Vec<String>, case: usize, name: &str, got: [f32; 4], want: [f32; 4]) {
    let clamp = |x: f32| x.clamp(0.0, 65408.0);
    let max = (0..3).map(|i| clamp(want[i])).fold(0.0, f32::max);
    for i in 0..3 {
        check(errors, case, name, got[i], clamp(want[i]), f64::from(max) * 2f64.powi(-9) + 2f64.powi(-24));
    }
}

/// An f16 channel: half a step, 2⁻¹¹ of the value (2⁻²⁵ below f16's
/// normal range).
fn half(errors: &mut Vec<String>, case: usize, name: &str, got: f32, want: f32) {
    check(errors, case, name, got, want, f64::from(want.abs()) * 2f64.powi(-11) + 2f64.powi(-25));
}

/// An 8-bit sqrt-encoded channel, dithered: one step of √c.
fn sqrt8(errors: &mut Vec<String>, case: usize, name: &str, got: f32, want: f32) {
    let root = want.clamp(0.0, 1.0).sqrt();
    check(errors, case, name, got, want.clamp(0.0, 1.0), f64::from(2.0 * root + 1.0 / 255.0) / 255.0);
}

#[test]
fn every_field_round_trips_within_its_bound() {
    let gpu = device();
    let definitions: Vec<_> = front::load_text(std::path::Path::new("pack.mat"), MATERIALS)
        .unwrap_or_else(|d| panic!("{d:?}"))
        .definitions
        .iter()
        .map(|d| crate::material::analysed(d).unwrap().def)
        .collect();
    let text = back::wgsl(&definitions, Bindings { group: 1, params: 0, instances: 1, textures: 2, sampler: 3 });
    let module = SourceFile::from_text(back::DISPLAY.into(), back::DISPLAY.into(), text.into());
    let kernel = Kernel::with_modules(&gpu, KERNEL, "main", std::slice::from_ref(&module)).unwrap_or_else(|e| panic!("{e}"));
    let input = cases();
    let output: Vec<Case> = kernel.run(&gpu, &input, input.len(), &[]).unwrap();

    let static_words = [words(&definitions[0]), words(&definitions[1])];
    assert_eq!(static_words, [2 + 2 * (4 + 9), 2 + 4], "the full material has every part: 9 optional words per closure");
    assert_eq!(program_words(&definitions), static_words[0]);
    let mut errors = Vec::new();
    for (k, (i, o)) in input.iter().zip(&output).enumerate() {
        let closures = i[11][0];
        let definition = i[11][1] as usize;
        let (written, class) = (o[11][2] as u32, o[11][3] as u32);
        if written > static_words[definition] {
            errors.push(format!("case {k}: {written} words written, more than definition {definition}'s {}", static_words[definition]));
        }
        check(&mut errors, k, "closures", o[11][0], closures, 0.0);
        check(&mut errors, k, "geometry normal (rad)", angle(o[10], i[10]) as f32, 0.0, 1e-4);
        if definition == 1 {
            // Simple: f16 base colour and roughness, 12-bit metallic, F0
            // recomputed from them.
            check(&mut errors, k, "class", class as f32, 0.0, 0.0);
            check(&mut errors, k, "words", written as f32, SIMPLE_WORDS as f32, 0.0);
            for c in 0..3 {
                half(&mut errors, k, "base colour", o[1][c], i[1][c]);
                check(&mut errors, k, "F0", o[2][c], i[2][c], f64::from(i[2][c]) * 2f64.powi(-11) + 1.0 / 8190.0);
            }
            half(&mut errors, k, "roughness", o[1][3], i[1][3]);
            check(&mut errors, k, "metallic", o[0][3], i[0][3], 1.0 / 8190.0);
            continue;
        }
        check(&mut errors, k, "class", class as f32, closures, 0.0);
        let unit = |x: f32| x.clamp(0.0, 1.0);
        rgb9e5(&mut errors, k, "weight", o[0], i[0]);
        rgb9e5(&mut errors, k, "emission", o[5], i[5]);
        for c in 0..3 {
            check(&mut errors, k, "base colour", o[1][c], unit(i[1][c]), 1.0 / 2046.0);
            check(&mut errors, k, "F0", o[2][c], unit(i[2][c]), 1.0 / 2046.0);
            check(&mut errors, k, "F90", o[3][c], unit(i[3][c]), 1.0 / 2046.0);
            sqrt8(&mut errors, k, "fuzz colour", o[4][c], i[4][c]);
            check(&mut errors, k, "tint", o[8][c], unit(i[8][c]), 1.0 / 2046.0);
            check(&mut errors, k, "film Fresnel", o[9][c], unit(i[9][c]), 1.0 / 510.0);
        }
        check(&mut errors, k, "metallic", o[0][3], unit(i[0][3]), 1.0 / 2046.0);
        check(&mut errors, k, "roughness", o[1][3], unit(i[1][3]), 1.0 / 8190.0);
        check(&mut errors, k, "haze share", o[2][3], unit(i[2][3]), 1.0 / 131070.0);
        check(&mut errors, k, "haze roughness", o[3][3], unit(i[3][3]), 1.0 / 131070.0);
        check(&mut errors, k, "fuzz roughness", o[4][3], unit(i[4][3]), 1.0 / 510.0);
        check(&mut errors, k, "anisotropy", o[5][3], unit(i[5][3]), 1.0 / 510.0);
        check(&mut errors, k, "slab normal (rad)", angle(o[6], i[6]) as f32, 0.0, 1e-4);
        check(&mut errors, k, "transmission", o[6][3], unit(i[6][3]), 1.0 / 510.0);
        if o[5][3] > 0.0 {
            check(&mut errors, k, "tangent (rad)", angle(o[7], i[7]) as f32, 0.0, 2e-3);
        }
        check(&mut errors, k, "eta", o[7][3], i[7][3], f64::from(i[7][3]) * 2f64.powi(-11));
        check(&mut errors, k, "thin", o[8][3], i[8][3], 0.0);
        check(&mut errors, k, "film weight", o[9][3], unit(i[9][3]), 1.0 / 510.0);
    }
    assert!(errors.is_empty(), "{} of {} cases out of bounds:\n{}", errors.len(), input.len(), errors[..errors.len().min(30)].join("\n"));
}
