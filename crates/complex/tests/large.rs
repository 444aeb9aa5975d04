//! Blocks of any size: a box of water minus 289 pins (the complement of a
//! tube is non-convex, so the block has 289 non-convex solids, far more
//! than an interval set carries), checked against the exact reference
//! (`reference::csg::block_set`) and against membership sampled along the
//! ray (`Block::contains_point`), alone and in a complex with other blocks.

use complex::{Block, BlockId, BlockIntervals, Complex, ComplexOptions, Partition, Precision};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Interval, Quadric, Ray, Solid, Transform};
use reference::csg::block_set;
use reference::Rng;

use crate::common::*;

/// The box `[-9, 9] × [-1, 1] × [-9, 9]` minus `n × n` pins of radius 0.3
/// along y, at integer `x, z` centred on the origin.
fn drilled(n: i32) -> Vec<Solid> {
    let mut solids = cuboid([-9.0, -1.0, -9.0], [9.0, 1.0, 9.0]);
    let thin = Transform::scale_xyz(Vector3::new(0.3, 1.0, 0.3)).expect("finite");
    let half = n / 2;
    for i in -half..n - half {
        for k in -half..n - half {
            let m = thin.then(&translate(i as f64, 0.0, k as f64));
            solids.push(Solid::from(Quadric::tube_y().transformed(&m)).complement());
        }
    }
    solids
}

/// Rays through the plate: nearly horizontal (crossing many holes), and
/// steep ones.
fn rays(rng: &mut Rng, n: usize) -> Vec<Ray> {
    (0..n)
        .filter_map(|k| {
            let origin = Point3::new(rng.range(-12.0, 12.0), rng.range(-0.9, 0.9), rng.range(-12.0, 12.0));
            let d = if k % 3 == 0 {
                Vector3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))
            } else {
                Vector3::new(rng.range(-1.0, 1.0), rng.range(-0.02, 0.02), rng.range(-1.0, 1.0))
            };
            Ray::new(origin, d).ok()
        })
        .collect()
}

/// Each interval's inside and each gap between intervals, sampled at a few
/// points, against `contains_point` (points within `margin` of an end are
/// skipped: there the surface is a rounding away).
fn check_membership(b: &Block, ray: &Ray, ivs: &[Interval], margin: f64) {
    let mut cursor = 0.0;
    let far = ivs.last().map_or(30.0, |iv| if iv.exit.t.is_finite() { iv.exit.t + 5.0 } else { iv.enter.t + 30.0 });
    let mut pieces: Vec<(f64, f64, bool)> = Vec::new();
    for iv in ivs {
        pieces.push((cursor, iv.enter.t, false));
        pieces.push((iv.enter.t, iv.exit.t.min(far), true));
        cursor = iv.exit.t;
    }
    pieces.push((cursor, far, false));
    for (a, b_end, inside) in pieces {
        for f in [0.13, 0.5, 0.87] {
            let t = a + f * (b_end - a);
            if t - a < margin || b_end - t < margin || !t.is_finite() {
                continue;
            }
            assert_eq!(b.contains_point(&ray.at(t)), inside, "t = {t} in ({a}, {b_end}), {ray:?}");
        }
    }
}

#[test]
fn a_box_minus_289_pins_matches_the_exact_reference() {
    let solids = drilled(17);
    let plate = block("water", solids.clone(), T, 1);
    assert!(!plate.fits_interval_set());
    let mut rng = Rng::new(0xA11_5123);
    let mut out = Vec::new();
    let (mut most, mut rays_seen) = (0, 0);
    for ray in rays(&mut rng, 120) {
        plate.intervals_into(&ray, &mut out);
        let exact = block_set(&solids, &ray);
        assert_eq!(out.len(), exact.len(), "{ray:?}");
        for (iv, (e0, e1)) in out.iter().zip(&exact) {
            for (got, want) in [(iv.enter, e0), (iv.exit, e1)] {
                let w = want.to_f64();
                assert!(got.t == w || (got.t - w).abs() <= 1e-12 * w.abs().max(1.0), "{} vs {w}, {ray:?}", got.t);
                assert_eq!(got.solid(), want.solid(), "{ray:?}");
            }
        }
        check_membership(&plate, &ray, &out, 1e-9);
        most = most.max(out.len());
        rays_seen += 1;
    }
    // The case is what it says: many rays cross far more pieces than fit a set.
    assert!(most > quadric::IntervalSet::CAPACITY, "at most {most} intervals in {rays_seen} rays");
}

