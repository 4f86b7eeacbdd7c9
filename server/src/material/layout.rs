//! The byte model of the adaptive G-buffer: how many bytes a material's
//! closures take per pixel once quantised into the material buffer, and in
//! which storage class. Static, per definition, from its `Analysis`: the
//! packer picks each pixel's class from values and never writes more words
//! than this counts, and the simplification (`simplify`) shrinks a tree
//! until this count fits `quality.material_bytes`.
//!
//! Everything is whole 32-bit words. Storage classes (two header bits),
//! cheapest first; a tile's class is its dearest pixel's:
//!
//! | class   | value | what                                                        | words |
//! |---------|-------|-------------------------------------------------------------|-------|
//! | simple  | 0     | one closure of weight 1, no optional feature, the shorthand's F0 | 4 (16 B) |
//! | single  | 1     | one closure, anything else                                   | 2 + its closure's words |
//! | complex | 2     | two or more closures                                         | 2 + the sum of its closures' words |
//!
//! A background pixel writes nothing (its tile's "empty" comes from depth).
//! There is no "special" class: glass and thin film are single or complex
//! closures with their feature words.
//!
//! The two words every class starts with (`HEADER_WORDS`): the header
//! (class, closure count, "simplified here", and a simple pixel's
//! metallic) and the octahedral shading normal. A simple pixel adds two
//! payload words: base colour and roughness as f16, the precision the
//! G-buffer had before it was packed, so the scene file's shorthand keeps
//! its image; its F0 is the shorthand's, `mix(0.04, base colour,
//! metalness)`, recomputed when unpacked. Every closure of a single or
//! complex pixel takes a four-word core (weight rgb9e5, base colour and F0
//! 10:10:10 each, roughness 12, metallic 10 and a grey F90 10) and
//! then one word per feature it may use, worst case (the packer writes only
//! the non-neutral ones):
//!
//! | feature (`analysis::Feature`)       | words | holds |
//! |-------------------------------------|-------|-------|
//! | `EdgeTint`                          | 1     | F90 10:10:10 |
//! | `Haze`                              | 1     | share 16, roughness 16 |
//! | `Fuzz`                              | 1     | colour × weight 8:8:8, roughness 8 |
//! | `Emission`                          | 1     | rgb9e5 |
//! | `Absorption`                        | 0     | spent in `init`, where it weights the base |
//! | a slab's own `normal` (a field)     | 1     | octahedral 16:16 |
//! | `Anisotropy`                        | 1     | anisotropy 8, tangent octahedral 12:12 |
//! | `Transmission`                      | 2     | weight 8, thin 1, η f16; tint 10:10:10 |
//! | `ThinFilm`                          | 1     | weight 8, film Fresnel 8:8:8 |
//! | `Diffuse`, `Specular`, `Metal`      | 0     | in the core |
//!
//! So `bytes = 4 × (2 + Σ closures (4 + feature words))`, or 16 for a
//! simple material. `material::pack` writes these words; its tests hold
//! it to this count. A slab the tree reaches along two paths (a `let` used
//! twice) is two closures, as the generated `init` makes two.

use std::collections::BTreeSet;

use serde::Serialize;

use super::analysis::{Analysis, Feature};
use super::tree::{Definition, ExprKind, Field, NodeId, NodeKind, Slab};

/// The header word and the normal word, in every class.
pub const HEADER_WORDS: u32 = 2;
/// A closure's core: weight, base colour, F0, roughness and metallic.
pub const CORE_WORDS: u32 = 4;
/// A simple pixel: header, normal, two payload words.
pub const SIMPLE_WORDS: u32 = 4;
pub const SIMPLE_BYTES: u32 = 4 * SIMPLE_WORDS;
/// The least a material can be made to take: one closure without
/// optional features (a single one; simple when its F0 is the shorthand's).
pub const MIN_BYTES: u32 = 4 * (HEADER_WORDS + CORE_WORDS);

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StorageClass {
    Simple = 0,
    Single = 1,
    Complex = 2,
}

