//! Axis-aligned boxes, possibly infinite, and the tight box of a block.
//!
//! A block's box is found in two steps (see `docs/complex.md`):
//!
//! 1. *Analytic boxes* of its convex quadrics: an ellipsoid's box from the
//!    inverse of its quadratic part, an elliptic cylinder's cross-section box
//!    swept along its axis over the range its half-spaces allow.
//! 2. *Interval constraint propagation*: every solid in turn narrows each
//!    axis of the running box to the values it allows given the other axes'
//!    ranges (a half-space exactly, a quadric by interval arithmetic on the
//!    quadratic in that coordinate), until nothing moves.
//!
//! Every bound is rounded outwards, so the box is conservative: it never
//! cuts off a point of the block.

use arrayvec::ArrayVec;
use quadric::nalgebra::{Matrix3, Point3, Vector3};
use quadric::roots::difference_of_products;
use quadric::{Ray, Solid};

/// An axis-aligned box `[min, max]`; coordinates may be `±∞` for unbounded blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lower corner.
    pub min: Point3<f64>,
    /// The upper corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// The box covering all of space.
    pub const INFINITE: Aabb = Aabb {
        min: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        max: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
    };

    /// The empty box.
    pub const EMPTY: Aabb = Aabb {
        min: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        max: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    };

    /// Whether the box is empty.
    pub fn is_empty(&self) -> bool {
        (0..3).any(|i| self.min[i] > self.max[i])
    }

    /// Whether every coordinate is finite (and the box is not empty).
    pub fn is_bounded(&self) -> bool {
        !self.is_empty() && self.min.iter().chain(self.max.iter()).all(|c| c.is_finite())
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.inf(&other.min), max: self.max.sup(&other.max) }
    }

    /// The intersection of both.
    pub fn intersection(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.sup(&other.min), max: self.max.inf(&other.max) }
    }

    /// The edge lengths `max - min`: zero on every axis of an empty box,
    /// `∞` on an unbounded axis, never NaN.
    ///
    /// ```
    /// use complex::Aabb;
    /// use quadric::nalgebra::{Point3, Vector3};
    /// let b = Aabb { min: Point3::new(-1.0, 0.0, 2.0), max: Point3::new(1.0, 0.5, 2.0) };
    /// assert_eq!(b.size(), Vector3::new(2.0, 0.5, 0.0));
    /// assert_eq!(Aabb::EMPTY.size(), Vector3::zeros());
    /// assert_eq!(Aabb::INFINITE.size().x, f64::INFINITY);
    /// ```
    pub fn size(&self) -> Vector3<f64> {
        if self.is_empty() {
            return Vector3::zeros();
        }
        self.max - self.min
    }

    /// The centre, for a bounded box; `None` for an empty or unbounded one
    /// (whose centre would be NaN).
    ///
    /// ```
    /// use complex::Aabb;
    /// use quadric::nalgebra::Point3;
    /// let b = Aabb { min: Point3::new(-1.0, 0.0, 2.0), max: Point3::new(1.0, 0.5, 4.0) };
    /// assert_eq!(b.center(), Some(Point3::new(0.0, 0.25, 3.0)));
    /// assert_eq!(Aabb::EMPTY.center(), None);
    /// assert_eq!(Aabb::INFINITE.center(), None);
    /// let huge = Aabb { min: Point3::new(-1e308, 0.0, 0.0), max: Point3::new(1.5e308, 0.0, 0.0) };
    /// assert_eq!(huge.center(), Some(Point3::new(0.25e308, 0.0, 0.0)));
    /// ```
    pub fn center(&self) -> Option<Point3<f64>> {
        // Halves first: `min + max` and `max - min` overflow for boxes
        // spanning more than the largest double, their halves never do.
        self.is_bounded().then(|| Point3::from(self.min.coords * 0.5 + self.max.coords * 0.5))
    }

    /// Whether `p` lies in the closed box.
    pub fn contains_point(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|i| self.min[i] <= p[i] && p[i] <= self.max[i])
    }

    /// The parameter range `[t0, t1]` (clipped to `[0, max_t]`) where the
    /// ray is inside the box, or `None`. Conservative: never misses a point
    /// of the box the ray passes through.
    #[inline]
    pub fn ray_range(&self, ray: &Ray, max_t: f64) -> Option<(f64, f64)> {
        let o = ray.origin();
        let d = ray.direction();
        let (mut t0, mut t1) = (0.0f64, max_t);
        for i in 0..3 {
            if d[i] == 0.0 {
                if o[i] < self.min[i] || o[i] > self.max[i] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d[i];
            let (mut a, mut b) = ((self.min[i] - o[i]) * inv, (self.max[i] - o[i]) * inv);
            if a > b {
                core::mem::swap(&mut a, &mut b);
            }
            // NaN (∞ - ∞ on an infinite box side) compares false and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        // Widen by a few ulps so rounding in the slab test never drops a grazing hit.
        let slack = 4.0 * f64::EPSILON * t1.abs().max(t0.abs());
        (t0 <= t1 + slack).then_some((t0, t1))
    }
}

/// Relative widening applied to every computed bound: far above the rounding
/// error of the few operations behind a bound, far below anything a user sees.
const WIDEN: f64 = 1e-9;
/// Widening relative to the absolute coordinates involved (their rounding
/// error is a few ulps; this is about a thousand).
const WIDEN_ABS: f64 = 1e-13;

/// `x` moved down by a margin relative to the magnitudes `local` of the
/// computation (taken around a local centre) and `abs` of the absolute
/// coordinates it went through.
#[inline]
fn widen_down(x: f64, local: f64, abs: f64) -> f64 {
    x - WIDEN * local - WIDEN_ABS * (x.abs() + abs) - f64::MIN_POSITIVE
}

/// `x` moved up; see [`widen_down`].
#[inline]
fn widen_up(x: f64, local: f64, abs: f64) -> f64 {
    x + WIDEN * local + WIDEN_ABS * (x.abs() + abs) + f64::MIN_POSITIVE
}

/// A ball that holds a block with room to spare, for the kernel's cheap
/// reject (`kernel.rs`): found here with the block's box for a bounded
/// polyhedron or a capped cylinder ([`block_bounds`]), or by the kernel for
/// an axis-aligned ellipsoid. An infinite radius stands for no ball.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ball {
    pub(crate) centre: [f64; 3],
    pub(crate) radius: f64,
}

