//! Exact settlement for [`Precision::Certified`](crate::Precision): the
//! coefficients `s`, `t`, `u` of a ray's quadratic are polynomials in the
//! stored doubles (the ray's origin and direction, the solid's centre and
//! coefficients), so they are exact dyadic rationals `m · 2^e`. Every sign
//! that decides a hit, a miss, a tangency or the order of two roots is
//! decided here without rounding; only the roots' values are rounded (to
//! [`BITS`] bits, then to the nearest double).
//!
//! Used only for the rare rays whose floating-point answer is ambiguous
//! within its error bound; this path allocates (big integers).

use core::cmp::Ordering;

use nalgebra::{Matrix3, Vector3};
use num_bigint::{BigInt, Sign};

use crate::Ray;

/// Bits kept by the rounded operations (square root, division): far beyond
/// the 53 of the double a root is rounded to.
pub(crate) const BITS: u64 = 160;

/// A dyadic rational `m · 2^e`, exact under `+`, `-`, `*`.
#[derive(Clone, Debug)]
pub(crate) struct Dyadic {
    m: BigInt,
    e: i64,
}

impl Dyadic {
    pub(crate) fn zero() -> Dyadic {
        Dyadic { m: BigInt::from(0), e: 0 }
    }

    /// The exact value of a finite double (callers check finiteness).
    pub(crate) fn from_f64(x: f64) -> Dyadic {
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i64;
        let frac = bits & ((1 << 52) - 1);
        let (mant, e) = if exp == 0 { (frac, -1074) } else { (frac | (1 << 52), exp - 1075) };
        let m = BigInt::from(mant);
        Dyadic { m: if bits >> 63 == 1 { -m } else { m }, e }
    }

    /// -1, 0 or 1.
    pub(crate) fn signum(&self) -> i32 {
        match self.m.sign() {
            Sign::Minus => -1,
            Sign::NoSign => 0,
            Sign::Plus => 1,
        }
    }

    pub(crate) fn add(&self, o: &Dyadic) -> Dyadic {
        let e = self.e.min(o.e);
        Dyadic { m: (&self.m << (self.e - e) as usize) + (&o.m << (o.e - e) as usize), e }
    }

    pub(crate) fn sub(&self, o: &Dyadic) -> Dyadic {
        self.add(&o.neg())
    }

    pub(crate) fn mul(&self, o: &Dyadic) -> Dyadic {
        Dyadic { m: &self.m * &o.m, e: self.e + o.e }
    }

    pub(crate) fn neg(&self) -> Dyadic {
        Dyadic { m: -&self.m, e: self.e }
    }

    fn scale2(&self, k: i64) -> Dyadic {
        Dyadic { m: self.m.clone(), e: self.e + k }
    }

    /// `self / o` truncated to about [`BITS`] bits (`o != 0`).
    fn div(&self, o: &Dyadic) -> Dyadic {
        let shift = (BITS as i64 + o.m.bits() as i64 - self.m.bits() as i64 + 2).max(0);
        Dyadic { m: (&self.m << shift as usize) / &o.m, e: self.e - shift - o.e }
    }

    /// `√self` for `self >= 0`, truncated to about [`BITS`] bits.
    fn sqrt(&self) -> Dyadic {
        if self.signum() <= 0 {
            return Dyadic::zero();
        }
        let mut shift = (2 * BITS as i64 - self.m.bits() as i64 + 2).max(0);
        if (self.e - shift) % 2 != 0 {
            shift += 1;
        }
        Dyadic { m: (&self.m << shift as usize).sqrt(), e: (self.e - shift) / 2 }
    }

    /// The nearest double (ties to even; `±∞` beyond the range, subnormals
    /// rounded through the scaling).
    pub(crate) fn to_f64(&self) -> f64 {
        let n = self.m.bits() as i64;
        if n == 0 {
            return 0.0;
        }
        let mag = self.m.magnitude();
        let (q, e) = if n <= 53 {
            (mag.clone(), self.e)
        } else {
            let shift = (n - 53) as usize;
            let q = mag >> shift;
            let rem = mag - (&q << shift);
            let half = num_bigint::BigUint::from(1u8) << (shift - 1);
            let up = rem > half || (rem == half && q.bit(0));
            (if up { q + 1u8 } else { q }, self.e + shift as i64)
        };
        let q = q.iter_u64_digits().next().unwrap_or(0) as f64;
        let v = ldexp(q, e);
        if self.signum() < 0 {
            -v
        } else {
            v
        }
    }
}

/// `x · 2^e` (saturating to `±∞` or `0`).
fn ldexp(mut x: f64, mut e: i64) -> f64 {
    let step = |k: i64| f64::from_bits(((k + 1023) as u64) << 52);
    while e > 1000 && x.is_finite() {
        x *= step(1000);
        e -= 1000;
    }
    while e < -1000 && x != 0.0 {
        x *= step(-1000);
        e += 1000;
    }
    x * step(e.clamp(-1022, 1023))
}

type V3 = [Dyadic; 3];

fn v3(x: &Vector3<f64>) -> V3 {
    [0, 1, 2].map(|i| Dyadic::from_f64(x[i]))
}

