//! # reference — the high-precision reference intersector of Komplex
//!
//! Used by the accuracy and stress tests of `quadric` and `complex` and by
//! the accuracy measurements (`quadric`'s `examples/accuracy.rs`); never by
//! the caster itself (`publish = false`).
//!
//! The true solid is the one the stored doubles define: `f(x) = (x-c)ᵀA(x-c)
//! + 2wᵀ(x-c) + k` with `c, A, w, k` from [`Quadric::local_parts`], and the
//! true ray is `p + λr` with the stored origin and unit direction. Every input
//! is a double, so `s`, `t`, `u`, the discriminant `t² - su` and `f` at any
//! double point are *exact* dyadic rationals here ([`Big`]): every hit/miss
//! decision of the reference is exact. Only square roots and quotients are
//! rounded, to [`PRECISION`] bits.
//!
//! [`csg`] extends this to blocks (intersections of the exact sets of their
//! solids) and complexes (the union with the priority partition of docs/model.md §3.5),
//! with every root held exactly so that ties between solids are exact too.

#![deny(missing_docs)]

pub mod csg;
pub use csg::{block_set, intersect, solid_set, ExactBlock, ExactEnd, ExactPartition, ExactSegment, ExactSet, Root};

use num_bigint::{BigInt, Sign};
use quadric::{HalfSpace, IntervalSet, Quadric, Ray, Solid, NO_SOLID};

/// Bits kept by the rounded operations (square root, division).
pub const PRECISION: u64 = 256;

/// A dyadic rational `m · 2^e`, exact under `+`, `-`, `*`.
#[derive(Clone, Debug)]
pub struct Big {
    m: BigInt,
    e: i64,
}

impl Big {
    /// Zero.
    pub fn zero() -> Big {
        Big { m: BigInt::from(0), e: 0 }
    }

    /// The exact value of a finite double.
    pub fn from_f64(x: f64) -> Big {
        assert!(x.is_finite(), "the reference takes finite doubles only");
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i64;
        let frac = bits & ((1 << 52) - 1);
        let (mant, e) = if exp == 0 { (frac, -1074) } else { (frac | (1 << 52), exp - 1075) };
        let m = BigInt::from(mant);
        Big { m: if bits >> 63 == 1 { -m } else { m }, e }
    }

    /// -1, 0 or 1.
    pub fn signum(&self) -> i32 {
        match self.m.sign() {
            Sign::Minus => -1,
            Sign::NoSign => 0,
            Sign::Plus => 1,
        }
    }

    /// `|self|`.
    pub fn abs(&self) -> Big {
        Big { m: self.m.magnitude().clone().into(), e: self.e }
    }

    /// `self / o`, truncated to about [`PRECISION`] bits.
    pub fn div(&self, o: &Big) -> Big {
        assert!(o.signum() != 0, "division by zero in the reference");
        let shift = (PRECISION as i64 + o.m.bits() as i64 - self.m.bits() as i64 + 2).max(0);
        Big { m: (&self.m << shift as usize) / &o.m, e: self.e - shift - o.e }.trimmed()
    }

    /// `√self` for `self >= 0`, truncated to about [`PRECISION`] bits.
    pub fn sqrt(&self) -> Big {
        assert!(self.signum() >= 0, "square root of a negative number in the reference");
        if self.signum() == 0 {
            return Big::zero();
        }
        let mut shift = (2 * PRECISION as i64 - self.m.bits() as i64 + 2).max(0);
        if (self.e - shift) % 2 != 0 {
            shift += 1;
        }
        Big { m: (&self.m << shift as usize).sqrt(), e: (self.e - shift) / 2 }
    }

    /// Drops low bits beyond twice [`PRECISION`] (keeps rounded values small).
    fn trimmed(self) -> Big {
        let extra = self.m.bits() as i64 - 2 * PRECISION as i64;
        if extra > 0 {
            Big { m: self.m >> extra as usize, e: self.e + extra }
        } else {
            self
        }
    }

