//! Precision modes of the kernel: [`Precision::Fast`], [`Precision::Accurate`]
//! (the default) and [`Precision::Certified`], and the certified roots with
//! their rigorous error bounds. See `docs/quadric.md`, "Precision modes".

use nalgebra::{Matrix3, Point3, Vector3};

use super::{from, linear_set, quadratic_set, up_to, whole_ray, Quadric};
use crate::exact::{Exact, ExactRoot};
use crate::interval::{Bound, IntervalSet, Pieces};
use crate::roots::{difference_of_products, two_sum_error};
use crate::{HalfSpace, Ray, Solid};

/// How the kernel trades speed for accuracy (see `docs/quadric.md`,
/// "Precision modes", for the measured cost and error of each).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Precision {
    /// The textbook evaluation at the ray's origin: `s`, `t`, `u` from
    /// `d = p - c` (no re-basing near the roots, no compensated sums), the
    /// discriminant `t² - su` as written, the stable root pair. For a camera
    /// far from a solid its error grows with the distance, like a
    /// world-space kernel's.
    Fast,
    /// The local-centre, re-based kernel of `docs/quadric.md`: hit points
    /// within about an ulp of the true surface at any distance. The default,
    /// chosen by the measurements (it costs little more than `Fast`).
    #[default]
    Accurate,
    /// Every root with a rigorous error bound ([`CertifiedIntervals`]), and
    /// every decision the bounds leave open (tangency, the sign of `s`, an
    /// end within its bound of the ray's origin, two roots within their
    /// bounds of each other) settled in exact arithmetic: no false hit or
    /// miss. Costs a few times `Accurate` (and allocates in the rare exact
    /// settlements).
    Certified,
}

/// A surface crossing `λ` with a rigorous bound: the true crossing of the
/// ray with the surface the stored doubles define lies in `[t - error, t + error]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CertifiedRoot {
    /// The computed crossing.
    pub t: f64,
    /// The bound on its error (`>= 0`).
    pub error: f64,
}

/// The interval set of [`Precision::Certified`] with the bound of each end.
#[derive(Clone, Copy, Debug)]
pub struct CertifiedIntervals {
    /// The set (the same conventions as [`Quadric::intervals`]); its shape
    /// (number of intervals, which ends are crossings) is exact.
    pub set: IntervalSet,
    roots: [CertifiedRoot; 2],
    count: usize,
    /// Whether the answer was settled in exact arithmetic.
    pub settled_exactly: bool,
}

impl CertifiedIntervals {
    fn new(set: Pieces, roots: &[CertifiedRoot], settled_exactly: bool) -> Self {
        let mut r = [CertifiedRoot { t: 0.0, error: 0.0 }; 2];
        let count = roots.len().min(2);
        r[..count].copy_from_slice(&roots[..count]);
        CertifiedIntervals { set: set.into(), roots: r, count, settled_exactly }
    }

    /// The set as [`Pieces`]: a solid's certified set has at most two
    /// intervals, since it is built as pieces (checked in debug builds).
    fn pieces(&self) -> Pieces {
        let s = self.set.as_slice();
        debug_assert!(s.len() <= 2, "a solid's certified set {} has more than two intervals", self.set);
        let piece = |k: usize| s.get(k).map_or_else(Pieces::empty, |iv| Pieces::from_interval(iv.enter, iv.exit));
        piece(0).then(piece(1)).unwrap_or_else(|| piece(0))
    }

    /// The same answer with the values of `other` (a set of the same
    /// shape, else `self` unchanged), each bound widened by the distance
    /// between the two values (`|x - λ| <= |x - t| + |t - λ|`).
    fn with_values_of(&self, other: &IntervalSet) -> Self {
        let ends = |set: &IntervalSet| {
            let mut out = [Bound::free(0.0); 2 * IntervalSet::CAPACITY];
            for (k, iv) in set.iter().enumerate() {
                (out[2 * k], out[2 * k + 1]) = (iv.enter, iv.exit);
            }
            (out, 2 * set.len())
        };
        let ((mine, n), (theirs, m)) = (ends(&self.set), ends(other));
        if n != m || mine[..n].iter().zip(&theirs[..m]).any(|(a, b)| a.solid != b.solid) {
            return *self;
        }
        let mut out = *self;
        for (a, b) in mine[..n].iter().zip(&theirs[..m]) {
            if a.solid().is_none() {
                continue;
            }
            for root in out.roots[..out.count].iter_mut() {
                if root.t + 0.0 == a.t {
                    *root = CertifiedRoot { t: b.t, error: up(root.error + (b.t - a.t).abs()) };
                }
            }
        }
        // The order of the roots is certified; the new values keep it
        // unless two roots moved within their bounds (then keep the old).
        if out.roots().windows(2).any(|w| w[0].t > w[1].t) {
            return *self;
        }
        out.set = *other;
        out
    }