/// The box and ball of each block, in order ([`block_bounds`]). Each
/// depends on its block alone, so large scenes compute them in parallel
/// (on rayon's global pool) and get the same ones whatever the number of
/// threads.
pub(crate) fn block_boxes(blocks: &[crate::Block]) -> (Vec<Aabb>, Vec<Option<Ball>>) {
    use rayon::prelude::*;
    /// Below this many blocks the boxes take under a millisecond: not worth waking the pool.
    const PARALLEL_FROM: usize = 1024;
    if blocks.len() < PARALLEL_FROM {
        return blocks.iter().map(|b| block_bounds(b.solids())).unzip();
    }
    blocks.par_iter().with_min_len(256).map(|b| block_bounds(b.solids())).unzip()
}

/// The tight, conservative box of the intersection of `solids`; infinite on
/// the axes where the block is unbounded, [`Aabb::EMPTY`] if it is provably empty.
///
/// With it, the smallest of the balls found on the way: around a
/// bounded polyhedron of the block's half-spaces (a box of six), or around
/// a quadric with bounded cross-sections cut to a finite length by the
/// half-spaces (a capped cylinder). Each holds a superset of the block, so
/// the block; `None` if neither is found or the ball's volume is not below
/// 1.5 times the box's (an ellipsoid's ball is the kernel's own, see
/// `kernel.rs`).
/// Computed here because the box needs the same vertices and axes.
pub(crate) fn block_bounds(solids: &[Solid]) -> (Aabb, Option<Ball>) {
    let smaller = |a: Option<Ball>, b: Option<Ball>| match (a, b) {
        (Some(x), Some(y)) => Some(if y.radius < x.radius { y } else { x }),
        (x, y) => x.or(y),
    };
    let mut bx = Aabb::INFINITE;
    let mut ball = None;
    for s in solids {
        if let Solid::Quadric(q) = s {
            let (b, around) = analytic_box(q, solids);
            bx = bx.intersection(&b);
            ball = smaller(ball, around);
        }
    }
    let (b, around) = polytope_box(solids);
    bx = bx.intersection(&b);
    ball = smaller(ball, around);
    if bx.is_empty() {
        return (Aabb::EMPTY, None);
    }
    for _round in 0..16 {
        let before = bx;
        for s in solids {
            match s {
                Solid::HalfSpace(h) => narrow_half_space(&mut bx, h),
                Solid::Quadric(q) => narrow_quadric(&mut bx, q),
            }
            if bx.is_empty() {
                return (Aabb::EMPTY, None);
            }
        }
        // Stop once a round gains less than a millionth of the extent.
        let settled = (0..3).all(|i| {
            let w = before.max[i] - before.min[i];
            let gain = (bx.min[i] - before.min[i]) + (before.max[i] - bx.max[i]);
            if w.is_finite() {
                gain <= 1e-6 * w
            } else {
                bx.min[i] == before.min[i] && bx.max[i] == before.max[i]
            }
        });
        if settled {
            break;
        }
    }
    // A ball much larger than the box (an axis-aligned box's is 2.7 times
    // its volume, a long upright cylinder's far more) would cost its test
    // on every visit and reject almost nothing the box has not. Below 1.5
    // times the box, the grid's turned boxes and cylinders keep nearly all
    // their gain and the table nothing (`docs/benchmarks.md`).
    let volume = (0..3).map(|i| bx.max[i] - bx.min[i]).product::<f64>();
    let ball = ball.filter(|b| 4.0 / 3.0 * std::f64::consts::PI * b.radius.powi(3) < 1.5 * volume);
    (bx, ball)
}

/// The box of the polyhedron cut out by the block's half-spaces, if it is
/// bounded (else infinite): the hull of its vertices, every intersection of
/// three planes that satisfies all half-spaces. It is bounded exactly when
/// the normals span space and no edge direction `±(nₐ × n_b)` is a direction
/// of recession (`nₖ·d <= 0` for all `k`). This covers rotated boxes, where
/// propagation alone cannot start from an infinite box. Triples of nearly
/// dependent normals (`|det| < 1e-10`) are skipped: their intersection is
/// rounding noise far away; a vertex that only such a triple forms (a spike
/// sharper than 10⁻¹⁰ rad) is the one case this does not cover.
fn polytope_box(solids: &[Solid]) -> (Aabb, Option<Ball>) {
    let Some((vertices, mut bx, slack)) = polytope_vertices(solids) else { return (Aabb::INFINITE, None) };
    // The ball: around the middle of the vertices' box, out to the farthest
    // vertex. Every point of the polyhedron lies in the hull of its
    // vertices, each within `slack` of its computed place on every axis, so
    // within `√3·slack` of the hull of the computed ones.
    let centre = (bx.min.coords + bx.max.coords) / 2.0;
    let reach = vertices.iter().fold(0.0f64, |m, v| m.max((v - centre).norm()));
    let radius = (reach + 2.0 * slack) * (1.0 + 1e-6);
    let ball = (radius.is_finite() && centre.iter().all(|c| c.is_finite()))
        .then_some(Ball { centre: [centre.x, centre.y, centre.z], radius });
    bx.min -= Vector3::repeat(slack);
    bx.max += Vector3::repeat(slack);
    (bx, ball)
}

