//! The compensated primitives of `quadric::roots` against exact arithmetic
//! (`reference::Big`, dyadic rationals: `+ - ×` without rounding). Each
//! primitive promises an error bound far below the naive formula's, so every
//! case is built to cancel: a primitive that lost its compensation (a dropped
//! FMA or error term) breaks the bound.

use proptest::prelude::*;
use quadric::nalgebra::Vector3;
use quadric::roots::{
    difference_of_products, dot2, exact_sign_of_sum, stable_roots, two_product, two_sum, two_sum_error,
};
use reference::Big;

const U: f64 = f64::EPSILON / 2.0;

fn big(x: f64) -> Big {
    Big::from_f64(x)
}

/// `|computed - exact| ≤ bound`, decided exactly.
fn within(computed: f64, exact: &Big, bound: f64) -> bool {
    (&big(computed) - exact).abs().to_f64() <= bound
}

/// `|x|` of an exact value, rounded (for bounds only).
fn magnitude(x: &Big) -> f64 {
    x.abs().to_f64()
}

/// Exactly `a·b - c·d`.
fn exact_dop(a: f64, b: f64, c: f64, d: f64) -> Big {
    &(&big(a) * &big(b)) - &(&big(c) * &big(d))
}

/// Kahan's difference of products with FMA is within `2u` of the exact
/// value, relative (Jeannerod, Louvet and Muller 2013).
fn check_dop(a: f64, b: f64, c: f64, d: f64) {
    let exact = exact_dop(a, b, c, d);
    let got = difference_of_products(a, b, c, d);
    assert!(
        within(got, &exact, 2.0 * U * magnitude(&exact)),
        "difference_of_products({a:e}, {b:e}, {c:e}, {d:e}) = {got:e}, exact {:e}",
        exact.to_f64()
    );
}

#[test]
fn difference_of_products_is_exact_to_two_units_where_the_naive_form_cancels() {
    let e = f64::EPSILON;
    // (rows: a, b, c, d) `c·d` is inexact and `a·b` nearly equals it, so the
    // product's lost bits are the whole answer.
    for (a, b, c, d) in [
        (1.0 + e, 1.0 + e, 1.0 + 2.0 * e, 1.0),
        (1.0 + 2f64.powi(-30), 1.0 + 2f64.powi(-30), 1.0 + 2f64.powi(-29), 1.0),
        (1.0, 1.0 + 2f64.powi(-29), 1.0 + 2f64.powi(-30), 1.0 + 2f64.powi(-30)),
        (3.0 + e * 3.0, 7.0 - e, 7.0 + e, 3.0 + e),
        (0.1, 0.1, 0.01, 1.0),
        (1e150, 1e150, 1e150, 1e150 * (1.0 + e)),
        (-2.5, 1.0 / 3.0, 5.0 / 6.0, -1.0),
        (0.0, 5.0, 0.0, 7.0),
    ] {
        check_dop(a, b, c, d);
    }
}

#[test]
fn the_naive_difference_of_products_fails_the_same_bound() {
    // The bound is tight enough to see the compensation: the plain formula
    // misses it on the first case above by the whole answer.
    let (a, b, c, d) = (1.0 + f64::EPSILON, 1.0 + f64::EPSILON, 1.0 + 2.0 * f64::EPSILON, 1.0);
    let exact = exact_dop(a, b, c, d);
    assert!(!within(a * b - c * d, &exact, 2.0 * U * magnitude(&exact)));
}

/// Factors of moderate exponent, so that no product or error term
/// overflows or underflows (where the primitives are exact by contract).
fn factor() -> impl Strategy<Value = f64> {
    prop_oneof![(-60i32..60, 1.0..2.0f64).prop_map(|(k, m)| m * 2f64.powi(k)), -1e6..1e6f64,]
        .prop_flat_map(|x| prop_oneof![Just(x), Just(-x)])
}