    /// The crossings of the whole line (before clipping to `λ >= 0`), in
    /// increasing order, with their bounds.
    pub fn roots(&self) -> &[CertifiedRoot] {
        &self.roots[..self.count]
    }

    /// The error bound of the end at `t`: that of the root computed as `t`,
    /// `0` for a free end (the ray's origin, `∞`) and for `t` no root gave.
    pub fn error_at(&self, t: f64) -> f64 {
        self.roots().iter().filter(|r| r.t + 0.0 == t).map(|r| r.error).fold(0.0, f64::max)
    }

    /// The largest bound of any finite end of the set.
    pub fn max_error(&self) -> f64 {
        self.set
            .iter()
            .flat_map(|iv| [iv.enter, iv.exit])
            .filter(|b| b.solid().is_some())
            .map(|b| self.error_at(b.t))
            .fold(0.0, f64::max)
    }
}

impl Quadric {
    /// [`Quadric::intervals`] in the given precision mode.
    #[inline]
    pub fn intervals_with(&self, ray: &Ray, solid: u32, precision: Precision) -> IntervalSet {
        match precision {
            Precision::Accurate => self.intervals_accurate(ray, solid).into(),
            Precision::Fast => self.intervals_fast(ray, solid).into(),
            Precision::Certified => self.intervals_certified(ray, solid).set,
        }
    }

    /// [`Quadric::intervals_with`] as [`Pieces`]: the same intervals
    /// without an [`IntervalSet`]'s buffer, for a caller that reads one
    /// solid's set and moves on (the ray kernels of a block).
    #[inline]
    pub fn pieces_with(&self, ray: &Ray, solid: u32, precision: Precision) -> Pieces {
        match precision {
            Precision::Accurate => self.intervals_accurate(ray, solid),
            Precision::Fast => self.intervals_fast(ray, solid),
            Precision::Certified => self.intervals_certified(ray, solid).pieces(),
        }
    }

    /// [`Precision::Fast`]: everything from the ray's origin, as written.
    #[inline(never)]
    fn intervals_fast(&self, ray: &Ray, solid: u32) -> Pieces {
        let (p, r) = (ray.origin().coords, ray.direction());
        let d = p - self.centre;
        let ar = self.a * r;
        let g = self.a * d + self.w;
        let s = r.dot(&ar);
        let s = match self.definite {
            Some(true) => s.max(0.0),
            Some(false) => s.min(0.0),
            None => s,
        };
        let t = r.dot(&g);
        let u = d.dot(&(g + self.w)) + self.k;
        if s == 0.0 {
            return linear_set(t, u, 0.0, solid);
        }
        quadratic_set(s, t, u, t * t - s * u, 0.0, solid)
    }

    /// [`Precision::Certified`]: the set with a rigorous bound on each root.
    /// The true solid is the one the stored doubles define
    /// ([`local_parts`](Self::local_parts)); every hit/miss decision is
    /// exact for it.
    ///
    /// The values are those of [`Precision::Accurate`] wherever its set has
    /// the certified shape (it is the more accurate of the two
    /// floating-point kernels), each with the certified bound widened by
    /// its distance from the certified root: still rigorous.
    pub fn intervals_certified(&self, ray: &Ray, solid: u32) -> CertifiedIntervals {
        let certified = Parts { c: self.centre, a: self.a, w: self.w, k: self.k }.certified(ray, solid);
        if certified.settled_exactly {
            return certified;
        }
        certified.with_values_of(&self.intervals_accurate(ray, solid).into())
    }
}

impl HalfSpace {
    /// [`HalfSpace::intervals`] in the given precision mode.
    #[inline]
    pub fn intervals_with(&self, ray: &Ray, solid: u32, precision: Precision) -> IntervalSet {
        let (enter, exit) = self.interval_with(ray, solid, precision);
        IntervalSet::from_interval(enter, exit)
    }

