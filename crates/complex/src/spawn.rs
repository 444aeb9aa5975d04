//! Secondary rays that never hit the surface they leave.
//!
//! A hit point `p̂` is a double near, not on, the true surface: the root `λ`
//! has an error, and `p + λr` is rounded to doubles. A shadow, reflection or
//! refraction ray started at `p̂` may therefore find its own surface again at
//! `λ ≈ 0` (acne), and the ε rule alone only hides that while the error stays
//! below ε. Here the origin is moved off the surface along its normal, to the
//! side the new ray leaves on, by a *bound* of the error (pbrt-v4 §6.8.6), and
//! the result is checked: the origin `o'` is accepted only when the solid's
//! defining function `f` at `o'` has the right sign by [`MARGIN`] times a
//! rigorous bound of its own evaluation error. A ray starting there crosses
//! its own surface near `λ = 0` only behind its origin, whatever the
//! direction, and the offset (a few tens of ulps of the point's coordinates)
//! is far too small to skip another surface that is not within rounding of
//! the first.
//!
//! ```
//! use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
//! use quadric::nalgebra::{Point3, Vector3};
//! use quadric::{Quadric, Ray, Solid, Transform};
//! let far = Transform::translate(Vector3::new(1e9, 0.0, 0.0)).unwrap();
//! let ball = Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&far))], Opacity::Opaque, MaterialKey(0))
//!     .unwrap();
//! let scene = Complex::new(vec![ball], ComplexOptions { epsilon: Some(0.0), ..Default::default() }).unwrap();
//! let ray = Ray::new(Point3::new(1e9 - 0.3, 0.2, -5.0), Vector3::z()).unwrap();
//! let hit = scene.cast_ray(&ray, f64::INFINITY).unwrap();
//! // The mirror direction leaves the ball: with ε = 0 nothing is hit again.
//! let n = hit.normal;
//! let mirror = ray.direction() - 2.0 * ray.direction().dot(&n) * n;
//! let bounce = scene.spawn_ray(hit.surface(), &hit.point, &mirror).unwrap();
//! assert!(scene.cast_ray(&bounce, f64::INFINITY).is_none());
//! ```

use quadric::nalgebra::{Point3, Vector3};
use quadric::{GeometryError, HalfSpace, Quadric, Ray, Solid};

use crate::block::SolidRef;

use crate::{Complex, Hit, Surface};

/// The spawned origin's `f` must have the right sign by this many times the
/// bound of its evaluation error: the solver of the new ray evaluates `f`
/// near the same point (at the foot of the perpendicular from the solid's
/// centre, no farther from it than `o'`) with an error of the same bound, so
/// a margin of a few bounds keeps its root near `λ = 0` behind the origin.
pub const MARGIN: f64 = 4.0;

/// Unit roundoff of `f64`, `u = 2⁻⁵³`.
const U: f64 = f64::EPSILON / 2.0;

/// Doublings of the offset tried before giving up (the first try succeeds
/// except where the normal is ill-defined, near a cone's apex).
const TRIES: u32 = 24;

impl Hit {
    /// The surface that was hit: `(block, solid)`, to spawn rays from.
    pub fn surface(&self) -> Surface {
        Surface { block: self.block, solid: self.solid }
    }

    /// A ray from this hit along `direction`, its origin moved off the
    /// surface to the side `direction` leaves on (see
    /// [`Complex::spawn_ray`]).
    pub fn spawn_ray(&self, complex: &Complex, direction: &Vector3<f64>) -> Result<Ray, GeometryError> {
        complex.spawn_ray(self.surface(), &self.point, direction)
    }
}

impl Complex {
    /// A secondary ray (shadow, reflection, refraction) from the hit point
    /// `point` on `surface`, along `direction`: its origin is
    /// [`spawn_origin`] of the solid the surface lies on, so the ray does not
    /// meet that surface again near its start, whatever ε is. An unknown
    /// surface (not a solid of this complex) spawns from `point` itself.
    ///
    /// Errors like [`Ray::new`]: a zero or non-finite direction, or a
    /// non-finite point.
    pub fn spawn_ray(
        &self,
        surface: Surface,
        point: &Point3<f64>,
        direction: &Vector3<f64>,
    ) -> Result<Ray, GeometryError> {
        let placed = self.placed_solid(surface.block, surface.solid);
        let solid = self.solid_ref(surface.block, surface.solid).or(placed.as_ref().map(SolidRef::from));
        match solid {
            Some(s) if point.iter().all(|c| c.is_finite()) => Ray::new(origin_from(s, point, direction), *direction),
            _ => Ray::new(*point, *direction),
        }
    }
}

