//! Pearson's chi-square test of a sampling routine against its density, the
//! way pbrt-v4 and Mitsuba 3 test their BSDFs: samples are binned on a grid,
//! the density is integrated over each cell (composite Simpson), cells with
//! fewer than five expected samples are pooled, and the statistic's p-value
//! comes from the regularised incomplete gamma function. Test-only.

use quadric::nalgebra::Vector3;

use crate::sampling::Sampler;
use crate::warp::Basis;

/// A rectangle `[a.0, a.1] × [b.0, b.1]` cut into `na × nb` cells.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    pub a: (f64, f64),
    pub b: (f64, f64),
    pub na: usize,
    pub nb: usize,
}

impl Grid {
    pub fn cells(&self) -> usize {
        self.na * self.nb
    }

    fn cell_of(&self, x: f64, y: f64) -> Option<usize> {
        let i = ((x - self.a.0) / (self.a.1 - self.a.0) * self.na as f64).floor();
        let j = ((y - self.b.0) / (self.b.1 - self.b.0) * self.nb as f64).floor();
        // Values on the far edge (θ = π, a rounding to 2π) go to the last cell.
        let i = (i.max(0.0) as usize).min(self.na - 1);
        let j = (j.max(0.0) as usize).min(self.nb - 1);
        (x.is_finite() && y.is_finite()).then_some(i * self.nb + j)
    }

    /// Counts of points per cell.
    pub fn histogram(&self, points: impl Iterator<Item = (f64, f64)>) -> Vec<f64> {
        let mut counts = vec![0.0; self.cells()];
        for (x, y) in points {
            counts[self.cell_of(x, y).expect("a finite point")] += 1.0;
        }
        counts
    }

    /// The integral of `density` over each cell, by adaptive Simpson in
    /// each axis (pbrt-v4's `AdaptiveSimpson2D`), so that a density with a
    /// jump inside a cell (a cone's rim, a lobe cut by the horizon) still
    /// integrates to within about `tolerance` of the cell's mass.
    pub fn integrate(&self, density: &impl Fn(f64, f64) -> f64, tolerance: f64) -> Vec<f64> {
        let (da, db) = ((self.a.1 - self.a.0) / self.na as f64, (self.b.1 - self.b.0) / self.nb as f64);
        let mut out = Vec::with_capacity(self.cells());
        for i in 0..self.na {
            let a0 = self.a.0 + i as f64 * da;
            for j in 0..self.nb {
                let b0 = self.b.0 + j as f64 * db;
                let inner = |x: f64| adaptive_simpson(&|y| density(x, y), b0, b0 + db, tolerance / da, DEPTH);
                out.push(adaptive_simpson(&inner, a0, a0 + da, tolerance, DEPTH));
            }
        }
        out
    }
}

/// The deepest bisection of one axis of a cell (2¹² pieces at most).
const DEPTH: u32 = 12;

/// `∫ f` over `[a, b]` by adaptive Simpson, with an error near `tolerance`
/// or `depth` bisections at most.
fn adaptive_simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64, tolerance: f64, depth: u32) -> f64 {
    /// An interval `[a, b]` with `f` at its ends and middle.
    #[derive(Clone, Copy)]
    struct Piece {
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
    }
    impl Piece {
        fn simpson(&self) -> f64 {
            (self.b - self.a) / 6.0 * (self.fa + 4.0 * self.fm + self.fb)
        }
    }
    fn step(f: &impl Fn(f64) -> f64, p: Piece, tol: f64, depth: u32) -> f64 {
        let m = 0.5 * (p.a + p.b);
        let left = Piece { a: p.a, b: m, fa: p.fa, fm: f(0.5 * (p.a + m)), fb: p.fm };
        let right = Piece { a: m, b: p.b, fa: p.fm, fm: f(0.5 * (m + p.b)), fb: p.fb };
        let (l, r) = (left.simpson(), right.simpson());
        let delta = l + r - p.simpson();
        if depth == 0 || delta.abs() <= 15.0 * tol {
            return l + r + delta / 15.0;
        }
        step(f, left, tol / 2.0, depth - 1) + step(f, right, tol / 2.0, depth - 1)
    }
    step(f, Piece { a, b, fa: f(a), fm: f(0.5 * (a + b)), fb: f(b) }, tolerance, depth)
}

/// The spherical coordinates `(θ, φ)` of a unit vector, `θ ∈ [0, π]` from
/// `+z`, `φ ∈ [0, 2π)`.
pub(crate) fn spherical(w: &Vector3<f64>) -> (f64, f64) {
    let phi = w.y.atan2(w.x);
    (w.z.clamp(-1.0, 1.0).acos(), if phi < 0.0 { phi + std::f64::consts::TAU } else { phi })
}

