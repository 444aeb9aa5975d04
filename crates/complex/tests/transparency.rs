//! The transparency cases of docs/model.md §3.8: two overlapping blocks A
//! and B, A transparent, B opaque or transparent, inserted in either order,
//! with the same or a different material; and the three-block case a single
//! running-bounds pass gets wrong.
//!
//! Along the x axis A covers `[0, 4]` and B covers `[2, 6]` (unit squares
//! across). A ray traced on inside A (it starts at `x = 0.5`, going `+x`)
//! asks for the next interface: the point where the medium changes.

use complex::Opacity;

use crate::common::*;

/// Builds the two blocks in the given order and checks the next interface
/// of a ray starting inside A: its `x`, the block whose surface it is and
/// whether the ray enters that block there.
fn check(a_first: bool, b: Opacity, same_material: bool, expected: (f64, &str, bool)) {
    let a = block("A", cuboid([0.0, -1.0, -1.0], [4.0, 1.0, 1.0]), T, 1);
    let bb = block("B", cuboid([2.0, -1.0, -1.0], [6.0, 1.0, 1.0]), b, if same_material { 1 } else { 2 });
    let c = complex(if a_first { vec![a, bb] } else { vec![bb, a] });
    let r = ray([0.5, 0.0, 0.0], [1.0, 0.0, 0.0]);
    let hit = c.cast_ray(&r, f64::INFINITY).expect("a next interface");
    let got = (hit.point.x, name(&c, hit.block), hit.entering);
    assert_eq!(got, expected, "A first: {a_first}, B {b:?}, same material: {same_material}");
    // From outside, every case first meets A's face at x = 0.
    let outside = c.cast_ray(&ray([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]), f64::INFINITY).expect("a hit");
    assert_eq!((outside.t, name(&c, outside.block), outside.entering), (1.0, "A", true));
}

#[test]
fn opaque_b_is_met_at_its_front_face_in_either_order() {
    check(true, O, false, (2.0, "B", true));
    check(false, O, false, (2.0, "B", true));
    // The material of an opaque block is irrelevant to ownership.
    check(true, O, true, (2.0, "B", true));
}

#[test]
fn transparent_b_after_a_starts_where_a_ends() {
    // A owns the overlap: the medium changes at A's back face.
    check(true, T, false, (4.0, "A", false));
}

#[test]
fn transparent_b_before_a_takes_over_at_its_front_face() {
    check(false, T, false, (2.0, "B", true));
}

#[test]
fn same_material_makes_one_medium_until_b_ends() {
    check(true, T, true, (6.0, "B", false));
    check(false, T, true, (6.0, "B", false));
}