/// The words a closure's feature takes beyond its core: the one table of
/// them, which `pack.rs` packs by.
pub const fn feature_words(f: Feature) -> u32 {
    match f {
        Feature::EdgeTint | Feature::Haze | Feature::Fuzz | Feature::Emission | Feature::Anisotropy | Feature::ThinFilm => 1,
        Feature::Transmission => 2,
        Feature::Diffuse | Feature::Specular | Feature::Metal | Feature::Absorption => 0,
    }
}

/// The words of a closure's own normal (not an analysis feature: a field
/// the back end gives every closure when set).
pub const NORMAL_WORDS: u32 = 1;

/// A closure's feature words (its core not counted).
pub fn closure_words(features: &BTreeSet<Feature>) -> u32 {
    features.iter().map(|&f| feature_words(f)).sum()
}

/// The words one closure of the slab `id` takes: its core, its features'
/// and its own normal's.
fn slab_words(analysis: &Analysis, id: NodeId, slab: &Slab) -> u32 {
    CORE_WORDS + closure_words(&analysis.features[id.0 as usize]) + if slab.get(Field::Normal).is_some() { NORMAL_WORDS } else { 0 }
}

/// The material's bytes per pixel, worst case over its instances.
pub fn bytes(analysis: &Analysis) -> u32 {
    if class(analysis) == StorageClass::Simple {
        return SIMPLE_BYTES;
    }
    let def = &analysis.def;
    let words: u32 = leaves(def, def.root).into_iter().map(|id| slab_words(analysis, id, slab(def, id))).sum();
    4 * (HEADER_WORDS + words)
}

pub fn class(analysis: &Analysis) -> StorageClass {
    let def = &analysis.def;
    match leaves(def, def.root).len() {
        1 if simple(analysis) => StorageClass::Simple,
        0 | 1 => StorageClass::Single,
        _ => StorageClass::Complex,
    }
}

/// The root is one slab (no operator weighs it), with no optional feature
/// and no normal of its own, whose F0 is the shorthand's for every
/// instance: no specular tint, weight or IOR of its own other than their
/// defaults (1.5 is the shorthand's 0.04).
fn simple(analysis: &Analysis) -> bool {
    let def = &analysis.def;
    let NodeKind::Slab(s) = &def.node(def.root).kind else { return false };
    let core = [Feature::Diffuse, Feature::Specular, Feature::Metal];
    let features = &analysis.features[def.root.0 as usize];
    if !features.iter().all(|f| core.contains(f)) || s.get(Field::Normal).is_some() {
        return false;
    }
    [Field::SpecularColor, Field::SpecularWeight, Field::SpecularIor].iter().all(|&f| default_or_unset(def, s, f))
}

/// Whether field `f` of slab `s` is unset or a constant equal to its
/// default.
fn default_or_unset(def: &Definition, s: &Slab, f: Field) -> bool {
    s.get(f).is_none_or(|e| matches!(def.expr(e).kind, ExprKind::Const(v) if v == f.default()))
}

/// The slabs under `root`, once per path that reaches them: the closures
/// the generated `init` makes (`back::closures` counts the same).
pub fn leaves(def: &Definition, root: NodeId) -> Vec<NodeId> {
    let mut out = Vec::new();
    let mut stack = vec![root];
    while let Some(id) = stack.pop() {
        match def.node(id).kind {
            NodeKind::Slab(_) => out.push(id),
            ref kind => stack.extend(super::analysis::children(kind).into_iter().rev()),
        }
    }
    out
}

fn slab(def: &Definition, id: NodeId) -> &Slab {
    match &def.node(id).kind {
        NodeKind::Slab(s) => s,
        _ => unreachable!("`leaves` gives slabs"),
    }
}

#[cfg(test)]
mod tests {
    use super::super::analysis::analyse;
    use super::super::build::Build;
    use super::super::tree::{Type, Value};
    use super::*;

