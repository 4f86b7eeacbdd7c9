//! The adaptive G-buffer's words: the part of the `loupe::material` module
//! that packs a pixel's `Surface` (after `init`, before the energy
//! compensation) into `u32` words in the smallest storage class that
//! holds it, and unpacks them for the lighting, which then needs neither
//! the material's `init` nor its textures. The byte model is
//! `/docs/materials.md` "Storage classes" (the contract with
//! `layout.rs`); the quantisers are `shaders/lib/pack.wgsl`.
//!
//! Which words a closure has is static: per definition and closure, a mask
//! of the features its slab has (`analysis::Feature`, and a `normal` of
//! its own). Single and complex pixels name their definition in the
//! header, so the unpacking finds the masks, and a pixel never writes more
//! than its definition's `words`. Fields the raster's consumers
//! (`material_eval`, `_ambient`, `_rect`, `_emission`) do not read are not
//! stored: a layer top's `transmittance` is spent in `init` (it weights
//! the base), and the compensation (`haze_compensation` too) is redone at
//! unpacking, at the lighting's n·v, when the header's bit 6 says so.

use std::collections::BTreeSet;
use std::fmt::Write;

use super::analysis::{self, Feature};
use super::features::Features;
use super::layout::{self, CORE_WORDS, HEADER_WORDS, NORMAL_WORDS, SIMPLE_WORDS, StorageClass, feature_words};
use super::tree::{Definition, Field, NodeKind};

/// Header (word 0) bits 0–1: the storage class (`layout` counts the words).
const SIMPLE: u32 = StorageClass::Simple as u32;
const SINGLE: u32 = StorageClass::Single as u32;
const COMPLEX: u32 = StorageClass::Complex as u32;

/// A closure's optional words: (mask bit, words (`layout`'s count),
/// WGSL to pack, WGSL to unpack). `w` is the word index, `c` the closure, `p.words` the output.
struct Part {
    bit: u32,
    words: u32,
    pack: &'static str,
    unpack: &'static str,
}

const EDGE: Part = Part {
    bit: 1,
    words: feature_words(Feature::EdgeTint),
    pack: "p.words[w] = pack_unorm3(c.edge, 10u, 0.0);",
    unpack: "c.edge = unpack_unorm3(words[w], 10u);",
};
const HAZE: Part = Part {
    bit: 2,
    words: feature_words(Feature::Haze),
    pack: "p.words[w] = unorm_encode(c.haze.x, 16u, 0.0) | (unorm_encode(c.haze.y, 16u, 0.0) << 16u);",
    unpack: "c.haze = vec2(unorm_decode(words[w], 0u, 16u), unorm_decode(words[w], 16u, 16u));",
};
const FUZZ: Part = Part {
    bit: 4,
    words: feature_words(Feature::Fuzz),
    pack: "p.words[w] = pack_sqrt3(c.fuzz_color, 8u, dither) | (unorm_encode(c.fuzz_roughness, 8u, 0.0) << 24u);",
    unpack: "c.fuzz_color = unpack_sqrt3(words[w], 8u);\n            c.fuzz_roughness = unorm_decode(words[w], 24u, 8u);",
};
const EMISSION: Part = Part {
    bit: 8,
    words: feature_words(Feature::Emission),
    pack: "p.words[w] = pack_rgb9e5(c.emission);",
    unpack: "c.emission = unpack_rgb9e5(words[w]);",
};
const NORMAL: Part = Part {
    bit: 16,
    words: NORMAL_WORDS,
    pack: "p.words[w] = pack_octahedral(closure_normal(c, n), 16u);",
    unpack: "c.normal = unpack_octahedral(words[w], 16u);",
};
const ANISOTROPY: Part = Part {
    bit: 32,
    words: feature_words(Feature::Anisotropy),
    pack: "p.words[w] = unorm_encode(c.anisotropy, 8u, 0.0) | (pack_octahedral(c.tangent, 12u) << 8u);",
    unpack: "c.anisotropy = unorm_decode(words[w], 0u, 8u);\n            c.tangent = select(unpack_octahedral(words[w] >> 8u, 12u), vec3(0.0), c.anisotropy == 0.0);",
};
const TRANSMISSION: Part = Part {
    bit: 64,
    words: feature_words(Feature::Transmission),
    pack: "p.words[w] = unorm_encode(c.transmission, 8u, 0.0) | (u32(c.thin > 0.5) << 8u) | (pack2x16float(vec2(min(c.eta, 65504.0), 0.0)) << 16u);\n            p.words[w + 1u] = pack_unorm3(c.tint, 10u, 0.0);",
    unpack: "c.transmission = unorm_decode(words[w], 0u, 8u);\n            c.thin = f32((words[w] >> 8u) & 1u);\n            c.eta = unpack2x16float(words[w] >> 16u).x;\n            c.tint = unpack_unorm3(words[w + 1u], 10u);",
};
const FILM: Part = Part {
    bit: 128,
    words: feature_words(Feature::ThinFilm),
    pack: "p.words[w] = unorm_encode(c.film, 8u, 0.0) | (pack_unorm3(c.film_fresnel, 8u, 0.0) << 8u);",
    unpack: "c.film = unorm_decode(words[w], 0u, 8u);\n            c.film_fresnel = unpack_unorm3(words[w] >> 8u, 8u);",
};