#[test]
fn the_invisible_interface_is_still_in_the_partition() {
    let a = block("A", cuboid([0.0, -1.0, -1.0], [4.0, 1.0, 1.0]), T, 1);
    let b = block("B", cuboid([2.0, -1.0, -1.0], [6.0, 1.0, 1.0]), T, 1);
    let c = complex(vec![a, b]);
    let p = c.partition(&ray([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    let events: Vec<(f64, bool)> = p.events.iter().map(|e| (e.t, e.same_medium)).collect();
    assert_eq!(events, [(1.0, false), (5.0, true), (7.0, false)]);
    assert_eq!(p.events.iter().filter(|e| c.is_visible(e)).count(), 2);
}

/// The single-pass shortcut of docs/model.md §3.8 ("Why the partition must
/// be exact"), literally: the blocks' single intervals in insertion order,
/// returning `[λmin, λmax]`.
fn single_pass_shortcut(blocks: &[(f64, f64, bool)]) -> (f64, f64) {
    let (mut lmin, mut lmax) = (f64::INFINITY, f64::INFINITY);
    for &(l1, l2, transparent) in blocks {
        if transparent {
            if l2 < lmin {
                lmax = l2;
            } else if l1 < lmax {
                lmax = lmax.max(l1);
            }
            lmin = lmin.min(l1);
        } else {
            lmin = lmin.min(l1);
            lmax = lmax.min(l1);
        }
    }
    (lmin, lmax)
}

#[test]
fn three_blocks_of_one_medium_joined_by_a_later_block() {
    // A = [0, 2] and C = [4, 6] are joined by B = [1, 5], inserted last; all
    // transparent with one material, so the ray crosses one medium from x = 0
    // to x = 6. The single pass sees C before the connecting piece B and so
    // ignores it.
    let a = block("A", cuboid([0.0, -1.0, -1.0], [2.0, 1.0, 1.0]), T, 7);
    let cc = block("C", cuboid([4.0, -1.0, -1.0], [6.0, 1.0, 1.0]), T, 7);
    let b = block("B", cuboid([1.0, -1.0, -1.0], [5.0, 1.0, 1.0]), T, 7);
    let c = complex(vec![a, cc, b]);
    let from_outside = ray([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    // The ray's intervals in insertion order: A [1, 3], C [5, 7], B [2, 6].
    let shortcut = single_pass_shortcut(&[(1.0, 3.0, true), (5.0, 7.0, true), (2.0, 6.0, true)]);
    assert_eq!(shortcut.0, 1.0);
    assert_ne!(shortcut.1, 7.0, "the single pass should miss the rear block");
    let first = c.cast_ray(&from_outside, f64::INFINITY).expect("entry");
    assert_eq!((first.t, name(&c, first.block), first.entering), (1.0, "A", true));
    let inside = ray([0.5, 0.0, 0.0], [1.0, 0.0, 0.0]);
    let next = c.cast_ray(&inside, f64::INFINITY).expect("exit");
    assert_eq!((next.point.x, name(&c, next.block), next.entering), (6.0, "C", false));
}

#[test]
fn three_overlapping_blocks_follow_priority() {
    // T1 = [0, 6] (first), O = [2, 3] opaque, T2 = [1, 8] other material.
    // Owners along x: T1 [0, 2], O [2, 3], T1 [3, 6], T2 [6, 8].
    let t1 = block("T1", cuboid([0.0, -1.0, -1.0], [6.0, 1.0, 1.0]), T, 1);
    let o = block("O", cuboid([2.0, -1.0, -1.0], [3.0, 1.0, 1.0]), O, 0);
    let t2 = block("T2", cuboid([1.0, -1.0, -1.0], [8.0, 1.0, 1.0]), T, 2);
    let c = complex(vec![t1, o, t2]);
    let p = c.partition(&ray([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    let got: Vec<(f64, &str, bool)> =
        p.events.iter().map(|e| (e.point.x, name(&c, e.surface.block), e.entering)).collect();
    assert_eq!(got, [(0.0, "T1", true), (2.0, "O", true), (3.0, "O", false), (6.0, "T1", false), (8.0, "T2", false)]);
    let owners: Vec<Option<&str>> = p.segments.iter().map(|s| s.owner.map(|id| name(&c, id))).collect();
    assert_eq!(owners, [None, Some("T1"), Some("O"), Some("T1"), Some("T2"), None]);
}

#[test]
fn same_material_behind_an_opaque_block_is_one_medium() {
    // As above with T2 in T1's material: from inside T1 past O (x = 3.5) the
    // change to T2 at x = 6 is no interface; the next one is T2's exit.
    let t1 = block("T1", cuboid([0.0, -1.0, -1.0], [6.0, 1.0, 1.0]), T, 1);
    let o = block("O", cuboid([2.0, -1.0, -1.0], [3.0, 1.0, 1.0]), O, 0);
    let t2 = block("T2", cuboid([1.0, -1.0, -1.0], [8.0, 1.0, 1.0]), T, 1);
    let c = complex(vec![t1, o, t2]);
    let hit = c.cast_ray(&ray([3.5, 0.0, 0.0], [1.0, 0.0, 0.0]), f64::INFINITY).expect("exit");
    assert_eq!((hit.point.x, name(&c, hit.block), hit.entering), (8.0, "T2", false));
    // From inside O, the next interface is O's back face into T1.
    let hit = c.cast_ray(&ray([2.5, 0.0, 0.0], [1.0, 0.0, 0.0]), f64::INFINITY).expect("exit");
    assert_eq!((hit.point.x, name(&c, hit.block), hit.entering), (3.0, "O", false));
}
