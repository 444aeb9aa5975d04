//! Minimised inputs from the `quadric_intervals` fuzz target (`fuzz/`), one
//! test each: the input that failed and the law it broke.

use nalgebra::{Matrix4, Point3, Vector3};
use quadric::{IntervalSet, Quadric, Ray, Solid, Transform};

fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
    Ray::new(Point3::from(o), Vector3::from(d)).expect("valid ray")
}

/// A solid and its complement cover the ray `[0, ∞)` with nothing left out.
fn check_cover(s: Solid, r: &Ray) {
    let (a, b) = (s.intervals(r, 0), s.complement().intervals(r, 0));
    let union = a.union(&b).expect("within capacity");
    let whole = IntervalSet::everything().clip(0.0, f64::INFINITY);
    assert!(union.same_points(&whole), "{a:?} ∪ {b:?} leaves a gap");
}

/// `t` of the re-based quadratic came out `+0.0` for both `Q` and `-Q`, so
/// `stable_roots` took the sign of `√disc` from `+0.0` in both and computed
/// each root by the other formula for the complement: a one-ulp gap
/// (7.824047192338361 vs …362) in no solid at all.
#[test]
fn complement_shares_roots_when_t_is_zero() {
    let m = Transform::scale_xyz(Vector3::new(2.0, 0.5, 1.0))
        .and_then(|m| Ok(m.then(&Transform::rotate_z_degrees(30.0)?)))
        .and_then(|m| Ok(m.then(&Transform::translate(Vector3::new(1.0, -2.0, 3.0))?)))
        .expect("finite");
    let cone = Solid::from(Quadric::cone().transformed(&m));
    check_cover(cone, &ray([-5.0, 1.0, 0.0], [1.0, 0.0, 0.0]));
}

/// A ray nearly along the cone's surface from 3e120 (inside the documented
/// range): the re-basing point `-t/s` overflowed and both the cone and its
/// complement gave the empty set, though the origin is in the complement.
#[test]
fn complement_covers_when_the_apex_of_the_quadratic_overflows() {
    let m = Transform::rotate_y_degrees(2.981200000000001e120).expect("finite");
    let cone = Solid::from(Quadric::cone().transformed(&m));
    let far = 2.981200000000001e120;
    let r = ray([far, far, far], [far, far, 116.0]);
    check_cover(cone, &r);
    assert!(cone.complement().intervals(&r, 0).contains(0.0), "the origin is outside the cone");
}

/// A gradient with an infinite and a NaN component (`∞ - ∞` far out) gave a
/// NaN normal: `amax` skips NaN, so the "not finite" test passed.
#[test]
fn no_nan_normal_from_an_overflowing_gradient() {
    let c = [
        4.4533304e-317,
        0.0,
        -118.99999999999831,
        -1.0137433199815556e-262,
        -2.9754888241172404e284,
        -0.0,
        0.0,
        2.0,
        -0.015625,
        -0.0,
    ];
    let m = Transform::translate(Vector3::new(-1e150, -1e150, 0.0))
        .and_then(|m| Ok(m.then(&Transform::rotate_x_degrees(-1e150)?).then(&Transform::rotate_x_degrees(-1e150)?)))
        .expect("finite");
    let q = Quadric::from_coefficients(c).expect("finite").transformed(&m);
    let n = q.normal(&Point3::new(-1e150, -1e150, -1e150));
    assert!(n.is_none_or(|n| n.iter().all(|x| x.is_finite())), "{n:?}");
}

/// Two rows equal but for 1e-300 (condition number about 1e316): the
/// residual `L·L⁻¹ - I` has NaN entries (∞ - ∞), `amax` skips them, and
/// `f64::max` ignores a NaN, so the matrix passed the "too close to
/// singular" check with an inverse of 1.7e301.
#[test]
fn nearly_singular_matrix_is_rejected() {
    let big = 9007199254740992.0;
    #[rustfmt::skip]
    let m = Matrix4::new(
        0.0, 4.0, 69.0, big,
        big, big, 1e-300, 76.00000000000108,
        big, big, -0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    );
    assert!(Transform::from_matrix(&m).is_err(), "{:?}", Transform::from_matrix(&m));
}