/// The parts in word order, with whether a module's closures have their
/// fields.
fn parts(f: Features) -> [(&'static Part, bool); 8] {
    [
        (&EDGE, f.edge),
        (&HAZE, f.haze),
        (&FUZZ, f.fuzz),
        (&EMISSION, f.emission),
        (&NORMAL, f.normal),
        (&ANISOTROPY, f.anisotropy),
        (&TRANSMISSION, f.transmission),
        (&FILM, f.thin_film),
    ]
}

/// The part a slab's feature (or its own normal) stores.
fn part_of(feature: Feature) -> Option<&'static Part> {
    match feature {
        Feature::EdgeTint => Some(&EDGE),
        Feature::Haze => Some(&HAZE),
        Feature::Fuzz => Some(&FUZZ),
        Feature::Emission => Some(&EMISSION),
        Feature::Anisotropy => Some(&ANISOTROPY),
        Feature::Transmission => Some(&TRANSMISSION),
        Feature::ThinFilm => Some(&FILM),
        Feature::Diffuse | Feature::Specular | Feature::Metal | Feature::Absorption => None,
    }
}

/// Per closure of `d` (as `init` orders them), the mask of its optional
/// words.
pub fn masks(d: &Definition) -> Vec<u32> {
    let a = analysis::analyse(d);
    layout::leaves(&a.def, a.def.root)
        .iter()
        .map(|&id| {
            let features: &BTreeSet<Feature> = &a.features[id.0 as usize];
            let own_normal = matches!(&a.def.node(id).kind, NodeKind::Slab(s) if s.get(Field::Normal).is_some());
            features.iter().filter_map(|&f| part_of(f)).map(|p| p.bit).sum::<u32>() | if own_normal { NORMAL.bit } else { 0 }
        })
        .collect()
}

fn mask_words(mask: u32) -> u32 {
    parts(Features {
        edge: true,
        haze: true,
        fuzz: true,
        emission: true,
        normal: true,
        anisotropy: true,
        transmission: true,
        thin_film: true,
        ..Features::default()
    })
    .iter()
    .filter(|(p, _)| mask & p.bit != 0)
    .map(|(p, _)| p.words)
    .sum()
}

/// The most words a pixel of `d` takes: the header and normal, then each
/// closure's core and optional words (a simple pixel takes fewer).
pub fn words(d: &Definition) -> u32 {
    HEADER_WORDS + masks(d).iter().map(|&m| CORE_WORDS + mask_words(m)).sum::<u32>()
}

/// The most words any pixel of the program takes: `MATERIAL_WORDS`.
pub fn program_words(definitions: &[Definition]) -> u32 {
    definitions.iter().map(words).max().unwrap_or(0).max(SIMPLE_WORDS)
}

