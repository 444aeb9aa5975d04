//! Minimised inputs from the `complex_queries` fuzz target (`fuzz/`), one
//! test each: the shape of the input that failed and the law it broke.

use complex::BlockId;
use quadric::nalgebra::Point3;
use quadric::{Quadric, Solid, Transform};

use crate::common::*;

/// The tube `x² + y² <= 1` along z, moved `shift` along its own axis (which
/// changes nothing but its stored centre) and tilted about x by `degrees`.
/// Tilted, it is unbounded in y, however small the tilt: it passes the
/// origin, while its centre sits `shift · sin(tilt)` away in y.
fn far_tilted_tube(shift: f64, degrees: f64) -> Vec<Solid> {
    let m = translate(0.0, 0.0, shift).then(&Transform::rotate_x_degrees(degrees).expect("finite"));
    vec![Solid::from(Quadric::tube_z().transformed(&m))]
}

/// The block box must hold every point of the block: an eigenvector solver
/// returned the tube's axis as exactly z (the tilt, far below its tolerance,
/// was lost), so the box was bounded in y around the far centre and the BVH
/// path missed the tube at the origin.
#[test]
fn tilted_tube_is_unbounded_across_its_axis() {
    for (shift, degrees) in [(1e20, 1e-14), (-1e300, 4.667261458384588e-62), (1e12, 1e-7)] {
        let c = complex(vec![block("tube", far_tilted_tube(shift, degrees), O, 0)]);
        let origin = Point3::origin();
        assert!(c.block(BlockId(0)).contains_point(&origin), "the tube passes the origin");
        assert!(c.block_aabb(BlockId(0)).contains_point(&origin), "box {:?}", c.block_aabb(BlockId(0)));
        assert_eq!(c.contains_point(&origin), Some(BlockId(0)));
        let r = ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let brute = c.block_intervals(BlockId(0), &r);
        assert!(!brute.is_empty(), "the ray crosses the tube at the origin");
        assert_eq!(c.intervals(&r), vec![(BlockId(0), brute)], "the BVH path must see the tube");
        assert_eq!(c.cast_ray(&r, f64::INFINITY).map(|h| h.t), Some(brute.as_slice()[0].enter.t));
    }
}

/// An untilted tube far along its axis keeps its tight cross-section box.
#[test]
fn straight_far_tube_stays_bounded_across_its_axis() {
    let c = complex(vec![block("tube", far_tilted_tube(1e20, 0.0), O, 0)]);
    let b = c.block_aabb(BlockId(0));
    for i in 0..2 {
        assert!(b.min[i] >= -1.0 - 1e-6 && b.max[i] <= 1.0 + 1e-6, "{b:?}");
    }
    assert!(b.min[2] == f64::NEG_INFINITY && b.max[2] == f64::INFINITY, "{b:?}");
}

/// `3.0e45·y² + 4.0e45·z² + 2·2.5e22·xy + 2·7.8e20·xz + 55 <= 0` (no x² term):
/// for fixed `y < 0` it holds for all large enough `x`, so the solid is
/// non-empty and unbounded. Its `A` has one eigenvalue of about -0.1 next to
/// 8e45, far below the eigen solver's rounding (about 1e30): computed as
/// positive, it made the quadric an "empty cylinder" and the box empty.
#[test]
fn eigenvalue_lost_in_rounding_keeps_the_box_conservative() {
    let c = [
        0.0,
        5.912640821733636e45,
        7.945111104204573e45,
        2.4635712928565464e22,
        7.8198990349039e20,
        0.0,
        0.0,
        0.0,
        0.0,
        55.0,
    ];
    let q = Quadric::from_coefficients(c).expect("finite");
    let c = complex(vec![block("sliver", vec![Solid::from(q)], O, 0)]);
    let p = Point3::new(5e23, -3.984375, 0.0);
    assert!(c.block(BlockId(0)).contains_point(&p), "a point of the solid");
    assert!(c.block_aabb(BlockId(0)).contains_point(&p), "box {:?}", c.block_aabb(BlockId(0)));
    assert_eq!(c.contains_point(&p), Some(BlockId(0)));
    let r = ray([0.0, -3.984375, 0.0], [1.0, 0.0, 0.0]);
    let brute = c.block_intervals(BlockId(0), &r);
    assert!(!brute.is_empty());
    assert_eq!(c.intervals(&r), vec![(BlockId(0), brute)]);
}

/// A ray starting on the plane `x = 0` of a transparent block and leaving
/// it: the kernel puts the exit at 4.4e-16 (an ulp of the origin's
/// coordinates, within its stated accuracy), just outside the block's exact
/// box, and with a degenerate second block ε is 1e-106. The partition (which
/// meets the box at t = 0) had the exit event; `cast_ray`, probing the boxes
/// at t = ε, missed the block and returned nothing.
#[test]
fn cast_ray_finds_an_exit_just_outside_the_exact_box() {
    let point_block = vec![Solid::from(Quadric::paraboloid()), hs(0.0, 1.0, 0.0, -2.0), hs(0.0, 43.0, 0.0, 0.0)];
    let wedge = vec![hs(0.0, 3.0, 3.0, 0.0).complement(), hs(6.0, 0.0, 0.0, 0.0)];
    let c = complex(vec![block("point", point_block, O, 0), block("wedge", wedge, T, 3)]);
    let r = ray([0.0, 4.0, 12.0], [4.0, 5.0, 0.015625]);
    let p = c.partition(&r);
    let first = p.events.iter().find(|e| e.t > c.epsilon() && c.is_visible(e)).map(|e| (e.t, e.surface.block));
    assert_eq!(c.cast_ray(&r, f64::INFINITY).map(|h| (h.t, h.block)), first, "{p:?}");
}

/// The degenerate slab `y² <= 0` (the plane y = 0, no interior): the kernel
/// gives a sliver of length 6e-8 around the crossing (the square root of a
/// rounding-level discriminant), which lies outside the block's exact box
/// (`|y| <=` 1e-308). The partition (which meets the box at the crossing)
/// has the sliver's events; `cast_ray` with a transparent block present
/// probes the boxes at the sliver's ends and misses it.
#[test]
#[ignore = "open: cast_ray's box probes miss intervals the kernel puts outside a block's exact box (sqrt-ε slivers)"]
fn cast_ray_agrees_with_the_partition_on_a_zero_thickness_slab() {
    let slab = vec![Solid::from(
        Quadric::from_coefficients([0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).expect("finite"),
    )];
    let capped = vec![Solid::from(Quadric::tube_y()), hs(0.0, 1.0, 0.0, -2.0), hs(0.0, 43.0, 0.0, 0.0)];
    let c = complex(vec![block("disc", capped, T, 0), block("slab", slab, O, 0)]);
    let r = ray([17.0, 19.0, 3.0], [-6.0, -19.0, 2.0]);
    let p = c.partition(&r);
    let first = p.events.iter().find(|e| e.t > c.epsilon() && c.is_visible(e)).map(|e| (e.t, e.surface.block));
    assert_eq!(c.cast_ray(&r, f64::INFINITY).map(|h| (h.t, h.block)), first, "{p:?}");
}