/// The vertices of [`polytope_box`]'s polyhedron, their box, and how far
/// each may lie from its computed place on every axis; `None` if it is
/// unbounded or no vertex is found.
fn polytope_vertices(solids: &[Solid]) -> Option<(Vec<Vector3<f64>>, Aabb, f64)> {
    // At most 24 planes, on the stack: a block of more is not taken as a polytope.
    let mut planes = ArrayVec::<(Vector3<f64>, f64), 24>::new();
    for s in solids {
        if let Solid::HalfSpace(h) = s {
            let n = *h.normal_vector();
            let m = n.norm();
            // n·x + (d - n·o) <= 0, normalised.
            let off = h.value(&Point3::origin());
            planes.try_push((n / m, off / m)).ok()?;
        }
    }
    if planes.len() < 4 {
        return None;
    }
    // A direction of recession makes the polyhedron unbounded; treating
    // near-recession as recession only loses tightness, never correctness.
    let recedes = |d: &Vector3<f64>| planes.iter().all(|(n, _)| n.dot(d) <= 1e-9);
    for (a, (na, _)) in planes.iter().enumerate() {
        for (nb, _) in &planes[a + 1..] {
            let d = na.cross(nb);
            let m = d.norm();
            if m < 1e-9 {
                continue;
            }
            let d = d / m;
            if recedes(&d) || recedes(&-d) {
                return None;
            }
        }
    }
    let scale = planes.iter().fold(0.0f64, |m, (_, off)| m.max(off.abs()));
    // A box's eight, in one allocation.
    let mut vertices = Vec::with_capacity(8);
    let mut bx = Aabb::EMPTY;
    for a in 0..planes.len() {
        for b in a + 1..planes.len() {
            for c in b + 1..planes.len() {
                let m =
                    Matrix3::from_rows(&[planes[a].0.transpose(), planes[b].0.transpose(), planes[c].0.transpose()]);
                let det = m.determinant();
                // Nearly dependent normals (two opposite faces and any third,
                // say) meet far away or nowhere; their rounded "vertex" is noise.
                if det.abs() < 1e-10 {
                    continue;
                }
                let Some(inv) = m.try_inverse() else { continue };
                let v = inv * -Vector3::new(planes[a].1, planes[b].1, planes[c].1);
                if !v.iter().all(|x| x.is_finite()) {
                    continue;
                }
                // The vertex's rounding error grows as the planes near parallel;
                // a too generous tolerance only adds a spurious far vertex.
                let tol = (1e-9 + 1e-15 / det.abs()) * (scale + v.norm());
                if planes.iter().all(|(n, off)| n.dot(&v) + off <= tol) {
                    vertices.push(v);
                    bx = bx.union(&Aabb { min: Point3::from(v), max: Point3::from(v) });
                }
            }
        }
    }
    if vertices.is_empty() {
        // Bounded but no vertex found: empty, or too degenerate to tell.
        return None;
    }
    let slack = 1e-8 * (bx.max - bx.min).norm()
        + WIDEN_ABS * 10.0 * (scale + bx.min.coords.amax().max(bx.max.coords.amax()))
        + f64::MIN_POSITIVE;
    Some((vertices, bx, slack))
}

/// The structure of a quadric whose cross-sections are bounded ellipses.
enum Core {
    /// `(x - centre)ᵀ A (x - centre) <= r`, `A` positive definite: an
    /// ellipsoid, with `A⁻¹`.
    Ellipsoid { centre: Vector3<f64>, inverse: Matrix3<f64>, r: f64, margin: f64 },
    /// `x = point + s·axis + q` with `q ⊥ axis` and `qᵀ A q <= r + spread·s²`:
    /// an elliptic cylinder (`spread = 0`), a cone (`r = 0`) or a hyperboloid,
    /// with `P` the pseudo-inverse of `A` on the plane across the axis.
    /// `widest` bounds the largest eigenvalue of `P` (`1 / λ` for the
    /// smaller of `A`'s two positive eigenvalues), so `|q|² <= widest · qᵀAq`.
    Axial { point: Vector3<f64>, axis: Vector3<f64>, p: Matrix3<f64>, r: f64, spread: f64, margin: f64, widest: f64 },
}

