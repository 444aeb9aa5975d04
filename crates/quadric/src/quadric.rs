//! Quadric solids `F(Q) = { x : [x;1]ᵀ Q [x;1] <= 0 }` and their ray intervals.

use nalgebra::{Matrix3, Matrix4, Point3, Vector3};

use crate::interval::{Bound, IntervalSet, Pieces};
use crate::roots::{
    difference_of_products, dot2, exact_sign_of_sum, stable_roots, two_product, two_sum, two_sum_error,
};
use crate::{GeometryError, Ray, Transform};

// The precision modes (a child module: they read the private parts).
#[path = "precision.rs"]
pub(crate) mod precision;
use precision::Precision;

/// A quadric solid, stored around a local centre `c`:
///
/// `f(x) = (x-c)ᵀ A (x-c) + 2 wᵀ(x-c) + k`, the solid being `f <= 0`.
///
/// Moving a solid moves `c` exactly and leaves `A`, `w` and `k` alone, so a
/// unit sphere placed at distance 10⁹ keeps the coefficients of a unit
/// sphere; the world-space matrix (with a constant term near 10¹⁸ that has
/// lost the sphere's radius to rounding) is only formed on request.
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use quadric::{Quadric, Ray, Transform};
/// let ball = Quadric::sphere().transformed(&Transform::translate(Vector3::new(0.0, 0.0, -5.0)).unwrap());
/// let ray = Ray::new(Point3::origin(), -Vector3::z()).unwrap();
/// let set = ball.intervals(&ray, 0);
/// assert_eq!(set.len(), 1);
/// assert_eq!((set.as_slice()[0].enter.t, set.as_slice()[0].exit.t), (4.0, 6.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    centre: Vector3<f64>,
    a: Matrix3<f64>,
    w: Vector3<f64>,
    k: f64,
    /// `A` is positive (`Some(true)`) or negative (`Some(false)`)
    /// semi-definite, or indefinite (`None`); see [`Quadric::is_convex`].
    definite: Option<bool>,
    /// Below this `|s|` the ray is nearly along a flat direction of `A` and
    /// `s`, `t` are recomputed compensated (`max |A_ij| / 16`).
    flat: f64,
    /// The exact null axis `n` of an ideal cylinder (zero if none): the
    /// solid is invariant along `n` (`A n = 0`, `w·n = 0` for the quadric it
    /// was built as), carried through transforms as `L n`, where rounding
    /// leaves the stored `A` slightly definite along it. Queries far along
    /// it slide the point along `n` first (see [`Quadric::axis`]).
    axis: Vector3<f64>,
    /// `A` is diagonal (its off-diagonal entries are exact zeros): an
    /// axis-aligned quadric, such as every sphere and every cylinder or
    /// ellipsoid in normal form, whose products `A v` take three
    /// multiplications (see `Quadric::a_times`).
    diagonal: bool,
    /// `‖A‖_F` and `|w|` of the stored parts, computed once: the magnitudes
    /// an error bound of `f` needs at every point (see [`Quadric::norms`]).
    norms: (f64, f64),
}

impl Quadric {
    /// Stores the parts scaled by a power of two that brings the largest
    /// coefficient into `[1, 2)`: the same solid (the scaling is exact unless
    /// a coefficient is below 2⁻¹⁰²² times the largest), and `f` then
    /// overflows only where `|x - c|²` does, whatever scale the input had.
    /// `A`'s definiteness is decided exactly.
    fn from_parts(centre: Vector3<f64>, a: Matrix3<f64>, w: Vector3<f64>, k: f64) -> Self {
        let definite = if semi_definite(&a) {
            Some(true)
        } else if semi_definite(&-a) {
            Some(false)
        } else {
            None
        };
        Self::with_definiteness(centre, a, w, k, definite, exact_axis(&a, &w))
    }

    fn with_definiteness(
        centre: Vector3<f64>,
        a: Matrix3<f64>,
        w: Vector3<f64>,
        k: f64,
        definite: Option<bool>,
        axis: Vector3<f64>,
    ) -> Self {
        let m = a.amax().max(w.amax()).max(k.abs());
        let (a, w, k) = if !(m > 0.0 && m.is_finite()) || (1.0..2.0).contains(&m) {
            (a, w, k)
        } else {
            // Two factors, each a normal power of two, cover every finite `m`.
            let e = m.log2().floor() as i32;
            let (f1, f2) = (pow2(-e / 2), pow2(-e - (-e / 2)));
            (a * f1 * f2, w * f1 * f2, k * f1 * f2)
        };
        let axis =
            if axis.iter().all(|x| x.is_finite()) && axis.amax() > 0.0 { axis / axis.amax() } else { Vector3::zeros() };
        let diagonal = (0..3).all(|i| (0..3).all(|j| i == j || a[(i, j)] == 0.0));
        Quadric { centre, a, w, k, definite, flat: a.amax() / 16.0, axis, diagonal, norms: (a.norm(), w.norm()) }
    }

    /// `(‖A‖_F, |w|)` of the stored parts ([`Quadric::local_parts`]),
    /// exactly `a.norm()` and `w.norm()`: the magnitudes from which callers
    /// bound the rounding error of `f` at a point (as the secondary-ray
    /// spawner of the `complex` crate does), without two square roots per
    /// point.
    #[inline]
    pub fn norms(&self) -> (f64, f64) {
        self.norms
    }

    /// `A v` with the stored `A` ([`Quadric::local_parts`]): for a diagonal
    /// `A` three products, the same values as the full product (whose other
    /// six products are exact zeros; at most the sign of a zero component
    /// can differ, which no decision reads).
    #[inline(always)]
    pub fn a_times(&self, v: &Vector3<f64>) -> Vector3<f64> {
        if self.diagonal {
            Vector3::new(self.a.m11 * v.x, self.a.m22 * v.y, self.a.m33 * v.z)
        } else {
            self.a * v
        }
    }

