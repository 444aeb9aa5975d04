//! A slab (two opposite half-spaces around one reference point) answers
//! exactly as its two half-spaces do, one at a time: the box kernels of
//! `complex` rely on the values being the same bits, not merely close.
//!
//! The half-spaces come from the scene's construction (`±x + d <= 0` moved
//! by random transforms, near the origin and far from it), the rays from
//! everywhere, including rays nearly parallel to the planes, where the slope
//! takes its compensated branch, and rays exactly in a plane's direction.

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use quadric::strategies;
use quadric::{Bound, HalfSpace, Ray, Rebased, Transform};

fn bits(b: (Bound, Bound)) -> (u64, Option<u32>, u64, Option<u32>) {
    (b.0.t.to_bits(), b.0.solid(), b.1.t.to_bits(), b.1.solid())
}

/// Two faces of a box on one axis, `n·x + d₀ <= 0` and `-n·x + d₁ <= 0` (as
/// the scene builds them), moved by `m` and then `far` away.
fn slab() -> impl Strategy<Value = (HalfSpace, HalfSpace)> {
    (
        0usize..3,
        -2.0f64..2.0,
        -2.0f64..2.0,
        strategies::transform(),
        prop_oneof![Just(0.0), Just(1e3), Just(1e9)],
        strategies::unit_vector(),
    )
        .prop_filter_map("finite", |(axis, d0, d1, m, far, at)| {
            let mut n = [0.0; 3];
            n[axis] = 1.0;
            let a = HalfSpace::new(n[0], n[1], n[2], d0).ok()?;
            let b = HalfSpace::new(-n[0], -n[1], -n[2], d1).ok()?;
            let m = m.then(&Transform::translate(at * far).ok()?);
            Some((a.transformed(&m), b.transformed(&m)))
        })
}

/// Rays near the slab: from anywhere within `extent` of its reference point,
/// in a random direction, or in one at `tilt` from the plane.
fn rays(o: Point3<f64>, n: Vector3<f64>) -> impl Strategy<Value = Vec<Ray>> {
    let u = n.normalize();
    let side = if u.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let along = u.cross(&side).normalize();
    proptest::collection::vec(
        (
            strategies::point(3.0),
            strategies::unit_vector(),
            prop_oneof![Just(0.0), Just(1e-17), Just(1e-9), 0.0f64..1.0],
            any::<bool>(),
        ),
        16,
    )
    .prop_map(move |v| {
        v.into_iter()
            .filter_map(|(p, dir, tilt, grazing)| {
                let dir = if grazing { along + u * tilt } else { dir };
                Ray::new(o + p.coords, dir).ok()
            })
            .collect()
    })
}

proptest! {
    #[test]
    fn a_slab_answers_bit_for_bit_as_its_two_half_spaces(
        ((a, b), rays) in slab().prop_flat_map(|(a, b)| {
            let rays = rays(a.reference_point(), *a.normal_vector());
            (Just((a, b)), rays)
        })
    ) {
        let Some(d) = a.opposite_offset(&b) else {
            return Err(TestCaseError::fail(format!("{a:?} and {b:?} are not found opposite")));
        };
        for ray in &rays {
            let at = Rebased::new(ray, &a.reference_point());
            let [ga, gb] = a.slab_intervals(d, ray, &at, 3);
            prop_assert_eq!(bits(ga), bits(a.interval(ray, 3)), "first face, ray {:?}", ray);
            prop_assert_eq!(bits(gb), bits(b.interval(ray, 4)), "second face, ray {:?}", ray);
            prop_assert_eq!(bits(a.interval_rebased(ray, &at, 3)), bits(a.interval(ray, 3)));
        }
    }
}

#[test]
fn opposites_are_found_by_value() {
    let a = HalfSpace::new(1.0, 0.0, 0.0, -1.0).expect("valid");
    let b = HalfSpace::new(-1.0, 0.0, 0.0, -1.0).expect("valid");
    // `-a`'s normal is (-1, -0, -0), `b`'s (-1, 0, 0): still opposite.
    assert_eq!(a.opposite_offset(&b), Some(-1.0));
    let moved = b.transformed(&Transform::translate(Vector3::new(0.0, 1e-12, 0.0)).expect("finite"));
    assert_eq!(a.opposite_offset(&moved), None);
    assert_eq!(a.opposite_offset(&a), None);
    let tilted = HalfSpace::new(-1.0, f64::EPSILON, 0.0, -1.0).expect("valid");
    assert_eq!(a.opposite_offset(&tilted), None);
}
