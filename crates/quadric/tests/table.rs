//! Every row of the case table of docs/model.md §2.2, written as data: `check(solid, ray, expected)`.
//!
//! Expected sets are derived by hand from `f(p + λr) = sλ² + 2tλ + u` (the
//! arithmetic is in a comment where it is not obvious) and compared with a
//! tolerance of a few ulps. Regularisation: a tangent ray touches the surface
//! in a single point, which is not part of any set.

use nalgebra::{Point3, Vector3};
use quadric::{Bound, HalfSpace, IntervalSet, Quadric, Ray, Solid, Transform, NO_SOLID};

const INF: f64 = f64::INFINITY;
/// The solid index every check passes to `intervals`, so tags can be checked.
const TAG: u32 = 7;
const X: [f64; 3] = [1.0, 0.0, 0.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];
const Z: [f64; 3] = [0.0, 0.0, 1.0];
const NEG_X: [f64; 3] = [-1.0, 0.0, 0.0];
const NEG_Y: [f64; 3] = [0.0, -1.0, 0.0];

fn ray(p: [f64; 3], d: [f64; 3]) -> Ray {
    Ray::new(Point3::from(p), Vector3::from(d)).expect("a valid test ray")
}

fn close(got: f64, want: f64, ulps: f64) -> bool {
    if want.is_infinite() || got.is_infinite() {
        return got == want;
    }
    (got - want).abs() <= ulps * f64::EPSILON * want.abs().max(1.0)
}

fn sets_close(got: &IntervalSet, want: &[(f64, f64)], ulps: f64) -> bool {
    got.len() == want.len()
        && got.iter().zip(want).all(|(iv, &(a, b))| close(iv.enter.t, a, ulps) && close(iv.exit.t, b, ulps))
}

/// Checks the set of `λ >= 0` inside `solid` along `ray` against `expected`
/// (within `ulps`), that the set is normalised, and the tagging rule: an
/// infinite end carries no solid, a finite end `> 0` carries [`TAG`].
#[track_caller]
fn check_ulps(solid: impl Into<Solid>, ray: Ray, expected: &[(f64, f64)], ulps: f64) {
    let solid = solid.into();
    let got = solid.intervals(&ray, TAG);
    assert!(got.is_normalised(), "not normalised: {got:?}");
    assert!(sets_close(&got, expected, ulps), "{solid:?} along {ray:?}:\n got {got:?}\nwant {expected:?}");
    for b in got.iter().flat_map(|iv| [iv.enter, iv.exit]) {
        if b.t.is_infinite() {
            assert_eq!(b.solid, NO_SOLID, "an infinite end carries a solid: {b:?}");
        } else if b.t > 0.0 {
            assert_eq!(b.solid, TAG, "a surface end lost its solid: {b:?}");
        } else {
            assert!(b.t == 0.0 && b.t.is_sign_positive(), "end at {b:?}");
        }
    }
}

#[track_caller]
fn check(solid: impl Into<Solid>, ray: Ray, expected: &[(f64, f64)]) {
    check_ulps(solid, ray, expected, 4.0);
}

/// The solids tagged at each end (`None` = a free end: infinite or the start
/// of a ray that begins inside).
#[track_caller]
fn check_tags(set: IntervalSet, expected: &[(Option<u32>, Option<u32>)]) {
    let got: Vec<_> = set.iter().map(|iv| (iv.enter.solid(), iv.exit.solid())).collect();
    assert_eq!(got, expected, "tags of {set:?}");
}

fn translate(x: f64, y: f64, z: f64) -> Transform {
    Transform::translate(Vector3::new(x, y, z)).expect("finite")
}

fn coefficients(c: [f64; 10]) -> Quadric {
    Quadric::from_coefficients(c).expect("finite coefficients")
}

fn half(a: f64, b: f64, c: f64, d: f64) -> HalfSpace {
    HalfSpace::new(a, b, c, d).expect("a valid half-space")
}

