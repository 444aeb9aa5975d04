//! Independent oracles for the ray kernel and transforms.
//!
//! `intervals(ray)` is checked against the sign of `f(p + λr)` evaluated
//! directly from the world-space coefficients (a different formula from the
//! kernel's `s, t, u` and roots), only at `λ` where `|f|` exceeds a rounding
//! bound computed alongside, so that no assertion depends on how a boundary
//! point rounds. Far from the origin, where f64 world coefficients are too
//! coarse, `f` is evaluated in double-double from the solid's local form
//! instead, sharp enough to see the kernel's own rounding.
//!
//! Each property runs on random solids and rays ([`strategies::solid`],
//! [`strategies::ray`]) and on exact grid ones ([`strategies::grid_solid`],
//! [`strategies::grid_ray`]: tangents, rays in the surface, `s = 0`, `t = 0`).
//!
//! Case counts come from `PROPTEST_CASES` (1000 in CI) through `ProptestConfig::default()`.

use nalgebra::{Matrix3, Matrix4, Point3, Vector3};
use proptest::prelude::*;
use quadric::strategies;
use quadric::{Bound, IntervalSet, Ray, Solid, Transform, NO_SOLID};

const EPS: f64 = f64::EPSILON;
const INF: f64 = f64::INFINITY;

/// A solid as plain world-space numbers, with what is needed to bound the
/// rounding error of evaluating it.
enum World {
    /// `[a, b, c, d, e, f, g, h, j, k]`, with error bounds for `k` and for
    /// `(g, h, j)` (formed from the local centre form; `A` is exact).
    Quadric([f64; 10], f64, Vector3<f64>),
    /// `[a, b, c, d]` and the error of `d`.
    Plane([f64; 4], f64),
}

fn world(solid: &Solid) -> World {
    match solid {
        Solid::Quadric(q) => {
            let (c, a, w, k) = q.local_parts();
            let (c, a) = (c.coords.abs(), a.abs());
            // `(g, h, j) = w - A c` and `k' = cᵀAc - 2wᵀc + k`, each a few
            // roundings of the sizes involved.
            let dg = (a * c + w.abs()) * (8.0 * EPS);
            let dk = 8.0 * EPS * (c.dot(&(a * c)) + 2.0 * w.abs().dot(&c) + k.abs());
            World::Quadric(q.coefficients(), dk, dg)
        }
        Solid::HalfSpace(h) => {
            let v = h.vector();
            let err = 8.0 * EPS * (h.normal_vector().abs().dot(&h.reference_point().coords.abs()) + v.w.abs());
            World::Plane([v.x, v.y, v.z, v.w], err)
        }
    }
}

/// `f(x)` from the world coefficients, and a bound on its error when `x` is
/// itself rounded by up to `pad` per coordinate.
fn eval(w: &World, x: &Point3<f64>, pad: f64) -> (f64, f64) {
    let ax = x.coords.abs();
    let (x, y, z) = (x.x, x.y, x.z);
    match *w {
        World::Quadric([a, b, c, d, e, f, g, h, j, k], dk, dg) => {
            let terms = [
                a * x * x,
                b * y * y,
                c * z * z,
                2.0 * d * x * y,
                2.0 * e * x * z,
                2.0 * f * y * z,
                2.0 * g * x,
                2.0 * h * y,
                2.0 * j * z,
                k,
            ];
            let value: f64 = terms.iter().sum();
            let size: f64 = terms.iter().map(|t| t.abs()).sum();
            let (ax, ay, az) = (ax.x, ax.y, ax.z);
            let grad = 2.0
                * ((a.abs() * ax + d.abs() * ay + e.abs() * az + g.abs())
                    + (d.abs() * ax + b.abs() * ay + f.abs() * az + h.abs())
                    + (e.abs() * ax + f.abs() * ay + c.abs() * az + j.abs()));
            let coeff = dk + 2.0 * (dg.x * ax + dg.y * ay + dg.z * az);
            (value, 32.0 * EPS * size + coeff + 4.0 * grad * pad)
        }
        World::Plane([a, b, c, d], err) => {
            let terms = [a * x, b * y, c * z, d];
            let value: f64 = terms.iter().sum();
            let size: f64 = terms.iter().map(|t| t.abs()).sum();
            let grad = a.abs() + b.abs() + c.abs();
            (value, 8.0 * EPS * size + err + 4.0 * grad * pad)
        }
    }
}

/// How far `ray.at(λ)` may be from the exact point, per coordinate.
fn pad(ray: &Ray, lambda: f64) -> f64 {
    4.0 * EPS * (ray.origin().coords.amax() + lambda.abs())
}

