//! Numerically careful building blocks for `sλ² + 2tλ + u <= 0`.

use nalgebra::Vector3;

/// `a·b - c·d` with one rounding error (Kahan's algorithm with FMA):
/// the error of the naive form, which cancels catastrophically when
/// `a·b ≈ c·d`, is recovered exactly by the fused multiply-add.
#[inline(always)]
pub fn difference_of_products(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let cd = c * d;
    let err = (-c).mul_add(d, cd);
    let dop = a.mul_add(b, -cd);
    dop + err
}

/// The exact rounding error of `sum = fl(a + b)`, so that `a + b = sum + err`
/// exactly (Knuth's TwoSum, branch-free; `sum` must be `a + b` as computed).
#[inline(always)]
pub fn two_sum_error(a: f64, b: f64, sum: f64) -> f64 {
    let bb = sum - a;
    (a - (sum - bb)) + (b - bb)
}

/// `a + b` as `(fl(a + b), error)` with `a + b = sum + error` exactly (TwoSum).
#[inline(always)]
pub fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let sum = a + b;
    (sum, two_sum_error(a, b, sum))
}

/// `a·b` as `(fl(a·b), error)` with `a·b = product + error` exactly (one FMA;
/// exact unless the error underflows).
#[inline(always)]
pub fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// The sign (-1, 0 or 1) of `Σ ± x·y·z` over `terms = [(sign, x, y, z)]`,
/// decided exactly: each triple product is split into four doubles without
/// rounding and the doubles are summed as a nonoverlapping expansion
/// (Shewchuk's Grow-Expansion), whose largest nonzero component carries the
/// sign. Exact while no product overflows or underflows. At most 6 terms.
///
/// The rounded sum answers first where its error bound shows its sign
/// (and the expansion would be exact): the same sign, without the
/// expansion's few hundred operations.
pub fn exact_sign_of_sum(terms: &[(f64, f64, f64, f64)]) -> i32 {
    filtered_sign_of_sum(terms).unwrap_or_else(|| expansion_sign_of_sum(terms))
}

/// The sign of `Σ fl(sign·x)·y·z` (the sum [`exact_sign_of_sum`]'s
/// expansion forms) from the rounded sum `S`, where certain: every factor
/// zero or of magnitude in `[2⁻³⁰⁰, 2³⁰⁰]`, so that no product or error
/// term overflows or underflows (the expansion is then exact, and the
/// nonzero triple products are normal numbers, each rounded twice), and
/// `|S|` above `8ε·Σ|products|`, twice the bound `7u·Σ|exact products|`
/// of two roundings per product and five of the sum. `None` otherwise.
#[inline]
fn filtered_sign_of_sum(terms: &[(f64, f64, f64, f64)]) -> Option<i32> {
    const LOW: f64 = 4.909093465297727e-91; // 2⁻³⁰⁰
    const HIGH: f64 = 2.037035976334486e90; // 2³⁰⁰
    let safe = |v: f64| v == 0.0 || (LOW..=HIGH).contains(&v.abs());
    let (mut sum, mut magnitude) = (0.0f64, 0.0f64);
    for &(sign, x, y, z) in terms.iter().take(6) {
        let a = sign * x;
        if !(safe(a) && safe(y) && safe(z)) {
            return None;
        }
        let p = a * y * z;
        sum += p;
        magnitude += p.abs();
    }
    if magnitude == 0.0 {
        // Every product is exactly zero (a nonzero one is at least 2⁻⁹⁰⁰).
        return Some(0);
    }
    let bound = 8.0 * f64::EPSILON * magnitude;
    if sum > bound {
        Some(1)
    } else if sum < -bound {
        Some(-1)
    } else {
        None
    }
}

/// [`exact_sign_of_sum`] by the expansion alone.
fn expansion_sign_of_sum(terms: &[(f64, f64, f64, f64)]) -> i32 {
    let mut e = [0.0f64; 24];
    let mut len = 0;
    for &(sign, x, y, z) in terms.iter().take(6) {
        let (p, pe) = two_product(sign * x, y);
        for part in [p, pe] {
            let (q, qe) = two_product(part, z);
            for b in [q, qe] {
                // Grow-Expansion: add `b` exactly, components stay nonoverlapping.
                let mut acc = b;
                for c in e.iter_mut().take(len) {
                    let (sum, err) = two_sum(acc, *c);
                    *c = err;
                    acc = sum;
                }
                e[len] = acc;
                len += 1;
            }
        }
    }
    e[..len].iter().rev().find(|c| **c != 0.0).map_or(0, |c| if *c > 0.0 { 1 } else { -1 })
}

/// `x·y` as `(sum, error)`: the sum rounded, and an estimate of its rounding
/// error good to about twice the working precision (Dot2).
#[inline(always)]
pub fn dot2(x: &Vector3<f64>, y: &Vector3<f64>) -> (f64, f64) {
    let (mut sum, mut err) = two_product(x.x, y.x);
    for i in 1..3 {
        let (p, pe) = two_product(x[i], y[i]);
        let (s, se) = two_sum(sum, p);
        sum = s;
        err += pe + se;
    }
    (sum, err)
}