#[test]
fn certified_and_fast_large_blocks_agree_with_accurate() {
    let solids = drilled(9);
    let mut rng = Rng::new(0xCE27);
    let accurate = block("plate", solids.clone(), O, 0);
    let mut want = Vec::new();
    let mut got = Vec::new();
    for precision in [Precision::Certified, Precision::Fast] {
        let mut b = accurate.clone();
        b.set_precision(precision);
        for ray in rays(&mut rng, 40) {
            accurate.intervals_into(&ray, &mut want);
            b.intervals_into(&ray, &mut got);
            assert_eq!(got.len(), want.len(), "{precision:?} {ray:?}");
            for (g, w) in got.iter().zip(&want) {
                assert_eq!((g.enter.solid(), g.exit.solid()), (w.enter.solid(), w.exit.solid()));
                assert!((g.enter.t - w.enter.t).abs() <= 1e-9 && (g.exit.t - w.exit.t).abs() <= 1e-9 || g == w);
            }
        }
    }
}

/// A complex with the drilled plate, a post standing in one of its holes
/// (earlier: it owns the hole and more) and a ball above: the partition,
/// `cast_ray`, `contains_point` and `classify` against membership.
#[test]
fn queries_on_a_complex_with_a_large_block() {
    let blocks = vec![
        block("post", post(0.0, 0.0, 0.2, -3.0, 3.0), O, 0),
        block("water", drilled(17), T, 1),
        block("ball", vec![Solid::from(Quadric::sphere().transformed(&translate(2.0, 3.0, 2.0)))], O, 2),
    ];
    let c = Complex::new(blocks, ComplexOptions::default()).expect("valid");
    let owner = |p: &Point3<f64>| -> Option<BlockId> {
        // The priority rule by brute force: the first opaque block, else the first transparent one.
        let holding = |opaque: bool| {
            (0..3u32).map(BlockId).find(|&id| c.block(id).is_transparent() != opaque && c.block(id).contains_point(p))
        };
        holding(true).or_else(|| holding(false))
    };
    let mut rng = Rng::new(0x9_0213);
    let mut partition = Partition::default();
    let mut lists = BlockIntervals::new();
    let mut points = Vec::new();
    let mut water_rays = 0;
    for ray in rays(&mut rng, 150) {
        c.partition_into(&ray, &mut partition);
        for s in &partition.segments {
            let end = if s.end.is_finite() { s.end } else { s.start + 30.0 };
            if end - s.start < 1e-6 {
                continue;
            }
            let p = ray.at(0.5 * (s.start + end));
            assert_eq!(s.owner, owner(&p), "segment {s:?} of {ray:?}");
            points.push(p);
        }
        // cast_ray: the first visible event after ε.
        let first = partition.events.iter().find(|e| e.t > c.epsilon() && c.is_visible(e)).map(|e| e.t);
        assert_eq!(c.cast_ray(&ray, f64::INFINITY).map(|h| h.t), first, "{ray:?}");
        assert_eq!(c.occluded(&ray, 50.0), first.is_some_and(|t| t <= 50.0), "{ray:?}");
        // intervals_into: each block's intervals as block_intervals_into gives them, with the ε rule.
        c.intervals_into(&ray, &mut lists);
        let mut one = Vec::new();
        for id in (0..3u32).map(BlockId) {
            c.block_intervals_into(id, &ray, &mut one);
            one.retain(|iv| iv.exit.t > c.epsilon());
            assert_eq!(lists.get(id).unwrap_or(&[]), &one[..], "block {id:?}, {ray:?}");
        }
        water_rays += usize::from(lists.get(BlockId(1)).is_some_and(|ivs| ivs.len() > 8));
    }
    assert!(water_rays > 10, "only {water_rays} rays met the water in more than 8 intervals");
    // cast_rays: each answer is cast_ray's.
    let four = rays(&mut rng, 40);
    for r in four.chunks_exact(4) {
        let got = c.cast_rays(&[r[0], r[1], r[2], r[3]], f64::INFINITY);
        for (g, ray) in got.iter().zip(r) {
            assert_eq!(*g, c.cast_ray(ray, f64::INFINITY));
        }
    }
    let mut owners = vec![None; points.len()];
    c.classify(&points, &mut owners).expect("lengths match");
    for (p, o) in points.iter().zip(&owners) {
        assert_eq!(*o, owner(p), "{p:?}");
        assert_eq!(c.contains_point(p), *o, "{p:?}");
    }
}

