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
pub fn exact_sign_of_sum(terms: &[(f64, f64, f64, f64)]) -> i32 {
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

/// Whether `x` is negative, treating `-0.0` as zero.
#[inline(always)]
pub fn is_negative(x: f64) -> bool {
    x < 0.0
}

/// Whether `x` is positive, treating `-0.0` as zero.
#[inline(always)]
pub fn is_positive(x: f64) -> bool {
    x > 0.0
}