    fn diagonal(a: f64, b: f64, c: f64, k: f64) -> Self {
        Self::from_parts(Vector3::zeros(), Matrix3::from_diagonal(&Vector3::new(a, b, c)), Vector3::zeros(), k)
    }

    /// From the ten coefficients `[a, b, c, d, e, f, g, h, j, k]` of
    /// `a x² + b y² + c z² + 2d xy + 2e xz + 2f yz + 2g x + 2h y + 2j z + k`.
    /// All zero (`0 <= 0`, all of space) or only `k > 0` (the empty set) is
    /// [`GeometryError::Degenerate`]: a coefficient list left unfilled, not
    /// a solid. (Only `k < 0`, all of space on purpose, is accepted.)
    pub fn from_coefficients(c: [f64; 10]) -> Result<Self, GeometryError> {
        if !c.iter().all(|x| x.is_finite()) {
            return Err(GeometryError::NonFinite { what: "a quadric coefficient" });
        }
        let [a, b, cc, d, e, f, g, h, j, k] = c;
        let m = Matrix3::new(a, d, e, d, b, f, e, f, cc);
        let w = Vector3::new(g, h, j);
        not_degenerate(&m, &w, k)?;
        Ok(Self::from_parts(Vector3::zeros(), m, w, k))
    }

    /// From a symmetric 4x4 matrix `Q` (exact symmetry is required); the
    /// degenerate cases of [`from_coefficients`](Self::from_coefficients)
    /// are errors here too.
    pub fn from_matrix(q: &Matrix4<f64>) -> Result<Self, GeometryError> {
        if !q.iter().all(|x| x.is_finite()) {
            return Err(GeometryError::NonFinite { what: "a quadric matrix entry" });
        }
        for row in 0..4 {
            for col in row + 1..4 {
                if q[(row, col)] != q[(col, row)] {
                    return Err(GeometryError::NotSymmetric { row, col });
                }
            }
        }
        let a = q.fixed_view::<3, 3>(0, 0).into_owned();
        let w = q.fixed_view::<3, 1>(0, 3).into_owned();
        not_degenerate(&a, &w, q[(3, 3)])?;
        Ok(Self::from_parts(Vector3::zeros(), a, w, q[(3, 3)]))
    }

    /// The unit ball `x² + y² + z² - 1 <= 0`; ellipsoids by scaling.
    pub fn sphere() -> Self {
        Self::diagonal(1.0, 1.0, 1.0, -1.0)
    }

    /// The infinite unit tube along x, `y² + z² - 1 <= 0`.
    pub fn tube_x() -> Self {
        Self::diagonal(0.0, 1.0, 1.0, -1.0)
    }

    /// The infinite unit tube along y, `x² + z² - 1 <= 0`.
    pub fn tube_y() -> Self {
        Self::diagonal(1.0, 0.0, 1.0, -1.0)
    }

    /// The infinite unit tube along z, `x² + y² - 1 <= 0`.
    pub fn tube_z() -> Self {
        Self::diagonal(1.0, 1.0, 0.0, -1.0)
    }

    /// The infinite double cone around y, `x² - y² + z² <= 0` (non-convex).
    pub fn cone() -> Self {
        Self::diagonal(1.0, -1.0, 1.0, 0.0)
    }

