//! Bad input gives a typed error; finite input never makes a public query
//! panic or return NaN, even at extreme magnitudes.

use nalgebra::{Matrix4, Point3, Vector3, Vector4};
use proptest::prelude::*;
use quadric::strategies;
use quadric::{GeometryError, HalfSpace, IntervalSet, Quadric, Ray, Solid, Transform};

const NON_FINITE: [f64; 3] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

fn non_finite(r: Result<impl std::fmt::Debug, GeometryError>) -> bool {
    matches!(r, Err(GeometryError::NonFinite { .. }))
}

fn singular(r: Result<impl std::fmt::Debug, GeometryError>) -> bool {
    matches!(r, Err(GeometryError::Singular { .. }))
}

#[test]
fn non_finite_coefficients() {
    for bad in NON_FINITE {
        for i in 0..10 {
            let mut c = [1.0; 10];
            c[i] = bad;
            assert!(non_finite(Quadric::from_coefficients(c)), "slot {i} = {bad}");
        }
        for i in 0..4 {
            for j in 0..4 {
                let mut m = Matrix4::identity();
                m[(i, j)] = bad;
                m[(j, i)] = bad;
                assert!(non_finite(Quadric::from_matrix(&m)), "entry ({i},{j}) = {bad}");
            }
            let mut q = Vector4::new(1.0, 1.0, 1.0, 1.0);
            q[i] = bad;
            assert!(non_finite(HalfSpace::from_vector(&q)), "slot {i} = {bad}");
            assert!(non_finite(HalfSpace::new(q.x, q.y, q.z, q.w)));
        }
    }
}

#[test]
fn malformed_solids() {
    // The first entry whose mirror differs is named.
    let mut m = Matrix4::identity();
    m[(1, 3)] = 2.0;
    m[(3, 1)] = 2.0;
    m[(2, 3)] = 0.5;
    assert_eq!(Quadric::from_matrix(&m), Err(GeometryError::NotSymmetric { row: 2, col: 3 }));
    // -0.0 and 0.0 are the same entry.
    m[(3, 2)] = 0.5;
    m[(0, 1)] = -0.0;
    assert!(Quadric::from_matrix(&m).is_ok());
    // A half-space needs a normal.
    assert_eq!(HalfSpace::new(0.0, 0.0, 0.0, 1.0), Err(GeometryError::ZeroNormal));
    assert_eq!(HalfSpace::new(-0.0, 0.0, -0.0, -1.0), Err(GeometryError::ZeroNormal));
    // A tiny normal is still a normal, and its unit normal is exact.
    let tiny = HalfSpace::new(5e-324, 0.0, 0.0, 0.0).expect("non-zero");
    assert_eq!(tiny.normal(), Vector3::x());
}

#[test]
fn bad_rays() {
    let o = Point3::origin();
    for bad in NON_FINITE {
        assert!(non_finite(Ray::new(Point3::new(0.0, bad, 0.0), Vector3::x())));
        assert!(non_finite(Ray::new(o, Vector3::new(1.0, 0.0, bad))));
    }
    assert_eq!(Ray::new(o, Vector3::zeros()), Err(GeometryError::ZeroDirection));
    assert_eq!(Ray::new(o, Vector3::new(-0.0, 0.0, -0.0)), Err(GeometryError::ZeroDirection));
    // Subnormal and huge directions normalise without underflow or overflow.
    let r = Ray::new(o, Vector3::new(5e-324, 0.0, 0.0)).expect("a direction");
    assert_eq!(r.direction(), Vector3::x());
    let r = Ray::new(o, Vector3::new(1e308, -1e308, 0.0)).expect("a direction");
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((r.direction() - Vector3::new(h, -h, 0.0)).amax() <= 2.0 * f64::EPSILON);
    let r = Ray::new(o, Vector3::new(3e-310, 4e-310, 0.0)).expect("a direction");
    assert!((r.direction() - Vector3::new(0.6, 0.8, 0.0)).amax() <= 2.0 * f64::EPSILON);
}