fn dot(a: &V3, b: &V3) -> Dyadic {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}

/// The exact coefficients of `f(p + λr) = sλ² + 2tλ + u` from the ray's
/// origin, for `f(x) = (x-c)ᵀA(x-c) + 2wᵀ(x-c) + k` given by doubles.
pub(crate) struct Exact {
    pub(crate) s: Dyadic,
    pub(crate) t: Dyadic,
    pub(crate) u: Dyadic,
}

impl Exact {
    pub(crate) fn new(c: &Vector3<f64>, a: &Matrix3<f64>, w: &Vector3<f64>, k: f64, ray: &Ray) -> Exact {
        let (p, r) = (ray.origin().coords, ray.direction());
        let (p, r, c, w) = (v3(&p), v3(&r), v3(c), v3(w));
        let rows = [0, 1, 2].map(|i| v3(&a.row(i).transpose()));
        let d = [0, 1, 2].map(|i| p[i].sub(&c[i]));
        let ar = [0, 1, 2].map(|i| dot(&rows[i], &r));
        // Half the gradient at the origin, `A d + w`.
        let g = [0, 1, 2].map(|i| dot(&rows[i], &d).add(&w[i]));
        let s = dot(&r, &ar);
        let t = dot(&r, &g);
        let gw = [0, 1, 2].map(|i| g[i].add(&w[i]));
        let u = dot(&d, &gw).add(&Dyadic::from_f64(k));
        Exact { s, t, u }
    }

    /// `t² - su`, exact.
    pub(crate) fn discriminant(&self) -> Dyadic {
        self.t.mul(&self.t).sub(&self.s.mul(&self.u))
    }

    /// The root `(-t - u/(2t))` of the linear case `s = 0`, as an [`ExactRoot`].
    pub(crate) fn linear_root(&self) -> ExactRoot {
        ExactRoot { a: self.u.neg(), b: 0, d: Dyadic::zero(), e: self.t.scale2(1) }
    }

    /// The smaller (`larger = false`) or larger root `(-t ± √D)/s` of the
    /// quadratic case (`s != 0`, `D = t² - su >= 0`).
    pub(crate) fn quadratic_root(&self, larger: bool) -> ExactRoot {
        // (-t + σ√D)/s is the larger root for σ·s > 0.
        let plus = larger == (self.s.signum() > 0);
        ExactRoot { a: self.t.neg(), b: if plus { 1 } else { -1 }, d: self.discriminant(), e: self.s.clone() }
    }
}

/// A real number `(a + b√d)/e` with `b ∈ {-1, 0, 1}`, `d >= 0`, `e != 0`:
/// every root the kernel reports, held exactly.
#[derive(Clone, Debug)]
pub(crate) struct ExactRoot {
    a: Dyadic,
    b: i32,
    d: Dyadic,
    e: Dyadic,
}

impl ExactRoot {
    /// The nearest double, to within an ulp (the value is computed to
    /// [`BITS`] bits first).
    pub(crate) fn to_f64(&self) -> f64 {
        let sq = if self.b == 0 { Dyadic::zero() } else { self.d.sqrt() };
        let num = if self.b < 0 { self.a.sub(&sq) } else { self.a.add(&sq) };
        // Cancellation in `a ± √d` is harmless here: `a` and `√d` carry
        // `BITS` bits each, far more than the result needs unless it is
        // nearly zero, where it is formed by the other root's product
        // (`num · other = a² - d`) instead.
        let other = if self.b < 0 { self.a.add(&sq) } else { self.a.sub(&sq) };
        let magnitude = |x: &Dyadic| x.m.bits() as i64 + x.e;
        let cancels = num.signum() == 0 || magnitude(&num) + 64 < magnitude(&self.a);
        let value = if self.b != 0 && cancels && other.signum() != 0 {
            // (a + b√d)(a - b√d) = a² - d, so the root is (a² - d)/(e (a - b√d)).
            self.a.mul(&self.a).sub(&self.d).div(&self.e.mul(&other))
        } else {
            num.div(&self.e)
        };
        value.to_f64()
    }

    /// The sign of the root (`a + b√d` over `e`).
    pub(crate) fn signum(&self) -> i32 {
        sign_of(&self.a, self.b, &self.d) * self.e.signum()
    }

    /// The exact order of two roots.
    pub(crate) fn cmp(&self, o: &ExactRoot) -> Ordering {
        // x/e1 - y/e2 has the sign of (x e2 - y e1) · sign(e1 e2), with
        // x e2 - y e1 = (a1 e2 - a2 e1) + b1 e2 √d1 - b2 e1 √d2.
        let c = self.a.mul(&o.e).sub(&o.a.mul(&self.e));
        let p = scaled(self.b, &o.e);
        let q = scaled(o.b, &self.e).neg();
        let sign = sign_of_three(&c, &p, &self.d, &q, &o.d) * self.e.signum() * o.e.signum();
        sign.cmp(&0)
    }
}