    /// The paraboloid opening up the y axis, `x² + z² - y <= 0`.
    pub fn paraboloid() -> Self {
        Self::from_parts(
            Vector3::zeros(),
            Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 1.0)),
            Vector3::new(0.0, -0.5, 0.0),
            0.0,
        )
    }

    /// The solid one-sheet hyperboloid around y, `x² - y² + z² - 1 <= 0`
    /// (the inside of the waisted tube; non-convex).
    pub fn hyperboloid_one_sheet() -> Self {
        Self::diagonal(1.0, -1.0, 1.0, -1.0)
    }

    /// The solid two-sheet hyperboloid around y, `x² - y² + z² + 1 <= 0`
    /// (the inside of both bowls, `|y| >= 1`; non-convex).
    pub fn hyperboloid_two_sheets() -> Self {
        Self::diagonal(1.0, -1.0, 1.0, 1.0)
    }

    /// The other side of the surface, `-Q` (exact).
    pub fn complement(&self) -> Self {
        Self::with_definiteness(self.centre, -self.a, -self.w, -self.k, self.definite.map(|psd| !psd), self.axis)
    }

    /// The solid moved by `m`: `M⁻ᵀ Q M⁻¹`, computed as `L⁻ᵀ A L⁻¹` for the
    /// quadratic part while the centre moves exactly by `m`. A congruence
    /// keeps `A`'s definiteness, so a convex solid stays convex even where
    /// rounding leaves the stored `L⁻ᵀ A L⁻¹` an eigenvalue of `-ε`. A null
    /// axis `n` (an ideal cylinder's) moves to `L n`, exactly the direction
    /// the moved solid is invariant along, however rounding left `A`.
    ///
    /// Unchecked: a placement that overflows leaves non-finite coefficients
    /// ([`Quadric::is_finite`]), one that underflows a different solid;
    /// [`try_transformed`](Self::try_transformed) reports both.
    pub fn transformed(&self, m: &Transform) -> Self {
        let (a, w) = self.placed_parts(m);
        let axis = m.linear() * self.axis;
        Self::with_definiteness(m.apply_point(&Point3::from(self.centre)).coords, a, w, self.k, self.definite, axis)
    }

    /// The solid moved by `v`: [`transformed`](Self::transformed) by a
    /// translation, without its matrix products. A translation leaves `A`,
    /// `w` and `k` as they are and moves the centre by one rounding per
    /// coordinate, so the two agree (to the sign of a zero coefficient,
    /// which no query reads; tested).
    pub fn translated(&self, v: &Vector3<f64>) -> Self {
        Quadric { centre: self.centre + v, ..*self }
    }

    /// `L⁻ᵀ A L⁻¹` (symmetrised) and `L⁻ᵀ w`, before the power-of-two
    /// normalisation of [`Quadric::with_definiteness`].
    fn placed_parts(&self, m: &Transform) -> (Matrix3<f64>, Vector3<f64>) {
        let li = m.linear_inverse();
        let a = li.transpose() * self.a * li;
        // Exact symmetry (the product is symmetric up to rounding only).
        let a = (a + a.transpose()) * 0.5;
        (a, li.transpose() * self.w)
    }

    /// [`transformed`](Self::transformed), checked: the same solid, or
    /// [`GeometryError::NonFinite`] if a coefficient overflows, or
    /// [`GeometryError::Underflow`] if a part of the solid underflows (see
    /// [`Quadric::underflow`] for the criterion).
    ///
    /// ```
    /// use quadric::{GeometryError, Quadric, Transform};
    /// let far = Transform::scale(1e170).unwrap();
    /// assert!(matches!(Quadric::sphere().try_transformed(&far), Err(GeometryError::Underflow { .. })));
    /// let big = Transform::scale(1e100).unwrap();
    /// assert_eq!(Quadric::sphere().try_transformed(&big), Ok(Quadric::sphere().transformed(&big)));
    /// ```
    pub fn try_transformed(&self, m: &Transform) -> Result<Self, GeometryError> {
        let placed = self.transformed(m);
        if !placed.is_finite() {
            return Err(GeometryError::NonFinite { what: "a coefficient of the placed solid" });
        }
        let (a, w) = self.placed_parts(m);
        match self.underflow(m.linear_inverse(), &a, &w, &placed) {
            Some(part) => Err(GeometryError::Underflow { part }),
            None => Ok(placed),
        }
    }

    /// Which part of this quadric, placed as `placed` by a map with linear
    /// inverse `li` (`a`, `w`: the placed parts before normalisation), lost
    /// its value to underflow; `None` if none did.
    ///
    /// Underflow, not smallness: in exact arithmetic a congruence by an
    /// invertible `L⁻¹` keeps every non-zero part non-zero (`A`'s rank and
    /// signs, `w ≠ 0`), and rounding in the normal range only perturbs a
    /// coefficient relative to the terms it is summed from. Below
    /// `f64::MIN_POSITIVE` the error becomes absolute, so a coefficient whose
    /// exact value is stored there (zero or subnormal, before or after the
    /// power-of-two normalisation) has lost its bits: a unit ball scaled by
    /// `1e170` has `A = 1e-340·I`, stored as zero (all of space), and one
    /// scaled by `[1e170, 1, 1]` loses the `x²` term (a tube). So a part is
    /// reported when its exact value is *real* and is stored below the
    /// normal range. Real is decided from unit-sized copies of the columns
    /// `l_i` of `L⁻¹` (`l_i = 2^p n_i`, `|n_i|∞` in `[1, 2)`, exact): the
    /// diagonal entry `A'_ii = 2^2p n_iᵀ A n_i` is real when `n_iᵀAn_i`
    /// exceeds `2⁻⁴⁰` of its terms `|n_i|ᵀ|A||n_i|` (a rotation's exact
    /// zeros come out as rounding residue near `2⁻⁵²` of their terms, and
    /// are never reported) and those terms are normal (a subnormal input
    /// coefficient is the input's). The checked parts: the whole of `A` and
    /// each diagonal entry (for a semi-definite `A` the diagonal bounds the
    /// rest, `|A_ij|² <= A_ii A_jj`); `w_i` where `A` is flat along `l_i`
    /// (a paraboloid's axis: there `w` alone shapes the solid; elsewhere it
    /// only shifts the centre by `w/A`, which underflows harmlessly); and
    /// `k`, which the normalisation alone can push down. Not reported: a
    /// curvature lost to ordinary rounding, such as a ball scaled by
    /// `[1e170, 1, 1]` and then rotated, whose `1e-340` sits in entries of
    /// `0.5` (the same as `[1e20, 1, 1]` rotated, docs/errors.md).
    fn underflow(
        &self,
        li: &Matrix3<f64>,
        a: &Matrix3<f64>,
        w: &Vector3<f64>,
        placed: &Quadric,
    ) -> Option<&'static str> {
        const NORMAL: f64 = f64::MIN_POSITIVE;
        const REAL: f64 = 1.0 / (1u64 << 40) as f64;
        let below = |raw: f64, stored: f64| raw.abs() < NORMAL || stored.abs() < NORMAL;
        if self.a.amax() >= NORMAL && below(a.amax(), placed.a.amax()) {
            return Some("quadratic part");
        }
        let abs_a = self.a.abs();
        for i in 0..3 {
            let n = unit_sized(&li.column(i).into_owned());
            let (b, terms) = (n.dot(&(self.a * n)), n.abs().dot(&(abs_a * n.abs())));
            let curved = terms >= NORMAL && b.abs() > REAL * terms;
            if curved && below(a[(i, i)], placed.a[(i, i)]) {
                return Some(
                    ["quadratic coefficient along x", "quadratic coefficient along y", "quadratic coefficient along z"]
                        [i],
                );
            }
            let (c, c_terms) = (n.dot(&self.w), n.abs().dot(&self.w.abs()));
            if !curved && c_terms >= NORMAL && c.abs() > REAL * c_terms && below(w[i], placed.w[i]) {
                return Some(
                    ["linear coefficient along x", "linear coefficient along y", "linear coefficient along z"][i],
                );
            }
        }
        if self.k.abs() >= NORMAL && placed.k.abs() < NORMAL {
            return Some("constant");
        }
        None
    }

    /// The local centre `c` the coefficients are taken around.
    pub fn centre(&self) -> Point3<f64> {
        Point3::from(self.centre)
    }

    /// The null axis `n` of an ideal cylinder, if the quadric is one: built
    /// with `A n = 0` and `w·n = 0` exactly (`tube_x/y/z`, or coefficients
    /// with a zero row of `A` and zero `w` there: an axis-aligned cylinder of
    /// any cross-section), then moved (`n` becomes `L n`). The solid is
    /// invariant along `n` by definition: `f(x)` is taken as `f(x - αn)` with
    /// `α n` the component of `x - c` along `n` wherever that component
    /// exceeds 2²⁰ times the rest (a point far along the axis), so that the
    /// rounding of the moved `A` (slightly definite along `n`: a rotated tube
    /// is stored as an ellipsoid ~10⁸ long) does not close the cylinder. Near
    /// the centre the two agree to rounding. Largest component ±1.
    pub fn axis(&self) -> Option<Vector3<f64>> {
        (self.axis != Vector3::zeros()).then_some(self.axis)
    }

    /// The quadratic part `A` (upper-left 3x3 of `Q`).
    pub fn quadratic_part(&self) -> &Matrix3<f64> {
        &self.a
    }

    /// The world-space matrix `Q` (for export; loses accuracy far from the
    /// origin). Like every stored coefficient it is the input's up to a
    /// power-of-two factor (see [`local_parts`](Self::local_parts)).
    pub fn matrix(&self) -> Matrix4<f64> {
        let c = self.centre;
        let ac = self.a * c;
        let w = self.w - ac;
        let k = c.dot(&ac) - 2.0 * self.w.dot(&c) + self.k;
        let mut q = self.a.to_homogeneous();
        q.fixed_view_mut::<3, 1>(0, 3).copy_from(&w);
        q.fixed_view_mut::<1, 3>(3, 0).copy_from(&w.transpose());
        q[(3, 3)] = k;
        q
    }

    /// The world-space coefficients `[a, b, c, d, e, f, g, h, j, k]`.
    pub fn coefficients(&self) -> [f64; 10] {
        let q = self.matrix();
        [q[(0, 0)], q[(1, 1)], q[(2, 2)], q[(0, 1)], q[(0, 2)], q[(1, 2)], q[(0, 3)], q[(1, 3)], q[(2, 3)], q[(3, 3)]]
    }

    /// The coefficients relative to the local centre, as `(c, A, w, k)`.
    ///
    /// They are stored scaled by a power of two that brings the largest of
    /// them into `[1, 2)`: the same solid, with `f` in range wherever
    /// `|x - c|²` is.
    pub fn local_parts(&self) -> (Point3<f64>, Matrix3<f64>, Vector3<f64>, f64) {
        (Point3::from(self.centre), self.a, self.w, self.k)
    }

    /// `f(x)`, evaluated relative to the centre. The solid is `f <= 0`.
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        self.value_at_offset(&self.offset(x))
    }

    /// `x - c`, slid along the null axis when far along it (see [`Quadric::axis`]).
    #[inline(always)]
    fn offset(&self, x: &Point3<f64>) -> Vector3<f64> {
        let d = x.coords - self.centre;
        if self.far_along_axis(&d) {
            self.slide(&d, &Vector3::zeros()).0
        } else {
            d
        }
    }

    /// Whether `d` is along the null axis beyond 2²⁰ times
    /// its distance from it: `(n·d)² > (1 - 2⁻⁴⁰) |n|²|d|²` (false without an axis).
    #[inline(always)]
    fn far_along_axis(&self, d: &Vector3<f64>) -> bool {
        let nd = self.axis.dot(d);
        nd != 0.0 && nd * nd > (1.0 - AXIS_SLIDE_RATIO_INV2) * (self.axis.norm_squared() * d.norm_squared())
    }

    /// `(d + lo) - αn` with `α = n·d / n·n`, as a double `d'` and its error
    /// `lo'`: the product `αn` exactly (FMA) and the cancellation against
    /// `d` exact (the two are close), so `d'` is right to its own ulps.
    #[cold]
    #[inline(never)]
    fn slide(&self, d: &Vector3<f64>, lo: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let n = &self.axis;
        let alpha = n.dot(d) / n.norm_squared();
        let (mut out, mut out_lo) = (Vector3::zeros(), Vector3::zeros());
        for i in 0..3 {
            let (p, p_lo) = two_product(alpha, n[i]);
            let (hi, hi_lo) = two_sum(d[i], -p);
            let rest = hi_lo + (lo[i] - p_lo);
            out[i] = hi + rest;
            out_lo[i] = two_sum_error(hi, rest, out[i]);
        }
        (out, out_lo)
    }

    /// Whether `x` lies in the closed solid.
    pub fn contains_point(&self, x: &Point3<f64>) -> bool {
        self.value(x) <= 0.0
    }

    /// The gradient `∇f(x) = 2 (A (x-c) + w)`, pointing out of the solid.
    pub fn gradient(&self, x: &Point3<f64>) -> Vector3<f64> {
        2.0 * (self.a * self.offset(x) + self.w)
    }

    /// The outward unit normal at `x` (the first three components of
    /// `Q [x;1]`, normalised); `None` where the gradient vanishes (a cone's apex).
    pub fn normal(&self, x: &Point3<f64>) -> Option<Vector3<f64>> {
        crate::normal::unit(self.gradient(x))
    }

    /// Whether every ray meets the solid in at most one interval: `A` is
    /// positive semi-definite (ellipsoids, cylinders, paraboloids, slabs).
    ///
    /// Decided exactly for a quadric built from coefficients or a matrix (all
    /// principal minors `>= 0`, each summed without rounding), and kept
    /// through [`transformed`](Self::transformed); `intervals` reads `s = rᵀAr`
    /// of a convex solid as `max(s, 0)` (and of a concave one as `min(s, 0)`),
    /// so it never returns more than one interval for a convex solid.
    pub fn is_convex(&self) -> bool {
        self.definite == Some(true) || self.a == Matrix3::zeros()
    }

    /// Whether every coefficient is finite.
    pub fn is_finite(&self) -> bool {
        self.a.iter().chain(self.w.iter()).chain(self.centre.iter()).all(|c| c.is_finite()) && self.k.is_finite()
    }

    /// `f(c + d)`, the value at an offset `d` from the centre.
    #[inline(always)]
    fn value_at_offset(&self, d: &Vector3<f64>) -> f64 {
        d.dot(&(self.a * d + self.w + self.w)) + self.k
    }

    /// The set of `λ >= 0` with `p + λr` inside the solid; every finite end
    /// carries `solid` as the surface it lies on.
    ///
    /// `f(p + λr) = sλ² + 2tλ + u` with `s = rᵀAr`, `t = rᵀ(A(p-c) + w)`,
    /// `u = f(p)`, solved by the case table of docs/model.md §2.2. Numerics (see
    /// `docs/quadric.md`): coefficients relative to the local centre `c`;
    /// the ray re-based exactly at the foot of the perpendicular from `c`,
    /// near the roots, so that nothing cancels however far the ray starts;
    /// `t² - su` by a fused difference of products; stable roots.
    ///
    /// This is [`Precision::Accurate`], the default; see
    /// [`intervals_with`](Self::intervals_with) for the other modes.
    #[inline]
    pub fn intervals(&self, ray: &Ray, solid: u32) -> IntervalSet {
        self.intervals_with(ray, solid, Precision::default())
    }

    /// The kernel of [`Precision::Accurate`] (see [`Quadric::intervals`]).
    fn intervals_accurate(&self, ray: &Ray, solid: u32) -> Pieces {
        let (p, r) = (ray.origin().coords, ray.direction());
        let d = p - self.centre;
        // The foot of the perpendicular from the centre, `λ₀ = -r·d`. Any `λ₀`
        // gives the same quadratic in `λ - λ₀`; this one puts the base point
        // within the quadric's own scale of the roots (`|x - c|² = |b|² + ρ²`
        // for a root `x = c + b + ρr`, so `|ρ| <= |x - c|`), costs no division
        // and is never far off even where `s ≈ 0` puts the apex `-t/s` at
        // infinity.
        let lambda0 = -r.dot(&d);
        let base = Vector3::new(lambda0.mul_add(r.x, d.x), lambda0.mul_add(r.y, d.y), lambda0.mul_add(r.z, d.z));
        // `base` is rounded at its own (small) scale; `d = p - c` was rounded
        // at the distance's. TwoSum recovers that error exactly as `lo`, which
        // enters `t` and `u` to first order (its square is far below rounding).
        let lo = Vector3::new(
            two_sum_error(p.x, -self.centre.x, d.x),
            two_sum_error(p.y, -self.centre.y, d.y),
            two_sum_error(p.z, -self.centre.z, d.z),
        );
        // Far along an ideal cylinder's axis: slide the origin along it (the
        // line moves, `λ` does not), see `Quadric::axis`.
        let (d, lo, lambda0, base) = if self.far_along_axis(&d) {
            let (d, lo) = self.slide(&d, &lo);
            let lambda0 = -r.dot(&d);
            (
                d,
                lo,
                lambda0,
                Vector3::new(lambda0.mul_add(r.x, d.x), lambda0.mul_add(r.y, d.y), lambda0.mul_add(r.z, d.z)),
            )
        } else {
            (d, lo, lambda0, base)
        };
        let ar = self.a_times(&r);
        let rw = r.dot(&self.w);
        let s = r.dot(&ar);
        // `t = rᵀ(A b + w) = (Ar)·b + rᵀw` (`A` symmetric), in parallel to `g`.
        let (s, t) = if s.abs() >= self.flat {
            (s, ar.dot(&base) + (rw + ar.dot(&lo)))
        } else {
            self.nearly_flat_s_t(&r, &base, &lo, rw)
        };
        // A semi-definite `A` (possibly carried through a transform whose
        // rounding left an eigenvalue of -ε) gives `s` of one sign only.
        let s = match self.definite {
            Some(true) => s.max(0.0),
            Some(false) => s.min(0.0),
            None => s,
        };
        let g = self.a_times(&base) + self.w;
        let u = base.dot(&(g + self.w)) + self.k + 2.0 * lo.dot(&g);
        if s == 0.0 {
            return linear_set(t, u, lambda0, solid);
        }
        let disc = difference_of_products(t, t, s, u);
        // `t² - su` is the same from any base, but from this one it is formed
        // from terms of size `t²` and `s·bᵀ(Ab + 2w)`, each rounded at `ε|b|`
        // per component. Where those terms swamp the discriminant (a ray
        // passing a cylinder far along its axis: `b` is far out, `t ≈ |A||b|`)
        // the decision is rounding noise: solve again from the apex, where
        // `t ≈ 0` and `u` is the ray's own offset. (`|b|` compared with the
        // apex's distance does not tell: along the axis `A` ignores `b`.)
        if t != 0.0 && disc.abs() < REBASE_MARGIN * (t * t + s.abs() * base.amax() * (g + self.w).amax()) {
            if let Some(set) = self.intervals_from_apex(&r, &d, &lo, (lambda0, s, t), (&g, &ar), solid) {
                return set;
            }
        }
        quadratic_set(s, t, u, disc, lambda0, solid)
    }

    /// The quadratic re-based at the apex `λ₁ = λ₀ - t/s` of the first solve
    /// (`g = Ab + w` and `Ar` from it), with `d = p - c` and its rounding
    /// error `lo` as before; `s` is the same from any base. `None` where the
    /// gradient at the apex is not much smaller than at the foot (a bounded
    /// solid near tangency: the apex is no nearer the solid's core, and the
    /// first solve is as good), or where the apex or the new coefficients
    /// overflow (coordinates near the documented limit): the first solve
    /// stands then.
    #[cold]
    #[inline(never)]
    fn intervals_from_apex(
        &self,
        r: &Vector3<f64>,
        d: &Vector3<f64>,
        lo: &Vector3<f64>,
        (lambda0, s, t): (f64, f64, f64),
        (g, ar): (&Vector3<f64>, &Vector3<f64>),
        solid: u32,
    ) -> Option<Pieces> {
        let mu = -t / s;
        let lambda1 = lambda0 + mu;
        let g_apex = Vector3::new(mu.mul_add(ar.x, g.x), mu.mul_add(ar.y, g.y), mu.mul_add(ar.z, g.z));
        if !(lambda1.is_finite() && g_apex.amax() < 0.25 * g.amax()) {
            return None;
        }
        let base = Vector3::new(lambda1.mul_add(r.x, d.x), lambda1.mul_add(r.y, d.y), lambda1.mul_add(r.z, d.z));
        let rw = r.dot(&self.w);
        let t = if s.abs() >= self.flat {
            ar.dot(&base) + (rw + ar.dot(lo))
        } else {
            self.nearly_flat_s_t(r, &base, lo, rw).1
        };
        let g = self.a_times(&base) + self.w;
        let u = base.dot(&(g + self.w)) + self.k + 2.0 * lo.dot(&g);
        let disc = difference_of_products(t, t, s, u);
        disc.is_finite().then(|| quadratic_set(s, t, u, disc, lambda1, solid))
    }

    /// `s` and `t` for a ray nearly along a direction in which the quadric is
    /// flat (a cylinder's or paraboloid's axis, a cone's generator): there
    /// `Ar` and `s = rᵀAr` cancel from `|A|` down to `|A| sin θ` and
    /// `|A| sin² θ`, and rounded at `|A|` they would move a hit at distance
    /// `ρ ~ 1/sin θ` by `ε ρ³`. Compensated dot products (Ogita, Rump, Oishi:
    /// `Dot2`) make them accurate to a few ulps of their own size.
    #[cold]
    #[inline(never)]
    fn nearly_flat_s_t(&self, r: &Vector3<f64>, base: &Vector3<f64>, lo: &Vector3<f64>, rw: f64) -> (f64, f64) {
        let mut ar = Vector3::zeros();
        let mut ar_lo = Vector3::zeros();
        for i in 0..3 {
            (ar[i], ar_lo[i]) = dot2(&self.a.row(i).transpose(), r);
        }
        let (s, s_lo) = dot2(r, &ar);
        let s = s + (s_lo + r.dot(&ar_lo));
        let (t, t_lo) = dot2(&ar, base);
        let t = t + (t_lo + ar_lo.dot(base) + rw + ar.dot(lo));
        (s, t)
    }
}