/// The eigen-decomposition `A = V diag(λ) Vᵀ` of a symmetric 3×3 matrix by
/// cyclic Jacobi rotations, `(λ, V)`, or `None` if it fails its own check.
///
/// Not nalgebra's `symmetric_eigen`: for some matrices it pairs eigenvalues
/// with the wrong eigenvectors (dimforge/nalgebra#1109; a circular double
/// cone with eigenvalues -2, 2, 2 comes back with its axis off by 30°, and
/// the box would cut off part of the block). Jacobi is backward stable,
/// with errors of a few ε·‖A‖, and structural zeros stay exact: a diagonal
/// `A` needs no rotation. The result is checked a posteriori anyway, since
/// every margin below assumes the residual `‖AV - VΛ‖` and `‖VᵀV - I‖` are
/// that small; the caller falls back to propagation alone if they are not.
fn symmetric_eigen(a: &Matrix3<f64>) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let norm = a.norm();
    if !norm.is_finite() {
        return None;
    }
    let mut m = *a;
    let mut v = Matrix3::identity();
    for _sweep in 0..64 {
        // Off-diagonal entries below ε²‖A‖ change no eigenvalue by more than rounding.
        let off = [(0, 1), (0, 2), (1, 2)];
        if off.iter().all(|&(p, q)| m[(p, q)].abs() <= f64::EPSILON * f64::EPSILON * norm) {
            break;
        }
        for (p, q) in off {
            let apq = m[(p, q)];
            if apq.abs() <= f64::EPSILON * f64::EPSILON * norm {
                continue;
            }
            // An entry too small to change either diagonal entry, even a
            // hundredfold, is zeroed without a rotation (Numerical Recipes
            // §11.1). Rotating instead turns a near multiple of the identity
            // (a rotated sphere) by 45° sweep after sweep while the entry
            // hovers at ε²‖A‖, and `V` drifts out of orthogonality until the
            // check below fails and the block loses its box.
            let g = 100.0 * apq.abs();
            if m[(p, p)].abs() + g == m[(p, p)].abs() && m[(q, q)].abs() + g == m[(q, q)].abs() {
                m[(p, q)] = 0.0;
                m[(q, p)] = 0.0;
                continue;
            }
            // The rotation that zeroes m[p][q], by its smaller angle (Numerical Recipes §11.1).
            let theta = (m[(q, q)] - m[(p, p)]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
            let cos = 1.0 / t.hypot(1.0);
            let sin = t * cos;
            let mut j = Matrix3::identity();
            j[(p, p)] = cos;
            j[(q, q)] = cos;
            j[(p, q)] = sin;
            j[(q, p)] = -sin;
            m = j.transpose() * m * j;
            // Symmetric by construction; the zeroed entry is exactly zero.
            m[(p, q)] = 0.0;
            m[(q, p)] = 0.0;
            v *= j;
        }
    }
    let lambda = m.diagonal();
    let residual = (a * v - v * Matrix3::from_diagonal(&lambda)).amax();
    let orthogonality = (v.transpose() * v - Matrix3::identity()).amax();
    (residual <= 32.0 * f64::EPSILON * norm && orthogonality <= 32.0 * f64::EPSILON).then_some((lambda, v))
}

fn core(q: &quadric::Quadric) -> Option<Core> {
    let (c, a, w, k) = q.local_parts();
    let (eigenvalues, eigenvectors) = symmetric_eigen(&a)?;
    let top = eigenvalues.amax();
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    let tol = 1e-9 * top;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eigenvalues[i].total_cmp(&eigenvalues[j]));
    let (l0, l1) = (eigenvalues[order[0]], eigenvalues[order[1]]);
    if l1 <= tol {
        return None; // at most one positive direction: unbounded cross-sections
    }
    // Rounding error of the inverse grows with the condition number.
    let smallest = if l0.abs() > tol { l0.abs().min(l1) } else { l1 };
    let margin = 1e-9 + 64.0 * f64::EPSILON * top / smallest;
    if l0 > tol {
        let inverse = a.cholesky()?.inverse();
        let d0 = -(inverse * w);
        // f = (d - d0)ᵀ A (d - d0) + k - wᵀA⁻¹w, so r = wᵀA⁻¹w - k = -(k + w·d0).
        let r = -(k + w.dot(&d0));
        let scale = k.abs() + w.dot(&d0).abs();
        let r = if r < -margin * scale { -1.0 } else { r.max(0.0) + margin * scale };
        return Some(Core::Ellipsoid { centre: c.coords + d0, inverse, r, margin });
    }
    let axis = eigenvectors.column(order[0]).into_owned();
    let mut p = Matrix3::zeros();
    for &i in &order[1..] {
        let v = eigenvectors.column(i);
        p += v * v.transpose() / eigenvalues[i];
    }
    // `linear`: what a linear term along the axis adds to both `r` and the
    // spread (below); zero for a cone or hyperboloid, whose `d0` absorbs it.
    let (d0, spread, linear) = if l0.abs() <= tol {
        if w.dot(&axis).abs() > 1e-9 * w.norm() {
            return None; // a parabolic cylinder: left to propagation
        }
        // A slightly negative eigenvalue makes a very slender hyperboloid:
        // keep its spread so the box stays conservative. The computed `l0`
        // is off by up to the solver's error, about ε·top (exact for a
        // diagonal `A`), which can hide a true eigenvalue of either sign:
        // the spread covers the most negative one it may be.
        let diagonal = a[(0, 1)] == 0.0 && a[(0, 2)] == 0.0 && a[(1, 2)] == 0.0;
        let noise = if diagonal { 0.0 } else { 64.0 * f64::EPSILON * top };
        // A linear term `2·lin·s` along the axis, however small against
        // `w`, moves the cross-section's level without bound far along it
        // (an elliptic paraboloid: a coefficient of 1e-45 at 1e48 from the
        // centre is a level of 1e3), so it is kept, folded in by
        // `2|lin·s| <= |lin|(1 + s²)`: `r` and the spread each grow by
        // `|lin|`, plus the rounding of the computed axis for a
        // non-diagonal `A`. (With the axis unbounded, the spread then
        // leaves the box open across it, as the paraboloid is.)
        let linear = w.dot(&axis).abs() + if diagonal { 0.0 } else { 64.0 * f64::EPSILON * w.norm() };
        (-(p * w), (noise - l0).max(0.0) + linear, linear)
    } else {
        // One negative direction: a cone or a hyperboloid around the axis.
        (-(p * w) - axis * (axis.dot(&w) / l0), -l0, 0.0)
    };
    let r = linear - (k + w.dot(&d0));
    let scale = k.abs() + w.dot(&d0).abs();
    let r = r + margin * scale;
    let spread = spread * (1.0 + margin);
    if spread == 0.0 && r < 0.0 {
        return Some(Core::Ellipsoid { centre: c.coords + d0, inverse: p, r: -1.0, margin });
    }
    // A two-sheet hyperboloid (r < 0) lies inside its asymptotic cone (r = 0).
    let widest = (1.0 + margin) / l1;
    Some(Core::Axial { point: c.coords + d0, axis, p, r: r.max(0.0), spread, margin, widest })
}