    /// The nearest double (ties to even); values here stay in the normal range.
    pub fn to_f64(&self) -> f64 {
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

/// `x · 2^e`, exact while the result is a normal double.
fn ldexp(mut x: f64, mut e: i64) -> f64 {
    let step = |k: i64| f64::from_bits(((k + 1023) as u64) << 52);
    while e > 1000 {
        x *= step(1000);
        e -= 1000;
    }
    while e < -1000 {
        x *= step(-1000);
        e += 1000;
    }
    x * step(e)
}

impl core::ops::Add<&Big> for &Big {
    type Output = Big;
    fn add(self, o: &Big) -> Big {
        let e = self.e.min(o.e);
        Big { m: (&self.m << (self.e - e) as usize) + (&o.m << (o.e - e) as usize), e }
    }
}

impl core::ops::Sub<&Big> for &Big {
    type Output = Big;
    fn sub(self, o: &Big) -> Big {
        self + &-o
    }
}

impl core::ops::Mul<&Big> for &Big {
    type Output = Big;
    fn mul(self, o: &Big) -> Big {
        Big { m: &self.m * &o.m, e: self.e + o.e }
    }
}

impl core::ops::Neg for &Big {
    type Output = Big;
    fn neg(self) -> Big {
        Big { m: -&self.m, e: self.e }
    }
}

type V3 = [Big; 3];

fn v3(x: [f64; 3]) -> V3 {
    x.map(Big::from_f64)
}

fn dot(a: &V3, b: &V3) -> Big {
    &(&(&a[0] * &b[0]) + &(&a[1] * &b[1])) + &(&a[2] * &b[2])
}

/// The unit in the last place of the largest coordinate of `x` (the spacing
/// of doubles at the hit point: what rounding the point to f64 costs).
pub fn ulp_of_point(x: [f64; 3]) -> f64 {
    let m = x.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if m < f64::MIN_POSITIVE {
        return f64::from_bits(1);
    }
    let exp = ((m.to_bits() >> 52) & 0x7ff) as i64;
    ldexp(1.0, exp - 1075)
}

/// One end of the exact interval set: a surface crossing at `λ`, or free
/// (infinite, or the ray origin where the ray starts inside).
pub type End = Option<Big>;

/// A quadric given by exact dyadic coefficients around its centre.
pub struct ExactQuadric {
    c: V3,
    a: [V3; 3],
    w: V3,
    k: Big,
}

/// The exact answer for one ray.
pub struct ExactRay {
    /// `s`, `t`, `u` of `sλ² + 2tλ + u`, exact.
    pub s: Big,
    /// See `s`.
    pub t: Big,
    /// See `s`.
    pub u: Big,
    /// The exact interval set within `λ >= 0` (regularised: no isolated points).
    pub set: Vec<(End, End)>,
}

impl ExactRay {
    /// The surface crossings within `λ >= 0`, in order.
    pub fn crossings(&self) -> Vec<&Big> {
        self.set.iter().flat_map(|(a, b)| [a.as_ref(), b.as_ref()]).flatten().collect()
    }
}

impl ExactQuadric {
    /// The solid `q` stands for: its stored centre and local coefficients.
    pub fn new(q: &Quadric) -> ExactQuadric {
        let (c, a, w, k) = q.local_parts();
        ExactQuadric {
            c: v3([c.x, c.y, c.z]),
            a: [0, 1, 2].map(|i| v3([a[(i, 0)], a[(i, 1)], a[(i, 2)]])),
            w: v3([w.x, w.y, w.z]),
            k: Big::from_f64(k),
        }
    }

    /// The half-space `n·(x - o) + d <= 0` as the quadric `A = 0`, `w = n/2`
    /// (halving is exact), around its stored reference point `o`.
    pub fn half_space(h: &HalfSpace) -> ExactQuadric {
        let (o, n) = (h.reference_point(), h.normal_vector());
        ExactQuadric {
            c: v3([o.x, o.y, o.z]),
            a: [0, 1, 2].map(|_| v3([0.0; 3])),
            w: v3([0.5 * n.x, 0.5 * n.y, 0.5 * n.z]),
            k: Big::from_f64(h.value(&o)),
        }
    }

    /// The reference for either kind of solid.
    pub fn solid(s: &Solid) -> ExactQuadric {
        match s {
            Solid::Quadric(q) => ExactQuadric::new(q),
            Solid::HalfSpace(h) => ExactQuadric::half_space(h),
        }
    }

    /// `A d + w`, half the gradient at `c + d`.
    fn half_gradient(&self, d: &V3) -> V3 {
        [0, 1, 2].map(|i| &dot(&self.a[i], d) + &self.w[i])
    }

    /// `f(c + d) = dᵀ(A d + 2w) + k`.
    fn value_rel(&self, d: &V3) -> Big {
        let g = self.half_gradient(d);
        let gw = [0, 1, 2].map(|i| &g[i] + &self.w[i]);
        &dot(d, &gw) + &self.k
    }

    fn rel(&self, x: &V3) -> V3 {
        [0, 1, 2].map(|i| &x[i] - &self.c[i])
    }

    /// `f(x)` at the double point `x`, exact.
    pub fn value(&self, x: [f64; 3]) -> Big {
        self.value_rel(&self.rel(&v3(x)))
    }

    /// The exact `s`, `t`, `u` and interval set of `ray`.
    pub fn solve(&self, ray: &Ray) -> ExactRay {
        let (p, r) = (ray.origin(), ray.direction());
        let (p, r) = (v3([p.x, p.y, p.z]), v3([r.x, r.y, r.z]));
        let d = self.rel(&p);
        let ar = [0, 1, 2].map(|i| dot(&self.a[i], &r));
        let s = dot(&r, &ar);
        let t = dot(&r, &self.half_gradient(&d));
        let u = self.value_rel(&d);
        let line = line_set(&s, &t, &u);
        let set = clip_to_ray(line);
        ExactRay { s, t, u, set }
    }

    /// Distance of the point `x` (any precision) from the surface `f = 0`,
    /// measured along the normal line `x + β∇f(x)`: exact for spheres, and
    /// equal to the Euclidean distance up to second order otherwise. Where
    /// the normal line misses the surface, the first-order `|f|/|∇f|`.
    /// `None` where the gradient vanishes.
    pub fn distance(&self, x: &V3) -> Option<f64> {
        let d = self.rel(x);
        let f = self.value_rel(&d);
        let g = self.half_gradient(&d);
        let b = dot(&g, &g);
        if b.signum() == 0 {
            return None;
        }
        if f.signum() == 0 {
            return Some(0.0);
        }
        let ag = [0, 1, 2].map(|i| dot(&self.a[i], &g));
        let a2 = dot(&g, &ag);
        // f(x + βg) = f + 2β|g|² + β² gᵀAg = f + 2bβ + a2β²; smallest root
        // in the stable form β = -f / (b + √(b² - a2 f)).
        let disc = &(&b * &b) - &(&a2 * &f);
        let den = if disc.signum() >= 0 { &b + &disc.sqrt() } else { &b + &b };
        let beta = f.abs().div(&den);
        Some((&beta * &b.sqrt()).to_f64())
    }

    /// Distance from the surface of the double point `x`.
    pub fn distance_f64(&self, x: [f64; 3]) -> Option<f64> {
        self.distance(&v3(x))
    }

    /// How close the line comes to touching the surface: the distance from
    /// the surface of the apex `p + λ₀r`, `λ₀ = -t/s`, where `f` along the
    /// line is extremal. Small only for near-tangent rays; `∞` for `s = 0`.
    pub fn tangency_gap(&self, ray: &Ray, exact: &ExactRay) -> f64 {
        if exact.s.signum() == 0 {
            return f64::INFINITY;
        }
        let l0 = (-&exact.t).div(&exact.s);
        let x0 = point_at(ray, &l0);
        self.distance(&x0).unwrap_or(0.0)
    }

    /// The exact point `p + λr` rounded to doubles, coordinate by coordinate.
    pub fn rounded_point(ray: &Ray, lambda: &Big) -> [f64; 3] {
        point_at(ray, lambda).map(|c| c.to_f64())
    }
}

/// `p + λr` in high precision.
pub fn point_at(ray: &Ray, lambda: &Big) -> V3 {
    let (p, r) = (ray.origin(), ray.direction());
    [0, 1, 2].map(|i| &Big::from_f64(p[i]) + &(lambda * &Big::from_f64(r[i])))
}

/// `{λ ∈ ℝ : sλ² + 2tλ + u <= 0}`, regularised (isolated points dropped),
/// ends `None` at infinity. Follows the case table of docs/model.md §2.2 exactly.
fn line_set(s: &Big, t: &Big, u: &Big) -> Vec<(End, End)> {
    let everything = vec![(None, None)];
    if s.signum() == 0 {
        if t.signum() == 0 {
            return if u.signum() <= 0 { everything } else { vec![] };
        }
        let root = (-u).div(&(t + t));
        return if t.signum() > 0 { vec![(None, Some(root))] } else { vec![(Some(root), None)] };
    }
    let disc = &(t * t) - &(s * u);
    if disc.signum() < 0 || (disc.signum() == 0 && s.signum() > 0) {
        // No crossing (or a single touching point, which a regularised set drops).
        return if s.signum() > 0 { vec![] } else { everything };
    }
    if disc.signum() == 0 {
        // s < 0 touching from outside: the two half-lines meet.
        return everything;
    }
    let root = disc.sqrt();
    let q = if t.signum() >= 0 { -&(t + &root) } else { -&(t - &root) };
    let (r1, r2) = (q.div(s), u.div(&q));
    let (r1, r2) = if (&r1 - &r2).signum() <= 0 { (r1, r2) } else { (r2, r1) };
    if s.signum() > 0 {
        vec![(Some(r1), Some(r2))]
    } else {
        vec![(None, Some(r1)), (Some(r2), None)]
    }
}

/// The part within `λ >= 0`; an end clipped at the origin is free.
fn clip_to_ray(set: Vec<(End, End)>) -> Vec<(End, End)> {
    set.into_iter()
        .filter(|(_, hi)| hi.as_ref().is_none_or(|h| h.signum() > 0))
        .map(|(lo, hi)| (lo.filter(|l| l.signum() >= 0), hi))
        .collect()
}

/// The surface crossings (finite ends carrying a solid) of a computed set.
pub fn computed_crossings(set: &IntervalSet) -> Vec<f64> {
    set.iter()
        .flat_map(|iv| [iv.enter, iv.exit])
        .filter(|b| b.solid != NO_SOLID && b.t.is_finite())
        .map(|b| b.t)
        .collect()
}

/// A small, fixed-seed generator (splitmix64), so runs are reproducible.
pub struct Rng(u64);

impl Rng {
    /// A generator with the given seed.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform on the unit sphere.
    pub fn direction(&mut self) -> [f64; 3] {
        loop {
            let v = [self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0)];
            let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if n2 > 1e-6 && n2 <= 1.0 {
                let n = n2.sqrt();
                return v.map(|c| c / n);
            }
        }
    }

    /// Uniform in the ball of radius `r`.
    pub fn in_ball(&mut self, r: f64) -> [f64; 3] {
        let d = self.direction();
        let l = r * self.unit().cbrt();
        d.map(|c| c * l)
    }
}

// ---------------------------------------------------------------------------
// Scenes: shapes placed far away, rays from a camera near the origin.

/// How [`Scene::rays`] aims its rays.
#[derive(Clone, Copy, PartialEq)]
pub enum Aim {
    /// From a camera near the world origin at points inside the shape, one in
    /// three bisected towards a tangent ray.
    Inside,
    /// Exactly along the unit frame's y axis (`s = 0` for a paraboloid), from
    /// `distance` below the shape.
    AlongY,
    /// From inside the shape near its centre, tilted from its unit frame's y
    /// axis by `10⁻⁵ … 10⁻¹` (nearly along a cylinder's axis: `s ≈ 0`).
    NearlyAlongY,
}

/// A shape in its unit frame with samplers for points inside and outside.
pub struct Shape {
    /// Name for the tables.
    pub name: &'static str,
    /// The solid in its unit frame, before placement.
    pub solid: Solid,
    /// The linear placement (scale, rotation) applied before moving it away.
    pub linear: Transform,
    /// A point inside the unit-frame solid.
    pub inside: fn(&mut Rng) -> [f64; 3],
    /// A point outside the unit-frame solid.
    pub outside: fn(&mut Rng) -> [f64; 3],
    /// The shape's size: errors are reported in these units ("radii").
    pub size: f64,
    /// How the rays are aimed.
    pub aim: Aim,
}

use quadric::nalgebra::{Point3, Vector3};
use quadric::Transform;

fn ring(rng: &mut Rng, radius: f64, y: (f64, f64)) -> [f64; 3] {
    let a = rng.range(0.0, core::f64::consts::TAU);
    [radius * a.cos(), rng.range(y.0, y.1), radius * a.sin()]
}

fn rotation(x: f64, y: f64, z: f64) -> Transform {
    let r = |t: Result<Transform, quadric::GeometryError>| t.expect("a fixed rotation is valid");
    r(Transform::rotate_x_degrees(x)).then(&r(Transform::rotate_y_degrees(y))).then(&r(Transform::rotate_z_degrees(z)))
}

/// The unit sphere (no rotation or scaling).
pub fn unit_sphere() -> Shape {
    Shape {
        name: "unit sphere",
        solid: Quadric::sphere().into(),
        linear: Transform::identity(),
        inside: |rng| rng.in_ball(0.95),
        outside: |rng| rng.direction().map(|c| c * 1.5),
        size: 1.0,
        aim: Aim::Inside,
    }
}

/// The other shapes of the second table.
pub fn other_shapes() -> Vec<Shape> {
    let scale = |v: [f64; 3]| Transform::scale_xyz(Vector3::from(v)).expect("a fixed scale is valid");
    vec![
        Shape {
            name: "ellipsoid 3 × 1 × 0.5, rotated",
            solid: Quadric::sphere().into(),
            linear: scale([3.0, 1.0, 0.5]).then(&rotation(20.0, 35.0, 50.0)),
            inside: |rng| rng.in_ball(0.95),
            outside: |rng| rng.direction().map(|c| c * 1.5),
            size: 1.0,
            aim: Aim::Inside,
        },
        Shape {
            name: "cylinder r = 1, rotated",
            solid: Quadric::tube_y().into(),
            linear: rotation(30.0, 0.0, 70.0),
            inside: |rng| {
                let radius = 0.95 * rng.unit().sqrt();
                ring(rng, radius, (-2.0, 2.0))
            },
            outside: |rng| ring(rng, 1.5, (-2.0, 2.0)),
            size: 1.0,
            aim: Aim::Inside,
        },
        Shape {
            name: "one-sheet hyperboloid, rotated",
            solid: Quadric::hyperboloid_one_sheet().into(),
            linear: rotation(60.0, 10.0, 25.0),
            inside: |rng| rng.in_ball(0.95),
            outside: |rng| ring(rng, 1.5, (-0.5, 0.5)),
            size: 1.0,
            aim: Aim::Inside,
        },
        Shape {
            name: "paraboloid, rotated",
            solid: Quadric::paraboloid().into(),
            linear: rotation(45.0, 45.0, 0.0),
            inside: |rng| {
                let b = rng.in_ball(0.5);
                [b[0], b[1] + 1.0, b[2]]
            },
            outside: |rng| ring(rng, 1.5, (0.0, 1.0)),
            size: 1.0,
            aim: Aim::Inside,
        },
        Shape {
            name: "half-space, rotated",
            solid: HalfSpace::new(0.0, 1.0, 0.0, 0.0).expect("a valid plane").into(),
            linear: rotation(15.0, 25.0, 35.0),
            inside: |rng| {
                let b = rng.in_ball(1.0);
                [b[0], -b[1].abs(), b[2]]
            },
            outside: |rng| {
                let b = rng.in_ball(1.0);
                [b[0], b[1].abs(), b[2]]
            },
            size: 1.0,
            aim: Aim::Inside,
        },
        Shape {
            name: "cylinder r = 1, rotated, rays from inside nearly along its axis (s ≈ 0)",
            solid: Quadric::tube_y().into(),
            linear: rotation(30.0, 0.0, 70.0),
            inside: |rng| rng.in_ball(0.5),
            outside: |rng| ring(rng, 1.5, (-2.0, 2.0)),
            size: 1.0,
            aim: Aim::NearlyAlongY,
        },
        Shape {
            name: "paraboloid, rays along its axis (s = 0)",
            solid: Quadric::paraboloid().into(),
            linear: Transform::identity(),
            inside: |rng| {
                let b = rng.in_ball(0.5);
                [b[0], b[1] + 1.0, b[2]]
            },
            outside: |rng| ring(rng, 1.5, (0.0, 1.0)),
            size: 1.0,
            aim: Aim::AlongY,
        },
    ]
}

/// A shape placed at `distance` from the origin in a random direction.
pub struct Scene {
    /// The placed solid.
    pub solid: Solid,
    /// Its centre (a half-space's reference point), to which errors are local.
    pub centre: Point3<f64>,
    /// Its exact reference.
    pub exact: ExactQuadric,
    /// Unit frame to world.
    pub placement: Transform,
    /// The shape's size.
    pub size: f64,
}

impl Scene {
    /// Places `shape` with its centre at `distance · (random unit vector)`.
    pub fn new(shape: &Shape, distance: f64, rng: &mut Rng) -> Scene {
        let centre = Vector3::from(rng.direction()) * distance;
        let placement = shape.linear.then(&Transform::translate(centre).expect("a finite translation is valid"));
        let solid = shape.solid.transformed(&placement);
        let centre = match &solid {
            Solid::Quadric(q) => q.centre(),
            Solid::HalfSpace(h) => h.reference_point(),
        };
        Scene { exact: ExactQuadric::solid(&solid), solid, centre, placement, size: shape.size }
    }