    /// [`HalfSpace::interval`] in the given precision mode.
    #[inline(always)]
    pub fn interval_with(&self, ray: &Ray, solid: u32, precision: Precision) -> (Bound, Bound) {
        match precision {
            Precision::Accurate => self.interval(ray, solid),
            Precision::Fast => self.interval_fast(ray, solid),
            Precision::Certified => {
                let set = self.intervals_certified(ray, solid).set;
                match set.as_slice().first() {
                    Some(iv) => (iv.enter, iv.exit),
                    None => (Bound::free(f64::INFINITY), Bound::free(f64::INFINITY)),
                }
            }
        }
    }

    /// [`Precision::Fast`]: `t = n·r`, `u = n·(p - o) + d` at the origin.
    #[inline(never)]
    fn interval_fast(&self, ray: &Ray, solid: u32) -> (Bound, Bound) {
        let t = self.normal_vector().dot(&ray.direction());
        let u = self.value(&ray.origin());
        let none = (Bound::free(f64::INFINITY), Bound::free(f64::INFINITY));
        let all = (Bound::free(0.0), Bound::free(f64::INFINITY));
        let root = -u / t + 0.0;
        if t == 0.0 || !root.is_finite() {
            return if u <= 0.0 { all } else { none };
        }
        match (t > 0.0, root < 0.0) {
            (true, true) => none,
            (true, false) => (Bound::free(0.0), Bound::new(root, solid)),
            (false, true) => all,
            (false, false) => (Bound::new(root, solid), Bound::free(f64::INFINITY)),
        }
    }

    /// [`Precision::Certified`] for the half-space (the quadric `A = 0`,
    /// `w = n/2`, `k = d` around the reference point).
    pub fn intervals_certified(&self, ray: &Ray, solid: u32) -> CertifiedIntervals {
        let o = self.reference_point();
        // `value(o) = n·0 + d = d` exactly; halving `n` is exact.
        let parts = Parts { c: o.coords, a: Matrix3::zeros(), w: self.normal_vector() * 0.5, k: self.value(&o) };
        let certified = parts.certified(ray, solid);
        if certified.settled_exactly {
            return certified;
        }
        certified.with_values_of(&self.intervals(ray, solid))
    }
}

impl Solid {
    /// [`Solid::intervals`] in the given precision mode.
    #[inline]
    pub fn intervals_with(&self, ray: &Ray, solid: u32, precision: Precision) -> IntervalSet {
        match self {
            Solid::Quadric(q) => q.intervals_with(ray, solid, precision),
            Solid::HalfSpace(h) => h.intervals_with(ray, solid, precision),
        }
    }

    /// [`Precision::Certified`] intervals with their bounds.
    pub fn intervals_certified(&self, ray: &Ray, solid: u32) -> CertifiedIntervals {
        match self {
            Solid::Quadric(q) => q.intervals_certified(ray, solid),
            Solid::HalfSpace(h) => h.intervals_certified(ray, solid),
        }
    }

    /// The exact order of two crossings of `ray`: root `i` (`0` the smaller)
    /// of the whole line of `self`'s surface and root `j` of `other`'s, as
    /// listed by [`CertifiedIntervals::roots`]. `None` if there is no such
    /// root. Settles ties between the ends of different solids.
    pub fn compare_roots(&self, i: usize, other: &Solid, j: usize, ray: &Ray) -> Option<core::cmp::Ordering> {
        Some(exact_roots(self, ray)?.get(i)?.cmp(exact_roots(other, ray)?.get(j)?))
    }
}

impl Quadric {
    /// The hit point of `ray` at the computed crossing `lambda`, to within
    /// about the rounding floor of the true hit point (`docs/quadric.md` §9):
    /// `p + λr`, then Newton steps along the ray onto the surface, each in
    /// world coordinates with `f` evaluated around the centre in
    /// double-double, each taken only if it lowers `|f|`. `λ` itself is a
    /// double and carries up to `ulp(λ)` of error, which, times `|r| = 1`,
    /// exceeds the hit point's own ulps when the ray starts farther from the
    /// origin than the hit; the steps remove it. For a `lambda` that is no crossing the
    /// result is still a point of the ray near `ray.at(lambda)`.
    #[inline]
    pub fn hit_point(&self, ray: &Ray, lambda: f64) -> Point3<f64> {
        refine(ray, lambda, &self.centre, |y| {
            // f(y) = yᵀAy + 2wᵀy + k in double-double: its plain rounding,
            // amplified by an anisotropic A (|y|ᵀ|A||y| ≫ |∇f|·|y|), would
            // move the point by several ulps.
            let (a, mut f) = (&self.a, Compensated::default());
            for i in 0..3 {
                f.add_product(a[(i, i)], y[i], y[i]);
                f.add_product2(2.0 * self.w[i], y[i]);
                // A diagonal `A`'s cross terms are exact zeros, which add nothing.
                for j in (i + 1..3).filter(|_| !self.diagonal) {
                    f.add_product(2.0 * a[(i, j)], y[i], y[j]);
                }
            }
            f.add(self.k);
            (f.value(), 2.0 * (self.a_times(y) + self.w))
        })
    }
}

