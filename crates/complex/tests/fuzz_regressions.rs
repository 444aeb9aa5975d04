//! Minimised inputs from the `complex_queries` fuzz target (`fuzz/`), one
//! test each: the shape of the input, the law it tests and what would break
//! it.

use complex::{BlockId, Complex};
use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::{strategies, Quadric, Ray, Solid, Transform};

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
/// returns the tube's axis as exactly z (the tilt is far below its
/// tolerance), and a box bounded in y around the far centre would hide the
/// tube at the origin from the BVH path.
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
/// positive, it would make the quadric an "empty cylinder" and the box empty.
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
/// meets the box at t = 0) has the exit event; `cast_ray`, probing the boxes
/// at t = ε, must find it too.
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
/// (`|y| <=` 1e-308). The partition meets the box at the crossing;
/// `cast_ray` with a transparent block present probes the boxes at the
/// sliver's ends, which lie outside it. Every query reads a block's set
/// clipped to its box (`Complex::block_intervals`), so both see the same
/// (clipped) sliver.
#[test]
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

/// A transparent block that is a huge capped tube: `x² + z² <= 1` with
/// `y <= 0` (and `y <= 2`), scaled by -1.35e28 (so it becomes `y >= 12`
/// after the move by (4, 12, 4), with a radius of 1.35e28). The plane `y = 0`
/// was first moved 59 along itself, so its reference point ends up 8e29 away
/// (in z); the half-space kernel is accurate to the ulps of that distance
/// (1e14), and puts the ray origin (y = 0) inside. Unclipped, the partition
/// (which crosses the block's box from t = 0) would start inside the block
/// with only the exit at t = 1.36e28, while `cast_ray`, probing the box
/// (y >= 11.99…) at t = ε, finds the ray outside. With the sets clipped to
/// the boxes both see the entry at y = 12 (t = 4√409, to the box's
/// widening) and then the exit.
#[test]
fn cast_ray_and_partition_agree_on_a_far_referenced_half_space() {
    let m = Transform::scale(-1.3476555094338099e28).expect("finite").then(&translate(4.0, 12.0, 4.0));
    let solids = vec![
        Solid::from(Quadric::tube_y()),
        hs(0.0, 1.0, 0.0, -2.0),
        hs(0.0, 1.0, 0.0, 0.0).transformed(&translate(0.0, 0.0, -59.0)),
    ];
    let c = complex(vec![block("huge", moved(&solids, &m), T, 3)]);
    let r = ray([0.0, 0.0, 0.046875], [0.0, 3.0, -20.0]);
    let p = c.partition(&r);
    let visible: Vec<_> = p.events.iter().filter(|e| e.t > c.epsilon() && c.is_visible(e)).collect();
    let first = visible.first().map(|e| (e.t, e.surface.block, e.entering));
    assert_eq!(c.cast_ray(&r, f64::INFINITY).map(|h| (h.t, h.block, h.entering)), first, "{p:?}");
    // The exact geometry: y = 3t/√409 reaches 12 at t = 4√409.
    let entry = 4.0 * 409f64.sqrt();
    let [e0, e1] = visible[..] else { panic!("an entry and an exit: {p:?}") };
    assert!(e0.entering && (e0.t - entry).abs() <= 1e-9 * entry, "entry {e0:?}, want t = {entry}");
    assert_eq!(e0.surface.solid, 2, "the entry is on the plane y = 12: {e0:?}");
    assert!(!e1.entering && (e1.t / 1.3627322987218422e28 - 1.0).abs() <= 1e-9, "exit {e1:?}");
    assert_eq!(c.contains_point(&r.at(1.0)), None, "the ray starts below y = 12");
}

/// The two cases above are one class: the kernel puts part of a block's set
/// outside the block's exact box (a √ε sliver of a degenerate quadric, a
/// crossing of a half-space whose reference point is far away), where a
/// query that probes the boxes could disagree with one that does not.
fn box_escaping_solid() -> impl Strategy<Value = Solid> {
    let axis = 0usize..3;
    // `x_i² <= 0` (or a slab of half-width 1e-9), placed anywhere.
    let slab = (axis.clone(), any::<bool>(), strategies::transform()).prop_map(|(i, thin, m)| {
        let mut c = [0.0; 10];
        c[i] = 1.0;
        c[9] = if thin { -1e-18 } else { 0.0 };
        Solid::from(Quadric::from_coefficients(c).expect("finite").transformed(&m))
    });
    // An axis-aligned plane near the origin with its reference point moved
    // 10^k along the plane (which leaves the plane where it is), then scaled.
    let far_plane = (axis, 1usize..3, any::<bool>(), -3.0f64..3.0, 10i32..30, -2i32..3, any::<bool>()).prop_map(
        |(i, j, up, d, k, e, flip)| {
            let mut n = [0.0; 3];
            n[i] = if up { 1.0 } else { -1.0 };
            let mut v = Vector3::zeros();
            v[(i + j) % 3] = 10f64.powi(k);
            let s = 10f64.powi(e) * if flip { -1.0 } else { 1.0 };
            let m = Transform::translate(v).expect("finite").then(&Transform::scale(s).expect("finite"));
            hs(n[0], n[1], n[2], d).transformed(&m)
        },
    );
    prop_oneof![slab, far_plane, strategies::solid()]
}