/// The analytic box of a quadric with bounded cross-sections: for an
/// ellipsoid, half-extent `sqrt(r (A⁻¹)ᵢᵢ)` around its centre; for a
/// cylinder, cone or hyperboloid, the range `[s0, s1]` of the axis
/// parameter the block's half-spaces allow, and the cross-section boxes at
/// both ends (the extent `s·axisᵢ ± sqrt((r + spread·s²) Pᵢᵢ)` is convex in
/// `s`, so its extremes over the range are at the ends).
fn analytic_box(q: &quadric::Quadric, solids: &[Solid]) -> (Aabb, Option<Ball>) {
    match core(q) {
        None => (Aabb::INFINITE, None),
        Some(Core::Ellipsoid { r, .. }) if r < 0.0 => (Aabb::EMPTY, None),
        Some(Core::Ellipsoid { centre, inverse, r, margin }) => {
            let mut bx = Aabb::EMPTY;
            for i in 0..3 {
                let h = (r * inverse[(i, i)].max(0.0)).sqrt();
                let slack = margin * h + WIDEN_ABS * centre[i].abs() + f64::MIN_POSITIVE;
                bx.min[i] = centre[i] - h - slack;
                bx.max[i] = centre[i] + h + slack;
            }
            (bx, None)
        }
        Some(Core::Axial { point, axis, p, r, spread, margin, widest }) => {
            let (mut s0, mut s1) = (f64::NEG_INFINITY, f64::INFINITY);
            for s in solids {
                let Solid::HalfSpace(h) = s else { continue };
                match axial_range(h, &point, &axis, &p, r, spread) {
                    Some((lo, hi)) => {
                        s0 = s0.max(lo);
                        s1 = s1.min(hi);
                    }
                    None => return (Aabb::EMPTY, None),
                }
            }
            if s0 > s1 {
                return (Aabb::EMPTY, None);
            }
            if !(s0.is_finite() && s1.is_finite()) {
                // Unbounded along the axis: only the axes across it are
                // bounded, and only for a cylinder.
                let mut bx = Aabb::INFINITE;
                if spread == 0.0 {
                    // Any tilt, however small, makes the cylinder unbounded on
                    // that axis, and the eigenvector solver drops tilts below
                    // its tolerance (1e-16 rad matters at distance 1e16 from
                    // the centre). So the zero components are taken from the
                    // kernel of `A` computed without that tolerance as well.
                    let kernel = kernel_direction(q.quadratic_part());
                    for i in 0..3 {
                        if axis[i] == 0.0 && kernel[i] == 0.0 {
                            let h = (r * p[(i, i)].max(0.0)).sqrt();
                            let slack = margin * h + WIDEN_ABS * point[i].abs() + f64::MIN_POSITIVE;
                            bx.min[i] = point[i] - h - slack;
                            bx.max[i] = point[i] + h + slack;
                        }
                    }
                }
                return (bx, None);
            }
            let mut bx = Aabb::EMPTY;
            for i in 0..3 {
                for s in [s0, s1] {
                    let h = ((r + spread * s * s) * p[(i, i)].max(0.0)).sqrt();
                    let c = point[i] + s * axis[i];
                    let slack = margin * (h + s.abs()) + WIDEN_ABS * (c.abs() + point[i].abs()) + f64::MIN_POSITIVE;
                    bx.min[i] = bx.min[i].min(c - h - slack);
                    bx.max[i] = bx.max[i].max(c + h + slack);
                }
            }
            // The ball: every point is `point + s·axis + q` with `s` in
            // `[s0, s1]` and `|q|² <= widest·(r + spread·s²)`, largest at an
            // end; so it lies within `sqrt(half² + reach²)` of the axis
            // point at the middle of the range.
            let far = s0.abs().max(s1.abs());
            let reach = (widest * (r + spread * far * far)).sqrt();
            let (mid, half) = (0.5 * s0 + 0.5 * s1, 0.5 * s1 - 0.5 * s0);
            let centre = point + axis * mid;
            let radius = ((half * half + reach * reach).sqrt()
                + margin * (reach + far)
                + WIDEN_ABS * 10.0 * (centre.amax() + point.amax()))
                * (1.0 + 1e-6)
                + f64::MIN_POSITIVE;
            let ball = (radius.is_finite() && centre.iter().all(|c| c.is_finite()))
                .then_some(Ball { centre: [centre.x, centre.y, centre.z], radius });
            (bx, ball)
        }
    }
}