#[test]
fn bad_transforms() {
    for bad in NON_FINITE {
        assert!(non_finite(Transform::translate(Vector3::new(bad, 0.0, 0.0))));
        assert!(non_finite(Transform::scale(bad)));
        assert!(non_finite(Transform::scale_xyz(Vector3::new(1.0, bad, 1.0))));
        assert!(non_finite(Transform::rotate_x_degrees(bad)));
        assert!(non_finite(Transform::rotate_y_degrees(bad)));
        assert!(non_finite(Transform::rotate_z_degrees(bad)));
        let mut m = Matrix4::identity();
        m[(1, 2)] = bad;
        assert!(non_finite(Transform::from_matrix(&m)));
    }
    // Singular scales, including ones whose inverse overflows.
    for s in [0.0, -0.0, 1e-310, 5e-324] {
        assert!(singular(Transform::scale(s)), "scale {s}");
        assert!(singular(Transform::scale_xyz(Vector3::new(1.0, 1.0, s))), "scale {s}");
    }
    // Large and small scales whose inverses are representable are fine.
    assert!(Transform::scale(1e308).is_ok());
    assert!(Transform::scale(1e-300).is_ok());
    // Huge angles are reduced exactly, not rejected (360·2⁴⁰ + 90 is representable).
    let r = Transform::rotate_z_degrees(360.0 * 2f64.powi(40) + 90.0).expect("finite");
    assert_eq!(r.apply_point(&Point3::new(1.0, 0.0, 0.0)), Point3::new(0.0, 1.0, 0.0));

    // General matrices: not affine, singular, nearly singular.
    let mut m = Matrix4::identity();
    m[(3, 0)] = 1.0;
    assert_eq!(Transform::from_matrix(&m), Err(GeometryError::NotAffine));
    let mut m = Matrix4::identity();
    m[(3, 3)] = 2.0;
    assert_eq!(Transform::from_matrix(&m), Err(GeometryError::NotAffine));
    let mut m = Matrix4::identity();
    m[(2, 2)] = 0.0;
    assert!(singular(Transform::from_matrix(&m)));
    #[rustfmt::skip]
    let rank2 = Matrix4::new(
        1.0, 2.0, 3.0, 0.0,
        4.0, 5.0, 6.0, 0.0,
        7.0, 8.0, 9.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    );
    assert!(singular(Transform::from_matrix(&rank2)));
    // Nearly singular: rejected, or accepted only with an inverse that reproduces
    // the identity to 1e-9 (the documented criterion).
    for eps in [1e-15, 1e-12, 1e-9, 1e-6] {
        #[rustfmt::skip]
        let near = Matrix4::new(
            1.0, 2.0, 3.0, 0.0,
            4.0, 5.0, 6.0, 0.0,
            7.0, 8.0, 9.0 + eps, 0.0,
            0.0, 0.0, 0.0, 1.0,
        );
        match Transform::from_matrix(&near) {
            Err(GeometryError::Singular { .. }) => {}
            Ok(t) => assert!((t.linear() * t.linear_inverse() - nalgebra::Matrix3::identity()).amax() <= 1e-9),
            Err(e) => panic!("{e}"),
        }
    }
    // A -0.0 in the last row is still [0, 0, 0, 1].
    let mut m = Matrix4::identity();
    m[(3, 1)] = -0.0;
    m[(0, 3)] = 5.0;
    let t = Transform::from_matrix(&m).expect("affine");
    assert_eq!(t.apply_point(&Point3::origin()), Point3::new(5.0, 0.0, 0.0));
}

#[test]
fn unit_normals() {
    use quadric::normal::unit;
    // A NaN component is caught even though `amax` skips it.
    for bad in NON_FINITE {
        assert_eq!(unit(Vector3::new(bad, 1.0, 0.0)), None);
        assert_eq!(unit(Vector3::new(1.0, 0.0, bad)), None);
    }
    assert_eq!(unit(Vector3::new(0.0, -0.0, 0.0)), None);
    assert_eq!(unit(Vector3::new(0.0, 0.0, -5e-324)), Some(-Vector3::z()));
    assert_eq!(unit(Vector3::new(1e308, 0.0, 0.0)), Some(Vector3::x()));
    let n = unit(Vector3::new(1e308, 1e308, 1e308)).expect("finite");
    assert!((n.norm() - 1.0).abs() <= 2.0 * f64::EPSILON);
    // A cone's apex has no normal; a half-space has one everywhere.
    assert_eq!(Quadric::cone().normal(&Point3::origin()), None);
    let h = HalfSpace::new(0.0, 0.0, -1e-300, 1.0).expect("valid");
    assert_eq!(Solid::from(h).normal(&Point3::new(1e300, 0.0, 0.0)), Some(-Vector3::z()));
}