/// Appends the packing and unpacking to the module `back::wgsl` writes.
pub fn write(w: &mut String, definitions: &[Definition], f: Features) {
    let _ = writeln!(
        w,
        "// The material buffer's words (server/src/material/pack.rs): the most a\n// pixel of these materials takes.\nconst MATERIAL_WORDS: u32 = {}u;\nconst MATERIAL_SIMPLE: u32 = {SIMPLE}u;\nconst MATERIAL_SINGLE: u32 = {SINGLE}u;\nconst MATERIAL_COMPLEX: u32 = {COMPLEX}u;\n",
        program_words(definitions)
    );
    w.push_str("struct PackedMaterial {\n    words: array<u32, MATERIAL_WORDS>,\n    count: u32,\n}\n\nstruct UnpackedMaterial {\n    surface: Surface,\n    normal: vec3<f32>,\n}\n\n");
    // The masks, by definition and closure.
    w.push_str("// Which optional words closure k of a definition has.\nfn closure_mask(definition: u32, k: u32) -> u32 {\n    switch definition * 8u + k {\n");
    for (i, d) in definitions.iter().enumerate() {
        for (k, m) in masks(d).iter().enumerate().filter(|(_, m)| **m != 0) {
            let _ = writeln!(w, "        case {}u: {{ return {m}u; }}", i * 8 + k);
        }
    }
    w.push_str("        default: { return 0u; }\n    }\n}\n\n");
    let _ = writeln!(
        w,
        "// The words a pixel takes, from its header alone.\nfn material_word_count(header: u32) -> u32 {{\n    if (header & 3u) == MATERIAL_SIMPLE {{\n        return {SIMPLE_WORDS}u;\n    }}\n    var w = {HEADER_WORDS}u;\n    for (var k = 0u; k < ((header >> 2u) & 7u); k++) {{\n        w += {CORE_WORDS}u + closure_extra_words(closure_mask(header >> 8u, k));\n    }}\n    return w;\n}}\n"
    );
    w.push_str("fn closure_extra_words(mask: u32) -> u32 {\n    var w = 0u;\n");
    for (p, on) in parts(f) {
        if on {
            let _ = writeln!(w, "    w += select(0u, {}u, (mask & {}u) != 0u);", p.words, p.bit);
        }
    }
    w.push_str("    return w;\n}\n\n");
    simple(w, f);
    pack(w, f);
    unpack(w, f);
}

/// Whether a closure fits the simple class: weight 1, the shorthand's F0
/// of its base colour and metalness (unpacking recomputes it), every
/// optional field neutral.
fn simple(w: &mut String, f: Features) {
    w.push_str("fn closure_is_simple(c: Closure) -> bool {\n    var simple = all(c.weight == vec3(1.0)) && all(abs(c.reflectance - specular_f0(c.base_color, c.metallic)) <= vec3(1e-6));\n");
    let tests = [
        (f.edge, "all(c.edge == vec3(1.0))"),
        (f.haze, "c.haze.x == 0.0"),
        (f.fuzz, "all(c.fuzz_color == vec3(0.0))"),
        (f.emission, "all(c.emission == vec3(0.0))"),
        (f.normal, "all(c.normal == vec3(0.0))"),
        (f.anisotropy, "c.anisotropy == 0.0"),
        (f.transmission, "c.transmission == 0.0"),
        (f.thin_film, "c.film == 0.0"),
    ];
    for (_, t) in tests.iter().filter(|(on, _)| *on) {
        let _ = writeln!(w, "    simple = simple && {t};");
    }
    w.push_str("    return simple;\n}\n\n");
}

