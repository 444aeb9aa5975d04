//! The fast paths of the ray kernel against the plain definitions: a
//! block's interval set is the intersection of its solids' sets (computed
//! here with `IntervalSet::intersect`, not by the crate), solid tags
//! included; concentric blocks (one centre, no SAH split) still answer
//! like brute force.

use complex::{Block, Complex, ComplexOptions, MaterialKey};
use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::{strategies, IntervalSet, Quadric, Ray, Solid, Transform};

use crate::common::O;

/// The definition: `[0, ∞) ∩ S_1 ∩ … ∩ S_m`, each end tagged by its solid.
fn reference(solids: &[Solid], ray: &Ray) -> IntervalSet {
    let mut acc = IntervalSet::everything().clip(0.0, f64::INFINITY);
    for (i, s) in solids.iter().enumerate() {
        acc = acc.intersect(&s.intervals(ray, i as u32)).expect("within capacity");
    }
    acc
}

/// Convex solids only (the two-bound path) or any (the set path).
fn solids(convex: bool) -> impl Strategy<Value = Vec<Solid>> {
    let ball = (strategies::transform(), 0.5f64..2.0)
        .prop_map(|(m, r)| Solid::from(Quadric::sphere().transformed(&Transform::scale(r).expect("finite").then(&m))));
    let tube = (strategies::transform(), 0.5f64..2.0)
        .prop_map(|(m, r)| Solid::from(Quadric::tube_y().transformed(&Transform::scale(r).expect("finite").then(&m))));
    let convex_solid = prop_oneof![ball, tube, strategies::half_space().prop_map(Solid::from)];
    let solid = if convex { convex_solid.boxed() } else { prop_oneof![convex_solid, strategies::solid()].boxed() };
    proptest::collection::vec(solid, 1..=6)
}

proptest! {
    #[test]
    fn block_intervals_are_the_intersection_of_the_solids(
        solids in any::<bool>().prop_flat_map(solids),
        rays in proptest::collection::vec(strategies::ray(4.0), 8),
    ) {
        let block = Block::new("b", solids.clone(), O, MaterialKey(0)).expect("valid");
        for ray in &rays {
            let got = block.intervals(ray);
            let want = reference(&solids, ray);
            // Same intervals and the same solid on every end.
            prop_assert_eq!(got.as_slice(), want.as_slice(), "{} vs {}", got, want);
        }
    }
}

/// `n` balls around one centre, radii `1, 2, …, n`; some pierced by a
/// tube so that the blocks differ in shape as well as size.
fn concentric(n: usize) -> Complex {
    let blocks = (1..=n)
        .map(|k| {
            let r = k as f64;
            let mut solids = vec![Solid::from(Quadric::sphere().transformed(&Transform::scale(r).expect("finite")))];
            if k % 3 == 0 {
                solids.push(Solid::from(Quadric::tube_x().transformed(&Transform::scale(0.5 * r).expect("finite"))));
            }
            Block::new(format!("shell {k}"), solids, O, MaterialKey(0)).expect("valid")
        })
        .collect();
    Complex::new(blocks, ComplexOptions::default()).expect("valid")
}

/// Brute force: the nearest entry after ε over every block, lowest id on ties.
fn brute_first_entry(c: &Complex, ray: &Ray) -> Option<(f64, u32)> {
    let mut best: Option<(f64, u32)> = None;
    for (i, b) in c.blocks().iter().enumerate() {
        if let Some(iv) = b.intervals(ray).iter().find(|iv| iv.enter.t > c.epsilon()) {
            if best.is_none_or(|(t, _)| iv.enter.t < t) {
                best = Some((iv.enter.t, i as u32));
            }
        }
    }
    best
}

#[test]
fn concentric_blocks_answer_like_brute_force() {
    let c = concentric(200);
    let check = |origin: Point3<f64>, dir: Vector3<f64>| {
        let ray = Ray::new(origin, dir).expect("valid");
        let hit = c.cast_ray(&ray, f64::INFINITY).map(|h| (h.t, h.block.0));
        assert_eq!(hit, brute_first_entry(&c, &ray), "ray from {origin} along {dir}");
    };
    // From outside everything: the outermost ball (or a miss).
    check(Point3::new(-300.0, 0.0, 0.0), Vector3::x());
    check(Point3::new(-300.0, 150.0, 20.0), Vector3::x());
    check(Point3::new(-300.0, 250.0, 0.0), Vector3::x());
    check(Point3::new(0.0, -300.0, 0.0), Vector3::new(0.1, 1.0, 0.3));
    // Inside a cavity-free stack every interval overlaps; from inside the
    // answer is the exit of the outermost ball.
    let inside = Ray::new(Point3::new(0.5, 0.0, 0.0), Vector3::y()).expect("valid");
    let hit = c.cast_ray(&inside, f64::INFINITY).expect("leaves the union");
    assert_eq!((hit.entering, hit.block.0), (false, 199));
    assert!((hit.t - (200.0f64 * 200.0 - 0.25).sqrt()).abs() < 1e-9 * 200.0, "{}", hit.t);
}

/// Rays along the axes (reciprocal directions `±∞` in the slab tests),
/// some exactly in the planes of box faces, through a grid of cubes and
/// balls: the BVH answers like brute force.
#[test]
fn axis_parallel_rays_answer_like_brute_force() {
    let mut blocks = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let (x, y, z) = (3.0 * i as f64, 3.0 * j as f64, 3.0 * k as f64);
                let solids = if (i + j + k) % 2 == 0 {
                    crate::common::cuboid([x, y, z], [x + 1.0, y + 1.0, z + 1.0])
                } else {
                    let m = Transform::translate(Vector3::new(x + 0.5, y + 0.5, z + 0.5)).expect("finite");
                    vec![Solid::from(Quadric::sphere().transformed(&Transform::scale(0.5).expect("finite").then(&m)))]
                };
                blocks.push(Block::new("cell", solids, O, MaterialKey(0)).expect("valid"));
            }
        }
    }
    let c = Complex::new(blocks, ComplexOptions::default()).expect("valid");
    let mut checked = 0;
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut dir = Vector3::zeros();
            dir[axis] = sign;
            // Across the other two axes: cell centres, face planes and gaps.
            for a in [0.0, 0.5, 1.0, 2.0, 3.0, 6.5, 10.0] {
                for b in [0.0, 0.5, 1.0, 4.0, 9.5] {
                    let mut origin = Point3::new(a, a, a);
                    origin[(axis + 1) % 3] = a;
                    origin[(axis + 2) % 3] = b;
                    origin[axis] = if sign > 0.0 { -5.0 } else { 15.0 };
                    let ray = Ray::new(origin, dir).expect("valid");
                    let hit = c.cast_ray(&ray, f64::INFINITY).map(|h| (h.t, h.block.0));
                    assert_eq!(hit, brute_first_entry(&c, &ray), "ray from {origin} along {dir}");
                    checked += usize::from(hit.is_some());
                }
            }
        }
    }
    // Most of these rays hit something: the test is not vacuous.
    assert!(checked > 100, "{checked}");
}