#[test]
fn s_positive() {
    let ball = Quadric::sphere();
    // s > 0, D < 0: the line y = 2 misses the ball.
    check(ball, ray([-5.0, 2.0, 0.0], X), &[]);
    // s > 0, D >= 0: through the centre, |x| <= 1 at λ = 5 ∓ 1.
    check(ball, ray([-5.0, 0.0, 0.0], X), &[(4.0, 6.0)]);
    // Off-centre chord at y = 0.6: x² <= 1 - 0.36 = 0.64, x = ±0.8.
    check(ball, ray([-5.0, 0.6, 0.0], X), &[(4.2, 5.8)]);
    // Diagonal through the centre, which it passes at λ = 5√2.
    let c = 5.0 * std::f64::consts::SQRT_2;
    check(ball, ray([-5.0, -5.0, 0.0], [1.0, 1.0, 0.0]), &[(c - 1.0, c + 1.0)]);
    // Origin inside (one root behind, one ahead): roots -1 and 1.
    check(ball, ray([0.0, 0.0, 0.0], X), &[(0.0, 1.0)]);
    check(ball, ray([0.5, 0.0, 0.0], NEG_X), &[(0.0, 1.5)]);
    // Both roots behind the origin (-6 and -4).
    check(ball, ray([5.0, 0.0, 0.0], X), &[]);
    // Tangent: t = -5, u = 25, D = 25 - 25 = 0; a single touching point is empty.
    check(ball, ray([-5.0, 1.0, 0.0], X), &[]);
    check(ball, ray([0.0, 1.0, -3.0], Z), &[]);
    // Origin on the surface, going in (u = 0): roots 0 and 2.
    check(ball, ray([-1.0, 0.0, 0.0], X), &[(0.0, 2.0)]);
    // Origin on the surface, going out: roots -2 and 0, nothing ahead.
    check(ball, ray([1.0, 0.0, 0.0], X), &[]);
}

#[test]
fn t_zero() {
    // The ray starts at the midpoint of its roots: t = rᵀ(A p + w) = 0.
    // s > 0: roots ±1, clipped to [0, 1].
    check(Quadric::sphere(), ray([0.0, 0.0, 0.0], Y), &[(0.0, 1.0)]);
    // s > 0, D < 0 at t = 0: y = 3 misses, u = 8.
    check(Quadric::sphere(), ray([0.0, 3.0, 0.0], X), &[]);
    // s < 0, D < 0: one-sheet hyperboloid along its axis, f = -y² - 1 < 0.
    check(Quadric::hyperboloid_one_sheet(), ray([0.0, 0.0, 0.0], Y), &[(0.0, INF)]);
    // s < 0, D > 0: the cone from (2, 0, 0) along y, f = 4 - λ² <= 0 for λ >= 2.
    check(Quadric::cone(), ray([2.0, 0.0, 0.0], Y), &[(2.0, INF)]);
}

#[test]
fn s_negative() {
    let outside = Quadric::sphere().complement();
    // s < 0, D < 0: the line y = 2 stays outside the ball: everything.
    check(outside, ray([-5.0, 2.0, 0.0], X), &[(0.0, INF)]);
    // s < 0, D >= 0: two pieces, (-∞, 4] ∪ [6, ∞) clipped to [0, ∞).
    check(outside, ray([-5.0, 0.0, 0.0], X), &[(0.0, 4.0), (6.0, INF)]);
    // Both roots behind: (-∞, -6] ∪ [-4, ∞) → [0, ∞).
    check(outside, ray([5.0, 0.0, 0.0], X), &[(0.0, INF)]);
    // Tangent from outside: the two pieces touch at λ = 5 and merge.
    check(outside, ray([-5.0, 1.0, 0.0], X), &[(0.0, INF)]);
    // Origin inside the ball, looking out: the exit of the ball at λ = 1.
    check(outside, ray([0.0, 0.0, 0.0], X), &[(1.0, INF)]);

    // The solid: x² - y² + z² <= 0.
    let cone = Quadric::cone();
    // Through both nappes at x = 1: 1 - y² <= 0, |y| >= 1, y = λ - 5.
    check(cone, ray([1.0, -5.0, 0.0], Y), &[(0.0, 4.0), (6.0, INF)]);
    // Along the axis: f = -y², D = t² - su = 25 - 25 = 0; the pieces touch at the apex.
    check(cone, ray([0.0, -5.0, 0.0], Y), &[(0.0, INF)]);
    // Across one nappe at y = 2 (s = 1 > 0): x² <= 4.
    check(cone, ray([-5.0, 2.0, 0.0], X), &[(3.0, 7.0)]);
    // Across at y = 0: x² <= 0 only at the apex, a touching point.
    check(cone, ray([-5.0, 0.0, 0.0], X), &[]);
    // Along a generator (x = y, z = 0) through the apex: f ≡ 0, the ray lies in the surface (u <= 0).
    check(cone, ray([-2.0, -2.0, 0.0], [1.0, 1.0, 0.0]), &[(0.0, INF)]);

    // The solid: x² - y² + z² - 1 <= 0.
    let sheet = Quadric::hyperboloid_one_sheet();
    // Along y at x = 2: 3 - y² <= 0, |y| >= √3.
    let r3 = 3f64.sqrt();
    check(sheet, ray([2.0, -5.0, 0.0], Y), &[(0.0, 5.0 - r3), (5.0 + r3, INF)]);
    // Across the waist: x² <= 1.
    check(sheet, ray([-5.0, 0.0, 0.0], X), &[(4.0, 6.0)]);
    // Across at y = 1: x² <= 2.
    let r2 = std::f64::consts::SQRT_2;
    check(sheet, ray([-5.0, 1.0, 0.0], X), &[(5.0 - r2, 5.0 + r2)]);
}