/// The unit vector with spherical coordinates `(θ, φ)`.
pub(crate) fn direction(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

/// The sphere in spherical coordinates, as pbrt bins it: `θ` and `φ` cells
/// of equal angle.
pub(crate) const SPHERE: Grid =
    Grid { a: (0.0, std::f64::consts::PI), b: (0.0, std::f64::consts::TAU), na: 24, nb: 48 };

/// `∫ f dω` over the sphere, by adaptive Simpson on [`SPHERE`]'s cells.
pub(crate) fn integrate_sphere(f: impl Fn(&Vector3<f64>) -> f64) -> f64 {
    SPHERE.integrate(&|t: f64, p: f64| f(&direction(t, p)) * t.sin(), 1e-7).iter().sum()
}

/// What a test of a direction sampler found.
#[derive(Debug)]
pub(crate) struct Outcome {
    /// `∫ pdf dω` over the sphere.
    pub mass: f64,
    /// The chi-square p-value of the samples against the pdf.
    pub p: f64,
    /// How many samples failed (`None`).
    pub failed: u64,
}

/// Tests `sample` (a direction from two uniform numbers, or `None` for a
/// sample that failed) against `pdf` (a density in solid angle over the
/// whole sphere) with `n` samples. Failed samples are left out of the
/// histogram (as in pbrt-v4), so they show as a deficit of samples where
/// the pdf expects them, and are counted apart. The grid's `θ` is measured
/// from `pole`: a density with an integrable `1/angle` peak at the pole is
/// bounded in `(θ, φ)` (the `sin θ` of the area element cancels it), so the
/// quadrature stays accurate there.
pub(crate) fn test_directions(
    pole: &Vector3<f64>,
    pdf: impl Fn(&Vector3<f64>) -> f64,
    sample: impl Fn([f64; 2]) -> Option<Vector3<f64>>,
    n: u64,
    seed: u64,
) -> Outcome {
    let basis = Basis::from_z(*pole);
    let mut failed = 0;
    let points: Vec<(f64, f64)> = (0..n)
        .filter_map(|i| {
            let w = sample(Sampler::new(seed, i, 0).uniform2(0));
            if w.is_none() {
                failed += 1;
            }
            w.map(|w| spherical(&basis.to_local(&w)))
        })
        .collect();
    let observed = SPHERE.histogram(points.into_iter());
    let mut expected = SPHERE.integrate(&|t: f64, p: f64| pdf(&basis.to_world(&direction(t, p))) * t.sin(), 1e-7);
    let mass: f64 = expected.iter().sum();
    for e in &mut expected {
        *e *= n as f64;
    }
    Outcome { mass, p: chi_square_p_value(&observed, &expected), failed }
}

/// The p-value of Pearson's statistic for observed against expected counts,
/// cells expecting fewer than 5 pooled (pbrt-v4's `ChiSquareTest`). A
/// sample in a cell of zero expectation gives 0.
pub(crate) fn chi_square_p_value(observed: &[f64], expected: &[f64]) -> f64 {
    const MIN_EXPECTED: f64 = 5.0;
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&i, &j| expected[i].total_cmp(&expected[j]));
    let (mut pooled_o, mut pooled_e, mut pooled_n) = (0.0, 0.0, 0);
    let (mut chsq, mut dof) = (0.0, 0usize);
    for &i in &order {
        if expected[i] == 0.0 {
            if observed[i] > 0.0 {
                return 0.0;
            }
        } else if expected[i] < MIN_EXPECTED {
            pooled_o += observed[i];
            pooled_e += expected[i];
            pooled_n += 1;
        } else if pooled_e > 0.0 && pooled_e < MIN_EXPECTED {
            // The pool is still too small: this cell joins it.
            pooled_o += observed[i];
            pooled_e += expected[i];
            pooled_n += 1;
        } else {
            chsq += (observed[i] - expected[i]).powi(2) / expected[i];
            dof += 1;
        }
    }
    if pooled_n > 0 {
        chsq += (pooled_o - pooled_e).powi(2) / pooled_e;
        dof += 1;
    }
    if dof <= 1 {
        return 1.0;
    }
    gamma_q((dof - 1) as f64 / 2.0, chsq / 2.0)
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, nine terms: about 15 digits).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
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
        // Reflection: Γ(x)Γ(1−x) = π / sin(πx).
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let sum = G[0] + G[1..].iter().enumerate().map(|(i, g)| g / (x + i as f64 + 1.0)).sum::<f64>();
    0.5 * std::f64::consts::TAU.ln() + (x + 0.5) * t.ln() - t + sum.ln()
}

/// The regularised upper incomplete gamma function `Q(a, x) = Γ(a, x)/Γ(a)`:
/// the series for `x < a + 1`, else the continued fraction (Numerical
/// Recipes' `gammq`).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let front = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        1.0 - sum * front
    } else {
        // Lentz's method.
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        front * h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p_values_match_the_chi_square_table() {
        // (statistic, degrees of freedom, upper-tail probability), from the
        // standard tables (e.g. NIST/SEMATECH e-Handbook §1.3.6.7.4).
        for (x, k, p) in [
            (3.841, 1.0, 0.05),
            (6.635, 1.0, 0.01),
            (18.307, 10.0, 0.05),
            (23.209, 10.0, 0.01),
            (124.342, 100.0, 0.05),
            (2.558, 10.0, 0.99),
        ] {
            let q = gamma_q(k / 2.0, x / 2.0);
            assert!((q - p).abs() < 0.01 * p, "χ² = {x}, {k} dof: {q} against {p}");
        }
        // Γ(n) = (n − 1)! and Γ(1/2) = √π.
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-13);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
    }

    #[test]
    fn simpson_integrates_a_smooth_density_over_the_sphere() {
        // ∫ z⁴ dω = 4π/5 (an independent closed form).
        let i = integrate_sphere(|w| w.z.powi(4));
        assert!((i - 4.0 * std::f64::consts::PI / 5.0).abs() < 1e-7, "{i}");
    }

    #[test]
    fn a_sampler_that_disagrees_with_its_pdf_is_rejected() {
        // Uniform-sphere samples tested against the cosine-weighted
        // hemisphere's density: the harness must notice.
        let pdf = |w: &Vector3<f64>| (w.z.max(0.0)) / std::f64::consts::PI;
        let sample = |u: [f64; 2]| {
            let z = 1.0 - 2.0 * u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f64::consts::TAU * u[1];
            Some(Vector3::new(r * phi.cos(), r * phi.sin(), z.abs()))
        };
        let o = test_directions(&Vector3::z(), pdf, sample, 20_000, 1);
        assert!((o.mass - 1.0).abs() < 1e-6);
        assert!(o.p < 1e-10, "p = {}", o.p);
    }
}