/// A vector spanning the kernel of a rank-2 symmetric `a` (the axis of a
/// cylinder), as the longest cross product of two of its rows. A component
/// is zero only if it is exactly zero in both rows' cross product (each one
/// a fused difference of products, zero only if exactly zero), so structural
/// zeros survive and any tilt shows.
fn kernel_direction(a: &Matrix3<f64>) -> Vector3<f64> {
    let cross = |x: usize, y: usize| {
        let (u, v) = (a.row(x), a.row(y));
        Vector3::new(
            difference_of_products(u[1], v[2], u[2], v[1]),
            difference_of_products(u[2], v[0], u[0], v[2]),
            difference_of_products(u[0], v[1], u[1], v[0]),
        )
    };
    [cross(0, 1), cross(0, 2), cross(1, 2)].into_iter().fold(Vector3::zeros(), |best, k| {
        if k.amax() > best.amax() {
            k
        } else {
            best
        }
    })
}

/// The range of `s` over which some point `point + s·axis + q` of the
/// cross-section ellipse (`qᵀAq <= r + spread·s²`) satisfies the half-space
/// `n·x + c <= 0`: `a s + c <= sqrt(α + β s²)` with `a = n·axis`,
/// `α = r g`, `β = spread g`, `g = nᵀPn` (the support of the ellipse in
/// direction `n`). When the plane is steeper than the cone (`a² > β`) the
/// left side minus the right is monotone in `s`, giving a half-line found by
/// bisection; otherwise the whole line. `None`: no `s` at all.
fn axial_range(
    h: &quadric::HalfSpace,
    point: &Vector3<f64>,
    axis: &Vector3<f64>,
    p: &Matrix3<f64>,
    r: f64,
    spread: f64,
) -> Option<(f64, f64)> {
    let Some(k) = Axial::new(h, point, axis, p, r, spread) else {
        return Some((f64::NEG_INFINITY, f64::INFINITY));
    };
    // A cylinder's cross-section does not widen (`β = 0`): its support is
    // the same square root at every `s` (`0·s² = 0`), taken once, off the
    // bisection's chain of dependent steps. Only the sign of a zero can
    // differ, which none of the comparisons in `Axial::solve` reads.
    let flat = k.alpha.max(0.0).sqrt();
    k.solve(|s: f64| k.a * s - if k.beta == 0.0 { flat } else { (k.alpha + k.beta * s * s).max(0.0).sqrt() } + k.c)
}

/// The parts of [`axial_range`]'s inequality `a s + c <= sqrt(α + β s²)`,
/// and the magnitude of the absolute coordinates `c` came from.
struct Axial {
    a: f64,
    c: f64,
    alpha: f64,
    beta: f64,
    abs: f64,
}

impl Axial {
    /// `None` where the plane is not clearly steeper than the cone (the
    /// range is then the whole line).
    fn new(
        h: &quadric::HalfSpace,
        point: &Vector3<f64>,
        axis: &Vector3<f64>,
        p: &Matrix3<f64>,
        r: f64,
        spread: f64,
    ) -> Option<Self> {
        let n = *h.normal_vector();
        let scale_n = n.norm();
        let n = n / scale_n;
        let c = h.value(&Point3::from(*point)) / scale_n;
        let a = n.dot(axis);
        let g = n.dot(&(p * n)).max(0.0);
        let (alpha, beta) = (r * g, spread * g);
        // Require a clear margin so that rounding cannot flip monotonicity.
        if a * a <= beta * (1.0 + 1e-6) + 1e-12 {
            return None;
        }
        // `c` came from the absolute coordinates of the plane and the axis point.
        let abs = (point.norm() + h.reference_point().coords.norm()) / a.abs();
        Some(Axial { a, c, alpha, beta, abs })
    }

