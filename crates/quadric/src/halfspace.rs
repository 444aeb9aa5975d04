//! Half-spaces `F(q) = { x : a x + b y + c z + d <= 0 }`, the cheap special case.

use nalgebra::{Point3, Vector3, Vector4};

use crate::interval::{Bound, IntervalSet};
use crate::roots::{dot2, two_sum_error};
use crate::{GeometryError, Ray, Transform};

/// A half-space `n·(x - o) + d <= 0` with `n = (a, b, c)`, stored around a
/// reference point `o` (the origin unless moved) so that a plane moved far
/// away keeps small coefficients, like [`crate::Quadric`].
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use quadric::{HalfSpace, Ray};
/// let below = HalfSpace::new(0.0, 1.0, 0.0, -1.0).unwrap(); // y <= 1
/// let up = Ray::new(Point3::origin(), Vector3::y()).unwrap();
/// let set = below.intervals(&up, 0);
/// assert_eq!((set.as_slice()[0].enter.t, set.as_slice()[0].exit.t), (0.0, 1.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    normal: Vector3<f64>,
    d: f64,
    origin: Vector3<f64>,
}

impl HalfSpace {
    /// `a x + b y + c z + d <= 0`; `(a, b, c)` must be non-zero and all finite.
    pub fn new(a: f64, b: f64, c: f64, d: f64) -> Result<Self, GeometryError> {
        Self::from_vector(&Vector4::new(a, b, c, d))
    }

    /// From `q = (a, b, c, d)`.
    pub fn from_vector(q: &Vector4<f64>) -> Result<Self, GeometryError> {
        if !q.iter().all(|x| x.is_finite()) {
            return Err(GeometryError::NonFinite { what: "a half-space coefficient" });
        }
        let normal = q.xyz();
        if normal == Vector3::zeros() {
            return Err(GeometryError::ZeroNormal);
        }
        Ok(HalfSpace { normal, d: q.w, origin: Vector3::zeros() })
    }

    /// The other half, `-q` (exact).
    pub fn complement(&self) -> Self {
        HalfSpace { normal: -self.normal, d: -self.d, origin: self.origin }
    }

    /// The half-space moved by `m`: `M⁻ᵀ q`, with the reference point moved exactly.
    pub fn transformed(&self, m: &Transform) -> Self {
        let normal = m.linear_inverse().transpose() * self.normal;
        HalfSpace { normal, d: self.d, origin: m.apply_point(&Point3::from(self.origin)).coords }
    }

    /// [`transformed`](Self::transformed), checked:
    /// [`GeometryError::NonFinite`] if a coefficient overflows,
    /// [`GeometryError::Underflow`] if the whole normal `L⁻ᵀ n` underflows
    /// (below `f64::MIN_POSITIVE`: the plane's direction is lost, and a zero
    /// normal would make it all of space or nothing). A normal with only
    /// some components underflowed tilts the plane by less than an ulp.
    pub fn try_transformed(&self, m: &Transform) -> Result<Self, GeometryError> {
        let placed = self.transformed(m);
        if !placed.is_finite() {
            return Err(GeometryError::NonFinite { what: "a coefficient of the placed solid" });
        }
        if self.normal.amax() >= f64::MIN_POSITIVE && placed.normal.amax() < f64::MIN_POSITIVE {
            return Err(GeometryError::Underflow { part: "half-space normal" });
        }
        Ok(placed)
    }

    /// `(a, b, c)`, not normalised.
    pub fn normal_vector(&self) -> &Vector3<f64> {
        &self.normal
    }

    /// The reference point `o`.
    pub fn reference_point(&self) -> Point3<f64> {
        Point3::from(self.origin)
    }

    /// World-space `q = (a, b, c, d)`.
    pub fn vector(&self) -> Vector4<f64> {
        Vector4::new(self.normal.x, self.normal.y, self.normal.z, self.d - self.normal.dot(&self.origin))
    }

