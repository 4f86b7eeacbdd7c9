//! Coverage and transmittance through Substrate's operators, as plain Rust.
//!
//! Every node of a material tree covers a fraction `C` of the pixel and lets
//! through a colour `T` of the light crossing it (the table in
//! docs/materials.md). The back end's WGSL mirrors these functions line for
//! line (`lerp` is WGSL's `mix`, `saturate` its `saturate`), so the property
//! tests here are the tests of that code's arithmetic too.

/// What a node covers of the pixel and what it lets through.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ct {
    pub coverage: f32,
    pub transmittance: [f32; 3],
}

/// Nothing: covers none of the pixel and lets everything through.
pub const EMPTY: Ct = Ct { coverage: 0.0, transmittance: [1.0; 3] };

/// WGSL's `mix(a, b, t)`, written as WGSL defines it (the analysis folds
/// `lerp` with it too).
pub(super) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// WGSL's `saturate`.
pub(super) fn saturate(x: f32) -> f32 {
    x.clamp(0.0, 1.0)
}

fn per_channel(a: [f32; 3], b: [f32; 3], f: impl Fn(f32, f32) -> f32) -> [f32; 3] {
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])]
}

/// A slab covers the whole pixel; its medium keeps `transmission_color` of
/// the light per unit of `thickness` (Beer–Lambert). A thickness of 0 (or
/// less) is no medium at all; the test keeps WGSL's `pow(0, 0)`, which is
/// undefined, out of the way.
pub fn slab(transmission_color: [f32; 3], thickness: f32) -> Ct {
    let keep = |c: f32| if thickness <= 0.0 { 1.0 } else { saturate(c).powf(thickness) };
    Ct { coverage: 1.0, transmittance: [keep(transmission_color[0]), keep(transmission_color[1]), keep(transmission_color[2])] }
}

/// `mix(a, b, w)`: coverage mixes by weight; transmittance by each side's
/// share of that coverage (an uncovered side has no say in what the pixel
/// transmits). With nothing covered, the plain weighted mix.
pub fn mix(a: Ct, b: Ct, weight: f32) -> Ct {
    let w = saturate(weight);
    let share_a = a.coverage * (1.0 - w);
    let coverage = share_a + b.coverage * w;
    let k = if coverage > 0.0 { share_a / coverage } else { 1.0 - w };
    Ct { coverage, transmittance: per_channel(a.transmittance, b.transmittance, |ta, tb| lerp(tb, ta, k)) }
}

/// `layer(top, base)`: what the top leaves uncovered the base may cover;
/// light crosses both.
pub fn layer(top: Ct, base: Ct) -> Ct {
    Ct {
        coverage: top.coverage + base.coverage * (1.0 - top.coverage),
        transmittance: per_channel(top.transmittance, base.transmittance, |t, b| t * b),
    }
}

/// `coverage(a, w)`: `a` over a fraction `w` of the pixel, nothing over the
/// rest.
pub fn coverage(a: Ct, weight: f32) -> Ct {
    let w = saturate(weight);
    Ct { coverage: w * a.coverage, transmittance: a.transmittance.map(|t| lerp(1.0, t, w)) }
}

/// `add(a, b)`: both lobes at once, the wider coverage, light crossing both.
pub fn add(a: Ct, b: Ct) -> Ct {
    Ct { coverage: a.coverage.max(b.coverage), transmittance: per_channel(a.transmittance, b.transmittance, |ta, tb| ta * tb) }
}