/// Below this fraction of the size of the terms it is formed from, the
/// discriminant at the foot of the perpendicular is not trusted
/// (`Quadric::intervals`); well above the few ulps those terms are rounded
/// to, so that every case that needs the apex is caught.
const REBASE_MARGIN: f64 = 1.0 / (1u64 << 40) as f64;

/// A point is "far along" a null axis when its component along the axis
/// exceeds 2²⁰ times its distance from it ([`Quadric::axis`]); this is
/// `2⁻⁴⁰`, the matching bound on `1 - cos²`. Below it the rounding of a
/// moved `A` (`ε|A|` per entry) changes `f` by at most `2⁻¹²` of the
/// distance term, about what the stored coefficients already carry.
const AXIS_SLIDE_RATIO_INV2: f64 = 1.0 / (1u64 << 40) as f64;

/// `v` times the power of two that brings its largest component into
/// `[1, 2)` (zero stays zero); exact unless a component falls below the
/// normal range relative to the largest.
fn unit_sized(v: &Vector3<f64>) -> Vector3<f64> {
    let m = v.amax();
    if !(m > 0.0 && m.is_finite()) {
        return *v;
    }
    // Two factors, each a normal power of two, cover every finite `m`.
    let e = m.log2().floor() as i32;
    v * pow2(-e / 2) * pow2(-e - (-e / 2))
}