/// The origin of a ray leaving `solid`'s surface at `point` along
/// `direction`: `point` moved along the surface normal to the side the ray
/// leaves on (outside where `direction · ∇f > 0`, inside where it is `< 0`)
/// until `f` there has that side's sign by [`MARGIN`] times a rigorous bound
/// of its evaluation error.
///
/// The offset starts at the first-order distance that achieves this (below)
/// and doubles until the check passes; it returns `point` unchanged where
/// the normal is undefined (a zero gradient, a cone's apex) or the direction
/// is tangent to the surface (`direction · ∇f = 0`: no side is left), and
/// the last candidate if no doubling satisfies the check (only for points
/// far from the surface or near overflow).
pub fn spawn_origin(solid: &Solid, point: &Point3<f64>, direction: &Vector3<f64>) -> Point3<f64> {
    origin_from(SolidRef::from(solid), point, direction)
}

/// [`spawn_origin`] for a solid wherever it is stored.
fn origin_from(solid: SolidRef, point: &Point3<f64>, direction: &Vector3<f64>) -> Point3<f64> {
    match Prepared::at(solid, point, None) {
        Some(p) => match p.side(direction) {
            Some(sigma) => p.offset(solid, point, sigma),
            None => *point,
        },
        None => *point,
    }
}

/// What [`spawn_origin`] needs of the point itself, whatever the direction:
/// the unit normal and the first-order offset to either side.
#[derive(Clone, Copy, Debug)]
struct Prepared {
    f: f64,
    err: f64,
    g: f64,
    n: Vector3<f64>,
    rounding: f64,
}

impl Prepared {
    /// `None` where the normal is undefined (a zero gradient, a cone's apex).
    /// `normal`: the unit normal at `point` if the caller has it (either
    /// orientation; it is turned along the gradient), else it is computed
    /// from the gradient, `normal::unit(∇f)` as [`Solid::normal`] does.
    fn at(solid: SolidRef, point: &Point3<f64>, normal: Option<&Vector3<f64>>) -> Option<Prepared> {
        let Bounded { f, err, gradient } = eval(solid, point);
        let n = match normal {
            Some(n) if n.iter().any(|c| *c != 0.0) && n.iter().all(|c| c.is_finite()) => {
                if n.dot(&gradient) < 0.0 {
                    -n
                } else {
                    *n
                }
            }
            _ => quadric::normal::unit(gradient)?,
        };
        // Rounding `o'` to doubles moves it by up to `u|o'ᵢ|` per
        // coordinate, i.e. `u Σ|o'ᵢ n̂ᵢ|` along the normal (the floor set by
        // the world coordinates; pbrt's `dot(|n|, pError)`).
        let rounding = 2.0 * U * point.coords.abs().dot(&n.abs());
        Some(Prepared { f, err, g: gradient.norm(), n, rounding })
    }

    /// `±1`, the side `direction` leaves on; `None` when tangent (no side is
    /// left) or not finite.
    fn side(&self, direction: &Vector3<f64>) -> Option<f64> {
        let side = self.n.dot(direction);
        (side != 0.0 && side.is_finite()).then(|| side.signum())
    }

    /// The origin on side `sigma`.
    fn offset(&self, solid: SolidRef, point: &Point3<f64>, sigma: f64) -> Point3<f64> {
        let Prepared { f, err, g, n, rounding } = *self;
        // Along the normal line `x(β) = p̂ + βn̂`, `f(x(β)) = f(p̂) + β|∇f| + β²n̂ᵀAn̂`:
        // to first order the sign we want is reached at `β = (σf + M·err)/|∇f|`
        // past the surface. The rounding of `o'` and the error bound of the
        // evaluation at `o'` enter the start value twice over, so the first
        // candidate nearly always passes. (At least the smallest normal
        // double: a point exactly on a plane through the world origin has no
        // error to bound.)
        let mut delta = (((-sigma * f).max(0.0) + 2.0 * MARGIN * err) / g + 2.0 * rounding).max(f64::MIN_POSITIVE);
        let mut origin = *point;
        for _ in 0..TRIES {
            origin = point + n * (sigma * delta);
            let at = eval(solid, &origin);
            if sigma * at.f > MARGIN * at.err {
                return origin;
            }
            delta *= 2.0;
        }
        origin
    }
}

/// Spawns every secondary ray of one hit point: the point's own work (the
/// error-bounded `f` and the normal) is done once, and each side's origin
/// the first time a ray leaves on that side — a hit with three lights and a
/// reflection computes one origin, not four. Each ray leaves from
/// [`Complex::spawn_ray`]'s origin; [`Spawner::ray`] is exactly that ray,
/// [`Spawner::unit_ray`] keeps an already normalised direction as it is.
/// From [`Complex::spawner`].
#[derive(Debug)]
pub struct Spawner<'c> {
    solid: Option<SolidRef<'c>>,
    /// The solid of a placed block, moved into the world
    /// ([`Complex::assemble`]), when `solid` is `None`.
    placed: Option<Solid>,
    point: Point3<f64>,
    /// The unit normal at `point`, when the caller knew it.
    normal: Option<Vector3<f64>>,
    prepared: Option<Option<Prepared>>,
    /// The origins for `σ = -1` and `σ = +1`.
    origins: [Option<Point3<f64>>; 2],
}