/// `cast_ray` against the first visible event of the partition, and
/// `occluded` against `cast_ray`.
fn check_cast_against_partition(c: &Complex, r: &Ray) -> Result<(), TestCaseError> {
    let p = c.partition(r);
    prop_assert_eq!(p.events.len() + 1, p.segments.len(), "{:?}", p);
    let first = p.events.iter().find(|e| e.t > c.epsilon() && c.is_visible(e));
    let want = first.map(|e| (e.t, e.surface.block, e.surface.solid, e.entering));
    let hit = c.cast_ray(r, f64::INFINITY);
    prop_assert_eq!(hit.map(|h| (h.t, h.block, h.solid, h.entering)), want, "{:?}", p);
    prop_assert_eq!(c.occluded(r, f64::INFINITY), want.is_some());
    for (id, set) in c.intervals(r) {
        let b = c.block_aabb(id);
        for iv in &set {
            for t in [iv.enter.t, iv.exit.t].into_iter().filter(|t| t.is_finite()) {
                // The box (grown by its pad of 1e-13 of the ray origin and a
                // few ulps of the slab test) holds every finite end.
                let x = r.at(t);
                let pad = 1e-12 * (1.0 + r.origin().coords.amax() + x.coords.amax());
                let inside = (0..3).all(|k| b.min[k] - pad <= x[k] && x[k] <= b.max[k] + pad);
                prop_assert!(inside, "end {} of block {:?} at {:?} outside its box {:?}", t, id, x, b);
            }
        }
    }
    Ok(())
}

proptest! {
    #[test]
    fn cast_ray_and_partition_agree_when_the_kernel_leaves_a_box(
        blocks in proptest::collection::vec(
            (proptest::collection::vec(box_escaping_solid(), 1..=3), any::<bool>(), 0u32..2), 1..=4),
        rays in proptest::collection::vec(strategies::ray(20.0), 4),
    ) {
        let blocks = blocks
            .into_iter()
            .enumerate()
            .filter_map(|(i, (solids, t, m))| {
                complex::Block::new(format!("b{i}"), solids, if t { T } else { O }, complex::MaterialKey(m)).ok()
            })
            .collect();
        let c = Complex::new(blocks, complex::ComplexOptions::default()).expect("valid");
        for r in &rays {
            check_cast_against_partition(&c, r)?;
        }
    }
}

/// A rotated tube is an ideal cylinder (it carries its axis, see
/// `Quadric::axis`) although its stored `A` is slightly definite: its box
/// must be unbounded along the axis, or clipping the sets to the box would
/// close it ~10⁸ out.
#[test]
fn a_rotated_tube_keeps_an_unbounded_box_and_its_far_exit() {
    let m = Transform::rotate_x_degrees(30.0).expect("finite");
    let c = complex(vec![block("tube", vec![Solid::from(Quadric::tube_z().transformed(&m))], O, 0)]);
    let b = c.block_aabb(BlockId(0));
    assert!(b.min.y == f64::NEG_INFINITY && b.max.z == f64::INFINITY, "{b:?}");
    let (axis, across) = (m.apply_vector(&Vector3::z()), m.apply_vector(&Vector3::y()));
    let dir = Vector3::x() + axis * 0.3;
    let r = Ray::new(Point3::from(axis * 1e9 + across * 0.5), dir).expect("valid ray");
    let expected = 0.75f64.sqrt() * dir.norm();
    let hit = c.cast_ray(&r, f64::INFINITY).expect("the ray leaves the tube");
    assert!(!hit.entering && (hit.t - expected).abs() < 16.0 * f64::EPSILON * 1e9, "{hit:?} vs {expected}");
}

/// The block box must hold every point of the block. The origin lies on a
/// sphere of radius 8.2e35 centred 8.2e35 away (rotated by 8.2e35° twice),
/// inside a tube along y and on a half-space's plane. Narrowing the tube's box by the
/// sphere, `C = k + a Σ dⱼ²` cancels to rounding noise (`dⱼ ≈ 8e35` rounded
/// at 1e20): the emptiness margin must be relative to the magnitudes `C` is
/// formed from, not to `|a C|` itself, or the box comes out empty.
#[test]
fn the_box_holds_a_point_on_a_huge_sphere() {
    let rot = Transform::rotate_y_degrees(8.224e35).expect("finite");
    let place = rot.then(&rot);
    let solids = vec![
        Solid::from(Quadric::tube_y()),
        hs(0.0, 1.0, 52.0, 0.0).complement().transformed(
            &Transform::rotate_x_degrees(2.0).expect("finite").then(&translate(3.0, 0.0, 3.3402806000149546e-294)),
        ),
        Solid::from(
            Quadric::sphere().transformed(&translate(0.0, 0.0, 1.0).then(&Transform::scale(8.224e35).expect("finite"))),
        ),
    ];
    let c = complex(vec![block("b", moved(&solids, &place), O, 0)]);
    let o = Point3::origin();
    assert!(c.block(BlockId(0)).contains_point(&o));
    assert!(c.block_aabb(BlockId(0)).contains_point(&o), "{:?}", c.block_aabb(BlockId(0)));
    assert_eq!(c.contains_point(&o), Some(BlockId(0)));
}