/// The degenerate coefficient sets `from_coefficients` and `from_matrix`
/// refuse: no quadratic or linear part and a constant `k >= 0`.
fn not_degenerate(a: &Matrix3<f64>, w: &Vector3<f64>, k: f64) -> Result<(), GeometryError> {
    if *a != Matrix3::zeros() || *w != Vector3::zeros() || k < 0.0 {
        Ok(())
    } else if k == 0.0 {
        Err(GeometryError::Degenerate { reason: "all ten coefficients are zero (0 <= 0 holds everywhere)" })
    } else {
        Err(GeometryError::Degenerate {
            reason: "only the constant k is non-zero and it is positive (k <= 0 holds nowhere: the solid is empty)",
        })
    }
}

/// The exact null axis of `A` that `w` is orthogonal to, for the cases
/// decided without rounding: exactly one zero row of `A` (an axis-aligned
/// cylinder, elliptic, hyperbolic or parabolic-free) with `w` zero there.
/// Zero otherwise (slabs have two null directions and no single axis).
fn exact_axis(a: &Matrix3<f64>, w: &Vector3<f64>) -> Vector3<f64> {
    let null = |i: usize| a.row(i).iter().all(|&x| x == 0.0) && w[i] == 0.0;
    match (null(0), null(1), null(2)) {
        (true, false, false) => Vector3::x(),
        (false, true, false) => Vector3::y(),
        (false, false, true) => Vector3::z(),
        _ => Vector3::zeros(),
    }
}