/// The sign of `f(ray.at(λ))` when it is clear: `Some(true)` inside, `Some(false)` outside.
fn clear_side(w: &World, ray: &Ray, lambda: f64) -> Option<bool> {
    let (f, bound) = eval(w, &ray.at(lambda), pad(ray, lambda));
    if f < -bound {
        Some(true)
    } else if f > bound {
        Some(false)
    } else {
        None
    }
}

/// Double-double arithmetic (a value as an unevaluated sum `hi + lo`), enough
/// to evaluate `f(p + λr)` from a solid's local form with about 106 bits:
/// sharp enough to see the kernel's own rounding far from the origin, where a
/// world-space f64 evaluation cannot.
mod dd {
    #[derive(Clone, Copy, Debug)]
    pub struct Dd(pub f64, pub f64);

    fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let bb = s - a;
        Dd(s, (a - (s - bb)) + (b - bb))
    }

    fn fast_two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        Dd(s, b - (s - a))
    }

    pub fn two_prod(a: f64, b: f64) -> Dd {
        let p = a * b;
        Dd(p, a.mul_add(b, -p))
    }

    impl Dd {
        pub fn from(x: f64) -> Dd {
            Dd(x, 0.0)
        }
        pub fn add(self, o: Dd) -> Dd {
            let s = two_sum(self.0, o.0);
            let t = two_sum(self.1, o.1);
            let s = fast_two_sum(s.0, s.1 + t.0);
            fast_two_sum(s.0, s.1 + t.1)
        }
        pub fn mul(self, o: Dd) -> Dd {
            let p = two_prod(self.0, o.0);
            fast_two_sum(p.0, p.1 + (self.0 * o.1 + self.1 * o.0))
        }
        pub fn value(self) -> f64 {
            self.0 + self.1
        }
    }
}

/// `f(p + λr)` in double-double from the solid's local form (the stored
/// centre, `A`, `w`, `k`, taken as the exact definition of the solid), a
/// bound on its error, and the sum of the magnitudes of its terms.
fn exact_f(solid: &Solid, ray: &Ray, lambda: f64) -> (f64, f64, f64) {
    use dd::{two_prod, Dd};
    let (p, r) = (ray.origin(), ray.direction());
    match solid {
        Solid::Quadric(q) => {
            let (c, a, w, k) = q.local_parts();
            // d = p + λr - c, exactly up to double-double rounding.
            let d: [Dd; 3] = core::array::from_fn(|i| two_prod(lambda, r[i]).add(Dd::from(p[i])).add(Dd::from(-c[i])));
            let mut f = Dd::from(k);
            let mut size = k.abs();
            for i in 0..3 {
                for j in 0..3 {
                    let term = Dd::from(a[(i, j)]).mul(d[i]).mul(d[j]);
                    size += term.value().abs();
                    f = f.add(term);
                }
                let term = Dd::from(2.0 * w[i]).mul(d[i]);
                size += term.value().abs();
                f = f.add(term);
            }
            (f.value(), 64.0 * EPS * EPS * size + f64::MIN_POSITIVE, size)
        }
        Solid::HalfSpace(h) => {
            let (n, o) = (h.normal_vector(), h.reference_point());
            // The stored d, exactly: the value at the reference point is n·0 + d.
            let mut f = Dd::from(h.value(&o));
            let mut size = f.value().abs();
            for i in 0..3 {
                let di = two_prod(lambda, r[i]).add(Dd::from(p[i])).add(Dd::from(-o[i]));
                let term = Dd::from(n[i]).mul(di);
                size += term.value().abs();
                f = f.add(term);
            }
            (f.value(), 64.0 * EPS * EPS * size + f64::MIN_POSITIVE, size)
        }
    }
}

/// The sign of the exact `f(p + λr)` when it is clear.
fn exact_side(solid: &Solid, ray: &Ray, lambda: f64) -> Option<bool> {
    let (f, bound, _) = exact_f(solid, ray, lambda);
    (f.abs() > bound).then_some(f < 0.0)
}