proptest! {
    /// TwoSum's pair is the exact sum, and its first half the rounded one.
    #[test]
    fn two_sum_is_exact(a in factor(), b in factor()) {
        let (s, err) = two_sum(a, b);
        prop_assert_eq!(s, a + b);
        prop_assert_eq!(err, two_sum_error(a, b, s));
        prop_assert_eq!((&big(s) + &big(err)).to_f64(), s);
        prop_assert_eq!((&(&big(s) + &big(err)) - &(&big(a) + &big(b))).signum(), 0);
    }

    /// TwoProduct's pair is the exact product.
    #[test]
    fn two_product_is_exact(a in factor(), b in factor()) {
        let (p, err) = two_product(a, b);
        prop_assert_eq!(p, a * b);
        prop_assert_eq!((&(&big(p) + &big(err)) - &(&big(a) * &big(b))).signum(), 0);
    }

    /// Difference of products near cancellation: `a·b` is `c·d` moved by a
    /// few ulps of `a`, the case the root finder's discriminant meets.
    #[test]
    fn difference_of_products_stays_within_two_units(
        a in factor(), c in factor(), d in factor(), k in -8i32..8
    ) {
        // `b` so that `a·b ≈ c·d`, then moved by `k` ulps.
        let b0 = (c * d) / a;
        let b = b0 + f64::from(k) * b0.abs() * f64::EPSILON;
        prop_assume!(b.is_finite());
        check_dop(a, b, c, d);
    }

    /// Dot2's pair is the dot product to about twice the working precision:
    /// `|sum + err - x·y| ≤ 8u²·Σ|xᵢyᵢ|` (Ogita, Rump and Oishi 2005, with
    /// room), far below the `u·Σ|xᵢyᵢ|` of the plain sum.
    #[test]
    fn dot2_is_accurate_to_twice_the_precision(
        x in prop::array::uniform3(factor()), y in prop::array::uniform3(factor())
    ) {
        let (xv, yv) = (Vector3::from(x), Vector3::from(y));
        let (sum, err) = dot2(&xv, &yv);
        let exact = (0..3).fold(Big::zero(), |acc, i| &acc + &(&big(x[i]) * &big(y[i])));
        let scale: f64 = (0..3).map(|i| (x[i] * y[i]).abs()).sum();
        let pair = &big(sum) + &big(err);
        prop_assert!(magnitude(&(&pair - &exact)) <= 8.0 * U * U * scale,
            "dot2({x:?}, {y:?}) = {sum:e} + {err:e}, exact {:e}", exact.to_f64());
    }

    /// Cancelling dot products, where the plain sum's error is its size:
    /// the same bound holds.
    #[test]
    fn dot2_keeps_its_bound_where_the_sum_cancels(a in factor(), b in factor(), c in factor()) {
        let x = [a, b, a];
        let y = [c, 1.0 + f64::EPSILON, -c * (1.0 + f64::EPSILON)];
        let (sum, err) = dot2(&Vector3::from(x), &Vector3::from(y));
        let exact = (0..3).fold(Big::zero(), |acc, i| &acc + &(&big(x[i]) * &big(y[i])));
        let scale: f64 = (0..3).map(|i| (x[i] * y[i]).abs()).sum();
        prop_assert!(magnitude(&(&(&big(sum) + &big(err)) - &exact)) <= 8.0 * U * U * scale);
    }

    /// The stable roots of `sλ² + 2tλ + u`, from the discriminant that
    /// `difference_of_products` gives, are within `6u` (relative) of the
    /// exact roots `(-t ∓ √(t² - su))/s`: `2u` from the discriminant (half of
    /// it after the square root), one rounding each in the square root, the
    /// sum of like signs and the division — no cancellation anywhere.
    #[test]
    fn stable_roots_are_within_six_units_of_the_exact_roots(
        s in factor(), t in factor(), u in factor()
    ) {
        prop_assume!(s != 0.0);
        // Two real roots: `su < 0` makes `t² - su` positive.
        let u = if (s > 0.0) == (u > 0.0) && difference_of_products(t, t, s, u) <= 0.0 { -u } else { u };
        let disc = difference_of_products(t, t, s, u);
        prop_assume!(disc > 0.0 && disc.is_finite());
        let (r1, r2) = stable_roots(s, t, u, disc);
        let (bs, bt) = (big(s), big(t));
        let root = (&(&bt * &bt) - &(&bs * &big(u))).sqrt();
        // The exact roots by Vieta's pair `q/s`, `u/q` with `q = -(t ± √)`
        // of like signs: the same numbers as `(-t ∓ √)/s`, but 256-bit
        // truncation would lose the small one to cancellation.
        let q = if t >= 0.0 { -&(&bt + &root) } else { &root - &bt };
        let a = q.div(&bs);
        let b = big(u).div(&q);
        let (lo, hi) = if (&a - &b).signum() <= 0 { (a, b) } else { (b, a) };
        for (got, exact) in [(r1, lo), (r2, hi)] {
            prop_assert!(within(got, &exact, 6.0 * U * magnitude(&exact)),
                "stable_roots({s:e}, {t:e}, {u:e}) root {got:e}, exact {:e}", exact.to_f64());
        }
    }

    /// The exact sign of a sum of triple products, against the dyadic sum.
    #[test]
    fn exact_sign_of_sum_is_the_dyadic_sign(
        terms in prop::collection::vec((prop_oneof![Just(1.0), Just(-1.0)], factor(), factor(), factor()), 0..7),
        cancel in any::<bool>()
    ) {
        let mut terms = terms;
        if cancel && !terms.is_empty() {
            // A near-copy with the other sign: the sum cancels to a few ulps.
            let (sg, x, y, z) = terms[0];
            terms.truncate(5);
            terms.push((-sg, x * (1.0 + f64::EPSILON), y, z));
        }
        let exact = terms.iter().fold(Big::zero(), |acc, &(sg, x, y, z)| {
            &acc + &(&(&big(sg * x) * &big(y)) * &big(z))
        });
        prop_assert_eq!(exact_sign_of_sum(&terms), exact.signum());
    }
}

#[test]
fn exact_sign_of_sum_sees_a_sum_below_the_rounding() {
    // (1 + 2⁻⁵²)² - (1 + 2⁻⁵¹) = 2⁻¹⁰⁴: the rounded sum is zero.
    let (u, w) = (1.0 + f64::EPSILON, 1.0 + 2.0 * f64::EPSILON);
    assert_eq!(exact_sign_of_sum(&[(1.0, u, u, 1.0), (-1.0, w, 1.0, 1.0)]), 1);
    assert_eq!(exact_sign_of_sum(&[(-1.0, u, u, 1.0), (1.0, w, 1.0, 1.0)]), -1);
    assert_eq!(exact_sign_of_sum(&[(1.0, u, w, 1.0), (-1.0, w, u, 1.0)]), 0);
}