/// Whether the symmetric `m` is positive semi-definite, decided exactly: all
/// seven principal minors are `>= 0` (for a symmetric matrix this is
/// equivalent), each evaluated without rounding.
fn semi_definite(m: &Matrix3<f64>) -> bool {
    let (a, b, c) = (m[(0, 0)], m[(1, 1)], m[(2, 2)]);
    let (d, e, f) = (m[(0, 1)], m[(0, 2)], m[(1, 2)]);
    let minor = |x: f64, y: f64, z: f64| exact_sign_of_sum(&[(1.0, x, y, 1.0), (-1.0, z, z, 1.0)]) >= 0;
    a >= 0.0
        && b >= 0.0
        && c >= 0.0
        && minor(a, b, d)
        && minor(a, c, e)
        && minor(b, c, f)
        && exact_sign_of_sum(&[(1.0, a, b, c), (2.0, d, e, f), (-1.0, a, f, f), (-1.0, b, e, e), (-1.0, c, d, d)]) >= 0
}

/// `2^e` for `-1022 <= e <= 1023`.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

// The sets below are built already clipped to the ray, `λ >= 0`, in one
// construction, as `Pieces` (an `IntervalSet` is a few hundred bytes, and
// building it whole and then clipping it copies it twice). They agree with
// `set.clip(0.0, ∞)` of the unclipped set: a clipped end is free at `+0.0`, a
// root at exactly zero keeps its solid, and no end is `-0.0` (`x + 0.0`).