/// Sample parameters: the given ones, the ends of `set` and points just
/// either side of them, midpoints between ends, and beyond the last end.
fn samples(set: &IntervalSet, extra: &[f64]) -> Vec<f64> {
    let mut out = extra.to_vec();
    out.push(0.0);
    let finite: Vec<f64> = set.iter().flat_map(|iv| [iv.enter.t, iv.exit.t]).filter(|t| t.is_finite()).collect();
    for (i, &t) in finite.iter().enumerate() {
        // Steps from far inside the rounding bound (skipped as unclear) to well
        // outside it. Not the end itself: how far an end may be from the
        // exact root is the residual check's business.
        out.push(2.0 * t + 1.0);
        for rel in [1e-12, 1e-10, 1e-8, 1e-6] {
            let step = rel * t.abs().max(1.0);
            out.extend([t - step, t + step]);
        }
        if let Some(&next) = finite.get(i + 1) {
            out.push(0.5 * (t + next));
        }
    }
    out.retain(|t| t.is_finite() && *t >= 0.0);
    out
}

fn sample_params() -> impl Strategy<Value = Vec<f64>> {
    proptest::collection::vec(0.0f64..40.0, 24)
}

fn inf_norm(m: &Matrix3<f64>) -> f64 {
    m.abs().row_sum().max()
}

/// The condition number of a transform's linear part (in the ∞-norm).
fn condition(m: &Transform) -> f64 {
    inf_norm(m.linear()) * inf_norm(m.linear_inverse())
}

/// The total length of a set's bounded part.
fn measure(set: &IntervalSet) -> f64 {
    set.iter().map(|iv| iv.length()).sum()
}

/// `λ ↦ L - λ` applied to a set within `[0, L]`.
fn mirrored(set: &IntervalSet, l: f64) -> IntervalSet {
    let clipped = set.clip(0.0, l);
    let items = clipped.iter().map(|iv| {
        quadric::Interval::new(Bound::new(l - iv.exit.t, iv.exit.solid), Bound::new(l - iv.enter.t, iv.enter.solid))
    });
    IntervalSet::from_intervals(items).expect("a clipped solid's set fits")
}

/// The kernel's set agrees with the sign of `f` wherever that sign is clear,
/// every finite end is a root of `f` up to rounding, ends carry the right
/// solid, and a convex solid gives at most one interval.
fn agrees_with_the_sign_of_f(solid: Solid, ray: Ray, extra: &[f64]) -> Result<(), TestCaseError> {
    let set = solid.intervals(&ray, 3);
    prop_assert!(set.is_normalised(), "{:?}", set);
    let w = world(&solid);
    // How far from 0 `f` at a computed end may be. The kernel may evaluate f
    // at the ray origin, or re-based anywhere between it, the foot of the
    // perpendicular from the solid's centre and the root, and adds the
    // re-basing parameter back: its rounding there (the oracle's bound at
    // those points is a multiple of ε·size) and of λ about the foot move the
    // computed root. Signs are only asserted where |f| exceeds this too.
    let foot = match &solid {
        Solid::Quadric(q) => -ray.direction().dot(&(ray.origin() - q.centre())),
        Solid::HalfSpace(h) => -ray.direction().dot(&(ray.origin() - h.reference_point())),
    };
    let elsewhere = eval(&w, &ray.origin(), 0.0).1 + eval(&w, &ray.at(foot), pad(&ray, foot)).1;
    let allowed = |lambda: f64| {
        let (f, bound) = eval(&w, &ray.at(lambda), pad(&ray, lambda) + 4.0 * EPS * foot.abs());
        (f, 4.0 * bound + 2.0 * elsewhere)
    };
    for lambda in samples(&set, extra) {
        let (f, tolerance) = allowed(lambda);
        if f.abs() > tolerance {
            prop_assert_eq!(set.contains(lambda), f < 0.0, "λ = {}: f = {} (±{}), set {:?}", lambda, f, tolerance, set);
        }
    }
    for b in set.iter().flat_map(|iv| [iv.enter, iv.exit]) {
        prop_assert!(b.t >= 0.0, "{:?}", b);
        if b.t.is_infinite() {
            prop_assert_eq!(b.solid, NO_SOLID);
        } else if b.solid == NO_SOLID {
            // Only the start of a ray that begins inside is free.
            prop_assert_eq!(b.t, 0.0);
            prop_assert_ne!(clear_side(&w, &ray, 0.0), Some(false), "free start outside: {:?}", set);
        } else {
            prop_assert_eq!(b.solid, 3);
            let (f, tolerance) = allowed(b.t);
            prop_assert!(f.abs() <= tolerance, "end {} is no root: f = {} > {}; {:?}", b.t, f, tolerance, set);
        }
    }
    prop_assert!(set.len() <= solid.max_intervals(), "{:?} has more pieces than {}", set, solid.max_intervals());
    Ok(())
}