/// A ray far out along an infinite tube's axis that never comes near the
/// tube (`y - x = 3` all along it): re-basing the ray at the foot of the
/// perpendicular from the tube's centre (1e17 away) rounded away the 3, and
/// the ray seemed to run inside the tube. Caught by the complex fuzz target
/// (the block's box, which is right, culls the tube; the brute force did not).
#[test]
fn far_along_a_tube_axis_the_offset_survives() {
    for (offset, far) in [(3.0, 1e17), (296.0, 1.9018000000000003e78)] {
        let r = ray([0.0, offset, far], [1.0, 1.0, 1.0]);
        let set = Quadric::tube_z().intervals(&r, 0);
        assert!(set.is_empty(), "offset {offset} at {far:e}: {set:?}");
    }
    // Found by `oracle::far_along_a_cylinder_axis_the_offset_decides`: y = -1.245
    // all along. The foot's `|b|` is its axis coordinate, which `A` ignores, so
    // comparing the apex's distance with `|b|` did not see the need to re-base.
    let r = ray([0.0, -1.245108159030882, 2.061082366195932e16], [0.6244329308725833, 0.0, 0.21787478454700887]);
    let set = Quadric::tube_z().intervals(&r, 0);
    assert!(set.is_empty(), "{set:?}");
    // Offset by 0.5 instead, the same line crosses the tube: with x = μ - 5,
    // y = μ - 4.5 and μ = λ/√3, x² + y² = 1 gives μ = (19 ± √7)/4. `λ` is
    // found as `λ₀ + μ` with `|λ₀| ≈ far`, so it is good to `ε·far` only (the
    // rounding floor of the hit point's distance from the centre): far
    // enough that the first solve's discriminant is noise, near enough that
    // the chord (4.6) is far above that floor.
    let (root7, root3) = (7f64.sqrt(), 3f64.sqrt());
    let expected = [root3 * (19.0 - root7) / 4.0, root3 * (19.0 + root7) / 4.0];
    for far in [1e9, 1e12] {
        let set = Quadric::tube_z().intervals(&ray([-5.0, -4.5, far], [1.0, 1.0, 1.0]), 0);
        let got: Vec<[f64; 2]> = set.as_slice().iter().map(|i| [i.enter.t, i.exit.t]).collect();
        let tolerance = 8.0 * f64::EPSILON * far;
        assert_eq!(got.len(), 1, "at {far:e}: {set:?}");
        assert!(
            (got[0][0] - expected[0]).abs() < tolerance && (got[0][1] - expected[1]).abs() < tolerance,
            "at {far:e}: {got:?}"
        );
    }
}

/// The same far along a *rotated* cylinder's axis: there `A` is full, and
/// `u = bᵀ(Ab + 2w) + k` at any base `b` far along the axis is formed from
/// `Ab` rounded at `ε|A||b|`, times `|b|`: an error of `ε|b|²`, even at the
/// apex. Worse, the stored, rounded `A` of the rotated tube is positive
/// *definite* (an ellipsoid reaching ~3.6e8 along the axis). From 10⁹ along
/// the axis (origin offset 0.5, so it starts inside and leaves after √0.75
/// across the axis) the exit came out at 1.8, then 3.6, then (stored
/// model) nowhere. The tube carries its exact axis `L·z` (`Quadric::axis`)
/// and a point far along it is slid back along the axis first, so the
/// answer is the ideal cylinder's, to the rounding of the cross-section.
/// The oracle is that ideal geometry, independent of the kernel.
#[test]
fn far_along_a_rotated_tube_axis_the_exit_is_found() {
    let m = Transform::rotate_x_degrees(30.0).expect("finite");
    let tube = Quadric::tube_z().transformed(&m);
    let (axis, across) = (m.apply_vector(&Vector3::z()), m.apply_vector(&Vector3::y()));
    let dir = Vector3::x() + axis * 0.3;
    assert_eq!(tube.axis().map(|n| (n.normalize() - axis).amax() < 1e-15), Some(true), "{tube:?}");
    let expected = 0.75f64.sqrt() * dir.norm();
    for far in [1e6, 1e9, 1e12, 1e15] {
        // The origin's coordinates are rounded at ulp(far), which moves it
        // across the axis by as much: that is the floor of the exit's error.
        let origin = Point3::from(axis * far + across * 0.5);
        let set = tube.intervals(&Ray::new(origin, dir).expect("valid ray"), 0);
        let exits: Vec<f64> = set.as_slice().iter().map(|i| i.exit.t).collect();
        let tolerance = 16.0 * f64::EPSILON * far;
        assert!(exits.len() == 1, "at {far:e}: {set:?}");
        assert!(far > 1e12 || (exits[0] - expected).abs() < tolerance, "at {far:e}: {set:?} vs exit {expected}");
        assert!(tube.contains_point(&origin), "at {far:e} the origin is inside");
        assert!(!tube.contains_point(&(origin + across)), "at {far:e} 1.5 off the axis is outside");
    }
}
