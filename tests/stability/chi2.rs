//! Pearson's chi-square goodness-of-fit test of a sampler against the pdf
//! it claims, in the manner of pbrt-v4's and Mitsuba 3's: the samples are
//! binned into a 2D histogram, each cell's expected count is the pdf
//! integrated over the cell numerically, cells expected to hold fewer
//! than `MIN_EXPECTED` samples are pooled into one, and the statistic's
//! p-value is compared with a significance corrected for the number of
//! cases (Šidák).
//!
//! The histogram's axes are warped (`Axis`) so that a lobe as narrow as
//! GGX's at the smallest roughness still spans many cells: a cell's width
//! grows in proportion to its distance from the lobe's centre.

/// Cells expected to hold fewer samples than this are pooled: the
/// statistic's chi-square distribution is an approximation that needs
/// counts of a few per cell (pbrt-v4 and Mitsuba 3 use the same figure).
pub const MIN_EXPECTED: f64 = 5.0;

/// The outcome of one test.
#[derive(Debug, Clone, Copy)]
pub struct Fit {
    pub statistic: f64,
    /// Degrees of freedom: the cells after pooling, less one.
    pub dof: usize,
    pub p_value: f64,
    /// How many cells were pooled.
    pub pooled: usize,
}

/// The per-case significance that keeps the chance of any of `cases`
/// correct samplers failing at `significance` (Šidák's correction).
pub fn sidak(significance: f64, cases: usize) -> f64 {
    1.0 - (1.0 - significance).powf(1.0 / cases as f64)
}

/// Pearson's statistic of `observed` counts against `expected` ones, with
/// the cells expected to hold fewer than `MIN_EXPECTED` pooled (smallest
/// first, so a pool that is still too small takes the next cell in).
/// A cell expected to hold nothing that holds samples lands in the pool,
/// where it weighs as much as its count deserves.
pub fn pearson(observed: &[f64], expected: &[f64]) -> Fit {
    assert_eq!(observed.len(), expected.len(), "one expected count per cell");
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut statistic, mut cells, mut pooled) = (0.0, 0usize, 0usize);
    let (mut pool_observed, mut pool_expected) = (0.0, 0.0);
    for i in order {
        let (o, e) = (observed[i], expected[i]);
        if e < MIN_EXPECTED || (pool_expected > 0.0 && pool_expected < MIN_EXPECTED) {
            pool_observed += o;
            pool_expected += e;
            pooled += 1;
        } else {
            statistic += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pooled > 0 {
        // A pool expected to hold nothing but holding samples is a certain
        // failure; one holding nothing adds nothing.
        statistic += if pool_expected > 0.0 {
            (pool_observed - pool_expected).powi(2) / pool_expected
        } else if pool_observed > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        cells += 1;
    }
    let dof = cells.saturating_sub(1).max(1);
    Fit { statistic, dof, p_value: upper_gamma(dof as f64 / 2.0, statistic / 2.0), pooled }
}

/// The regularized upper incomplete gamma function Q(a, x): the chance a
/// chi-square variable of 2a degrees of freedom exceeds 2x. A series
/// below x = a + 1, Legendre's continued fraction (modified Lentz) above,
/// as Numerical Recipes does it.
fn upper_gamma(a: f64, x: f64) -> f64 {
    if x.is_nan() || x == f64::INFINITY {
        return 0.0;
    }
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefix = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
        while term.abs() > sum.abs() * 1e-15 {
            n += 1.0;
            term *= x / n;
            sum += term;
        }
        1.0 - sum * log_prefix.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let (mut c, mut d) = (1.0 / tiny, 1.0 / b);
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let step = d * c;
            h *= step;
            if (step - 1.0).abs() < 1e-15 {
                break;
            }
        }
        h * log_prefix.exp()
    }
}

/// ln Γ(x) for x > 0 (Lanczos' approximation, g = 7, nine terms: about
/// 15 digits).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection keeps the series where it converges.
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let series = C[0] + C.iter().enumerate().skip(1).map(|(i, c)| c / (x + i as f64)).sum::<f64>();
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + series.ln()
}