/// The old forms still answer for blocks that fit, and say so (a panic
/// naming the block and the way out) where a set does not.
#[test]
fn interval_sets_answer_where_they_fit() {
    let c = complex(vec![block("water", drilled(17), T, 1), block("ball", vec![Solid::from(Quadric::sphere())], O, 0)]);
    // Through one row of holes: 17 holes, 18 pieces.
    let along = ray([-12.0, 0.0, 0.5], [1.0, 0.0, 0.0]);
    let mut ivs = Vec::new();
    c.block_intervals_into(BlockId(0), &along, &mut ivs);
    assert_eq!(ivs.len(), 1, "z = 0.5 runs between the rows");
    let across = ray([-12.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    c.block_intervals_into(BlockId(0), &across, &mut ivs);
    assert_eq!(ivs.len(), 18);
    // A set of the ball along the same ray, and of the plate where it fits.
    assert_eq!(c.block_intervals(BlockId(1), &across).len(), 1);
    assert_eq!(c.block_intervals(BlockId(0), &along).as_slice(), &ivs_of(&c, 0, &along)[..]);
    let blocked = std::panic::catch_unwind(|| c.block_intervals(BlockId(0), &across));
    let message = blocked.expect_err("18 intervals do not fit a set");
    let text = message.downcast_ref::<String>().expect("a formatted message");
    assert!(text.contains("\"water\"") && text.contains("block_intervals_into"), "{text}");
    assert!(std::panic::catch_unwind(|| c.intervals(&across)).is_err());
    assert!(std::panic::catch_unwind(|| c.block(BlockId(0)).intervals(&across)).is_err());
}

fn ivs_of(c: &Complex, id: u32, ray: &Ray) -> Vec<Interval> {
    let mut out = Vec::new();
    c.block_intervals_into(BlockId(id), ray, &mut out);
    out
}

/// `intervals_into` gives what `intervals` gives, on ordinary scenes.
#[test]
fn intervals_into_equals_intervals() {
    let mut rng = Rng::new(0x1_2077);
    let blocks: Vec<Block> = (0..40)
        .map(|k| {
            let (x, z) = (rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
            let solids = if k % 2 == 0 {
                post(x, z, rng.range(0.2, 1.0), -1.0, rng.range(0.0, 2.0))
            } else {
                // A hollow ball: non-convex, two pieces per ray.
                let m = Transform::scale(rng.range(0.5, 1.5)).expect("finite").then(&translate(x, 0.0, z));
                let inner = Transform::scale(0.5).expect("finite").then(&m);
                vec![
                    Solid::from(Quadric::sphere().transformed(&m)),
                    Solid::from(Quadric::sphere().transformed(&inner)).complement(),
                ]
            };
            block("b", solids, if k % 3 == 0 { T } else { O }, k % 2)
        })
        .collect();
    let c = complex(blocks);
    let mut lists = BlockIntervals::new();
    let mut met = 0;
    for ray in rays(&mut rng, 200) {
        c.intervals_into(&ray, &mut lists);
        let old = c.intervals(&ray);
        assert_eq!(lists.len(), old.len());
        for ((id, ivs), (old_id, set)) in lists.iter().zip(&old) {
            assert_eq!((id, ivs), (*old_id, set.as_slice()));
        }
        met += lists.len();
    }
    assert!(met > 100, "the rays met only {met} blocks");
}

/// `Precision::Certified` with two copies of a large block: every end of
/// the later one ties exactly with one of the earlier, so the partition
/// settles ties between large sets; its owners follow membership, and
/// the later copy owns nothing.
#[test]
fn certified_partition_settles_ties_between_large_blocks() {
    let plate = drilled(9);
    let mut c = complex(vec![block("first", plate.clone(), T, 0), block("second", plate, T, 1)]);
    c.set_precision(Precision::Certified);
    let mut rng = Rng::new(0x7_1E5);
    let mut partition = Partition::default();
    let mut inside = 0;
    for ray in rays(&mut rng, 30) {
        c.partition_into(&ray, &mut partition);
        for s in &partition.segments {
            assert_ne!(s.owner, Some(BlockId(1)), "the later copy owns {s:?} of {ray:?}");
            let end = if s.end.is_finite() { s.end } else { s.start + 30.0 };
            if end - s.start < 1e-6 {
                continue;
            }
            let p = ray.at(0.5 * (s.start + end));
            assert_eq!(s.owner.is_some(), c.block(BlockId(0)).contains_point(&p), "{s:?} of {ray:?}");
            inside += usize::from(s.owner.is_some());
        }
    }
    assert!(inside > 30, "only {inside} segments inside the plate");
}