#[test]
fn s_zero() {
    // The solid: x² + z² - y <= 0.
    let bowl = Quadric::paraboloid();
    // s = 0, t != 0 along the axis: f = -y, y = λ - 5 >= 0.
    check(bowl, ray([0.0, -5.0, 0.0], Y), &[(5.0, INF)]);
    // The other way: y = 5 - λ >= 0.
    check(bowl, ray([0.0, 5.0, 0.0], NEG_Y), &[(0.0, 5.0)]);
    // Off the axis at x = 1: 1 - y <= 0, y >= 1.
    check(bowl, ray([1.0, -5.0, 0.0], Y), &[(6.0, INF)]);
    // Going away from the bowl, outside: y = -5 - λ < 0, so f = -y > 0 all along.
    check(bowl, ray([0.0, -5.0, 0.0], NEG_Y), &[]);
    // Across at y = 4: x² <= 4.
    check(bowl, ray([-5.0, 4.0, 0.0], X), &[(3.0, 7.0)]);

    // The solid: x² + z² - 1 <= 0.
    let tube = Quadric::tube_y();
    // s = 0, t = 0, u <= 0: along the axis inside: everything.
    check(tube, ray([0.0, 0.0, 0.0], Y), &[(0.0, INF)]);
    check(tube, ray([0.5, 3.0, -0.5], NEG_Y), &[(0.0, INF)]);
    // s = 0, t = 0, u > 0: parallel outside: empty.
    check(tube, ray([2.0, 0.0, 0.0], Y), &[]);
    // s = 0, t = 0, u = 0: in the surface (u <= 0): everything.
    check(tube, ray([1.0, 0.0, 0.0], Y), &[(0.0, INF)]);
    // Across: [4, 6].
    check(tube, ray([-5.0, 100.0, 0.0], X), &[(4.0, 6.0)]);
}