impl HalfSpace {
    /// [`Quadric::hit_point`] for the plane: `p + λr` around the reference
    /// point, moved along the ray onto the plane by Newton steps.
    #[inline]
    pub fn hit_point(&self, ray: &Ray, lambda: f64) -> Point3<f64> {
        let o = self.reference_point();
        // `value(o) = n·0 + d = d` exactly.
        let (n, d) = (*self.normal_vector(), self.value(&o));
        refine(ray, lambda, &o.coords, |y| {
            let mut f = Compensated::default();
            for i in 0..3 {
                f.add_product2(n[i], y[i]);
            }
            f.add(d);
            (f.value(), n)
        })
    }
}

impl Solid {
    /// The hit point of `ray` at the crossing `lambda` of this solid's
    /// surface, refined onto the surface ([`Quadric::hit_point`]).
    #[inline]
    pub fn hit_point(&self, ray: &Ray, lambda: f64) -> Point3<f64> {
        match self {
            Solid::Quadric(q) => q.hit_point(ray, lambda),
            Solid::HalfSpace(h) => h.hit_point(ray, lambda),
        }
    }
}

/// The most Newton steps of [`refine`]: one suffices away from tangency.
const NEWTON_STEPS: usize = 4;

/// A sum in double-double (TwoSum/TwoProduct, Ogita–Rump–Oishi `Dot2`):
/// relative error about `u` of the result plus `u²` of the terms' magnitude.
#[derive(Default)]
struct Compensated {
    hi: f64,
    lo: f64,
}

impl Compensated {
    #[inline(always)]
    fn add(&mut self, x: f64) {
        let (sum, error) = crate::roots::two_sum(self.hi, x);
        self.hi = sum;
        self.lo += error;
    }

    /// Adds `a·b·c` (`b·c` exactly by TwoProduct, then `a` times each part).
    #[inline(always)]
    fn add_product(&mut self, a: f64, b: f64, c: f64) {
        let bc = b * c;
        let bc_lo = b.mul_add(c, -bc);
        let p = a * bc;
        let p_lo = a.mul_add(bc, -p);
        self.add(p);
        self.lo += a.mul_add(bc_lo, p_lo);
    }

    /// Adds `a·b` (exactly by TwoProduct): `add_product(a, b, 1.0)`
    /// without the products by one, the same sum for finite `b`.
    #[inline(always)]
    fn add_product2(&mut self, a: f64, b: f64) {
        let p = a * b;
        let p_lo = a.mul_add(b, -p);
        self.add(p);
        self.lo += p_lo;
    }

    #[inline(always)]
    fn value(&self) -> f64 {
        self.hi + self.lo
    }
}