    /// `n·(x - o) + d`; the half-space is where this is `<= 0`.
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        self.normal.dot(&(x.coords - self.origin)) + self.d
    }

    /// Whether `x` lies in the closed half-space.
    pub fn contains_point(&self, x: &Point3<f64>) -> bool {
        self.value(x) <= 0.0
    }

    /// The outward unit normal `(a, b, c)/|(a, b, c)|` (the same everywhere).
    pub fn normal(&self) -> Vector3<f64> {
        // Non-zero by construction; a transform cannot make it zero.
        crate::normal::unit(self.normal).unwrap_or_else(Vector3::y)
    }

    /// Whether every coefficient is finite.
    pub fn is_finite(&self) -> bool {
        self.normal.iter().chain(self.origin.iter()).all(|c| c.is_finite()) && self.d.is_finite()
    }

    /// The set of `λ >= 0` with `p + λr` inside; the finite end carries `solid`.
    #[inline]
    pub fn intervals(&self, ray: &Ray, solid: u32) -> IntervalSet {
        let (enter, exit) = self.interval(ray, solid);
        IntervalSet::from_interval(enter, exit)
    }

    /// The single interval (possibly empty: `enter.t >= exit.t`) of `λ >= 0`
    /// inside the half-space: the allocation-free fast path blocks use.
    #[inline(always)]
    pub fn interval(&self, ray: &Ray, solid: u32) -> (Bound, Bound) {
        self.interval_rebased(ray, &Rebased::new(ray, &self.reference_point()), solid)
    }

    /// [`HalfSpace::interval`] from the ray re-based at this half-space's
    /// reference point, which half-spaces around the same point share (a
    /// box's six faces): the same value, bit for bit.
    #[inline(always)]
    pub fn interval_rebased(&self, ray: &Ray, at: &Rebased, solid: u32) -> (Bound, Bound) {
        let t = self.slope(&ray.direction());
        let u = self.normal.dot(&at.base) + (self.d + self.normal.dot(&at.lo));
        crossing(t, at.lambda0, u, solid)
    }

    /// `Some(d)` if `other` is `-n·(x - o) + d <= 0`, the opposite of this
    /// half-space (together a slab: a box's two faces on one axis, a
    /// cylinder's two caps): a normal of equal components with the opposite
    /// sign, the same reference point bit for bit. A zero component may have
    /// either sign (a scene's `[0, -1, 0, d]` is no bitwise negation of
    /// `[0, 1, 0, d']`); no interval tells them apart, so
    /// [`HalfSpace::slab_intervals`] answers for `other` bit for bit.
    pub fn opposite_offset(&self, other: &HalfSpace) -> Option<f64> {
        let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
        (other.normal == -self.normal && bits(&other.origin) == bits(&self.origin)).then_some(other.d)
    }

    /// `[self.interval(ray, solid), other.interval(ray, solid + 1)]` for the
    /// opposite `other` with offset `d` ([`HalfSpace::opposite_offset`]),
    /// bit for bit, at little more than the cost of one. Negating the
    /// normal negates every product and sum of the slope and of both dot
    /// products exactly (IEEE rounding is symmetric in sign, and so are
    /// Dot2's error terms), so `t' = -t` and `u' = -(n·base) + (d - n·lo)`.
    /// A zero component of either sign only changes the sign of a zero `t'`
    /// or `u'`, which no branch and no root tells apart (`t = ±0` is a
    /// parallel ray, `u = ±0` gives the root `+0`).
    #[inline(always)]
    pub fn slab_intervals(&self, d: f64, ray: &Ray, at: &Rebased, solid: u32) -> [(Bound, Bound); 2] {
        let t = self.slope(&ray.direction());
        let (on_base, on_lo) = (self.normal.dot(&at.base), self.normal.dot(&at.lo));
        [
            crossing(t, at.lambda0, on_base + (self.d + on_lo), solid),
            crossing(-t, at.lambda0, -on_base + (d - on_lo), solid + 1),
        ]
    }

    /// `t = n·r`; nearly parallel to the plane it cancels from `|n|` down to
    /// `|n| sin θ`, and is then recomputed compensated (Dot2) so that its
    /// sign, and the far root `-u/t`, stay right.
    #[inline(always)]
    fn slope(&self, r: &Vector3<f64>) -> f64 {
        let t = self.normal.dot(r);
        if t.abs() >= self.normal.amax() / 16.0 {
            return t;
        }
        let (t, t_lo) = dot2(&self.normal, r);
        t + t_lo
    }
}

/// The interval of `λ >= 0` inside a half-space with slope `t = n·r` and
/// value `u = f(p + λ₀r)`: before the root `λ₀ - u/t` if `t > 0`, after it
/// if `t < 0`, all or nothing on a parallel ray.
#[inline(always)]
fn crossing(t: f64, lambda0: f64, u: f64, solid: u32) -> (Bound, Bound) {
    let none = (Bound::free(f64::INFINITY), Bound::free(f64::INFINITY));
    let all = (Bound::free(0.0), Bound::free(f64::INFINITY));
    if t == 0.0 || !t.is_finite() {
        return if u <= 0.0 { all } else { none };
    }
    // `+ 0.0` turns a root of -0.0 (u = -0.0 on the plane) into +0.0.
    let root = -u / t + 0.0;
    if !root.is_finite() {
        return if u <= 0.0 { all } else { none };
    }
    let root = lambda0 + root;
    if t > 0.0 {
        // Inside before the plane.
        if root < 0.0 {
            none
        } else {
            (Bound::free(0.0), Bound::new(root, solid))
        }
    } else if root < 0.0 {
        all
    } else {
        (Bound::new(root, solid), Bound::free(f64::INFINITY))
    }
}

/// A ray re-based at a reference point `o`, the part of
/// [`HalfSpace::interval`] that every half-space stored around `o` shares:
/// the foot `λ₀ = -r·(p - o)` of the perpendicular from `o` onto the ray, so
/// that `u` is taken near `o` and the root is as accurate far away as near
/// (see `docs/quadric.md`). The base point `(p - o) + λ₀r` is formed by one
/// FMA at the scale of `|x - o|` for any point `x` of the line, and the
/// rounding of `p - o` (half an ulp of the distance) is recovered by TwoSum
/// and added back, the same exact re-basing as `Quadric::intervals`.
#[derive(Clone, Copy, Debug)]
pub struct Rebased {
    lambda0: f64,
    base: Vector3<f64>,
    lo: Vector3<f64>,
}

impl Rebased {
    /// `ray` re-based at `origin`.
    #[inline(always)]
    pub fn new(ray: &Ray, origin: &Point3<f64>) -> Self {
        let (p, r, o) = (ray.origin().coords, ray.direction(), origin.coords);
        let d = p - o;
        let lambda0 = -r.dot(&d);
        let base = Vector3::new(lambda0.mul_add(r.x, d.x), lambda0.mul_add(r.y, d.y), lambda0.mul_add(r.z, d.z));
        let lo =
            Vector3::new(two_sum_error(p.x, -o.x, d.x), two_sum_error(p.y, -o.y, d.y), two_sum_error(p.z, -o.z, d.z));
        Rebased { lambda0, base, lo }
    }
}
