//! Numerical stress suite of the kernel, judged by the `reference` crate's
//! exact answers (exact decisions, roots to 256 bits):
//! - solids translated 1 … 10⁹ from the origin and from the camera, scaled
//!   10⁻⁶ and 10⁶, grazing and exactly tangent rays, nearly flat quadrics
//!   (`s ≈ 0`), rays starting inside and exactly on the surface;
//! - [`Precision::Certified`]: the exact number of crossings (no false hit or
//!   miss at all) and every crossing within its stated bound;
//! - the default mode: a false hit or miss only where the certified bound
//!   says the answer is ambiguous (the certified kernel settled it exactly),
//!   and hit points within 4× the float64 rounding floor of the exact hit
//!   point.
//!
//! Bounded in size: a few thousand rays, seconds at the test profile.

use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::{strategies, HalfSpace, Precision, Quadric, Ray, Solid, Transform};
use reference::{
    computed_crossings, median_max, other_shapes, unit_sphere, Big, ExactQuadric, ExactRay, Judge, Rng, Scene, Shape,
    Tally,
};

/// What one ray tells about each mode.
#[derive(Default)]
struct Verdicts {
    rays: usize,
    crossings: usize,
    /// Rays the certified kernel settled exactly (its bounds left them open).
    ambiguous: usize,
    /// Default-mode false hits or misses on rays the certified bound called clear.
    unexcused_default: Vec<String>,
}

/// Checks the certified answer for `ray` exactly, and records whether the
/// default mode's crossing count is right where the bound calls the ray clear.
fn judge_ray(solid: &Solid, ray: &Ray, verdicts: &mut Verdicts) -> Result<(), String> {
    let exact = ExactQuadric::solid(solid).solve(ray);
    let want = exact.crossings();
    let certified = solid.intervals_certified(ray, 0);
    let got = computed_crossings(&certified.set);
    verdicts.rays += 1;
    verdicts.crossings += want.len();
    if got.len() != want.len() {
        return Err(format!(
            "certified: {} crossings, exact {}: {solid:?} {ray:?} {:?}",
            got.len(),
            want.len(),
            certified.set
        ));
    }
    for (l, &t) in want.iter().zip(&got) {
        let error = certified.error_at(t);
        let off = (&Big::from_f64(t) - l).abs();
        if (&off - &Big::from_f64(error)).signum() > 0 {
            return Err(format!(
                "certified: crossing {t:e} off by {:e} > its bound {error:e}: {solid:?} {ray:?}",
                off.to_f64()
            ));
        }
    }
    if certified.settled_exactly {
        verdicts.ambiguous += 1;
    } else {
        let default = computed_crossings(&solid.intervals(ray, 0));
        if default.len() != want.len() {
            verdicts.unexcused_default.push(format!("{solid:?} {ray:?}"));
        }
    }
    Ok(())
}

fn check_rays(solid: &Solid, rays: &[Ray], context: &str) -> Verdicts {
    let mut v = Verdicts::default();
    for ray in rays {
        if let Err(e) = judge_ray(solid, ray, &mut v) {
            panic!("{context}: {e}");
        }
    }
    assert!(
        v.unexcused_default.is_empty(),
        "{context}: default mode wrong where the bound is clear: {:?}",
        v.unexcused_default
    );
    v
}

/// Rays from a camera `3·size` from the shape's centre in a random direction
/// (the camera moves with the shape), aimed at points inside the unit-frame
/// shape, one in three bisected towards a tangent ray.
fn rays_from_nearby_camera(scene: &Scene, shape: &Shape, n: usize, rng: &mut Rng) -> Vec<Ray> {
    let world = |p: [f64; 3]| scene.placement.apply_point(&Point3::from(p));
    let crosses = |r: &Ray| !scene.exact.solve(r).crossings().is_empty();
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let camera = world(rng.direction().map(|c| 3.0 * c));
        let aim = |x: Point3<f64>| Ray::new(camera, x - camera).ok();
        let mut a = world((shape.inside)(rng));
        let Some(ray) = aim(a) else { continue };
        if out.len() % 3 != 2 {
            out.push(ray);
            continue;
        }
        let mut b = world((shape.outside)(rng));
        if aim(b).is_none_or(|r| crosses(&r)) || !crosses(&ray) {
            out.push(ray);
            continue;
        }
        for _ in 0..(10 + rng.next_u64() % 50) {
            let m = Point3::from((a.coords + b.coords) * 0.5);
            match aim(m) {
                Some(r) if crosses(&r) => a = m,
                Some(_) => b = m,
                None => break,
            }
        }
        out.extend(aim(if rng.unit() < 0.5 { a } else { b }));
    }
    out
}