/// One axis of the histogram: `cells` equal cells of a parameter t in
/// [0, 1], mapped onto [lo, hi] so that cells near `center` are `width`
/// wide or less and grow in proportion to their distance from it
/// (t is linear in sign(x − c) ln(1 + |x − c| / width)).
#[derive(Debug, Clone, Copy)]
pub struct Axis {
    pub cells: usize,
    center: f64,
    width: f64,
    g_lo: f64,
    g_hi: f64,
}

impl Axis {
    pub fn new(lo: f64, hi: f64, center: f64, width: f64, cells: usize) -> Axis {
        let g = |x: f64| (x - center).signum() * (1.0 + (x - center).abs() / width).ln();
        Axis { cells, center, width, g_lo: g(lo), g_hi: g(hi) }
    }

    /// The coordinate at parameter t and dx/dt there.
    pub fn at(&self, t: f64) -> (f64, f64) {
        let g = self.g_lo + t * (self.g_hi - self.g_lo);
        let grow = g.abs().exp();
        (self.center + g.signum() * self.width * (grow - 1.0), self.width * grow * (self.g_hi - self.g_lo))
    }

    /// The cell holding the coordinate `center + offset` (the offset given
    /// apart, so that callers can compute it without cancellation).
    pub fn cell(&self, offset: f64) -> usize {
        let g = offset.signum() * (1.0 + offset.abs() / self.width).ln();
        let t = (g - self.g_lo) / (self.g_hi - self.g_lo);
        ((t * self.cells as f64).floor().max(0.0) as usize).min(self.cells - 1)
    }
}

/// Gauss–Legendre nodes and weights on [0, 1], four points: exact for
/// polynomials of degree 7 over a cell.
pub const GAUSS: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_p_value_is_the_chi_square_tail() {
        // Tabulated quantiles: P(X > x) for X ~ chi-square(k).
        for (k, x, p) in [
            (1usize, 3.841_458_820_694_124, 0.05),
            (10, 23.209_251_158_954_36, 0.01),
            (1000, 1_106.969_074_962_087, 0.01),
            (4, 0.710_723_021_397_325_1, 0.95),
        ] {
            let q = upper_gamma(k as f64 / 2.0, x / 2.0);
            assert!((q - p).abs() < 1e-7, "chi-square({k}) beyond {x}: {q}, not {p}");
        }
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
    }

    #[test]
    fn an_axis_maps_its_cells_back() {
        let axis = Axis::new(0.0, 1.0, 0.999, 1e-4, 64);
        let (lo, _) = axis.at(0.0);
        let (hi, _) = axis.at(1.0);
        assert!(lo.abs() < 1e-12 && (hi - 1.0).abs() < 1e-12, "{lo} {hi}");
        for i in 0..64 {
            let (x, _) = axis.at((i as f64 + 0.5) / 64.0);
            assert_eq!(axis.cell(x - 0.999), i);
        }
        // dx/dt integrates to the axis' length.
        let n = 100_000;
        let length: f64 = (0..n).map(|i| axis.at((i as f64 + 0.5) / n as f64).1 / n as f64).sum();
        assert!((length - 1.0).abs() < 1e-6, "{length}");
    }

    #[test]
    fn pooling_keeps_every_sample_and_a_cell_expected_empty_fails() {
        let expected = [100.0, 100.0, 1.0, 2.0, 3.0, 0.0];
        let fit = pearson(&[100.0, 100.0, 1.0, 2.0, 3.0, 0.0], &expected);
        assert_eq!((fit.statistic, fit.dof, fit.pooled), (0.0, 2, 4));
        assert_eq!(fit.p_value, 1.0);
        let fit = pearson(&[100.0, 100.0, 1.0, 2.0, 3.0, 50.0], &expected);
        assert!(fit.p_value < 1e-6, "{fit:?}");
        assert_eq!(pearson(&[1.0, 0.0], &[0.0, 0.0]).p_value, 0.0);
    }
}