/// The whole ray, `[0, ∞)`.
#[inline(always)]
fn whole_ray() -> Pieces {
    Pieces::from_interval(Bound::free(0.0), Bound::free(f64::INFINITY))
}

/// `(-∞, root] ∩ [0, ∞)`.
#[inline(always)]
fn up_to(root: f64, solid: u32) -> Pieces {
    Pieces::from_interval(Bound::free(0.0), Bound::new(root + 0.0, solid))
}

/// `[root, ∞) ∩ [0, ∞)`.
#[inline(always)]
fn from(root: f64, solid: u32) -> Pieces {
    let enter = if root >= 0.0 { Bound::new(root + 0.0, solid) } else { Bound::free(0.0) };
    Pieces::from_interval(enter, Bound::free(f64::INFINITY))
}

/// `{λ >= 0 : 2tλ + u <= 0}` (the `s = 0` rows of the table), for the ray
/// re-based at `lambda0`.
#[inline(always)]
fn linear_set(t: f64, u: f64, lambda0: f64, solid: u32) -> Pieces {
    if !(t.is_finite() && u.is_finite()) {
        return Pieces::empty();
    }
    if t == 0.0 {
        return if u <= 0.0 { whole_ray() } else { Pieces::empty() };
    }
    let root = lambda0 + -u / (2.0 * t);
    if t > 0.0 {
        up_to(root, solid)
    } else {
        from(root, solid)
    }
}