    /// The half-line where `phi(s) = a s - sqrt(α + β s²) + c` has the
    /// feasible sign, by bracketing and bisection, widened for rounding.
    fn solve(&self, phi: impl Fn(f64) -> f64) -> Option<(f64, f64)> {
        let a = self.a;
        // phi is increasing for a > 0 (feasible: s <= root), decreasing for a < 0.
        let sign = a.signum();
        let (mut lo, mut hi) = (-1.0f64, 1.0f64);
        let mut guard = 0;
        while sign * phi(lo) > 0.0 || sign * phi(hi) < 0.0 {
            if sign * phi(lo) > 0.0 {
                lo *= 2.0;
            }
            if sign * phi(hi) < 0.0 {
                hi *= 2.0;
            }
            guard += 1;
            if guard > 2100 || !lo.is_finite() || !hi.is_finite() {
                return Some((f64::NEG_INFINITY, f64::INFINITY));
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if sign * phi(mid) <= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let local = self.c.abs() / a.abs() + lo.abs();
        if a > 0.0 {
            Some((f64::NEG_INFINITY, widen_up(hi, local, self.abs)))
        } else {
            Some((widen_down(lo, local, self.abs), f64::INFINITY))
        }
    }
}

/// Closed interval `[lo, hi]` in extended arithmetic (`0 · ∞ = 0`, which is
/// right for bounds: a zero coefficient constrains nothing).
#[derive(Clone, Copy)]
struct I(f64, f64);

#[inline]
fn mul0(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

impl I {
    fn scale(self, c: f64) -> I {
        if c >= 0.0 {
            I(mul0(c, self.0), mul0(c, self.1))
        } else {
            I(mul0(c, self.1), mul0(c, self.0))
        }
    }
    fn mul(self, o: I) -> I {
        let p = [mul0(self.0, o.0), mul0(self.0, o.1), mul0(self.1, o.0), mul0(self.1, o.1)];
        I(p.iter().copied().fold(f64::INFINITY, f64::min), p.iter().copied().fold(f64::NEG_INFINITY, f64::max))
    }
    fn square(self) -> I {
        if self.0 >= 0.0 {
            I(self.0 * self.0, self.1 * self.1)
        } else if self.1 <= 0.0 {
            I(self.1 * self.1, self.0 * self.0)
        } else {
            I(0.0, (self.0 * self.0).max(self.1 * self.1))
        }
    }
    fn add(self, o: I) -> I {
        I(self.0 + o.0, self.1 + o.1)
    }
    fn mag(self) -> f64 {
        self.0.abs().max(self.1.abs())
    }
}

/// The largest absolute coordinate of the box on axis `j`.
fn magnitude(bx: &Aabb, j: usize) -> f64 {
    bx.min[j].abs().max(bx.max[j].abs())
}

fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// Narrows the box with `n·(x - o) + d <= 0`: on axis `i`,
/// `nᵢ (xᵢ - oᵢ) <= -d - Σ_{j≠i} nⱼ (xⱼ - oⱼ)`.
fn narrow_half_space(bx: &mut Aabb, h: &quadric::HalfSpace) {
    let n = *h.normal_vector();
    let o = h.reference_point();
    let d = h.value(&o);
    for i in 0..3 {
        if n[i] == 0.0 {
            continue;
        }
        let mut rest = I(d, d);
        let mut mag = d.abs();
        for j in (0..3).filter(|&j| j != i) {
            let term = I(bx.min[j] - o[j], bx.max[j] - o[j]).scale(n[j]);
            mag += term.0.abs();
            rest = rest.add(term);
        }
        // The smallest the rest can be; -∞ means no information.
        let lo = rest.0;
        if !lo.is_finite() {
            continue;
        }
        let bound = -lo / n[i];
        let local = mag / n[i].abs();
        // The differences xⱼ - oⱼ round relative to the absolute coordinates.
        // (An infinite side left the bound alone above, or has a zero coefficient.)
        let abs =
            (0..3).map(|j| finite_or_zero(n[j].abs() * (o[j].abs() + magnitude(bx, j)))).sum::<f64>() / n[i].abs();
        if n[i] > 0.0 {
            let b = widen_up(o[i] + bound, local, abs);
            if b < bx.max[i] {
                bx.max[i] = b;
            }
        } else {
            let b = widen_down(o[i] + bound, local, abs);
            if b > bx.min[i] {
                bx.min[i] = b;
            }
        }
    }
}

/// Narrows the box with `f(x) <= 0`, written on axis `i` as
/// `a dᵢ² + 2 B dᵢ + C <= 0` (`d = x - c`) with `B` and `C` intervals over the
/// other axes. A feasible `dᵢ` satisfies `a dᵢ² + 2 B' dᵢ + C_lo <= 0` for `B'`
/// one of `B`'s ends, so it lies in the hull of those two root intervals.
fn narrow_quadric(bx: &mut Aabb, q: &quadric::Quadric) {
    let (c, a, w, k) = q.local_parts();
    for i in 0..3 {
        let others: [usize; 2] = match i {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        };
        let dj = |j: usize| I(bx.min[j] - c[j], bx.max[j] - c[j]);
        let mut b = I(w[i], w[i]);
        let mut cc = I(k, k);
        // Sum of the magnitudes behind C's lower end: its rounding scale.
        let mut cmag = k.abs();
        let mut add_c = |cc: &mut I, term: I| {
            cmag += term.0.abs();
            *cc = cc.add(term);
        };
        // What rounding `dⱼ = xⱼ - cⱼ` at the absolute coordinates (a few
        // ulps of `eⱼ`) can move `B` and `C` by, unscaled: far from the
        // origin it swamps the terms' own magnitudes (a huge sphere touching
        // the box, whose `C` cancels to rounding noise).
        let e = |j: usize| finite_or_zero(c[j].abs() + magnitude(bx, j));
        let mut b_abs = 0.0;
        let mut c_abs = 2.0
            * a[(others[0], others[1])].abs()
            * (dj(others[0]).mag() * e(others[1]) + dj(others[1]).mag() * e(others[0]));
        for &j in &others {
            b_abs += a[(i, j)].abs() * e(j);
            c_abs += 2.0 * (a[(j, j)].abs() * dj(j).mag() + w[j].abs()) * e(j);
            b = b.add(dj(j).scale(a[(i, j)]));
            add_c(&mut cc, dj(j).square().scale(a[(j, j)]));
            add_c(&mut cc, dj(j).scale(2.0 * w[j]));
        }
        add_c(&mut cc, dj(others[0]).mul(dj(others[1])).scale(2.0 * a[(others[0], others[1])]));
        let (blo, bhi, clo) = (b.0, b.1, cc.0);
        if !(blo.is_finite() && bhi.is_finite() && clo.is_finite()) {
            continue;
        }
        let aii = a[(i, i)];
        // The magnitude the bound was computed from, for the rounding margin.
        let (lo, hi, scale) = if aii > 0.0 {
            // The discriminant grown by what rounding may hide in it, and in
            // `f` wherever it is evaluated (`aᵢᵢ` times a few ulps of the
            // terms of `f` at a root, of sizes `|C|` and `B²/aᵢᵢ`): near a
            // double root the roots then move by `sqrt(δ)/aᵢᵢ`, not by a
            // multiple of their scale (a parabola whose vertex dips 1e-18
            // below zero from terms of 1.16, where the computed `f` is
            // negative 2 units either side of the exact roots).
            let roots = |bb: f64| {
                let delta = 64.0 * f64::EPSILON * (bb * bb + aii * cmag);
                let disc = bb * bb - aii * clo + delta;
                (disc >= 0.0).then(|| {
                    let s = disc.sqrt();
                    ((-bb - s) / aii, (-bb + s) / aii)
                })
            };
            let scale = (b.mag() + (aii * cmag).sqrt()) / aii;
            match (roots(blo), roots(bhi)) {
                (None, None) => {
                    // Only claim emptiness when it is not a rounding artefact:
                    // of the terms of `C` (`cmag`), and of the `dⱼ` (`c_abs`).
                    let margin = 1e-9 * (blo * blo + bhi * bhi + aii * cmag)
                        + WIDEN_ABS * (2.0 * b.mag() * b_abs + aii * finite_or_zero(c_abs));
                    if blo * blo - aii * clo < -margin && bhi * bhi - aii * clo < -margin {
                        *bx = Aabb::EMPTY;
                        return;
                    }
                    continue;
                }
                (Some(r), None) | (None, Some(r)) => (r.0, r.1, scale),
                (Some(r), Some(s)) => (r.0.min(s.0), r.1.max(s.1), scale),
            }
        } else if aii == 0.0 && blo > 0.0 {
            // 2B dᵢ + C_lo <= 0 for some B in [blo, bhi]: dᵢ <= max_B(-C_lo / 2B).
            (f64::NEG_INFINITY, (-clo / (2.0 * blo)).max(-clo / (2.0 * bhi)), cmag / blo)
        } else if aii == 0.0 && bhi < 0.0 {
            ((-clo / (2.0 * blo)).min(-clo / (2.0 * bhi)), f64::INFINITY, cmag / -bhi)
        } else {
            continue;
        };
        // The differences xⱼ - cⱼ round relative to the absolute coordinates.
        let abs =
            c[i].abs() + others.iter().map(|&j| finite_or_zero(c[j].abs() + magnitude(bx, j))).fold(0.0, f64::max);
        let lo = widen_down(c[i] + lo, scale, abs);
        let hi = widen_up(c[i] + hi, scale, abs);
        if lo > bx.min[i] {
            bx.min[i] = lo;
        }
        if hi < bx.max[i] {
            bx.max[i] = hi;
        }
        if bx.min[i] > bx.max[i] {
            *bx = Aabb::EMPTY;
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// `axial_range` with the square root taken at every step of the search,
    /// also for a flat cross-section (where `axial_range` takes it once):
    /// the oracle of `axial_range_is_the_per_step_one`.
    fn axial_range_per_step(
        h: &quadric::HalfSpace,
        point: &Vector3<f64>,
        axis: &Vector3<f64>,
        p: &Matrix3<f64>,
        r: f64,
        spread: f64,
    ) -> Option<(f64, f64)> {
        let Some(k) = Axial::new(h, point, axis, p, r, spread) else {
            return Some((f64::NEG_INFINITY, f64::INFINITY));
        };
        k.solve(|s: f64| k.a * s - (k.alpha + k.beta * s * s).max(0.0).sqrt() + k.c)
    }

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![(-4i32..4).prop_map(|k| f64::from(k) * 0.5), -10.0..10.0f64, Just(0.0), Just(-0.0)]
    }

    proptest! {
        /// The same range, bit for bit, for cylinders (`spread = 0`; also
        /// with `r = 0`, a line) and cones or hyperboloids.
        #[test]
        fn axial_range_is_the_per_step_one(
            n in [coord(), coord(), coord()],
            d in coord(),
            point in [coord(), coord(), coord()],
            axis in [coord(), coord(), coord()],
            diag in [0.0..4.0f64, 0.0..4.0f64, 0.0..4.0f64],
            r in prop_oneof![Just(0.0), 0.0..4.0f64],
            spread in prop_oneof![Just(0.0), Just(-0.0), 0.0..2.0f64],
        ) {
            let Ok(h) = quadric::HalfSpace::new(n[0], n[1], n[2], d) else { return Ok(()) };
            let axis = Vector3::from(axis);
            let axis = if axis.norm() > 0.0 { axis / axis.norm() } else { Vector3::z() };
            let (point, p) = (Vector3::from(point), Matrix3::from_diagonal(&Vector3::from(diag)));
            let bits = |x: Option<(f64, f64)>| x.map(|(lo, hi)| (lo.to_bits(), hi.to_bits()));
            prop_assert_eq!(
                bits(axial_range(&h, &point, &axis, &p, r, spread)),
                bits(axial_range_per_step(&h, &point, &axis, &p, r, spread))
            );
        }
    }
}