/// The default mode's hit points ([`Solid::hit_point`] at its crossings)
/// against the rounding floor of the same rays: the largest exact distance
/// from the true surface of a computed hit point, against the largest such
/// distance of an exact hit point rounded to doubles.
fn check_floor(scene: &Scene, rays: &[Ray], factor: f64, context: &str) {
    let mut floor = Tally::default();
    let mut ours = Tally::default();
    let judge = Judge { band_ulps: f64::INFINITY };
    for ray in rays {
        let exact: ExactRay = scene.exact.solve(ray);
        floor.add_floor(scene, ray, &exact);
        let set = scene.solid.intervals(ray, 0);
        ours.add_with_points(scene, ray, &exact, &set, &judge, |t| scene.solid.hit_point(ray, t));
    }
    let (_, floor_max) = median_max(&floor.size_units);
    let (_, ours_max) = median_max(&ours.size_units);
    eprintln!("{context}: max error / max floor = {:.2}", ours_max / floor_max);
    assert!(ours.size_units.len() * 2 >= floor.size_units.len(), "{context}: too few crossings compared");
    assert!(
        ours_max <= factor * floor_max,
        "{context}: max hit-point error {ours_max:e} sizes over {factor}× the rounding floor {floor_max:e}"
    );
}

const RAYS: usize = 300;

/// Shapes translated 1 … 10⁹ from the origin, the camera near the origin or
/// near the shape: certified exact, default within 4× the floor.
#[test]
fn translated_shapes() {
    let mut shapes = vec![unit_sphere()];
    shapes.extend(other_shapes());
    for (i, shape) in shapes.iter().enumerate() {
        for (j, distance) in [1.0, 1e3, 1e6, 1e9].into_iter().enumerate() {
            let mut rng = Rng::new(0x57e5_0000 + 16 * i as u64 + j as u64);
            let scene = Scene::new(shape, distance, &mut rng);
            let far = scene.rays(shape, 0.25 * distance.min(1.0), RAYS, &mut rng);
            let context = format!("{} at {distance:e}, camera at the origin", shape.name);
            check_rays(&scene.solid, &far, &context);
            check_floor(&scene, &far, 4.0, &context);
            if shape.aim == reference::Aim::Inside {
                let near = rays_from_nearby_camera(&scene, shape, RAYS / 3, &mut rng);
                let context = format!("{} at {distance:e}, camera at the shape", shape.name);
                check_rays(&scene.solid, &near, &context);
            }
        }
    }
}

/// A sphere of radius 10⁻⁶ and one of radius 10⁶, each far away.
#[test]
fn extreme_sizes() {
    for (k, size) in [1e-6, 1e6].into_iter().enumerate() {
        for (j, distance) in [1.0, 1e3, 1e9].into_iter().enumerate() {
            let mut rng = Rng::new(0x5123_0000 + 8 * k as u64 + j as u64);
            let linear = Transform::scale(size).expect("a valid scale");
            let shape = Shape { linear, size, ..unit_sphere() };
            let scene = Scene::new(&shape, distance * size.max(1.0), &mut rng);
            let rays = rays_from_nearby_camera(&scene, &shape, RAYS, &mut rng);
            check_rays(&scene.solid, &rays, &format!("sphere of radius {size:e} at {distance:e}"));
        }
    }
}