impl Spawner<'_> {
    /// The ray from the hit point along `direction` (as
    /// [`Complex::spawn_ray`]).
    pub fn ray(&mut self, direction: &Vector3<f64>) -> Result<Ray, GeometryError> {
        Ray::new(self.origin(direction), *direction)
    }

    /// [`Spawner::ray`] along a direction already normalised (a light
    /// direction `v / |v|`, a mirror or refracted direction built from unit
    /// vectors): the same origin, and the direction kept as it is when it
    /// is a unit vector to within [`Ray::UNIT_TOLERANCE`] ([`Ray::new_unit`]).
    pub fn unit_ray(&mut self, direction: &Vector3<f64>) -> Result<Ray, GeometryError> {
        Ray::new_unit(self.origin(direction), *direction)
    }

    /// The origin of a ray leaving along `direction`.
    #[inline(never)]
    fn origin(&mut self, direction: &Vector3<f64>) -> Point3<f64> {
        let point = self.point;
        let placed = self.placed;
        let Some(solid) = self.solid.or(placed.as_ref().map(SolidRef::from)) else { return point };
        let normal = self.normal;
        let prepared = *self.prepared.get_or_insert_with(|| Prepared::at(solid, &point, normal.as_ref()));
        match prepared.and_then(|p| p.side(direction).map(|sigma| (p, sigma))) {
            None => point,
            Some((p, sigma)) => {
                *self.origins[usize::from(sigma > 0.0)].get_or_insert_with(|| p.offset(solid, &point, sigma))
            }
        }
    }
}

impl Complex {
    /// A [`Spawner`] for the hit `point` on `surface`: many secondary rays
    /// from one point, each from [`Complex::spawn_ray`]'s origin.
    pub fn spawner(&self, surface: Surface, point: &Point3<f64>) -> Spawner<'_> {
        let solid = self.solid_ref(surface.block, surface.solid);
        let finite = point.iter().all(|c| c.is_finite());
        let placed = self.placed_solid(surface.block, surface.solid).filter(|_| finite);
        Spawner {
            solid: solid.filter(|_| finite),
            placed,
            point: *point,
            normal: None,
            prepared: None,
            origins: [None; 2],
        }
    }

    /// [`Complex::spawner`] for a hit whose unit normal is known
    /// ([`Hit::normal`], `Event::normal`; either orientation), so that the
    /// point's normal is not computed a second time. `normal` must be the
    /// solid's own normal at `point` ([`Solid::normal`], as a hit's is):
    /// the rays are then exactly `spawner`'s (tested), except far along an
    /// ideal cylinder's axis, where `Solid::normal` slides the point along
    /// the axis first and is the more accurate of the two. It decides which
    /// side a direction leaves on; a zero or non-finite `normal` is ignored
    /// (the normal is computed).
    pub fn spawner_with_normal(&self, surface: Surface, point: &Point3<f64>, normal: &Vector3<f64>) -> Spawner<'_> {
        Spawner { normal: Some(*normal), ..self.spawner(surface, point) }
    }
}

/// `f` of either kind of solid at `x`, with its error bound and gradient
/// (inlined: the check of a candidate origin reads no gradient).
#[inline(always)]
fn eval(solid: SolidRef, x: &Point3<f64>) -> Bounded {
    match solid {
        SolidRef::Quadric(q) => quadric_value(q, x),
        SolidRef::HalfSpace(h) => half_space_value(h, x),
    }
}

/// `f(x)` with a bound of its rounding error and the gradient `∇f(x)`.
struct Bounded {
    f: f64,
    err: f64,
    gradient: Vector3<f64>,
}

/// `γₙ = nu/(1 - nu)`, the classic bound of `n` roundings (Higham, §3.1).
const fn gamma(n: u32) -> f64 {
    let nu = n as f64 * U;
    nu / (1.0 - nu)
}