/// `p + λr` moved along the ray onto the surface by Newton steps
/// `-f(x) / (∇f(x)·r)` while they lower `|f|`. Each step is taken in world
/// coordinates (so the point ends within rounding of its own ulps, however
/// its coordinates compare with the centre's), with `f` evaluated around
/// the centre `c`: `x - c` exactly as a TwoSum pair `d + lo`, `f(d)` in
/// double-double by `f_grad` (which also gives `∇f(d)`), plus `∇f(d)·lo`.
/// Non-finite input gives `ray.at(lambda)`.
#[inline(always)]
fn refine(
    ray: &Ray,
    lambda: f64,
    c: &Vector3<f64>,
    f_grad: impl Fn(&Vector3<f64>) -> (f64, Vector3<f64>),
) -> Point3<f64> {
    let r = ray.direction();
    let eval = |x: &Vector3<f64>| {
        let d = x - c;
        let lo =
            Vector3::new(two_sum_error(x.x, -c.x, d.x), two_sum_error(x.y, -c.y, d.y), two_sum_error(x.z, -c.z, d.z));
        let (f, grad) = f_grad(&d);
        (f + grad.dot(&lo), grad)
    };
    let start = ray.at(lambda);
    let mut x = start.coords;
    // Near a tangency the first step can undershoot (the quadratic term),
    // so a few steps while |f| keeps falling.
    let (mut f, mut grad) = eval(&x);
    for _ in 0..NEWTON_STEPS {
        let step = -f / grad.dot(&r);
        if !step.is_finite() || step == 0.0 {
            break;
        }
        let moved = x + r * step;
        // A step below the point's rounding leaves it where it is (and |f|
        // as it is): converged, without another evaluation.
        if moved == x {
            break;
        }
        let (f_moved, grad_moved) = eval(&moved);
        if f_moved.abs().partial_cmp(&f.abs()) != Some(core::cmp::Ordering::Less) {
            break;
        }
        (x, f, grad) = (moved, f_moved, grad_moved);
    }
    if x.iter().all(|v| v.is_finite()) {
        Point3::from(x)
    } else {
        start
    }
}

/// The exact roots of the whole line, in increasing order; `None` for
/// non-finite inputs.
fn exact_roots(solid: &Solid, ray: &Ray) -> Option<Vec<ExactRoot>> {
    let parts = match solid {
        Solid::Quadric(q) => Parts { c: q.centre, a: q.a, w: q.w, k: q.k },
        Solid::HalfSpace(h) => {
            let o = h.reference_point();
            Parts { c: o.coords, a: Matrix3::zeros(), w: h.normal_vector() * 0.5, k: h.value(&o) }
        }
    };
    parts.finite(ray).then(|| parts.exact_roots(&Exact::new(&parts.c, &parts.a, &parts.w, parts.k, ray)))
}

/// The unit roundoff `u = 2⁻⁵³`.
const U: f64 = f64::EPSILON / 2.0;

/// `γₙ = nu / (1 - nu)` (Higham), rounded up: bounds the relative error of
/// `n` chained roundings. Computed for small `n` only, where `nu < 1`.
#[inline(always)]
fn gamma(n: u32) -> f64 {
    let nu = n as f64 * U;
    next_up(nu / (1.0 - nu))
}

/// The next double up (`x >= 0` finite), for outward rounding of bounds.
#[inline(always)]
fn next_up(x: f64) -> f64 {
    f64::from_bits(x.to_bits() + 1)
}

/// An error bound evaluated in floating point, rounded outward: each bound
/// below is a short sum of non-negative products, whose own rounding is at
/// most `γ₄` relative; one multiplication by `1 + γ₅` covers it.
#[inline(always)]
fn up(x: f64) -> f64 {
    x * (1.0 + gamma(5))
}

/// The largest relative bound on a root for which the floating-point answer
/// stands; above it (a root from a nearly vanishing `s` or `t`) the root is
/// recomputed exactly.
const MAX_RELATIVE: f64 = 1.0 / (1u64 << 20) as f64;

/// A solid as `f(x) = (x-c)ᵀA(x-c) + 2wᵀ(x-c) + k` (half-spaces with `A = 0`).
struct Parts {
    c: Vector3<f64>,
    a: Matrix3<f64>,
    w: Vector3<f64>,
    k: f64,
}

impl Parts {
    fn finite(&self, ray: &Ray) -> bool {
        let ok = |v: &[f64]| v.iter().all(|x| x.is_finite());
        ok(self.c.as_slice()) && ok(self.a.as_slice()) && ok(self.w.as_slice()) && self.k.is_finite() && {
            let p = ray.origin();
            ok(p.coords.as_slice()) && ok(ray.direction().as_slice())
        }
    }