    #[test]
    fn a_plastic_is_simple_and_a_tinted_one_single() {
        let mut b = Build::new("m");
        let red = b.rgb([0.8, 0.1, 0.1]);
        let s = b.slab(&[(Field::BaseColor, red)]);
        let a = analyse(&b.finish(s));
        assert_eq!((class(&a), bytes(&a)), (StorageClass::Simple, 16), "a coloured diffuse keeps the shorthand's F0");

        let mut b = Build::new("m");
        let tint = b.rgb([1.0, 0.5, 0.5]);
        let s = b.slab(&[(Field::SpecularColor, tint)]);
        let a = analyse(&b.finish(s));
        assert_eq!((class(&a), bytes(&a)), (StorageClass::Single, 24), "a tinted F0 needs the core");
    }

    #[test]
    fn a_metal_is_simple_and_a_parameter_ior_or_weight_is_not() {
        let mut b = Build::new("m");
        let c = b.param("c", Type::Color, Value::Vec3([0.9, 0.6, 0.2]), Some((0.0, 1.0)));
        let m = b.param("m", Type::Float, Value::Float(1.0), Some((0.0, 1.0)));
        let s = b.slab(&[(Field::BaseMetalness, m), (Field::BaseColor, c)]);
        assert_eq!(class(&analyse(&b.finish(s))), StorageClass::Simple, "a metal's F0 is its colour, as the shorthand's");

        for field in [Field::SpecularIor, Field::SpecularWeight] {
            let mut b = Build::new("m");
            let x = b.param("x", Type::Float, field.default(), None);
            let s = b.slab(&[(field, x)]);
            let a = analyse(&b.finish(s));
            assert_eq!((class(&a), bytes(&a)), (StorageClass::Single, 24), "{field:?} as a parameter may move F0 off the shorthand's");
        }
        let mut b = Build::new("m");
        let ior = b.float(1.5);
        let s = b.slab(&[(Field::SpecularIor, ior)]);
        assert_eq!(class(&analyse(&b.finish(s))), StorageClass::Simple, "IOR 1.5 is the shorthand's 0.04");
    }

    #[test]
    fn features_and_normals_add_their_words() {
        let mut b = Build::new("m");
        let one = b.float(1.0);
        let n = b.param("n", Type::Vec3, Value::Vec3([0.0, 0.0, 1.0]), None);
        let s = b.slab(&[(Field::TransmissionWeight, one), (Field::HazeWeight, one), (Field::Normal, n)]);
        let a = analyse(&b.finish(s));
        // 2 + 4 core + 2 transmission + 1 haze + 1 normal.
        assert_eq!((class(&a), bytes(&a)), (StorageClass::Single, 40));
    }

    #[test]
    fn every_closure_counts_and_a_shared_slab_twice() {
        let mut b = Build::new("m");
        let half = b.float(0.5);
        let one = b.float(1.0);
        let plastic = b.slab(&[]);
        let lamp = b.slab(&[(Field::EmissionLuminance, one)]);
        let mix = b.mix(plastic, lamp, half);
        let root = b.layer(plastic, mix);
        let a = analyse(&b.finish(root));
        // 2 + (4) + (4) + (4 + 1 emission), the plastic twice.
        assert_eq!((class(&a), bytes(&a)), (StorageClass::Complex, 60));

        let mut b = Build::new("m");
        let half = b.float(0.5);
        let s = b.slab(&[]);
        let root = b.coverage(s, half);
        assert_eq!(class(&analyse(&b.finish(root))), StorageClass::Single, "coverage weighs the closure");
    }

    #[test]
    fn the_feature_table() {
        let words = |f: &[Feature]| closure_words(&f.iter().copied().collect());
        use Feature::*;
        assert_eq!(words(&[Diffuse, Specular, Metal, Absorption]), 0);
        assert_eq!(words(&[EdgeTint, Haze, Fuzz, Emission, Anisotropy, ThinFilm]), 6);
        assert_eq!(words(&[Transmission]), 2);
    }
}