    /// The world-space coefficients `[a, b, c, d, e, f, g, h, j, k]`, as a
    /// textbook kernel would take them.
    pub fn world_coefficients(&self) -> [f64; 10] {
        match &self.solid {
            Solid::Quadric(q) => q.coefficients(),
            Solid::HalfSpace(h) => {
                let v = h.vector();
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5 * v.x, 0.5 * v.y, 0.5 * v.z, v.w]
            }
        }
    }

    /// The error unit at the point `x`: an ulp of its largest coordinate,
    /// taken in world space or relative to the quadric's centre, whichever is
    /// coarser (near the world origin the local coordinates set the floor).
    pub fn ulp_at(&self, x: [f64; 3]) -> f64 {
        ulp_of_point(x).max(self.local_ulp(x))
    }

    /// An ulp of the largest coordinate of `x - c` (the quadric's own scale).
    pub fn local_ulp(&self, x: [f64; 3]) -> f64 {
        let c = self.centre;
        ulp_of_point([x[0] - c.x, x[1] - c.y, x[2] - c.z])
    }

    /// How close the line of `ray` comes to tangency: the exact distance of
    /// its apex `-t/s` from the surface, in [`Scene::local_ulp`]s there
    /// (infinite for `s = 0`).
    pub fn apex_gap_ulps(&self, ray: &Ray, exact: &ExactRay) -> f64 {
        if exact.s.signum() == 0 {
            return f64::INFINITY;
        }
        let apex = point_at(ray, &(-&exact.t).div(&exact.s)).map(|c| c.to_f64());
        self.exact.tangency_gap(ray, exact) / self.local_ulp(apex)
    }