fn pack(w: &mut String, f: Features) {
    let grey = if f.edge { "c.edge.g" } else { "1.0" };
    let _ = write!(
        w,
        "// A pixel's surface `s` (before the compensation; `compensated`: the
// instance's) with shading normal `n` as words: header, normal, then the
// simple payload or each closure's core and optional words. `pixel` seeds
// the 8-bit colours' dither.
fn material_pack(s: Surface, n: vec3<f32>, definition: u32, compensated: bool, simplified: bool, pixel: vec2<u32>) -> PackedMaterial {{
    var p: PackedMaterial;
    let dither = pack_dither(pixel);
    let flags = (u32(simplified) << 5u) | (u32(compensated) << 6u);
    p.words[1] = pack_octahedral(n, 16u);
    let first = s.closures[0];
    if s.count == 1u && closure_is_simple(first) {{
        p.words[0] = MATERIAL_SIMPLE | (1u << 2u) | flags | (unorm_encode(first.metallic, 12u, 0.0) << 8u);
        p.words[2] = pack2x16float(first.base_color.rg);
        p.words[3] = pack2x16float(vec2(first.base_color.b, first.roughness));
        p.count = {SIMPLE_WORDS}u;
        return p;
    }}
    p.words[0] = select(MATERIAL_COMPLEX, MATERIAL_SINGLE, s.count == 1u) | (s.count << 2u) | flags | (definition << 8u);
    var w = {HEADER_WORDS}u;
    for (var k = 0u; k < s.count; k++) {{
        let c = s.closures[k];
        let mask = closure_mask(definition, k);
        p.words[w] = pack_rgb9e5(c.weight);
        p.words[w + 1u] = pack_unorm3(c.base_color, 10u, 0.0);
        p.words[w + 2u] = pack_unorm3(c.reflectance, 10u, 0.0);
        p.words[w + 3u] = unorm_encode(c.roughness, 12u, 0.0) | (unorm_encode(c.metallic, 10u, 0.0) << 12u) | (unorm_encode({grey}, 10u, 0.0) << 22u);
        w += {CORE_WORDS}u;
"
    );
    for (p, _) in parts(f).iter().filter(|(_, on)| *on) {
        let _ = writeln!(w, "        if (mask & {}u) != 0u {{\n            {}\n            w += {}u;\n        }}", p.bit, p.pack, p.words);
    }
    w.push_str("    }\n    p.count = w;\n    return p;\n}\n\n");
}

fn unpack(w: &mut String, f: Features) {
    let grey = if f.edge { "        c.edge = vec3(unorm_decode(words[w + 3u], 22u, 10u));\n" } else { "" };
    let _ = write!(
        w,
        "// The surface and shading normal `material_pack` stored, seen from v
// (the compensation's n·v).
fn material_unpack(words: array<u32, MATERIAL_WORDS>, v: vec3<f32>) -> UnpackedMaterial {{
    var s: Surface;
    let header = words[0];
    let n = unpack_octahedral(words[1], 16u);
    if (header & 3u) == MATERIAL_SIMPLE {{
        s.count = 1u;
        let b_roughness = unpack2x16float(words[3]);
        let base = vec3(unpack2x16float(words[2]), b_roughness.x);
        let metallic = unorm_decode(header, 8u, 12u);
        s.closures[0] = make_closure(base, metallic, specular_f0(base, metallic), b_roughness.y);
    }} else {{
        s.count = (header >> 2u) & 7u;
        var w = {HEADER_WORDS}u;
        for (var k = 0u; k < s.count; k++) {{
            let mask = closure_mask(header >> 8u, k);
            var c = make_closure(unpack_unorm3(words[w + 1u], 10u), unorm_decode(words[w + 3u], 12u, 10u), unpack_unorm3(words[w + 2u], 10u), unorm_decode(words[w + 3u], 0u, 12u));
            c.weight = unpack_rgb9e5(words[w]);
{grey}            w += {CORE_WORDS}u;
"
    );
    for (p, _) in parts(f).iter().filter(|(_, on)| *on) {
        let _ = writeln!(
            w,
            "            if (mask & {}u) != 0u {{\n                {}\n                w += {}u;\n            }}",
            p.bit,
            p.unpack.replace("\n            ", "\n                "),
            p.words
        );
    }
    w.push_str("            s.closures[k] = c;\n        }\n    }\n");
    if f.compensated {
        w.push_str("    if (header & (1u << 6u)) != 0u {\n        s = material_compensate(s, max(dot(n, v), 1e-4));\n    }\n");
    }
    w.push_str("    return UnpackedMaterial(s, n);\n}\n\n");
    // The G-buffer's entry: the instance's definition and compensation.
    w.push_str("// `material_pack` for a pixel of `instance`.\nfn material_pack_at(instance: u32, s: Surface, n: vec3<f32>, pixel: vec2<u32>) -> PackedMaterial {\n    let header = material_instances[instance];\n    return material_pack(s, n, header.x, header.z != 0u, material_simplified(header.x), pixel);\n}\n\n");
}

#[cfg(test)]
mod tests;