/// Exactly tangent rays (a touching point is no crossing), rays along a
/// plane, rays starting exactly on the surface, at translations of powers
/// of two (kept exact).
#[test]
fn exact_tangencies_and_starts_on_the_surface() {
    for e in [0, 10, 30, 48] {
        let c = Vector3::new(2f64.powi(e), -(2f64.powi(e)), 3.0 * 2f64.powi(e));
        let move_to = Transform::translate(c).expect("valid");
        let sphere = Solid::from(Quadric::sphere().transformed(&move_to));
        let tube = Solid::from(Quadric::tube_y().transformed(&move_to));
        let cone = Solid::from(Quadric::cone().transformed(&move_to));
        let plane = Solid::from(HalfSpace::new(0.0, 1.0, 0.0, 0.0).expect("valid").transformed(&move_to));
        let at = |x: f64, y: f64, z: f64, dir: Vector3<f64>| {
            Ray::new(Point3::from(c + Vector3::new(x, y, z)), dir).expect("valid")
        };
        let cases: Vec<(&Solid, Ray, usize)> = vec![
            // Tangent to the sphere and the tube from outside: no crossing.
            (&sphere, at(-5.0, 1.0, 0.0, Vector3::x()), 0),
            (&sphere, at(-5.0, 0.0, -1.0, Vector3::x()), 0),
            (&tube, at(-5.0, 7.0, 1.0, Vector3::x()), 0),
            // Along the tube's wall (s = 0, t = 0, u = 0: on the surface, inside).
            (&tube, at(1.0, -4.0, 0.0, Vector3::y()), 0),
            // Along a generator of the cone through its apex.
            (&cone, at(-3.0, -3.0, 0.0, Vector3::new(1.0, 1.0, 0.0)), 0),
            // In the plane: inside all along.
            (&plane, at(-3.0, 0.0, 2.0, Vector3::x()), 0),
            // Starting exactly on the surface, going in and going out.
            (&sphere, at(1.0, 0.0, 0.0, -Vector3::x()), 2),
            (&sphere, at(1.0, 0.0, 0.0, Vector3::x()), 0),
            (&plane, at(0.0, 0.0, 0.0, Vector3::y()), 0),
            (&plane, at(0.0, 0.0, 0.0, -Vector3::y()), 1),
        ];
        for (solid, ray, crossings) in cases {
            let mut v = Verdicts::default();
            judge_ray(solid, &ray, &mut v).unwrap_or_else(|e| panic!("2^{e}: {e}"));
            let exact = ExactQuadric::solid(solid).solve(&ray);
            // The case is what it says (the reference's count), so the check above is of it.
            assert_eq!(exact.crossings().len(), crossings, "2^{e}: {solid:?} {ray:?}");
        }
    }
}

/// Nearly tangent rays at every closeness: a sphere at `10^k` grazed by rays
/// offset from the tangent line by `2^-j` of its radius, j = 0 … 60.
#[test]
fn grazing_rays() {
    let mut rng = Rng::new(0x62a2);
    for distance in [1.0, 1e4, 1e9] {
        let c = Vector3::from(rng.direction()) * distance;
        let sphere = Solid::from(Quadric::sphere().transformed(&Transform::translate(c).expect("valid")));
        let mut rays = Vec::new();
        for j in 0..=60 {
            let off = 2f64.powi(-j);
            for side in [1.0 - off, 1.0 + off] {
                let dir = Vector3::from(rng.direction());
                let n = dir.cross(&Vector3::from(rng.direction())).normalize();
                let o = Point3::from(c + n * side - dir * 3.0);
                rays.extend(Ray::new(o, dir).ok());
            }
        }
        let v = check_rays(&sphere, &rays, &format!("grazing a sphere at {distance:e}"));
        assert!(v.crossings > 0 && v.crossings < 2 * rays.len(), "{distance:e}: hits and misses both");
    }
}