#[test]
fn reversed_far_beyond_range() {
    let ray = Ray::new(Point3::new(1e300, 0.0, 0.0), Vector3::x()).expect("valid");
    assert!(non_finite(ray.try_reversed_at(f64::INFINITY)));
    assert!(non_finite(ray.try_reversed_at(f64::NAN)));
    assert!(non_finite(ray.try_reversed_at(f64::MAX)));
    let back = ray.try_reversed_at(1e300).expect("finite");
    assert_eq!((back.origin(), back.direction()), (Point3::new(2e300, 0.0, 0.0), -Vector3::x()));
}

#[test]
fn overflowing_compositions() {
    // Each step is fine; the composition is not.
    let big = Transform::scale(1e200).expect("valid");
    let small = Transform::scale(1e-200).expect("valid");
    assert!(non_finite(big.checked_then(&big)));
    assert!(singular(small.checked_then(&small)));
    // A composition that stays representable passes and equals `then`.
    let ok = big.checked_then(&small).expect("1e200 · 1e-200 is fine");
    assert_eq!(ok, big.then(&small));
    assert_eq!(ok.apply_point(&Point3::new(1.0, 2.0, 3.0)), Point3::new(1.0, 2.0, 3.0));
    let far = Transform::translate(Vector3::new(1e308, 0.0, 0.0)).expect("valid");
    assert!(non_finite(far.checked_then(&far)));
    assert!(non_finite(far.checked_then(&Transform::scale(10.0).expect("valid"))));
}

/// A magnitude `±10^e`, `e` uniform in `[lo, hi]`.
fn magnitude(lo: f64, hi: f64) -> impl Strategy<Value = f64> + Clone {
    (lo..=hi, any::<bool>()).prop_map(|(e, neg): (f64, bool)| if neg { -(10f64.powf(e)) } else { 10f64.powf(e) })
}

/// A transform of extreme magnitude: scales of `10^±12` per axis, rotations,
/// and translations up to `10^150`.
fn extreme_transform() -> impl Strategy<Value = Transform> + Clone {
    let factor = magnitude(-12.0, 12.0);
    let step = prop_oneof![
        (magnitude(-10.0, 150.0), magnitude(-10.0, 150.0), magnitude(-10.0, 150.0))
            .prop_filter_map("valid", |(x, y, z)| Transform::translate(Vector3::new(x, y, z)).ok()),
        (factor.clone(), factor.clone(), factor)
            .prop_filter_map("valid", |(x, y, z)| Transform::scale_xyz(Vector3::new(x, y, z)).ok()),
        strategies::elementary_transform(),
    ];
    proptest::collection::vec(step, 1..4)
        .prop_filter_map("representable", |s| s.iter().try_fold(Transform::identity(), |m, x| m.checked_then(x).ok()))
}

fn extreme_solid() -> impl Strategy<Value = Solid> + Clone {
    (strategies::solid(), extreme_transform()).prop_map(|(s, m)| s.transformed(&m))
}

/// A ray from anywhere up to `10^150` in a direction with components of any size.
fn extreme_ray() -> impl Strategy<Value = Ray> + Clone {
    let c = magnitude(-10.0, 150.0);
    // Zero components of either sign are common, all three zero rare (1 in 27).
    let d = prop_oneof![4 => magnitude(-300.0, 300.0), 1 => Just(0.0), 1 => Just(-0.0)];
    (c.clone(), c.clone(), c, d.clone(), d.clone(), d)
        .prop_filter_map("valid", |(x, y, z, a, b, e)| Ray::new(Point3::new(x, y, z), Vector3::new(a, b, e)).ok())
}