    /// The certified kernel. Forward error analysis in the style of pbrt-v4
    /// (Pharr, Jakob, Humphreys, §6.8): each computed quantity `x̂` comes with
    /// a bound `e_x >= |x̂ - x|` on its distance from the exact value `x` for
    /// the stored doubles, from the standard model `fl(a ∘ b) = (a ∘ b)(1 + δ)`,
    /// `|δ| <= u`, and `γₙ` for chains of `n` roundings; the bounds are
    /// evaluated with outward rounding ([`up`]). Where a bound leaves a
    /// decision open, [`Parts::settle`] decides it exactly.
    fn certified(&self, ray: &Ray, solid: u32) -> CertifiedIntervals {
        if !self.finite(ray) {
            return CertifiedIntervals::new(Pieces::empty(), &[], false);
        }
        let (p, r) = (ray.origin().coords, ray.direction());
        let abs_a = self.a.abs();
        let abs_r = r.abs();
        // d = p - c exactly as d̂ + lo (TwoSum).
        let d = p - self.c;
        let lo = Vector3::new(
            two_sum_error(p.x, -self.c.x, d.x),
            two_sum_error(p.y, -self.c.y, d.y),
            two_sum_error(p.z, -self.c.z, d.z),
        );
        // The base point b* = d + lo + λ₀r (λ₀ any double: the quadratic in
        // μ = λ - λ₀ from b* has exactly the roots of the original, shifted).
        // b̂ = fl(λ₀r + d̂) (one FMA), so |b* - b̂ - lo| <= γ₁|b̂|: the offset
        // δ = b* - b̂ satisfies |δ| <= |lo| + γ₁|b̂| =: δ̄ componentwise.
        let lambda0 = -r.dot(&d);
        let base = Vector3::new(lambda0.mul_add(r.x, d.x), lambda0.mul_add(r.y, d.y), lambda0.mul_add(r.z, d.z));
        let abs_b = base.abs();
        let abs_lo = lo.abs();
        let delta = (abs_lo + abs_b * gamma(1)) * (1.0 + gamma(2));

        // s = rᵀAr: Âr has |Âr - Ar| <= γ₃|A||r|, and the dot product adds
        // γ₃|r|ᵀ|Âr|; with |Âr| <= (1 + γ₃)|A||r| this is <= γ₇|r|ᵀ|A||r|.
        let ar = self.a * r;
        let abs_ar = abs_a * abs_r;
        let s = r.dot(&ar);
        let e_s = up(gamma(7) * abs_r.dot(&abs_ar));

        // t* = (Ar)ᵀb* + rᵀw, computed as t̂ = Âr·b̂ + (rᵀw + Âr·lo). The
        // neglected (Ar)ᵀ(δ - lo) is <= γ₁|A||r|·|b̂|; Âr's error enters
        // through |b̂| + |lo|; the five-term sum rounds by γ₅ of its
        // magnitude (with |Âr| for |Ar|, one more γ₃): all within γ₁₀.
        let rw = r.dot(&self.w);
        let t = ar.dot(&base) + (rw + ar.dot(&lo));
        let e_t = up(gamma(10) * (abs_ar.dot(&(abs_b + abs_lo)) + abs_r.dot(&self.w.abs())));

        // u* = f(b̂ + δ) = f(b̂) + 2δᵀ(Ab̂ + w) + δᵀAδ, computed as
        // û = b̂ᵀ(ĝ + w) + k + 2 loᵀĝ with ĝ = fl(Ab̂ + w) (|ĝ - g| <= γ₄ G,
        // G = |A||b̂| + |w|). f(b̂) rounds within γ₁₀(|b̂|ᵀ(G + |w|) + |k|);
        // 2δᵀg - 2loᵀĝ is <= 2(γ₁|b̂| + γ₄|lo|)ᵀG plus γ₄ of 2|lo|ᵀG; the
        // quadratic term is <= δ̄ᵀ|A|δ̄.
        let g = self.a * base + self.w;
        let u = base.dot(&(g + self.w)) + self.k + 2.0 * lo.dot(&g);
        let big_g = abs_a * abs_b + self.w.abs();
        let e_u = up(gamma(10) * (abs_b.dot(&(big_g + self.w.abs())) + self.k.abs())
            + 2.0 * (abs_b * gamma(1) + abs_lo * gamma(9)).dot(&big_g)
            + delta.dot(&(abs_a * delta)));

        if !(s.is_finite() && t.is_finite() && u.is_finite() && e_s.is_finite() && e_t.is_finite() && e_u.is_finite()) {
            return self.settle(ray, solid);
        }
        if e_s == 0.0 && s == 0.0 {
            return self.linear(ray, solid, (t, e_t), (u, e_u), lambda0);
        }
        if s.abs() <= e_s {
            // The sign of s is open (a ray nearly along a flat direction).
            return self.settle(ray, solid);
        }
        // D = t² - su by Kahan's difference of products (relative error
        // <= 2u, within γ₃ of |D̂|), and the propagated input errors:
        // |t*² - t̂²| <= e_t(2|t̂| + e_t), |s*u* - ŝû| <= |ŝ|e_u + |û|e_s + e_s e_u.
        let disc = difference_of_products(t, t, s, u);
        let e_d = up(gamma(3) * disc.abs() + e_t * (2.0 * t.abs() + e_t) + s.abs() * e_u + u.abs() * e_s + e_s * e_u);
        if !(disc.is_finite() && e_d.is_finite()) || disc.abs() <= e_d {
            // Tangency (or a miss or hit by less than the bound): exact.
            return self.settle(ray, solid);
        }
        if disc < 0.0 {
            let set = if s > 0.0 { Pieces::empty() } else { whole_ray() };
            return CertifiedIntervals::new(set, &[], false);
        }
        // √D: |√D* - √D̂| <= e_D / (√D̂ + √(D̂ - e_D)) <= e_D/√D̂, plus the
        // square root's own rounding u√D̂.
        let sq = disc.sqrt();
        let e_sq = up(e_d / sq + U * sq);
        // q = -(t + sign(t)√D): no cancellation; |q̂ - q*| <= e_t + e_sq + u|q̂|.
        let sign = if t == 0.0 { s } else { t };
        let q = -(t + sq.copysign(sign));
        let e_q = up(e_t + e_sq + U * q.abs());
        if q.abs() <= e_q {
            return self.settle(ray, solid);
        }
        // μ₁ = q/s, μ₂ = u/q: |q*/s* - q̂/ŝ| <= (e_q + |q̂/ŝ| e_s)/(|ŝ| - e_s),
        // |u*/q* - û/q̂| <= (e_u + |û/q̂| e_q)/(|q̂| - e_q), each plus the
        // division's rounding u|μ̂|.
        let (m1, m2) = (q / s, u / q);
        let e1 = up((e_q + m1.abs() * e_s) / down(s.abs() - e_s) + U * m1.abs());
        let e2 = up((e_u + m2.abs() * e_q) / down(q.abs() - e_q) + U * m2.abs());
        // λ = λ₀ + μ rounds once more: u|λ̂|.
        let (l1, l2) = (lambda0 + m1, lambda0 + m2);
        let (e1, e2) = (up(e1 + U * l1.abs()), up(e2 + U * l2.abs()));
        let ((l1, e1), (l2, e2)) = if l1 <= l2 { ((l1, e1), (l2, e2)) } else { ((l2, e2), (l1, e1)) };
        let open = |l: f64, e: f64| !(e.is_finite() && l.is_finite()) || l.abs() <= e || e > MAX_RELATIVE * l.abs();
        if open(l1, e1) || open(l2, e2) || l2 - l1 <= e1 + e2 {
            // An end within its bound of the origin, two roots within their
            // bounds of each other, or a loose bound: exact.
            return self.settle(ray, solid);
        }
        let set = quadratic_pieces(s > 0.0, l1, l2, solid);
        CertifiedIntervals::new(set, &[CertifiedRoot { t: l1, error: e1 }, CertifiedRoot { t: l2, error: e2 }], false)
    }

