//! Accuracy of `Quadric::intervals` (and `HalfSpace::intervals`) against the
//! high-precision reference of the `reference` crate (exact dyadic
//! arithmetic, roots to 256 bits): the bound stated in `docs/quadric.md` §8.
//!
//! With `x` the exact crossing and `U = ulp(max(|x|∞, |x - c|∞))` the spacing
//! of doubles there (in world space or around the centre `c`, whichever is
//! coarser):
//! - every crossing that the exact answer and `intervals` both report lies,
//!   as the double point `ray.at(λ)`, within `K·U` of the true surface, with
//!   `K = 1.5` for a camera far from the shape (distance >= 1000 sizes) and
//!   `K = 16` for a camera at the shape (distance 1), where the rounding of
//!   `f` itself, amplified by the shape's anisotropy, is no longer hidden
//!   below the ulps of the far hit point;
//! - `intervals` reports more or fewer crossings than exist (a false hit or
//!   miss) only for rays whose line passes within 4 ulps of the local
//!   coordinates `x - c` of touching the surface (measured at the apex
//!   `-t/s`), or that start within 4 such ulps of it.
//!
//! The rounding floor itself (the exact crossing rounded to doubles) reaches
//! about `0.87 U`.

use reference::{median_max, other_shapes, unit_sphere, Judge, Rng, Scene, Shape, Tally};

/// Rays per shape and distance: the reference costs some microseconds per
/// ray at the test profile's opt-level.
const RAYS: usize = 1000;
const BAND: Judge = Judge { band_ulps: 4.0 };

fn check(shape: &Shape, distance: f64, k: f64, seed: u64) {
    let mut rng = Rng::new(seed);
    let scene = Scene::new(shape, distance, &mut rng);
    let rays = scene.rays(shape, 0.25 * distance.min(1.0), RAYS, &mut rng);
    let mut tally = Tally::default();
    let mut crossings = 0;
    for ray in &rays {
        let exact = scene.exact.solve(ray);
        crossings += exact.crossings().len();
        tally.add(&scene, ray, &exact, &scene.solid.intervals(ray, 0), &BAND);
    }
    let (median, max) = median_max(&tally.ulps);
    let context = format!("{} at distance {distance:e}: median {median:.2} U, max {max:.2} U", shape.name);
    // The rays must exercise what is asserted: most of them cross the surface.
    assert!(2 * crossings >= RAYS, "{context}: only {crossings} crossings");
    assert!(tally.ulps.len() * 10 >= crossings * 9, "{context}: too few crossings compared");
    assert!(max <= k, "{context}: over the bound of {k} U");
    assert_eq!(
        tally.unexcused, 0,
        "{context}: {} false hits, {} false misses, worst tangency gap {:.2} U",
        tally.false_hits, tally.false_misses, tally.worst_gap_ulps
    );
}

fn check_distances(shape: &Shape, seed: u64) {
    check(shape, 1.0, 16.0, seed);
    for (i, distance) in [1e3, 1e6, 1e9].into_iter().enumerate() {
        check(shape, distance, 1.5, seed + 1 + i as u64);
    }
}

#[test]
fn unit_sphere_within_bound() {
    check_distances(&unit_sphere(), 0x5eed_0001);
}

#[test]
fn other_shapes_within_bound() {
    for (i, shape) in other_shapes().iter().enumerate() {
        check_distances(shape, 0x5eed_0100 + 16 * i as u64);
    }
}

/// The bound is not vacuous: the world-space textbook formula breaks it.
#[test]
fn world_space_formula_breaks_the_bound() {
    let shape = unit_sphere();
    let mut rng = Rng::new(0x5eed_0200);
    let scene = Scene::new(&shape, 1e6, &mut rng);
    let world = quadric::Quadric::from_coefficients(scene.world_coefficients()).expect("finite coefficients");
    let mut tally = Tally::default();
    for ray in scene.rays(&shape, 0.25, 100, &mut rng) {
        let exact = scene.exact.solve(&ray);
        tally.add(&scene, &ray, &exact, &world.intervals(&ray, 0), &BAND);
    }
    let (_, max) = median_max(&tally.ulps);
    assert!(max > 100.0 || tally.unexcused > 0, "max {max} U, {} unexcused", tally.unexcused);
}
