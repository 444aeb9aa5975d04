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