    /// Whether the line of `ray` crosses the surface (exact).
    fn crosses(&self, ray: &Ray) -> bool {
        !self.exact.solve(ray).crossings().is_empty()
    }

    /// `n` rays from a camera within `camera` of the origin: most aimed at
    /// points inside the solid, one in three bisected towards a tangent ray
    /// (between an inside and an outside target, with the exact reference
    /// deciding) to a random closeness.
    pub fn rays(&self, shape: &Shape, camera: f64, n: usize, rng: &mut Rng) -> Vec<Ray> {
        let world = |p: [f64; 3]| self.placement.apply_point(&Point3::from(p));
        let aim = |o: Point3<f64>, x: Point3<f64>| Ray::new(o, x - o).ok();
        let mut out = Vec::with_capacity(n);
        if shape.aim == Aim::NearlyAlongY {
            let axis = self.placement.apply_vector(&Vector3::y());
            while out.len() < n {
                let o = self.placement.apply_point(&Point3::from(rng.in_ball(0.5)));
                let tilt = 10f64.powf(rng.range(-5.0, -1.0));
                out.extend(Ray::new(o, axis + Vector3::from(rng.direction()) * tilt).ok());
            }
            return out;
        }
        if shape.aim == Aim::AlongY {
            // From `distance` below the shape straight up its axis: the
            // direction is exact, so `s = rᵀAr` is exactly zero.
            let c = self.centre;
            let below = c.coords.norm();
            while out.len() < n {
                let off = rng.in_ball(1.5);
                let o = Point3::new(c.x + off[0], c.y - below, c.z + off[2]);
                out.extend(Ray::new(o, Vector3::y()).ok());
            }
            return out;
        }
        while out.len() < n {
            let o = Point3::from(rng.in_ball(camera));
            let hit = world((shape.inside)(rng));
            let Some(ray) = aim(o, hit) else { continue };
            if out.len() % 3 != 2 {
                out.push(ray);
                continue;
            }
            let mut a = hit;
            let mut b = world((shape.outside)(rng));
            if !self.crosses(&ray) || aim(o, b).is_none_or(|r| self.crosses(&r)) {
                out.push(ray);
                continue;
            }
            let steps = 10 + (rng.next_u64() % 50) as usize;
            for _ in 0..steps {
                let m = Point3::from((a.coords + b.coords) * 0.5);
                match aim(o, m) {
                    Some(r) if self.crosses(&r) => a = m,
                    Some(_) => b = m,
                    None => break,
                }
            }
            let pick = if rng.unit() < 0.5 { a } else { b };
            if let Some(r) = aim(o, pick) {
                out.push(r);
            }
        }
        out
    }
}