/// The two real roots of `sλ² + 2tλ + u` given `disc = t² - su >= 0`,
/// in increasing order, by the stable form `q = -(t + copysign(√disc, t))`,
/// `λ = q/s` and `u/q`: neither root is formed by cancelling `-t ± √disc`.
///
/// Requires `s != 0`. If `q == 0` (then `t = 0` and `disc = 0`, i.e. `u = 0`)
/// both roots are 0.
#[inline(always)]
pub fn stable_roots(s: f64, t: f64, u: f64, disc: f64) -> (f64, f64) {
    // The sign is taken from `s` when `t` is zero, so that the roots are an
    // odd function of `(s, t, u)`: `t` may come out as `+0.0` for both `Q`
    // and `-Q`, and a solid and its complement must share their roots bit
    // for bit.
    let sign = if t == 0.0 { s } else { t };
    let q = -(t + disc.sqrt().copysign(sign));
    if q == 0.0 {
        return (0.0, 0.0);
    }
    let (r1, r2) = (q / s, u / q);
    if r1 <= r2 {
        (r1, r2)
    } else {
        (r2, r1)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// Factors from every range the filter treats differently: zeros, the
    /// safe range, beyond it both ways, and non-finite values.
    fn factor() -> impl Strategy<Value = f64> {
        prop_oneof![
            4 => (-8i32..8).prop_map(|k| f64::from(k) * 0.25),
            4 => -4.0..4.0f64,
            1 => prop::num::f64::ANY,
            1 => (-1100i32..1100, 1.0..2.0f64).prop_map(|(e, m)| m * 2f64.powi(e)),
            1 => Just(-0.0),
        ]
    }

    fn terms() -> impl Strategy<Value = Vec<(f64, f64, f64, f64)>> {
        let sign = prop_oneof![Just(1.0), Just(-1.0), Just(2.0), factor()];
        prop::collection::vec((sign, factor(), factor(), factor()), 0..8)
    }

    proptest! {
        /// The filter answers only what the expansion answers.
        #[test]
        fn the_filter_keeps_the_expansions_sign(terms in terms()) {
            if let Some(sign) = filtered_sign_of_sum(&terms) {
                prop_assert_eq!(sign, expansion_sign_of_sum(&terms));
            }
        }

        /// Sums that cancel to a few ulps or to zero, where the filter must
        /// defer to the expansion.
        #[test]
        fn cancelling_sums_reach_the_expansion(x in factor(), y in factor(), z in factor(), w in factor()) {
            let terms = [(1.0, x, y, z), (-1.0, x, y, z), (1.0, w, f64::EPSILON, 1.0), (1.0, x * y, z, 1.0)];
            prop_assert_eq!(exact_sign_of_sum(&terms), expansion_sign_of_sum(&terms));
            let terms = [(1.0, x, y, z), (-1.0, z, y, x)];
            prop_assert_eq!(exact_sign_of_sum(&terms), expansion_sign_of_sum(&terms));
        }
    }

    /// Factors in the filter's safe range `[2⁻³⁰⁰, 2³⁰⁰]`, or zero.
    fn safe_factor() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => (-290i32..290, 1.0..2.0f64, any::<bool>())
                .prop_map(|(e, m, neg)| if neg { -m * 2f64.powi(e) } else { m * 2f64.powi(e) }),
            1 => Just(0.0),
        ]
    }

    proptest! {
        /// The filter is the fast path: it decides every sum of safe
        /// factors whose rounded value clears sixteen times the rounding
        /// (twice its own bound), so that the expansion runs only near
        /// cancellation; all-zero sums included.
        #[test]
        fn the_filter_decides_clear_sums(
            terms in prop::collection::vec((prop_oneof![Just(1.0), Just(-1.0)], safe_factor(), safe_factor(), safe_factor()), 1..7)
        ) {
            let sum: f64 = terms.iter().map(|&(sg, x, y, z)| sg * x * y * z).sum();
            let magnitude: f64 = terms.iter().map(|&(sg, x, y, z)| (sg * x * y * z).abs()).sum();
            if magnitude == 0.0 || sum.abs() > 16.0 * f64::EPSILON * magnitude {
                prop_assert_eq!(filtered_sign_of_sum(&terms), Some(expansion_sign_of_sum(&terms)));
            }
        }

        /// Outside the safe range the filter's bound is not proven, and it
        /// defers whichever factor is out.
        #[test]
        fn the_filter_defers_factors_beyond_its_range(
            x in safe_factor(), y in safe_factor(), at in 0usize..3, tiny in any::<bool>()
        ) {
            let out = if tiny { 2f64.powi(-400) } else { 2f64.powi(400) };
            let mut f = [x.max(1.0), y.max(1.0), 1.0];
            f[at] = out;
            prop_assert_eq!(filtered_sign_of_sum(&[(1.0, f[0], f[1], f[2])]), None);
        }
    }

    #[test]
    fn semi_definite_minors() {
        // A diagonal matrix's minors (the quadrics of spheres and tubes).
        assert_eq!(exact_sign_of_sum(&[(1.0, 1.0, 1.0, 1.0), (-1.0, 0.0, 0.0, 1.0)]), 1);
        assert_eq!(exact_sign_of_sum(&[(1.0, 1.0, 0.0, 1.0), (-1.0, 0.0, 0.0, 1.0)]), 0);
        // (1 + 2⁻⁵²)² - (1 + 2⁻⁵¹) = 2⁻¹⁰⁴, whose rounded sum is zero.
        let (u, w) = (1.0 + f64::EPSILON, 1.0 + 2.0 * f64::EPSILON);
        assert_eq!(filtered_sign_of_sum(&[(1.0, u, u, 1.0), (-1.0, w, 1.0, 1.0)]), None);
        assert_eq!(exact_sign_of_sum(&[(1.0, u, u, 1.0), (-1.0, w, 1.0, 1.0)]), 1);
        assert_eq!(exact_sign_of_sum(&[(-1.0, u, u, 1.0), (1.0, w, 1.0, 1.0)]), -1);
    }
}