/// `b · x` for `b ∈ {-1, 0, 1}`.
fn scaled(b: i32, x: &Dyadic) -> Dyadic {
    match b {
        0 => Dyadic::zero(),
        b if b > 0 => x.clone(),
        _ => x.neg(),
    }
}

/// The sign of `a + b√d` (`b ∈ {-1, 0, 1}`, `d >= 0`).
fn sign_of(a: &Dyadic, b: i32, d: &Dyadic) -> i32 {
    sign_of_sum(a, &scaled(b, &Dyadic::from_f64(1.0)), d)
}

/// The sign of `a + p√d` (`d >= 0`): where the two terms disagree in sign,
/// compare their squares.
fn sign_of_sum(a: &Dyadic, p: &Dyadic, d: &Dyadic) -> i32 {
    let (sa, sp) = (a.signum(), if d.signum() == 0 { 0 } else { p.signum() });
    if sp == 0 || sa == sp {
        return if sa != 0 { sa } else { sp };
    }
    if sa == 0 {
        return sp;
    }
    // Opposite signs: |a| vs |p|√d, i.e. a² vs p²d.
    let diff = a.mul(a).sub(&p.mul(p).mul(d));
    diff.signum() * sa
}

/// The sign of `c + p√d1 + q√d2` (`d1, d2 >= 0`): with `L = c + p√d1` and
/// `R = -q√d2`, `L - R` has the sign of `L` and `-R` where they agree, else
/// of `L² - R² = (c² + p²d1 - q²d2) + 2cp√d1` times the sign of `L`.
fn sign_of_three(c: &Dyadic, p: &Dyadic, d1: &Dyadic, q: &Dyadic, d2: &Dyadic) -> i32 {
    let sl = sign_of_sum(c, p, d1);
    let sr = if d2.signum() == 0 { 0 } else { -q.signum() };
    if sr == 0 {
        return sl;
    }
    if sl == 0 {
        return -sr;
    }
    if sl != sr {
        return sl;
    }
    let rest = c.mul(c).add(&p.mul(p).mul(d1)).sub(&q.mul(q).mul(d2));
    let cross = c.mul(p).scale2(1);
    sign_of_sum(&rest, &cross, d1) * sl
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root(a: f64, b: i32, d: f64, e: f64) -> ExactRoot {
        ExactRoot { a: Dyadic::from_f64(a), b, d: Dyadic::from_f64(d), e: Dyadic::from_f64(e) }
    }

    #[test]
    fn roots_compare_exactly() {
        // √2 vs 1.5: 1.5 is larger.
        assert_eq!(root(0.0, 1, 2.0, 1.0).cmp(&root(1.5, 0, 0.0, 1.0)), Ordering::Less);
        // (1 + √2)/2 vs (3 - √2)/... : 1.2071 vs 0.7929 (with e = 2).
        assert_eq!(root(1.0, 1, 2.0, 2.0).cmp(&root(3.0, -1, 2.0, 2.0)), Ordering::Greater);
        // √8/2 = √2 exactly.
        assert_eq!(root(0.0, 1, 8.0, 2.0).cmp(&root(0.0, 1, 2.0, 1.0)), Ordering::Equal);
        // Negative denominators flip.
        assert_eq!(root(1.0, 0, 0.0, -1.0).cmp(&root(0.0, 0, 0.0, 1.0)), Ordering::Less);
        // √2 + √3 vs √(5 + 2√6) = √2 + √3, written as 1·√2 and (√3 + ...): use 1 + √2 vs √(3 + 2√2).
        // (√3 - 1) vs (√2 - 0.3): 0.7320 vs 1.1142.
        assert_eq!(root(-1.0, 1, 3.0, 1.0).cmp(&root(-0.3, 1, 2.0, 1.0)), Ordering::Less);
        // √3 - √2 vs 0.3178 (0.31783724...): tighter.
        assert_eq!(root(0.0, 1, 3.0, 1.0).cmp(&root(0.3178, 1, 2.0, 1.0)), Ordering::Greater);
        assert_eq!(root(0.0, 1, 3.0, 1.0).cmp(&root(0.3179, 1, 2.0, 1.0)), Ordering::Less);
        assert_eq!(root(0.0, 1, 2.0, 1.0).signum(), 1);
        assert_eq!(root(1.0, -1, 2.0, 1.0).signum(), -1);
        assert_eq!(root(1.0, -1, 1.0, 3.0).signum(), 0);
    }

    #[test]
    fn roots_round_to_the_nearest_double() {
        assert_eq!(root(0.0, 1, 2.0, 1.0).to_f64(), 2f64.sqrt());
        // √2 - 1 = 0.41421356237309504880…; `2f64.sqrt() - 1.0` is an ulp off.
        assert_eq!(root(-1.0, 1, 2.0, 1.0).to_f64(), 0.414_213_562_373_095_03);
        // A small root formed by cancellation: 2⁶⁰ - √(2¹²⁰ - 2⁶⁸) = 2⁷ (1 + 2⁻⁵⁴ + …).
        assert_eq!(root(2f64.powi(60), -1, 2f64.powi(120) - 2f64.powi(68), 1.0).to_f64(), 128.0);
    }
}