// ---------------------------------------------------------------------------
// Error tallies.

/// Errors of one method over many rays.
#[derive(Default)]
pub struct Tally {
    /// Hit-point distance from the surface, in units of the shape's size.
    pub size_units: Vec<f64>,
    /// The same distance in ulps of the hit point's largest coordinate.
    pub ulps: Vec<f64>,
    /// `|λ̂ - λ| / λ`.
    pub lambda_rel: Vec<f64>,
    /// Rays where this method reports more surface crossings than exist.
    pub false_hits: usize,
    /// Rays where it reports fewer.
    pub false_misses: usize,
    /// Of those, how many lie outside the tangency band (see [`Judge`]).
    pub unexcused: usize,
    /// The largest tangency gap (in local ulps at the apex) of a false hit or miss.
    pub worst_gap_ulps: f64,
}

/// How [`Tally::add`] excuses false hits and misses: only rays whose line
/// passes within `band_ulps` ulps of touching the surface (the tangency gap,
/// measured at the apex `-t/s`) or that start within `band_ulps` ulps of it,
/// in ulps of the quadric's own coordinates `x - c` (not of the distance).
pub struct Judge {
    /// Width of the tangency band in ulps of the apex coordinates relative to the centre.
    pub band_ulps: f64,
}

/// Median and maximum (NaN for no data).
pub fn median_max(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[s.len() - 1])
}