/// The weight of a layer's base: `(1 - E_top) * T`, with `E_top` the top's
/// directional albedo (from the precomputed table) and `T` its
/// transmittance. The layer's response is `f_top + base_weight * f_base`.
pub fn base_weight(top_albedo: f32, top_transmittance: [f32; 3]) -> [f32; 3] {
    let through = 1.0 - saturate(top_albedo);
    top_transmittance.map(|t| through * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn unit() -> impl Strategy<Value = f32> {
        0.0f32..=1.0
    }

    fn ct() -> impl Strategy<Value = Ct> {
        (unit(), unit(), unit(), unit()).prop_map(|(coverage, r, g, b)| Ct { coverage, transmittance: [r, g, b] })
    }

    fn in_unit(x: Ct) -> bool {
        (0.0..=1.0).contains(&x.coverage) && x.transmittance.iter().all(|t| (0.0..=1.0).contains(t))
    }

    fn close(x: Ct, y: Ct) -> bool {
        let near = |a: f32, b: f32| (a - b).abs() <= 1e-5;
        near(x.coverage, y.coverage) && (0..3).all(|i| near(x.transmittance[i], y.transmittance[i]))
    }

    proptest! {
        #[test]
        fn every_operator_stays_in_range(a in ct(), b in ct(), w in -1.0f32..2.0) {
            for out in [mix(a, b, w), layer(a, b), coverage(a, w), add(a, b)] {
                prop_assert!(in_unit(out), "{out:?} from {a:?}, {b:?}, {w}");
            }
        }

        #[test]
        fn a_slab_stays_in_range(c in (unit(), unit(), unit()), thickness in 0.0f32..100.0) {
            let out = slab([c.0, c.1, c.2], thickness);
            prop_assert!(in_unit(out), "{out:?}");
        }

        #[test]
        fn mixing_a_slab_with_itself_gives_the_slab(a in ct(), w in unit()) {
            let out = mix(a, a, w);
            prop_assert!(close(out, a), "{out:?} from {a:?} at {w}");
        }

        #[test]
        fn an_uncovered_side_has_no_say_in_what_a_mix_transmits(a in ct(), w in 0.01f32..=1.0) {
            prop_assume!(a.coverage > 0.01);
            let out = mix(EMPTY, a, w);
            prop_assert!((out.coverage - w * a.coverage).abs() <= 1e-6);
            prop_assert!(close(Ct { coverage: a.coverage, ..out }, a), "{out:?} from {a:?} at {w}");
        }

        #[test]
        fn mix_at_its_ends_is_one_side(a in ct(), b in ct()) {
            prop_assert!(close(mix(a, b, 0.0), a));
            prop_assert!(close(mix(a, b, 1.0), b));
        }

        #[test]
        fn layering_follows_its_formula(top in ct(), base in ct()) {
            let out = layer(top, base);
            let expected = 1.0 - (1.0 - top.coverage) * (1.0 - base.coverage);
            prop_assert!((out.coverage - expected).abs() <= 1e-6);
            prop_assert!(out.coverage >= top.coverage.max(base.coverage) - 1e-6, "a layer covers at least what each covers");
            for i in 0..3 {
                prop_assert!((out.transmittance[i] - top.transmittance[i] * base.transmittance[i]).abs() <= 1e-6);
            }
            prop_assert!(close(layer(EMPTY, base), base), "an empty top leaves the base");
        }

        #[test]
        fn layering_is_associative(a in ct(), b in ct(), c in ct()) {
            prop_assert!(close(layer(a, layer(b, c)), layer(layer(a, b), c)));
        }

        #[test]
        fn full_coverage_is_the_child(a in ct()) {
            prop_assert_eq!(coverage(a, 1.0), a);
            prop_assert_eq!(coverage(a, 0.0), EMPTY);
        }

        #[test]
        fn the_base_weight_is_what_the_top_lets_through(e in unit(), t in (unit(), unit(), unit())) {
            let w = base_weight(e, [t.0, t.1, t.2]);
            for (wi, ti) in w.into_iter().zip([t.0, t.1, t.2]) {
                prop_assert!((0.0..=ti).contains(&wi));
                prop_assert!((wi - (1.0 - e) * ti).abs() <= 1e-6);
            }
        }
    }

    #[test]
    fn a_thin_or_clear_slab_transmits_everything() {
        assert_eq!(slab([0.2, 0.5, 0.0], 0.0), Ct { coverage: 1.0, transmittance: [1.0; 3] });
        assert_eq!(slab([1.0; 3], 3.0).transmittance, [1.0; 3]);
        // Two units keep the square of what one keeps.
        let t = slab([0.5, 0.25, 0.0], 2.0).transmittance;
        assert!((t[0] - 0.25).abs() < 1e-6 && (t[1] - 0.0625).abs() < 1e-6 && t[2] == 0.0);
    }
}