fn no_nan_in(set: &IntervalSet) -> bool {
    set.iter().all(|iv| !iv.enter.t.is_nan() && !iv.exit.t.is_nan())
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    /// Interval sets are normalised, within `[0, ∞)`, and free of NaN for any finite input.
    #[test]
    fn intervals_never_nan(solid in extreme_solid(), ray in extreme_ray()) {
        let set = solid.intervals(&ray, 0);
        prop_assert!(no_nan_in(&set) && set.is_normalised(), "{:?}", set);
        prop_assert!(set.iter().all(|iv| iv.enter.t >= 0.0), "{:?}", set);
        if let Solid::HalfSpace(h) = solid {
            let (a, b) = h.interval(&ray, 0);
            prop_assert!(!a.t.is_nan() && !b.t.is_nan());
        }
        prop_assert!(ray.direction().iter().all(|c| c.is_finite()));
        prop_assert!((ray.direction().norm() - 1.0).abs() <= 4.0 * f64::EPSILON);
    }

    /// Unit normals are unit vectors or `None`.
    #[test]
    fn normals_never_nan(solid in extreme_solid(), ray in extreme_ray(), lambda in magnitude(-10.0, 150.0)) {
        let x = ray.at(lambda.abs());
        if let Some(n) = solid.normal(&x) {
            prop_assert!(n.iter().all(|c| c.is_finite()) && (n.norm() - 1.0).abs() <= 4.0 * f64::EPSILON, "{:?} at {:?}", n, x);
        }
        // Points of the ray a query is asked about are always finite here.
        prop_assert!(x.iter().all(|c| c.is_finite()));
    }

    /// Transforms apply to finite points without NaN; their inverse too.
    #[test]
    fn transforms_never_nan(m in extreme_transform(), p in (magnitude(-10.0, 150.0), magnitude(-10.0, 150.0), magnitude(-10.0, 150.0))) {
        let p = Point3::new(p.0, p.1, p.2);
        prop_assert!(m.is_finite());
        for q in [m.apply_point(&p), m.inverse().apply_point(&p)] {
            prop_assert!(q.iter().all(|c| !c.is_nan()), "{:?}", q);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    /// `value` and `contains_point` never give NaN or panic (see `value_of_a_far_cone`).
    #[test]
    fn values_never_nan(solid in extreme_solid(), x in (magnitude(-10.0, 150.0), magnitude(-10.0, 150.0), magnitude(-10.0, 150.0))) {
        let x = Point3::new(x.0, x.1, x.2);
        prop_assert!(!solid.value(&x).is_nan(), "{:?} at {:?}", solid, x);
        let _ = solid.contains_point(&x);
    }
}

/// A cone scaled by 1e-12 (so `A = diag(1e24, -1e24, 1e24)`) queried at
/// `(1e150, 1e150, 0)`: `(x-c)ᵀA(x-c)` has the terms `+1e324` and `-1e324`,
/// which overflow to `+∞` and `-∞`, and `value` returns NaN; the world
/// coefficients are finite. The same overflow makes `intervals` return the
/// empty set for a ray from that point along x, though the point is inside
/// (`|x - 1e138| < |y|`). Normalising the stored coefficients (dividing
/// `A`, `w`, `k` by a power of two near their largest magnitude, which leaves
/// the solid unchanged) would keep these products in range.
#[test]
fn value_of_a_far_cone() {
    let cone = Quadric::cone().transformed(&Transform::scale(1e-12).expect("valid"));
    let x = Point3::new(1e150, 1e150, 0.0);
    assert!(cone.coefficients().iter().all(|c| c.is_finite()));
    assert!(!cone.value(&x).is_nan(), "value is NaN");
    let moved = Quadric::cone()
        .transformed(&Transform::translate(Vector3::new(1e150, 0.0, 0.0)).expect("valid"))
        .transformed(&Transform::scale(1e-12).expect("valid"));
    let ray = Ray::new(x, Vector3::x()).expect("valid");
    assert!(moved.contains_point(&x));
    assert!(!moved.intervals(&ray, 0).is_empty(), "the ray starts inside");
}

/// Constant coefficient sets: all zero and a positive constant alone are
/// refused by both constructors; a negative constant (all of space) is a
/// solid.
#[test]
fn constant_quadrics_are_refused_unless_all_of_space() {
    let degenerate = |r: Result<Quadric, GeometryError>| matches!(r, Err(GeometryError::Degenerate { .. }));
    let cases: [([f64; 10], bool); 6] = [
        ([0.0; 10], true),
        ([-0.0; 10], true),
        ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0], true),
        ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5e-324], true),
        ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], false),
        ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5e-324, 0.0, 0.0, 1.0], false),
    ];
    for (c, refused) in cases {
        assert_eq!(degenerate(Quadric::from_coefficients(c)), refused, "{c:?}");
        let [a, b, cc, d, e, f, g, h, j, k] = c;
        let m = Matrix4::new(a, d, e, g, d, b, f, h, e, f, cc, j, g, h, j, k);
        assert_eq!(degenerate(Quadric::from_matrix(&m)), refused, "{m:?}");
    }
    assert_eq!(
        Quadric::from_coefficients([0.0; 10]).expect_err("all zero").to_string(),
        "the quadric is degenerate: all ten coefficients are zero (0 <= 0 holds everywhere)"
    );
    // The half-space's constant alone is the zero normal, refused as before.
    assert_eq!(HalfSpace::new(0.0, 0.0, 0.0, 1.0), Err(GeometryError::ZeroNormal));
    assert_eq!(HalfSpace::new(0.0, 0.0, 0.0, 0.0), Err(GeometryError::ZeroNormal));
}