impl Tally {
    /// The rounding floor for one ray: each exact crossing rounded to doubles.
    pub fn add_floor(&mut self, scene: &Scene, ray: &Ray, exact: &ExactRay) {
        for l in exact.crossings() {
            let x = ExactQuadric::rounded_point(ray, l);
            if let Some(dist) = scene.exact.distance_f64(x) {
                self.size_units.push(dist / scene.size);
                self.ulps.push(dist / scene.ulp_at(x));
            }
        }
    }

    /// Scores a computed set against the exact one for one ray, each hit
    /// point formed as `ray.at(λ̂)` (the textbook point from the double `λ̂`).
    pub fn add(&mut self, scene: &Scene, ray: &Ray, exact: &ExactRay, computed: &IntervalSet, judge: &Judge) {
        self.add_with_points(scene, ray, exact, computed, judge, |t| ray.at(t));
    }

    /// [`Tally::add`] with the hit point of the computed crossing `λ̂` given
    /// by `point` (e.g. the kernel's refined `Solid::hit_point`): the
    /// hit-point error is the exact distance of `point(λ̂)` from the true
    /// surface; the relative error of `λ` is that of `λ̂` itself.
    pub fn add_with_points(
        &mut self,
        scene: &Scene,
        ray: &Ray,
        exact: &ExactRay,
        computed: &IntervalSet,
        judge: &Judge,
        point: impl Fn(f64) -> Point3<f64>,
    ) {
        let want = exact.crossings();
        let got = computed_crossings(computed);
        if want.len() != got.len() {
            if got.len() > want.len() {
                self.false_hits += 1;
            } else {
                self.false_misses += 1;
            }
            let gap = scene.apex_gap_ulps(ray, exact);
            let p = ray.origin();
            let p = [p.x, p.y, p.z];
            let start = scene.exact.distance_f64(p).unwrap_or(0.0) / scene.local_ulp(p);
            let gap = gap.min(start);
            self.worst_gap_ulps = self.worst_gap_ulps.max(gap);
            if gap > judge.band_ulps {
                self.unexcused += 1;
            }
            return;
        }
        for (l, &lh) in want.into_iter().zip(&got) {
            let exact_point = ExactQuadric::rounded_point(ray, l);
            let x = point(lh);
            if let Some(dist) = scene.exact.distance_f64([x.x, x.y, x.z]) {
                self.size_units.push(dist / scene.size);
                self.ulps.push(dist / scene.ulp_at(exact_point));
            }
            let err = &Big::from_f64(lh) - l;
            self.lambda_rel.push(if l.signum() == 0 { err.abs().to_f64() } else { err.div(l).abs().to_f64() });
        }
    }
}