    /// The linear case `s = 0` (exactly: `|r|ᵀ|A||r| = 0`): `2tμ + u <= 0`.
    fn linear(
        &self,
        ray: &Ray,
        solid: u32,
        (t, e_t): (f64, f64),
        (u, e_u): (f64, f64),
        lambda0: f64,
    ) -> CertifiedIntervals {
        if t.abs() <= e_t {
            return self.settle(ray, solid);
        }
        // μ = -u/(2t): |u*/t* - û/t̂| <= (e_u + |û/t̂| e_t)/(|t̂| - e_t) (halved), plus rounding.
        let m = -u / (2.0 * t);
        let e = up((e_u + 2.0 * m.abs() * e_t) / (2.0 * down(t.abs() - e_t)) + U * m.abs());
        let l = lambda0 + m;
        let e = up(e + U * l.abs());
        if !(e.is_finite() && l.is_finite()) || l.abs() <= e || e > MAX_RELATIVE * l.abs() {
            return self.settle(ray, solid);
        }
        let set = if t > 0.0 { up_to(l, solid) } else { from(l, solid) };
        CertifiedIntervals::new(set, &[CertifiedRoot { t: l, error: e }], false)
    }

    /// The exact answer: every decision from the exact `s`, `t`, `u` and
    /// discriminant, the roots rounded to the nearest double (error <= 1 ulp).
    #[cold]
    #[inline(never)]
    fn settle(&self, ray: &Ray, solid: u32) -> CertifiedIntervals {
        let exact = Exact::new(&self.c, &self.a, &self.w, self.k, ray);
        let roots = self.exact_roots(&exact);
        let rounded: Vec<CertifiedRoot> = roots
            .iter()
            .map(|x| {
                let t = x.to_f64();
                CertifiedRoot { t, error: ulp(t) }
            })
            .collect();
        let clip = |x: &ExactRoot, t: f64| if x.signum() < 0 { -f64::INFINITY } else { t };
        let set = match exact.s.signum() {
            0 => match exact.t.signum() {
                0 if exact.u.signum() <= 0 => whole_ray(),
                0 => Pieces::empty(),
                sign => {
                    let l = clip(&roots[0], rounded[0].t);
                    if sign > 0 {
                        up_to(l, solid)
                    } else {
                        from(l, solid)
                    }
                }
            },
            sign => match roots.len() {
                // No crossing, or a touching point (dropped: sets are regularised).
                0 | 1 => {
                    if sign > 0 {
                        Pieces::empty()
                    } else {
                        whole_ray()
                    }
                }
                _ => quadratic_pieces(sign > 0, clip(&roots[0], rounded[0].t), clip(&roots[1], rounded[1].t), solid),
            },
        };
        CertifiedIntervals::new(set, &rounded, true)
    }