fn scale(s: f64) -> Transform {
    Transform::scale(s).expect("valid")
}

fn scale_xyz(x: f64, y: f64, z: f64) -> Transform {
    Transform::scale_xyz(Vector3::new(x, y, z)).expect("valid")
}

fn rotate_x(deg: f64) -> Transform {
    Transform::rotate_x_degrees(deg).expect("valid")
}

fn rotate_z(deg: f64) -> Transform {
    Transform::rotate_z_degrees(deg).expect("valid")
}

/// `solid` placed by `steps` in order (composed with `then`, as a scene
/// composes them): `Ok(())` or the error `try_transformed` gives; when it
/// is accepted, it is exactly the unchecked `transformed`.
fn check_placement(solid: impl Into<Solid>, steps: &[Transform], expected: Result<(), GeometryError>) {
    let solid = solid.into();
    let m = steps.iter().fold(Transform::identity(), |m, s| m.then(s));
    let got = solid.try_transformed(&m);
    assert_eq!(got.as_ref().map(|_| ()).map_err(Clone::clone), expected, "{solid:?} by {steps:?}");
    if let Ok(placed) = got {
        assert_eq!(placed, solid.transformed(&m));
    }
}

fn underflow(part: &'static str) -> Result<(), GeometryError> {
    Err(GeometryError::Underflow { part })
}

const OVERFLOW: Result<(), GeometryError> = Err(GeometryError::NonFinite { what: "a coefficient of the placed solid" });

#[test]
fn placements_that_underflow_or_overflow_are_errors() {
    let plane = HalfSpace::new(1.0, 0.0, 0.0, -1.0).expect("valid");
    let faint_plane = HalfSpace::new(1e-200, 0.0, 0.0, -1.0).expect("valid");
    let sphere = Quadric::sphere();
    // A unit ball scaled far: `A = 1e-340·I` is zero, all of space.
    check_placement(sphere, &[scale(1e170)], underflow("quadratic part"));
    // `1e-320` is subnormal: eleven bits left of the radius.
    check_placement(sphere, &[scale(1e160)], underflow("quadratic part"));
    check_placement(sphere, &[scale(1e170), rotate_x(30.0)], underflow("quadratic part"));
    check_placement(sphere, &[scale(1e85), scale(1e85)], underflow("quadratic part"));
    // Tiny scales overflow `A` (`1e340`; `1e308` too, doubled when it is
    // symmetrised). Just short of that, the normalisation pushes a `k`
    // below 1 (here `-0.75` beside `A = 1.5`) into the subnormals.
    check_placement(sphere, &[scale(1e-170)], OVERFLOW);
    check_placement(sphere, &[scale(1e-160)], OVERFLOW);
    check_placement(sphere, &[scale(1e-154)], OVERFLOW);
    let half = Quadric::from_coefficients([1.5, 1.5, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.75]).expect("a ball");
    check_placement(half, &[scale(2f64.powi(-511))], underflow("constant"));
    check_placement(half, &[scale(2f64.powi(-510))], Ok(()));
    // One axis: the ball becomes a tube.
    check_placement(sphere, &[scale_xyz(1e170, 1.0, 1.0)], underflow("quadratic coefficient along x"));
    check_placement(sphere, &[scale_xyz(1.0, 1.0, 1e170)], underflow("quadratic coefficient along z"));
    check_placement(sphere, &[scale_xyz(1.0, 1e170, 1.0), rotate_z(90.0)], underflow("quadratic coefficient along x"));
    check_placement(Quadric::tube_y(), &[scale_xyz(1e170, 1.0, 1.0)], underflow("quadratic coefficient along x"));
    check_placement(Quadric::cone(), &[scale(1e170)], underflow("quadratic part"));
    check_placement(Quadric::cone(), &[scale_xyz(1.0, 1e170, 1.0)], underflow("quadratic coefficient along y"));
    // A paraboloid squeezed across its axis: `A = 2^1022`, `w` normalised to a subnormal.
    check_placement(
        Quadric::paraboloid(),
        &[scale_xyz(2f64.powi(-511), 1.0, 2f64.powi(-511))],
        underflow("linear coefficient along y"),
    );
    check_placement(faint_plane, &[scale(1e170)], underflow("half-space normal"));
    check_placement(plane, &[scale(1e200), scale(1e200)], OVERFLOW);
}