#[test]
fn degenerate_quadrics() {
    // A plane written as a quadric (s = 0, t != 0): 2·0.5·x - 1 = x - 1 <= 0.
    let plane = coefficients([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -1.0]);
    check(plane, ray([-5.0, 0.0, 0.0], X), &[(0.0, 6.0)]);
    check(plane, ray([5.0, 0.0, 0.0], NEG_X), &[(4.0, INF)]);
    check(plane, ray([5.0, 0.0, 0.0], Y), &[]);
    // A slab as a pair of planes: x² - 1 <= 0.
    let slab = coefficients([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
    check(slab, ray([-5.0, 0.0, 0.0], X), &[(4.0, 6.0)]);
    check(slab, ray([0.0, -5.0, 3.0], Y), &[(0.0, INF)]);
    // A double plane x² <= 0: crossing it touches one point (empty); lying in it is everything.
    let double = coefficients([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    check(double, ray([-5.0, 0.0, 0.0], X), &[]);
    check(double, ray([0.0, -5.0, 0.0], Y), &[(0.0, INF)]);
    // Two crossing planes xy <= 0 (d = 1/2): at y = 1, x <= 0, x = λ - 5.
    let cross = coefficients([0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    check(cross, ray([-5.0, 1.0, 0.0], X), &[(0.0, 5.0)]);
    // Along (1, 1)/√2 from (-3, 1): xy = (μ - 3)(μ + 1) <= 0 for μ in [-1, 3], μ = λ/√2.
    let r2 = std::f64::consts::SQRT_2;
    check(cross, ray([-3.0, 1.0, 0.0], [1.0, 1.0, 0.0]), &[(0.0, 3.0 * r2)]);
    // Constant quadrics (s = t = 0): k <= 0 everywhere or nowhere. All zero
    // and a positive constant are refused (tests/bad_input.rs); the empty
    // set is still the complement of everything.
    let mut c = [0.0; 10];
    c[9] = -1.0;
    check(coefficients(c), ray([1.0, 2.0, 3.0], X), &[(0.0, INF)]);
    check(coefficients(c).complement(), ray([1.0, 2.0, 3.0], X), &[]);
}

#[test]
fn elementary_solids() {
    let r3 = 3f64.sqrt();
    check(Quadric::sphere(), ray([0.0, 0.0, -5.0], Z), &[(4.0, 6.0)]);
    check(Quadric::tube_x(), ray([0.0, -5.0, 0.0], Y), &[(4.0, 6.0)]);
    check(Quadric::tube_x(), ray([-5.0, 0.0, 0.5], X), &[(0.0, INF)]);
    check(Quadric::tube_y(), ray([0.0, 0.0, -5.0], Z), &[(4.0, 6.0)]);
    check(Quadric::tube_z(), ray([-5.0, 0.0, 0.0], X), &[(4.0, 6.0)]);
    check(Quadric::tube_z(), ray([0.0, 0.0, -5.0], Z), &[(0.0, INF)]);
    check(Quadric::tube_z(), ray([3.0, 0.0, -5.0], Z), &[]);
    check(Quadric::cone(), ray([0.0, 3.0, -5.0], Z), &[(2.0, 8.0)]);
    check(Quadric::paraboloid(), ray([0.0, 1.0, -5.0], Z), &[(4.0, 6.0)]);
    check(Quadric::hyperboloid_one_sheet(), ray([0.0, 0.0, -5.0], Z), &[(4.0, 6.0)]);
    // Two sheets, x² - y² + z² + 1 <= 0: along the axis 1 - y² <= 0.
    let two = Quadric::hyperboloid_two_sheets();
    check(two, ray([0.0, -5.0, 0.0], Y), &[(0.0, 4.0), (6.0, INF)]);
    // Across at y = 2: x² - 3 <= 0; at y = 0: x² + 1 > 0.
    check(two, ray([-5.0, 2.0, 0.0], X), &[(5.0 - r3, 5.0 + r3)]);
    check(two, ray([-5.0, 0.0, 0.0], X), &[]);
}

#[test]
fn complements() {
    // The other side of each surface, with the same ends.
    check(Quadric::tube_y().complement(), ray([-5.0, 0.0, 0.0], X), &[(0.0, 4.0), (6.0, INF)]);
    check(Quadric::tube_y().complement(), ray([0.0, 0.0, 0.0], Y), &[]);
    check(Quadric::cone().complement(), ray([1.0, -5.0, 0.0], Y), &[(4.0, 6.0)]);
    check(Quadric::paraboloid().complement(), ray([0.0, -5.0, 0.0], Y), &[(0.0, 5.0)]);
    check(Quadric::hyperboloid_one_sheet().complement(), ray([0.0, 0.0, 0.0], Y), &[]);
    check(half(0.0, 1.0, 0.0, -1.0).complement(), ray([0.0, 0.0, 0.0], Y), &[(1.0, INF)]);
    // Complementing twice is exact.
    let q = Quadric::sphere().transformed(&translate(0.25, -1.5, 3.0));
    assert_eq!(q.complement().complement(), q);
    let h = half(1.0, -2.0, 3.0, 0.5);
    assert_eq!(h.complement().complement(), h);
}

#[test]
fn half_spaces() {
    // The solid: y <= 1.
    let below = half(0.0, 1.0, 0.0, -1.0);
    // Parallel inside / outside / in the plane (t = 0: u <= 0 decides).
    check(below, ray([0.0, 0.0, 0.0], X), &[(0.0, INF)]);
    check(below, ray([0.0, 2.0, 0.0], X), &[]);
    check(below, ray([0.0, 1.0, 0.0], Z), &[(0.0, INF)]);
    // Facing out of it from inside: leave at the plane.
    check(below, ray([0.0, 0.0, 0.0], Y), &[(0.0, 1.0)]);
    // Facing into it from outside: enter at the plane.
    check(below, ray([0.0, 5.0, 0.0], NEG_Y), &[(4.0, INF)]);
    // Outside facing away / inside facing further in.
    check(below, ray([0.0, 5.0, 0.0], Y), &[]);
    check(below, ray([0.0, 0.0, 0.0], NEG_Y), &[(0.0, INF)]);
    // Origin on the plane, facing out (a touching point) / facing in.
    check(below, ray([0.0, 1.0, 0.0], Y), &[]);
    check(below, ray([0.0, 1.0, 0.0], NEG_Y), &[(0.0, INF)]);
    // Oblique: x + y <= 0 from (1, 1) along -(1, 1)/√2: u = 2, t = -√2, λ = √2.
    let r2 = std::f64::consts::SQRT_2;
    check(half(1.0, 1.0, 0.0, 0.0), ray([1.0, 1.0, 0.0], [-1.0, -1.0, 0.0]), &[(r2, INF)]);
    // An unnormalised normal: 2y - 2 <= 0 is the same half-space.
    check(half(0.0, 2.0, 0.0, -2.0), ray([0.0, 5.0, 0.0], NEG_Y), &[(4.0, INF)]);
    // The fast path agrees with the set.
    let (enter, exit) = below.interval(&ray([0.0, 5.0, 0.0], NEG_Y), TAG);
    assert_eq!((enter, exit), (Bound::new(4.0, TAG), Bound::free(INF)));
    let (enter, exit) = below.interval(&ray([0.0, 5.0, 0.0], Y), TAG);
    assert!(enter.t >= exit.t, "empty: {enter:?} {exit:?}");
}

#[test]
fn transformed_solids() {
    // Ellipsoid x²/4 + y² + z² <= 1 (the ball scaled by (2, 1, 1)).
    let egg = Quadric::sphere().transformed(&Transform::scale_xyz(Vector3::new(2.0, 1.0, 1.0)).expect("valid"));
    check(egg, ray([-5.0, 0.0, 0.0], X), &[(3.0, 7.0)]);
    check(egg, ray([0.0, -5.0, 0.0], Y), &[(4.0, 6.0)]);
    // At x = 1: y² <= 3/4.
    let h = 0.75f64.sqrt();
    check(egg, ray([1.0, -5.0, 0.0], Y), &[(5.0 - h, 5.0 + h)]);
    // The same ellipsoid from raw coefficients.
    check(coefficients([0.25, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]), ray([-5.0, 0.0, 0.0], X), &[(3.0, 7.0)]);
    // A uniform scale by 3: radius 3.
    let big = Quadric::sphere().transformed(&Transform::scale(3.0).expect("valid"));
    check(big, ray([-5.0, 0.0, 0.0], X), &[(2.0, 8.0)]);

    // Tube along y turned 90° about z: a tube along x.
    let turned = Quadric::tube_y().transformed(&Transform::rotate_z_degrees(90.0).expect("valid"));
    check(turned, ray([0.0, -5.0, 0.0], Y), &[(4.0, 6.0)]);
    check(turned, ray([-5.0, 0.0, 0.0], X), &[(0.0, INF)]);
    // Turned 45°: the axis is (-1, 1, 0)/√2; a point (x, 0, 0) is |x|/√2 from it,
    // inside for |x| <= √2. sin and cos of 45° are rounded: allow a few more ulps.
    let r2 = std::f64::consts::SQRT_2;
    let diagonal = Quadric::tube_y().transformed(&Transform::rotate_z_degrees(45.0).expect("valid"));
    check_ulps(diagonal, ray([-5.0, 0.0, 0.0], X), &[(5.0 - r2, 5.0 + r2)], 16.0);
    // Rotations about x and y: the y tube turned 90° about x lies along z.
    let along_z = Quadric::tube_y().transformed(&Transform::rotate_x_degrees(90.0).expect("valid"));
    check(along_z, ray([0.0, 0.0, -5.0], Z), &[(0.0, INF)]);
    check(along_z, ray([-5.0, 0.0, 0.0], X), &[(4.0, 6.0)]);
    let along_x = Quadric::tube_z().transformed(&Transform::rotate_y_degrees(-90.0).expect("valid"));
    check(along_x, ray([-5.0, 0.0, 0.0], X), &[(0.0, INF)]);

    // The cone with its apex moved to (3, 0, 0): (x-3)² - y² + z² <= 0.
    let cone = Quadric::cone().transformed(&translate(3.0, 0.0, 0.0));
    // At y = 2: |x - 3| <= 2, x in [1, 5].
    check(cone, ray([-5.0, 2.0, 0.0], X), &[(6.0, 10.0)]);
    // Along y at x = 4: 1 - y² <= 0.
    check(cone, ray([4.0, -5.0, 0.0], Y), &[(0.0, 4.0), (6.0, INF)]);

    // Composition order: scale by 2 then translate by 10 is a ball of radius 2 at x = 10.
    let m = Transform::scale(2.0).expect("valid").then(&translate(10.0, 0.0, 0.0));
    check(Quadric::sphere().transformed(&m), ray([0.0, 0.0, 0.0], X), &[(8.0, 12.0)]);
    // … while translating first moves the centre to 20.
    let m = translate(10.0, 0.0, 0.0).then(&Transform::scale(2.0).expect("valid"));
    check(Quadric::sphere().transformed(&m), ray([0.0, 0.0, 0.0], X), &[(18.0, 22.0)]);

    // A general (sheared) matrix: (x, y, z) ↦ (x + y, y, z). At y = 0.5 the ball
    // has x² <= 0.75, moved to x' = x + 0.5, so λ = 5.5 ∓ √0.75 from x' = -5.
    #[rustfmt::skip]
    let shear = Transform::from_matrix(&nalgebra::Matrix4::new(
        1.0, 1.0, 0.0, 0.0,
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, 1.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    ))
    .expect("invertible");
    check(Quadric::sphere().transformed(&shear), ray([-5.0, 0.5, 0.0], X), &[(5.5 - h, 5.5 + h)]);
    // The plane x <= 0 sheared is x' - y <= 0: at y = 2, x' <= 2.
    check(half(1.0, 0.0, 0.0, 0.0).transformed(&shear), ray([-5.0, 2.0, 0.0], X), &[(0.0, 7.0)]);

    // A half-space moved: y <= 1 turned 90° about z becomes -x <= 1, moved by 5 in x: x >= 4.
    let m = Transform::rotate_z_degrees(90.0).expect("valid").then(&translate(5.0, 0.0, 0.0));
    check(half(0.0, 1.0, 0.0, -1.0).transformed(&m), ray([0.0, 0.0, 0.0], X), &[(4.0, INF)]);

    // Far from the origin the hits stay exact (all values here are representable):
    // the local centre keeps the ball's coefficients, so t² - su does not lose the radius.
    for d in [1e3, 1e6, 1e9] {
        let far = Quadric::sphere().transformed(&translate(d, 0.0, 0.0));
        check(far, ray([0.0, 0.0, 0.0], X), &[(d - 1.0, d + 1.0)]);
        check(far, ray([2.0 * d, 0.0, 0.0], NEG_X), &[(d - 1.0, d + 1.0)]);
        let far_plane = half(-1.0, 0.0, 0.0, 0.0).transformed(&translate(d, 0.0, 0.0));
        check(far_plane, ray([0.0, 0.0, 0.0], X), &[(d, INF)]);
    }
}

#[test]
fn endpoint_tags() {
    let ball = Quadric::sphere();
    check_tags(ball.intervals(&ray([-5.0, 0.0, 0.0], X), 3), &[(Some(3), Some(3))]);
    // Starting inside: the start is free.
    check_tags(ball.intervals(&ray([0.0, 0.0, 0.0], X), 3), &[(None, Some(3))]);
    // Starting on the surface going in: the start is the surface.
    check_tags(ball.intervals(&ray([-1.0, 0.0, 0.0], X), 3), &[(Some(3), Some(3))]);
    // Two pieces of a non-convex solid: free start, surface, surface, free infinite end.
    let outside = ball.complement();
    check_tags(outside.intervals(&ray([-5.0, 0.0, 0.0], X), 4), &[(None, Some(4)), (Some(4), None)]);
    check_tags(Quadric::tube_y().intervals(&ray([0.0, 0.0, 0.0], Y), 4), &[(None, None)]);
    check_tags(Quadric::paraboloid().intervals(&ray([0.0, -5.0, 0.0], Y), 4), &[(Some(4), None)]);
    let below = half(0.0, 1.0, 0.0, -1.0);
    check_tags(below.intervals(&ray([0.0, 0.0, 0.0], Y), 5), &[(None, Some(5))]);
    check_tags(below.intervals(&ray([0.0, 5.0, 0.0], NEG_Y), 5), &[(Some(5), None)]);
    check_tags(below.intervals(&ray([0.0, 1.0, 0.0], NEG_Y), 5), &[(Some(5), None)]);
    check_tags(below.intervals(&ray([0.0, 0.0, 0.0], X), 5), &[(None, None)]);

    // A capped cylinder: each end names the surface that bounds it there.
    let tube = Quadric::tube_y();
    let top = half(0.0, 1.0, 0.0, -2.0); // y <= 2
    let bottom = half(0.0, -1.0, 0.0, 0.0); // y >= 0
    let capped = |r: &Ray| {
        tube.intervals(r, 0)
            .intersect(&top.intervals(r, 1))
            .and_then(|s| s.intersect(&bottom.intervals(r, 2)))
            .expect("within capacity")
    };
    let up = ray([0.0, -5.0, 0.0], Y);
    assert!(sets_close(&capped(&up), &[(5.0, 7.0)], 4.0));
    check_tags(capped(&up), &[(Some(2), Some(1))]);
    check_tags(capped(&ray([-5.0, 1.0, 0.0], X)), &[(Some(0), Some(0))]);
    // In through the side, out through the top: (x, y) = (-3 + μ, -0.5 + μ), μ = λ/√2. The side
    // |x| <= 1 holds for μ in [2, 4], the caps 0 <= y <= 2 for μ in [0.5, 2.5]: μ in [2, 2.5].
    let r2 = std::f64::consts::SQRT_2;
    let slant = ray([-3.0, -0.5, 0.0], [1.0, 1.0, 0.0]);
    assert!(sets_close(&capped(&slant), &[(2.0 * r2, 2.5 * r2)], 8.0), "{:?}", capped(&slant));
    check_tags(capped(&slant), &[(Some(0), Some(1))]);
}

#[test]
fn negative_zero_components() {
    // A direction or origin component of -0.0 must act exactly like +0.0:
    // s, t or u may come out as -0.0, and the table's `= 0` rows must still be taken.
    let solids: [Solid; 6] = [
        Quadric::tube_y().into(),
        Quadric::paraboloid().into(),
        Quadric::cone().into(),
        Quadric::sphere().complement().into(),
        half(1.0, 0.0, 0.0, -1.0).into(),
        half(0.0, 1.0, 0.0, -1.0).into(),
    ];
    let cases = [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-0.0, 0.0, -0.0], [-0.0, 1.0, -0.0]),
        ([0.5, -5.0, 0.0], [0.0, 1.0, 0.0], [0.5, -5.0, -0.0], [-0.0, 1.0, -0.0]),
        ([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [1.0, -0.0, -0.0], [-0.0, -1.0, -0.0]),
        ([0.0, 2.0, 0.0], [1.0, 0.0, 0.0], [-0.0, 2.0, -0.0], [1.0, -0.0, -0.0]),
        ([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-5.0, -0.0, -0.0], [1.0, -0.0, 0.0]),
    ];
    for solid in solids {
        for (p, d, mp, md) in cases {
            let plain = solid.intervals(&ray(p, d), TAG);
            let signed = solid.intervals(&ray(mp, md), TAG);
            assert_eq!(plain, signed, "{solid:?}: {p:?} {d:?} vs {mp:?} {md:?}");
        }
    }
    // Spot values: along the tube's axis with -0.0 components (s = 0, t = 0, u = -1).
    check(Quadric::tube_y(), ray([-0.0, 0.0, -0.0], [-0.0, 1.0, -0.0]), &[(0.0, INF)]);
    // In the plane x = 1 of x <= 1, direction (−0, 1, 0): t = -0.0 is "parallel", u = 0 inside.
    check(half(1.0, 0.0, 0.0, -1.0), ray([1.0, 0.0, 0.0], [-0.0, 1.0, 0.0]), &[(0.0, INF)]);
    // A coefficient of -0.0: the tube with b = -0.0 is still s = 0 along y.
    let tube = coefficients([1.0, -0.0, 1.0, -0.0, 0.0, -0.0, 0.0, -0.0, 0.0, -1.0]);
    check(tube, ray([0.0, 0.0, 0.0], Y), &[(0.0, INF)]);
    check(tube, ray([0.0, 0.0, 0.0], [0.0, -1.0, 0.0]), &[(0.0, INF)]);
    check(half(-0.0, 1.0, 0.0, -1.0), ray([0.0, 5.0, 0.0], NEG_Y), &[(4.0, INF)]);
    // Roots of -0.0 come out as +0.0 (`check` rejects an end at -0.0): on the plane
    // y = 0 with d = -0.0 from the origin (-0, -0, -0), u = -0.0 and -u/t = 0/(-1) = -0.0.
    let origin = [-0.0, -0.0, -0.0];
    check(half(0.0, 1.0, 0.0, -0.0), ray(origin, NEG_Y), &[(0.0, INF)]);
    check_tags(half(0.0, 1.0, 0.0, -0.0).intervals(&ray(origin, NEG_Y), 2), &[(Some(2), None)]);
    // The same plane as a quadric, 2·0.5·y - 0.0 <= 0: s = 0 and -u/(2t) = -0.0.
    let plane = coefficients([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, -0.0]);
    check(plane, ray(origin, NEG_Y), &[(0.0, INF)]);
    check_tags(plane.intervals(&ray(origin, NEG_Y), 2), &[(Some(2), None)]);
}

#[test]
fn reversed_rays() {
    // Ray::reversed_at(L) maps λ to L - λ.
    let forward = ray([-5.0, 0.0, 0.0], X);
    let back = forward.reversed_at(10.0);
    assert_eq!(back.origin(), Point3::new(5.0, 0.0, 0.0));
    assert_eq!(back.direction(), Vector3::new(-1.0, 0.0, 0.0));
    check(Quadric::sphere(), back, &[(4.0, 6.0)]);
    // From (0.5, 0, 0) along -x, inside the ball: outside again where 0.5 - λ <= -1.
    check(Quadric::sphere().complement(), forward.reversed_at(5.5), &[(1.5, INF)]);
}

#[test]
fn pieces_per_solid() {
    // Convex solids meet a ray in at most one interval, the others in up to two.
    let one: [Solid; 6] = [
        Quadric::sphere().into(),
        Quadric::tube_x().into(),
        Quadric::tube_z().into(),
        Quadric::paraboloid().into(),
        half(1.0, 2.0, 3.0, 4.0).into(),
        half(1.0, 2.0, 3.0, 4.0).complement().into(),
    ];
    let two: [Solid; 6] = [
        Quadric::cone().into(),
        Quadric::hyperboloid_one_sheet().into(),
        Quadric::hyperboloid_two_sheets().into(),
        Quadric::sphere().complement().into(),
        Quadric::tube_y().complement().into(),
        Quadric::paraboloid().complement().into(),
    ];
    for s in one {
        assert_eq!(s.max_intervals(), 1, "{s:?}");
    }
    for s in two {
        assert_eq!(s.max_intervals(), 2, "{s:?}");
    }
    // The outside of the paraboloid really has two pieces across it: at y = 1, x² >= 1.
    check(Quadric::paraboloid().complement(), ray([-5.0, 1.0, 0.0], X), &[(0.0, 4.0), (6.0, INF)]);
}

/// `Solid::max_intervals` must bound `intervals(ray).len()`: blocks size
/// their interval sets by it (`complex::Block::new`), and an overflow there
/// is silently an empty set. `Quadric::is_convex` accepts eigenvalues down to
/// `-1e-12·max|A|` as rounding noise, but the kernel takes the sign of the
/// computed `s` as it is, so a slightly hyperbolic tube `x² - 1e-13·y² + z² <= 1`
/// counts as convex (one interval) yet meets a ray outside it, parallel to
/// its axis, in two: `3 - 1e-13·y² <= 0` for `|y| >= √(3·10¹³) ≈ 5.48·10⁶`.
/// Either the classification must be exact, or the kernel must treat `s` of
/// a quadric it calls convex as `max(s, 0)` so the two agree by construction.
#[test]
fn max_intervals_bounds_the_pieces() {
    let waisted = coefficients([1.0, -1e-13, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
    let solid = Solid::from(waisted);
    let set = solid.intervals(&ray([2.0, -1e7, 0.0], Y), TAG);
    let root = 3e13f64.sqrt();
    assert!(sets_close(&set, &[(0.0, 1e7 - root), (1e7 + root, INF)], 64.0), "{set:?}");
    assert!(set.len() <= solid.max_intervals(), "{} pieces, max_intervals {}", set.len(), solid.max_intervals());
}