    /// The exact crossings of the whole line, in increasing order (a
    /// touching point counts once).
    fn exact_roots(&self, exact: &Exact) -> Vec<ExactRoot> {
        if exact.s.signum() == 0 {
            return if exact.t.signum() == 0 { vec![] } else { vec![exact.linear_root()] };
        }
        match exact.discriminant().signum() {
            -1 => vec![],
            0 => vec![exact.quadratic_root(false)],
            _ => vec![exact.quadratic_root(false), exact.quadratic_root(true)],
        }
    }
}

/// The set `{λ >= 0 : inside}` for two crossings `l1 < l2` of the line (an
/// end at `-∞` stands for a crossing behind the origin): `[l1, l2]` for
/// `s > 0`, `(-∞, l1] ∪ [l2, ∞)` for `s < 0`, clipped to the ray.
fn quadratic_pieces(positive: bool, l1: f64, l2: f64, solid: u32) -> Pieces {
    if positive {
        if l2 <= 0.0 {
            return Pieces::empty();
        }
        let enter = if l1 >= 0.0 { Bound::new(l1 + 0.0, solid) } else { Bound::free(0.0) };
        Pieces::from_interval(enter, Bound::new(l2 + 0.0, solid))
    } else if l1 > 0.0 {
        up_to(l1, solid).then(from(l2, solid)).unwrap_or_else(whole_ray)
    } else {
        from(l2, solid)
    }
}

/// Rounds a positive denominator of a bound down (so the bound rounds up);
/// callers have checked it is positive.
#[inline(always)]
fn down(x: f64) -> f64 {
    x * (1.0 - gamma(2))
}

/// The spacing of doubles at `x` (its ulp), the error bound of a root
/// rounded to the nearest double from far more bits.
fn ulp(x: f64) -> f64 {
    let a = x.abs();
    if !a.is_finite() {
        return f64::INFINITY;
    }
    next_up(a) - a
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn finite() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1e300..1e300f64,
            -1e3..1e3f64,
            Just(0.0),
            Just(-0.0),
            Just(f64::MIN_POSITIVE / 3.0),
            Just(-f64::MAX),
            any::<f64>().prop_filter("finite", |x| x.is_finite()),
        ]
    }

    proptest! {
        /// `add_product2(a, b)` leaves the pair bit for bit where
        /// `add_product(a, b, 1.0)` does, for finite terms in any order.
        #[test]
        fn a_product_of_two_adds_what_a_product_by_one_adds(terms in proptest::collection::vec((finite(), finite()), 1..6)) {
            let (mut two, mut three) = (Compensated::default(), Compensated::default());
            for (a, b) in terms {
                two.add_product2(a, b);
                three.add_product(a, b, 1.0);
                prop_assert_eq!(two.hi.to_bits(), three.hi.to_bits());
                prop_assert!(two.lo.to_bits() == three.lo.to_bits() || (two.lo.is_nan() && three.lo.is_nan()), "{} against {}", two.lo, three.lo);
            }
        }
    }
}