/// A solid and its complement split the ray: together everything, shared
/// nothing, except when the ray lies in the surface (f ≡ 0 along it),
/// where both closed solids hold the whole ray.
fn complement_splits(solid: Solid, ray: Ray, extra: &[f64]) -> Result<(), TestCaseError> {
    let set = solid.intervals(&ray, 0);
    let other = solid.complement().intervals(&ray, 1);
    prop_assert!(other.is_normalised());
    let whole = IntervalSet::from_interval(Bound::free(0.0), Bound::free(INF));
    if set.same_points(&whole) && other.same_points(&whole) {
        let w = world(&solid);
        for &lambda in extra {
            prop_assert_eq!(clear_side(&w, &ray, lambda), None, "the ray is not in the surface at λ = {}", lambda);
        }
    } else {
        // The two sets should meet exactly; when the re-based `t` is exactly
        // zero they can miss by an ulp (see `complement_meets_exactly_when_t_is_zero`).
        // So: no overlap or gap longer than a few ulps of the ends.
        let shared = set.intersect(&other).expect("fits");
        let gaps = set.union(&other).expect("fits").complement().expect("fits");
        let scale = set
            .iter()
            .chain(other.iter())
            .flat_map(|iv| [iv.enter.t, iv.exit.t])
            .filter(|t| t.is_finite())
            .fold(1.0, f64::max);
        let ulps = 8.0 * EPS * scale;
        prop_assert!(
            measure(&shared) <= ulps && measure(&gaps) <= ulps,
            "{:?} vs {:?}: overlap {:?}, gaps {:?}",
            set,
            other,
            shared,
            gaps
        );
    }
    Ok(())
}

/// Reversing the ray at `L` mirrors the set on `[0, L]`: `λ ↦ L - λ`.
fn reversal_mirrors(solid: Solid, ray: Ray, l: f64, extra: &[f64]) -> Result<(), TestCaseError> {
    let back = ray.reversed_at(l);
    let (set, rev) = (solid.intervals(&ray, 0), solid.intervals(&back, 0));
    let w = world(&solid);
    for &lambda in extra.iter().filter(|&&x| x <= l) {
        if clear_side(&w, &ray, lambda).is_some() && clear_side(&w, &back, l - lambda).is_some() {
            prop_assert_eq!(
                set.contains(lambda),
                rev.contains(l - lambda),
                "λ = {}, L = {}: {:?} vs {:?}",
                lambda,
                l,
                set,
                rev
            );
        }
    }
    // The ends agree up to rounding: where the two sets differ by more than a
    // negligible length, f must be within rounding of 0 (a ray lying in the
    // surface, which the rounded new origin may leave).
    let (a, b) = (set.clip(0.0, l), mirrored(&rev, l));
    let both = a.intersect(&b).expect("fits");
    let differ = a.union(&b).expect("fits").intersect(&both.complement_within(0.0, l).expect("fits")).expect("fits");
    let tol = 1e-6 * (1.0 + l + ray.origin().coords.amax());
    for iv in differ.iter().filter(|iv| iv.length() > tol) {
        let mid = 0.5 * (iv.enter.t + iv.exit.t);
        prop_assert!(
            clear_side(&w, &ray, mid).is_none(),
            "{:?} vs mirrored {:?} differ on {:?}, where f = {:?}",
            a,
            b,
            iv,
            eval(&w, &ray.at(mid), pad(&ray, mid))
        );
    }
    Ok(())
}

/// Where to put a solid far away and where to look at it from:
/// `(distance, direction, aim offset, ray origin)`.
type FarRay = (f64, Vector3<f64>, Point3<f64>, Point3<f64>);

fn far_ray() -> impl Strategy<Value = FarRay> {
    (
        (1.0f64..9.0).prop_map(|e| 10f64.powf(e)),
        strategies::unit_vector(),
        strategies::point(2.0),
        strategies::point(2.0),
    )
}

/// The solid moved `distance` along `towards`, and a ray from `origin` aimed
/// at its new place (offset by `aim`).
fn place_far(solid: &Solid, &(distance, towards, aim, origin): &FarRay) -> (Solid, Ray, f64) {
    let centre = towards * distance;
    let moved = solid.transformed(&Transform::translate(centre).expect("finite"));
    let ray = Ray::new(origin, centre + aim.coords - origin.coords).expect("a direction");
    (moved, ray, distance)
}

/// Ellipsoids (a positive definite quadratic part: every ray meets them in a
/// bounded interval whose ends cluster when seen from afar) and half-spaces.
fn bounded_or_plane() -> impl Strategy<Value = Solid> {
    let ellipsoid =
        (Just(quadric::Quadric::sphere()), strategies::transform()).prop_map(|(q, m)| Solid::from(q.transformed(&m)));
    prop_oneof![3 => ellipsoid, 1 => strategies::half_space().prop_map(Solid::from)]
}