#[test]
fn placements_near_the_limits_are_accepted() {
    let plane = HalfSpace::new(1.0, 0.0, 0.0, -1.0).expect("valid");
    let sphere = Quadric::sphere();
    for s in [1e100, 1e-100, 1e150, 1e-150, 1e153, -1e153] {
        check_placement(sphere, &[scale(s)], Ok(()));
        check_placement(sphere, &[scale(s), rotate_x(30.0), rotate_z(-70.0)], Ok(()));
        check_placement(Quadric::cone(), &[rotate_x(1e-120), scale(s)], Ok(()));
        check_placement(plane, &[scale(s)], Ok(()));
    }
    // Scaling a tube along its own axis leaves its exact zero alone.
    check_placement(Quadric::tube_y(), &[scale_xyz(1.0, 1e170, 1.0)], Ok(()));
    check_placement(Quadric::tube_y(), &[scale_xyz(1.0, 1e300, 1.0)], Ok(()));
    // A plane's normal underflowing in one component only tilts it by nothing.
    check_placement(plane, &[rotate_z(1e-200), scale_xyz(1.0, 1e170, 1.0)], Ok(()));
    // The curvature `1e-340` is lost in entries of `0.5` by rounding, not by
    // underflow: the same solid as `[1e20, 1, 1]` rotated (a tube).
    check_placement(sphere, &[scale_xyz(1e170, 1.0, 1.0), rotate_z(45.0)], Ok(()));
    // Far and back again.
    check_placement(sphere, &[scale(1e200), scale(1e-199)], Ok(()));
}

/// The near-limit placements are the right solids: inside and outside
/// points at ±1 % of the radius, and a ray through the centre enters and
/// leaves at the radius.
#[test]
fn near_limit_scales_give_the_right_solid() {
    for r in [1e100, 1e-100, 1e150, 1e-150] {
        for turn in [Transform::identity(), rotate_x(30.0).then(&rotate_z(-70.0))] {
            let ball = Quadric::sphere().try_transformed(&scale(r).then(&turn)).expect("in range");
            for d in [Vector3::x(), Vector3::y(), Vector3::new(1.0, 2.0, -2.0) / 3.0] {
                assert!(ball.contains_point(&Point3::from(d * 0.99 * r)), "{r} {d:?}");
                assert!(!ball.contains_point(&Point3::from(d * 1.01 * r)), "{r} {d:?}");
                let ray = Ray::new(Point3::from(-d * 3.0 * r), d).expect("valid");
                let set = ball.intervals(&ray, 0);
                assert_eq!(set.len(), 1, "{r} {d:?}");
                let iv = set.as_slice()[0];
                for (t, want) in [(iv.enter.t, 2.0 * r), (iv.exit.t, 4.0 * r)] {
                    assert!((t - want).abs() <= 1e-12 * r, "{r} {d:?}: {t} vs {want}");
                }
            }
        }
        let plane = HalfSpace::new(1.0, 0.0, 0.0, -1.0).expect("valid").try_transformed(&scale(r)).expect("in range");
        assert!(plane.contains_point(&Point3::new(0.99 * r, 0.0, 0.0)));
        assert!(!plane.contains_point(&Point3::new(1.01 * r, 0.0, 0.0)));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    /// No false positives: moderate placements (random steps, up to four,
    /// scales 0.25 … 4, and a scale of up to `10^±100`) of any solid are
    /// accepted, and give exactly the unchecked placement.
    #[test]
    fn moderate_placements_never_underflow(
        solid in strategies::solid(),
        m in strategies::transform(),
        far in magnitude(-100.0, 100.0),
    ) {
        for m in [m, m.then(&scale(far)), scale(far).then(&m)] {
            let placed = solid.try_transformed(&m);
            prop_assert_eq!(placed, Ok(solid.transformed(&m)), "{:?} by {:?}", solid, m);
        }
    }
}