/// `{λ >= 0 : sλ² + 2tλ + u <= 0}` for `s != 0`, for the ray re-based at
/// `lambda0`.
#[inline(always)]
fn quadratic_set(s: f64, t: f64, u: f64, disc: f64, lambda0: f64, solid: u32) -> Pieces {
    if !(disc.is_finite() && lambda0.is_finite()) {
        return Pieces::empty();
    }
    if disc < 0.0 {
        return if s > 0.0 { Pieces::empty() } else { whole_ray() };
    }
    let (r1, r2) = stable_roots(s, t, u, disc);
    let (l1, l2) = (lambda0 + r1, lambda0 + r2);
    if s > 0.0 {
        let enter = if l1 >= 0.0 { Bound::new(l1 + 0.0, solid) } else { Bound::free(0.0) };
        Pieces::from_interval(enter, Bound::new(l2 + 0.0, solid))
    } else if l1 < l2 && l1 > 0.0 {
        // Two disjoint pieces, `[0, l1]` and `[l2, ∞)`: within capacity.
        up_to(l1, solid).then(from(l2, solid)).unwrap_or_else(whole_ray)
    } else if l1 < l2 {
        from(l2, solid)
    } else if l1 == l2 {
        // The pieces touch (a tangent ray from outside): the whole line.
        whole_ray()
    } else {
        Pieces::empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The cached norms are the stored parts' norms, through transforms
        /// and complements (every constructor goes through
        /// `with_definiteness`).
        #[test]
        fn norms_are_those_of_the_stored_parts(
            q in proptest::prop_oneof![crate::strategies::quadric(), crate::strategies::elementary_quadric()],
        ) {
            for q in [q, q.complement()] {
                let (_, a, w, _) = q.local_parts();
                proptest::prop_assert_eq!(q.norms(), (a.norm(), w.norm()));
            }
        }

        /// The diagonal fast path (`Quadric::a_times`, the hit point's
        /// cross terms) answers exactly what the full product does.
        #[test]
        fn diagonal_path_is_the_full_product(
            abc in proptest::array::uniform3(-4.0..4.0f64),
            ghj in proptest::array::uniform3(-2.0..2.0f64),
            k in -3.0..3.0f64,
            ray in crate::strategies::ray(6.0),
        ) {
            let Ok(q) = Quadric::from_coefficients([abc[0], abc[1], abc[2], 0.0, 0.0, 0.0, ghj[0], ghj[1], ghj[2], k]) else {
                return Ok(());
            };
            proptest::prop_assert!(q.diagonal);
            let full = Quadric { diagonal: false, ..q };
            let (fast, slow) = (q.intervals(&ray, 0), full.intervals(&ray, 0));
            proptest::prop_assert_eq!(fast.as_slice(), slow.as_slice());
            for iv in fast.iter() {
                for t in [iv.enter.t, iv.exit.t].into_iter().filter(|t| t.is_finite()) {
                    proptest::prop_assert_eq!(q.hit_point(&ray, t), full.hit_point(&ray, t));
                }
            }
        }
    }

    proptest::proptest! {
        /// `pieces_with` is `intervals_with` without the set's buffer, in
        /// every precision mode; the grid quadrics hit the tangent and
        /// two-piece cases exactly.
        #[test]
        fn pieces_are_the_interval_set(
            q in proptest::prop_oneof![crate::strategies::quadric(), crate::strategies::elementary_quadric()],
            ray in proptest::prop_oneof![crate::strategies::ray(6.0), crate::strategies::grid_ray(3)],
        ) {
            for precision in [Precision::Fast, Precision::Accurate, Precision::Certified] {
                let (pieces, set) = (q.pieces_with(&ray, 3, precision), q.intervals_with(&ray, 3, precision));
                proptest::prop_assert_eq!(pieces.as_slice(), set.as_slice(), "{:?}", precision);
                proptest::prop_assert_eq!(IntervalSet::from(pieces), set);
            }
        }

        /// `Pieces::then` is the union of the two sets where the second
        /// starts no earlier than the first.
        #[test]
        fn then_is_the_union(
            a in (-4i32..4, 1i32..4),
            b in proptest::collection::vec((0i32..4, 1i32..4), 0..=2),
        ) {
            let iv = |(lo, len): (i32, i32), solid: u32| (Bound::new(f64::from(lo), solid), Bound::new(f64::from(lo + len), solid));
            let first = iv(a, 0);
            let later: Vec<_> = b.iter().map(|&(gap, len)| iv((a.0 + gap, len), 1)).collect();
            // `later` as pieces: sorted, disjoint (skipped where they are not).
            let mut b_set = IntervalSet::empty();
            let mut b_pieces = Pieces::empty();
            for &(e, x) in &later {
                if b_set.as_slice().last().is_some_and(|last| e.t <= last.exit.t) {
                    return Ok(());
                }
                let one = IntervalSet::from_interval(e, x);
                let (Ok(u), Some(p)) = (b_set.union(&one), b_pieces.then(Pieces::from_interval(e, x))) else { return Ok(()) };
                (b_set, b_pieces) = (u, p);
            }
            proptest::prop_assert_eq!(b_pieces.as_slice(), b_set.as_slice());
            let want = IntervalSet::from_interval(first.0, first.1).union(&b_set).expect("within capacity");
            match Pieces::from_interval(first.0, first.1).then(b_pieces) {
                Some(got) => proptest::prop_assert_eq!(got.as_slice(), want.as_slice()),
                None => proptest::prop_assert!(want.len() > 2),
            }
        }
    }

    fn check_semi_definite(rows: [[f64; 3]; 3], expected: bool) {
        let m = Matrix3::from_fn(|i, j| rows[i][j]);
        assert_eq!(semi_definite(&m), expected, "{rows:?}");
    }

    #[test]
    fn semi_definiteness_is_exact() {
        let up = 1.0 + f64::EPSILON;
        check_semi_definite([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], true);
        check_semi_definite([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]], true);
        check_semi_definite([[1.0, 0.0, 0.0], [0.0, -1e-300, 0.0], [0.0, 0.0, 1.0]], false);
        // Rank one: every minor is exactly zero.
        check_semi_definite([[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]], true);
        // A 2x2 minor of 1 - (1 + ε)² < 0.
        check_semi_definite([[1.0, up, 0.0], [up, 1.0, 0.0], [0.0, 0.0, 1.0]], false);
        // Only the determinant is negative: 2x2 minors 1 - 1 = 0, det = -(ε)²-ish.
        check_semi_definite([[1.0, 1.0, 1.0], [1.0, 1.0, up], [1.0, up, 1.0]], false);
        check_semi_definite([[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]], true);
        check_semi_definite([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], false);
    }

    #[test]
    fn convexity_survives_transforms_and_flips_with_the_complement() {
        let turn = Transform::rotate_x_degrees(30.0)
            .and_then(|r| Ok(r.then(&Transform::rotate_z_degrees(70.0)?)))
            .expect("valid rotations");
        for q in [Quadric::sphere(), Quadric::tube_y(), Quadric::paraboloid()] {
            let moved = q.transformed(&turn);
            assert!(moved.is_convex(), "{moved:?}");
            assert!(!moved.complement().is_convex());
            assert!(moved.complement().complement().is_convex());
        }
        for q in [Quadric::cone(), Quadric::hyperboloid_one_sheet(), Quadric::hyperboloid_two_sheets()] {
            assert!(!q.transformed(&turn).is_convex());
        }
        let slightly_waisted = Quadric::from_coefficients([1.0, -1e-13, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
        assert!(!slightly_waisted.expect("finite").is_convex());
    }

    #[test]
    fn coefficients_are_normalised_by_a_power_of_two() {
        let big = Quadric::from_coefficients([4.0, 4.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -12.0]).expect("finite");
        assert_eq!(big.coefficients(), [0.5, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.5]);
        let tiny = Quadric::sphere().transformed(&Transform::scale(1e-100).expect("valid"));
        let (_, a, _, k) = tiny.local_parts();
        assert!((1.0..2.0).contains(&a.amax().max(k.abs())), "{tiny:?}");
        assert!(tiny.contains_point(&Point3::new(0.0, 0.0, 0.9e-100)));
        assert!(!tiny.contains_point(&Point3::new(0.0, 0.0, 1.1e-100)));
    }
}