/// Accurate and Certified agree on the interval set's shape for rays the
/// certified bound calls clear, and `intervals` is `intervals_with` in the default mode.
#[test]
fn modes_agree_away_from_ambiguity() {
    assert_eq!(Precision::default(), Precision::Accurate);
    let shape = unit_sphere();
    let mut rng = Rng::new(0xa9ee);
    let scene = Scene::new(&shape, 10.0, &mut rng);
    for ray in scene.rays(&shape, 0.25, 200, &mut rng) {
        let default = scene.solid.intervals(&ray, 0);
        assert_eq!(default, scene.solid.intervals_with(&ray, 0, Precision::Accurate));
        let certified = scene.solid.intervals_certified(&ray, 0);
        if certified.settled_exactly {
            continue;
        }
        // (Fast is not bound by the certified bound: it may miss a clear crossing.)
        for mode in [Precision::Accurate, Precision::Certified] {
            let set = scene.solid.intervals_with(&ray, 0, mode);
            assert_eq!(set.len(), certified.set.len(), "{mode:?} {ray:?}");
            for (a, b) in set.iter().zip(certified.set.iter()) {
                for (x, y) in [(a.enter, b.enter), (a.exit, b.exit)] {
                    assert_eq!(x.solid, y.solid, "{mode:?}");
                    // Within the certified bound plus a few ulps.
                    let slack = certified.error_at(y.t) + 4.0 * f64::EPSILON * y.t.abs();
                    assert!((x.t - y.t).abs() <= slack, "{mode:?}: {} vs {} ± {slack:e}", x.t, y.t);
                }
            }
        }
    }
}

proptest! {
    /// Any solid, any ray: the certified kernel's crossings are the exact
    /// ones, each within its bound.
    #[test]
    fn certified_is_exact_for_any_solid(solid in strategies::solid(), ray in strategies::ray(4.0)) {
        let mut v = Verdicts::default();
        judge_ray(&solid, &ray, &mut v).map_err(TestCaseError::fail)?;
    }

    /// On the integer grid, where exact tangencies and rays on surfaces are common.
    #[test]
    fn certified_is_exact_on_the_grid(solid in strategies::grid_solid(), ray in strategies::grid_ray(3)) {
        let mut v = Verdicts::default();
        judge_ray(&solid, &ray, &mut v).map_err(TestCaseError::fail)?;
    }
}

/// Ties between the roots of two solids are decided exactly: the unit
/// sphere and the plane `x <= 1` meet the x axis at the same point; a plane
/// `2⁻⁴⁰` further out does not.
#[test]
fn ties_between_solids_are_exact() {
    use core::cmp::Ordering;
    let ray = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).expect("valid");
    let sphere = Solid::from(Quadric::sphere());
    let plane = |d: f64| Solid::from(HalfSpace::new(1.0, 0.0, 0.0, -d).expect("valid"));
    assert_eq!(sphere.compare_roots(1, &plane(1.0), 0, &ray), Some(Ordering::Equal));
    assert_eq!(sphere.compare_roots(0, &plane(1.0), 0, &ray), Some(Ordering::Less));
    assert_eq!(sphere.compare_roots(1, &plane(1.0 + 2f64.powi(-40)), 0, &ray), Some(Ordering::Less));
    assert_eq!(sphere.compare_roots(2, &plane(1.0), 0, &ray), None);
    // The ball of radius 5 and the plane 3x + 4y <= 25 through its point
    // (3, 4, 0): the ray up x = 3 leaves both there (at λ = 14).
    let five =
        Solid::from(Quadric::from_coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -25.0]).expect("finite"));
    let up = Ray::new(Point3::new(3.0, -10.0, 0.0), Vector3::y()).expect("valid");
    let tangent = Solid::from(HalfSpace::new(3.0, 4.0, 0.0, -25.0).expect("valid"));
    assert_eq!(five.compare_roots(1, &tangent, 0, &up), Some(Ordering::Equal));
    assert_eq!(five.compare_roots(0, &tangent, 0, &up), Some(Ordering::Less));
    let certified = five.intervals_certified(&up, 0);
    assert_eq!(certified.roots().iter().map(|r| r.t).collect::<Vec<_>>(), [6.0, 14.0]);
}