/// The quadric at `x`, relative to its stored centre `c`:
/// `f = dᵀ(A d + 2w) + k` with `d = x - c`.
///
/// Error: `d̂ᵢ = fl(xᵢ - cᵢ)` is off by at most `u|d̂ᵢ|`, which moves `f` by
/// at most `|∇f|·u|d̂| + |A|u²|d̂|² <= 2u(|d̂|ᵀ(|A||d̂| + |w|)) (1 + u)`. The
/// evaluation from `d̂` is three length-3 dot products (`A d̂`, `γ₃`), an add
/// of `2w` and one of `w` (`γ₅`), a dot with `d̂` (`γ₈`) and the add of `k`
/// (`γ₉`), each bounded by `γ₉·F₀` with `F₀ = |d̂|ᵀ(|A||d̂| + 2|w|) + |k|`
/// (Higham's running bound for sums of products). `F₀` itself is computed in
/// floating point (relative error `<= γ₉`), hence the bound
/// `(γ₉ + 2u(1 + u))·F₀·(1 + γ₉)`, rounded up by taking `γ₁₂`.
///
/// `F₀` is replaced by `F = (‖A‖_F |d̂| + 2|w|)|d̂| + |k| >= F₀`, which does
/// not depend on the axes: the solver of the new ray forms its base point
/// `d + λ₀r` with a rounding of `u|λ₀| <= u|d|` in *every* coordinate, so an
/// axis-aligned surface (`A` or `n` with zeros) must not get a bound that
/// ignores the other coordinates (that left acne on a floor `y = 0`).
fn quadric_value(q: &Quadric, x: &Point3<f64>) -> Bounded {
    let (c, _, w, k) = q.local_parts();
    let (a_norm, w_norm) = q.norms();
    let d = x - c;
    let ad = q.a_times(&d);
    let half = ad + w;
    let f = d.dot(&(half + w)) + k;
    let dn = d.norm();
    let mag = (a_norm * dn + 2.0 * w_norm) * dn + k.abs();
    Bounded { f, err: gamma(12) * mag, gradient: 2.0 * half }
}

/// The half-space at `x`, `f = n·(x - o) + d` around its reference point
/// `o` (`d = f(o)`, exact): one rounding per coordinate of `x - o`
/// (`u|n||d̂|`), a length-3 dot product (`γ₃`) and the add of `d` (`γ₄`),
/// bounded by `γ₆·(|n|·|d̂| + |d|)` with the same allowance for computing
/// the magnitude in floating point; norms rather than `|n|ᵀ|d̂|` for the
/// reason given at [`quadric_value`].
fn half_space_value(h: &HalfSpace, x: &Point3<f64>) -> Bounded {
    let (o, n) = (h.reference_point(), *h.normal_vector());
    let d0 = h.value(&o);
    let d = x - o;
    let f = n.dot(&d) + d0;
    let mag = n.norm() * d.norm() + d0.abs();
    Bounded { f, err: gamma(8) * mag, gradient: n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadric::Transform;

    fn check_side(solid: Solid, point: [f64; 3], direction: [f64; 3]) {
        let (p, r) = (Point3::from(point), Vector3::from(direction));
        let o = spawn_origin(&solid, &p, &r);
        let g = match &solid {
            Solid::Quadric(q) => q.gradient(&p),
            Solid::HalfSpace(h) => *h.normal_vector(),
        };
        let want = g.dot(&r).signum();
        assert_eq!(solid.value(&o).signum(), want, "{solid:?} at {point:?} towards {direction:?}: origin {o:?}");
        // Within a few dozen ulps of the point's largest coordinate.
        let scale = point.iter().fold(1.0f64, |m, c| m.max(c.abs()));
        assert!((o - p).norm() <= 1e-13 * scale, "offset {:e} at scale {scale:e}", (o - p).norm());
    }

    #[test]
    fn origins_leave_on_the_side_of_the_direction() {
        let far = Transform::translate(Vector3::new(1e9, -3e8, 2e7)).expect("finite");
        let ball = Solid::from(Quadric::sphere().transformed(&far));
        let pole = [1e9, -3e8 + 1.0, 2e7];
        check_side(ball, pole, [0.0, 1.0, 0.0]);
        check_side(ball, pole, [0.3, -1.0, 0.0]);
        check_side(ball.complement(), pole, [0.3, -1.0, 0.0]);
        check_side(ball, pole, [1.0, 1e-12, 0.0]);
        let plane = Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -0.5).expect("valid"));
        check_side(plane, [3.0, 0.5, -2.0], [1.0, 1e-15, 0.0]);
        check_side(plane, [3.0, 0.5, -2.0], [1.0, -1e-15, 0.0]);
    }

    #[test]
    fn a_tangent_direction_or_a_cone_apex_leaves_the_point_alone() {
        let p = Point3::origin();
        assert_eq!(spawn_origin(&Solid::from(Quadric::cone()), &p, &Vector3::x()), p);
        let plane = Solid::from(HalfSpace::new(0.0, 1.0, 0.0, 0.0).expect("valid"));
        assert_eq!(spawn_origin(&plane, &p, &Vector3::x()), p);
    }
}