/// The exact sign of `f` (double-double) agrees with the set at points
/// 64, 1024 and 10⁶ rounding units either side of every finite end, and at `extra`.
///
/// A unit is `ε·(λ + (|p| + |c|)·|∇f|/|f'| + size/|f'|)`: the kernel rounds λ
/// itself, the ray origin relative to the centre (moving the root by that
/// times `|∇f|/|f'|`, large for grazing rays), and `f` near the root (by
/// `ε·size`, `size` the sum of the magnitudes of `f`'s terms). With
/// `at_origin`, `size` is also taken at the ray origin: where the kernel does
/// not re-base the ray (the roots do not cluster, e.g. a ray close to a cone's
/// asymptote), `u = f(p)` is evaluated there and its rounding moves the root.
fn exact_sign_near_ends(solid: &Solid, ray: &Ray, extra: &[f64], at_origin: bool) -> Result<(), TestCaseError> {
    let set = solid.intervals(ray, 0);
    let mut probes = extra.to_vec();
    let position = ray.origin().coords.amax()
        + match solid {
            Solid::Quadric(q) => q.centre().coords.amax(),
            Solid::HalfSpace(h) => h.reference_point().coords.amax(),
        };
    for t in set.iter().flat_map(|iv| [iv.enter.t, iv.exit.t]).filter(|t| t.is_finite()) {
        let (_, _, mut size) = exact_f(solid, ray, t);
        if at_origin {
            size += exact_f(solid, ray, 0.0).2;
        }
        let h = 1e-6 * (t + 1.0);
        let slope = ((exact_f(solid, ray, t + h).0 - exact_f(solid, ray, t - h).0) / (2.0 * h)).abs();
        let grad = match solid {
            Solid::Quadric(q) => q.gradient(&ray.at(t)).norm(),
            Solid::HalfSpace(hs) => hs.normal_vector().norm(),
        };
        let unit = EPS * (t + (position * grad + size) / slope);
        for k in [64.0, 1024.0, 1e6] {
            probes.extend([t - k * unit, t + k * unit]);
        }
    }
    for lambda in probes.into_iter().filter(|&l| l >= 0.0) {
        if let Some(inside) = exact_side(solid, ray, lambda) {
            prop_assert_eq!(
                set.contains(lambda),
                inside,
                "λ = {}: exact f = {:?}, set {:?}, solid {:?}, ray {:?}",
                lambda,
                exact_f(solid, ray, lambda),
                set,
                solid,
                ray
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn intervals_agree_with_the_sign_of_f(solid in strategies::solid(), ray in strategies::ray(6.0), extra in sample_params()) {
        agrees_with_the_sign_of_f(solid, ray, &extra)?;
    }

    /// Exact solids and grid rays: tangents, rays in the surface, `s = 0`, `t = 0`.
    #[test]
    fn grid_intervals_agree_with_the_sign_of_f(solid in strategies::grid_solid(), ray in strategies::grid_ray(3), extra in sample_params()) {
        agrees_with_the_sign_of_f(solid, ray, &extra)?;
    }

    /// Solids moved up to 10⁹ away and a ray from near the origin aimed at
    /// them: the far-away path (local centre, ray re-based at the roots). The
    /// world coefficients lose accuracy there, which the f64 oracle's bound
    /// accounts for; the double-double oracle then checks the sign a few
    /// rounding units either side of every end, where a unit allows for the
    /// rounding of `f` at the ray origin as well (see `far_solid_ends_are_sharp`).
    #[test]
    fn far_intervals_agree_with_the_sign_of_f(solid in strategies::solid(), far in far_ray(), offsets in proptest::collection::vec(-8.0f64..8.0, 16)) {
        let (moved, ray, distance) = place_far(&solid, &far);
        let extra: Vec<f64> = offsets.iter().map(|o| distance + o).collect();
        agrees_with_the_sign_of_f(moved, ray, &extra)?;
        exact_sign_near_ends(&moved, &ray, &extra, true)?;
    }

    /// Ellipsoids and half-spaces far away: their ends are within a few
    /// rounding units of the exact roots, counted at the end itself (the
    /// kernel re-bases the ray there, so the distance from the origin must
    /// not matter).
    #[test]
    fn far_solid_ends_are_sharp(solid in bounded_or_plane(), far in far_ray(), offsets in proptest::collection::vec(-8.0f64..8.0, 16)) {
        let (moved, ray, distance) = place_far(&solid, &far);
        let extra: Vec<f64> = offsets.iter().map(|o| distance + o).collect();
        exact_sign_near_ends(&moved, &ray, &extra, false)?;
    }

    #[test]
    fn complement_splits_the_ray(solid in strategies::solid(), ray in strategies::ray(6.0), extra in sample_params()) {
        complement_splits(solid, ray, &extra)?;
    }

    #[test]
    fn grid_complement_splits_the_ray(solid in strategies::grid_solid(), ray in strategies::grid_ray(3), extra in sample_params()) {
        complement_splits(solid, ray, &extra)?;
    }

    #[test]
    fn reversing_mirrors_the_set(solid in strategies::solid(), ray in strategies::ray(6.0), l in prop_oneof![1.0f64..50.0, 50.0f64..1e4], extra in sample_params()) {
        reversal_mirrors(solid, ray, l, &extra)?;
    }

    #[test]
    fn grid_reversing_mirrors_the_set(solid in strategies::grid_solid(), ray in strategies::grid_ray(3), l in prop_oneof![1.0f64..50.0, 50.0f64..1e4], extra in sample_params()) {
        reversal_mirrors(solid, ray, l, &extra)?;
    }


    /// Sets of two solids along one ray combine like their points: the
    /// intersection and union agree with both signs of `f` wherever both are
    /// clear, and the half-space fast path (`interval` + `intersect_interval`)
    /// gives the same set as the general one.
    #[test]
    fn two_solids_combine(a in strategies::solid(), b in strategies::solid(), h in strategies::half_space(), ray in strategies::ray(6.0), extra in sample_params()) {
        let (sa, sb) = (a.intervals(&ray, 0), b.intervals(&ray, 1));
        let (and, or) = (sa.intersect(&sb).expect("fits"), sa.union(&sb).expect("fits"));
        let (wa, wb) = (world(&a), world(&b));
        let mut probes = samples(&sa, &extra);
        probes.extend(samples(&sb, &[]));
        for lambda in probes {
            if let (Some(ia), Some(ib)) = (clear_side(&wa, &ray, lambda), clear_side(&wb, &ray, lambda)) {
                prop_assert_eq!(and.contains(lambda), ia && ib, "λ = {}: {:?} ∩ {:?} = {:?}", lambda, sa, sb, and);
                prop_assert_eq!(or.contains(lambda), ia || ib, "λ = {}: {:?} ∪ {:?} = {:?}", lambda, sa, sb, or);
            }
        }
        let (enter, exit) = h.interval(&ray, 2);
        prop_assert_eq!(sa.intersect_interval(enter, exit), sa.intersect(&h.intervals(&ray, 2)).expect("fits"));
    }

    /// Applying a transform and then its inverse gives the point back.
    #[test]
    fn transform_round_trip(m in strategies::transform(), p in strategies::point(10.0)) {
        let q = m.apply_point(&p);
        let back = m.inverse().apply_point(&q);
        let tol = 64.0 * EPS * (inf_norm(m.linear_inverse()) * (inf_norm(m.linear()) * p.coords.amax() + m.translation().amax()) + p.coords.amax());
        prop_assert!((back - p).amax() <= tol, "{} vs {}: {} > {}", back, p, (back - p).amax(), tol);
        // The stored inverse is the inverse of the linear part and of the matrix.
        let k = condition(&m);
        prop_assert!((m.linear() * m.linear_inverse() - Matrix3::identity()).amax() <= 64.0 * EPS * k);
        let mm = m.matrix() * m.inverse().matrix();
        prop_assert!((mm - nalgebra::Matrix4::identity()).amax() <= 64.0 * EPS * k * (1.0 + m.translation().amax()));
        // A transform rebuilt from its matrix maps points the same way.
        let rebuilt = Transform::from_matrix(&m.matrix()).expect("an invertible transform's matrix");
        prop_assert!((rebuilt.apply_point(&p) - q).amax() <= tol);
        // Vectors ignore the translation.
        let v = m.apply_vector(&p.coords);
        prop_assert!((v + m.translation() - q.coords).amax() <= tol);
    }

    /// `a.then(b)` applies `a` first, then `b`.
    #[test]
    fn then_composes_in_order(a in strategies::transform(), b in strategies::transform(), p in strategies::point(10.0)) {
        let both = a.then(&b).apply_point(&p);
        let stepwise = b.apply_point(&a.apply_point(&p));
        let tol = 64.0 * EPS * (inf_norm(b.linear()) * (inf_norm(a.linear()) * p.coords.amax() + a.translation().amax()) + b.translation().amax());
        prop_assert!((both - stepwise).amax() <= tol, "{} vs {}", both, stepwise);
        let back = a.then(&b).inverse().apply_point(&both);
        let k = condition(&a) * condition(&b);
        prop_assert!((back - p).amax() <= 64.0 * EPS * k * (1.0 + p.coords.amax() + a.translation().amax() + b.translation().amax()));
    }

    /// `M · F(Q) = F(M⁻ᵀ Q M⁻¹)`: the moved solid holds the moved point exactly
    /// when the solid holds the point; moving back gives the same membership.
    #[test]
    fn transformed_membership(solid in strategies::solid(), m in strategies::transform(), x in strategies::point(6.0)) {
        let w = world(&solid);
        let k = condition(&m);
        // Moving the point rounds it by about ε·κ·|x| in the solid's frame, and
        // the moved coefficients carry a relative error of about ε·κ².
        let (f, bound) = eval(&w, &x, 8.0 * EPS * k * (1.0 + x.coords.amax()));
        let guard = 4.0 * bound * k * k;
        if f.abs() > guard {
            let inside = f < 0.0;
            let moved = solid.transformed(&m);
            prop_assert_eq!(moved.contains_point(&m.apply_point(&x)), inside, "f = {}, guard {}", f, guard);
            let back = moved.transformed(&m.inverse());
            prop_assert_eq!(back.contains_point(&x), inside, "f = {}, guard {}", f, guard);
            prop_assert_eq!(solid.contains_point(&x), inside);
        }
    }
}

/// A solid and its complement should split every ray exactly (their roots are
/// the same numbers: every step of the kernel is odd in `(s, t, u)`).
///
/// It fails when the ray is re-based at its roots' midpoint and `t` comes out
/// as exactly `+0.0` for both `Q` and `-Q`: `roots::stable_roots` then takes
/// `q = -(t + copysign(√D, t)) = -√D` for both, so the smaller root of `Q` is
/// `q/s` while that of `-Q` is `u/q`, and the two differ in the last bit
/// (here 7.664955967388052 vs 7.664955967388053), leaving an ulp of overlap
/// or gap between a solid and its complement. Taking the sign from `s` when
/// `t == 0` would make the step odd again.
#[test]
fn complement_meets_exactly_when_t_is_zero() {
    let (a, w) = (
        [
            [0.8021659338119439, 0.7829007191018057, 0.727166007171698],
            [0.7829007191018057, 0.21641349956267436, -0.5535293478317709],
            [0.727166007171698, -0.5535293478317709, 0.841739149260231],
        ],
        [-0.41041918773894287, -0.38652220656940134, 1.0791615710618627],
    );
    #[rustfmt::skip]
    let q = Matrix4::new(
        a[0][0], a[0][1], a[0][2], w[0],
        a[1][0], a[1][1], a[1][2], w[1],
        a[2][0], a[2][1], a[2][2], w[2],
        w[0], w[1], w[2], 0.0,
    );
    let q = quadric::Quadric::from_matrix(&q).expect("symmetric");
    let ray = Ray::new(
        Point3::new(-0.36798169985051166, -1.7256604776131164, 5.911524351673923),
        Vector3::new(0.5506157588527372, 0.09642466868787597, -0.8291710133449298),
    )
    .expect("a valid ray");
    let (inside, outside) = (q.intervals(&ray, 0), q.complement().intervals(&ray, 1));
    assert_eq!(inside.len(), 1);
    let whole = IntervalSet::from_interval(Bound::free(0.0), Bound::free(INF));
    assert!(inside.union(&outside).expect("fits").same_points(&whole), "{inside:?} ∪ {outside:?}");
    assert!(inside.intersect(&outside).expect("fits").is_empty(), "{inside:?} ∩ {outside:?}");
}

/// A ray close to an asymptotic direction of a one-sheet hyperboloid about
/// 1.6·10³ (and 1.6·10⁶) away: `s = rᵀAr` is nearly 0, so the two roots do not
/// cluster and the kernel does not re-base the ray; `u = f(p)` is then formed
/// at the ray origin from terms of size |p - c|² that cancel, and its rounding
/// moves the near root by `ε·|p - c|²/|f'|`, about 180 units of `ε·λ` at
/// 1.6·10³ and growing with the distance. Re-basing at (or refining from)
/// the computed near root, not only at the midpoint of clustered roots,
/// would keep it at the floor.
#[test]
fn asymptotic_ray_far_away() {
    for scale in [1.0, 1e3] {
        let centre = Vector3::new(-810.0963274500517, -1155.3656515368925, 824.8410024824279) * scale;
        let sheet =
            quadric::Quadric::hyperboloid_one_sheet().transformed(&Transform::translate(centre).expect("finite"));
        let ray = Ray::new(
            Point3::new(0.9678603143235994, 0.0, 0.0),
            Vector3::new(-0.49588608855295685, -0.7072932755817254, 0.5038186275799282),
        )
        .expect("a direction");
        if let Err(e) = exact_sign_near_ends(&Solid::from(sheet), &ray, &[], false) {
            panic!("at scale {scale}: {e}");
        }
    }
}

/// A ray lying in a cone's surface (a generator through the apex): the whole
/// ray is in the closed solid; reversed at a point whose rounding leaves the
/// surface, it may not be. The reversal property must allow for that.
#[test]
fn reversal_of_a_ray_in_the_surface() {
    let cone = Solid::from(
        quadric::Quadric::cone().transformed(&Transform::translate(Vector3::new(-3.0, -3.0, -1.0)).expect("finite")),
    );
    let ray = Ray::new(Point3::new(-3.0, -0.5, 1.5), Vector3::new(0.0, -1.0, -1.0)).expect("a direction");
    assert_eq!(cone.intervals(&ray, 0), IntervalSet::from_interval(Bound::free(0.0), Bound::free(INF)));
    reversal_mirrors(cone, ray, 11.643963013486482, &[]).expect("tolerated: f is 0 up to rounding all along");
}

proptest! {
    /// Far along a cylinder's axis, whether and where the ray crosses it is
    /// decided by its offset across the axis alone, whatever the distance:
    /// for `tube_z` the line's `xy` trace is exact small numbers, so its
    /// distance from the axis and its crossings are computed here directly.
    /// Only the `λ` of a crossing is limited, to `ε` of the distance.
    #[test]
    fn far_along_a_cylinder_axis_the_offset_decides(
        origin in (-3.0f64..3.0, -3.0f64..3.0),
        dir in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        far in 1e3f64..1e17,
    ) {
        let (px, py) = origin;
        let (dx, dy, dz) = dir;
        prop_assume!(dx.abs().max(dy.abs()) > 1e-3);
        let r = Ray::new(Point3::new(px, py, far), Vector3::new(dx, dy, dz)).expect("nonzero");
        let v = r.direction();
        // In `xy`: p + λv, |·|² = 1 ⇔ aλ² + 2bλ + c = 0.
        let (a, b, c) = (v.x * v.x + v.y * v.y, px * v.x + py * v.y, px * px + py * py - 1.0);
        let miss = (px * v.y - py * v.x).powi(2) / a - 1.0; // squared distance from the axis, minus 1
        prop_assume!(miss.abs() > 1e-9);
        let set = quadric::Quadric::tube_z().intervals(&r, 0);
        if miss > 0.0 {
            prop_assert!(set.is_empty(), "{r:?}: {set:?}");
        } else {
            let h = (b * b - a * c).sqrt();
            let (l1, l2) = ((-b - h) / a, (-b + h) / a);
            let tolerance = 16.0 * EPS * far + 1e-9;
            if l2 <= tolerance {
                prop_assert!(set.as_slice().iter().all(|i| i.exit.t <= 2.0 * tolerance), "{r:?}: {set:?}");
            } else {
                prop_assert_eq!(set.len(), 1, "{:?}: {:?}", r, set);
                let i = set.as_slice()[0];
                prop_assert!((i.enter.t - l1.max(0.0)).abs() <= tolerance, "{r:?}: {set:?} vs {l1}");
                prop_assert!((i.exit.t - l2).abs() <= tolerance, "{r:?}: {set:?} vs {l2}");
            }
        }
    }
}

proptest! {
    /// `translated` is `transformed` by the translation: the same solid, to
    /// the sign of a zero coefficient (which `==` does not tell apart), so
    /// the same intervals along any ray.
    #[test]
    fn translated_is_transformed_by_the_translation(
        solid in strategies::solid(),
        v in strategies::point(1e3),
        ray in strategies::ray(10.0),
    ) {
        let m = quadric::Transform::translate(v.coords).expect("a finite translation");
        let (fast, slow) = (solid.translated(&v.coords), solid.transformed(&m));
        prop_assert_eq!(fast, slow);
        prop_assert_eq!(fast.intervals(&ray, 0), slow.intervals(&ray, 0));
    }
}
