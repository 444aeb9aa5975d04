//! `cast_ray`, `cast_rays` and `occluded` never allocate, with or without
//! transparent blocks; nor do the batch queries into buffers already grown.

use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::TestRunner;
use quadric::{strategies, Quadric, Ray, Solid};

use crate::common::*;

fn scene(transparent_every: usize) -> (Complex, Vec<Ray>) {
    let mut runner = TestRunner::deterministic();
    let mut blocks = Vec::new();
    for i in 0..300 {
        let m = strategies::transform().new_tree(&mut runner).expect("tree").current();
        let m = quadric::Transform::scale(0.2).expect("finite").then(&m);
        let mut solids = vec![Solid::from(Quadric::sphere().transformed(&m))];
        if i % 3 == 0 {
            solids.push(hs(0.0, 1.0, 0.0, 0.0).transformed(&m));
        }
        let opacity =
            if transparent_every > 0 && i % transparent_every == 0 { Opacity::Transparent } else { Opacity::Opaque };
        blocks.push(Block::new("b", solids, opacity, MaterialKey(i as u32 % 3)).expect("valid"));
    }
    // An unbounded block too, so that list is exercised.
    blocks.push(Block::new("floor", vec![hs(0.0, 1.0, 0.0, 6.0)], Opacity::Opaque, MaterialKey(9)).expect("valid"));
    let rays = (0..500).map(|_| strategies::ray(5.0).new_tree(&mut runner).expect("tree").current()).collect();
    (Complex::new(blocks, ComplexOptions::default()).expect("valid"), rays)
}

fn hits(c: &Complex, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| c.cast_ray(r, f64::INFINITY).is_some()).count()
}

#[test]
fn the_counter_sees_allocations() {
    let info = allocation_counter::measure(|| {
        std::hint::black_box(vec![1u8; 16]);
    });
    assert!(info.count_total >= 1, "the counting allocator is not installed");
}

#[test]
fn cast_ray_does_not_allocate() {
    for transparent_every in [0, 4] {
        let (c, rays) = scene(transparent_every);
        let mut n = 0;
        let info = allocation_counter::measure(|| n = hits(&c, &rays));
        assert!(n > 50, "the scene should be hit often, got {n}");
        assert_eq!(info.count_total, 0, "cast_ray allocated (transparent every {transparent_every})");
    }
}

#[test]
fn cast_rays_does_not_allocate() {
    for transparent_every in [0, 4] {
        let (c, rays) = scene(transparent_every);
        let mut n = 0;
        let info = allocation_counter::measure(|| {
            for r in rays.chunks_exact(4) {
                n += c.cast_rays(&[r[0], r[1], r[2], r[3]], f64::INFINITY).iter().flatten().count();
            }
        });
        assert!(n > 50, "the scene should be hit often, got {n}");
        assert_eq!(info.count_total, 0, "cast_rays allocated (transparent every {transparent_every})");
    }
}

#[test]
fn occluded_does_not_allocate() {
    for transparent_every in [0, 4] {
        let (c, rays) = scene(transparent_every);
        let mut n = 0;
        let info = allocation_counter::measure(|| n = rays.iter().filter(|r| c.occluded(r, 8.0)).count());
        assert!(n > 50, "the scene should block often, got {n}");
        assert_eq!(info.count_total, 0, "occluded allocated (transparent every {transparent_every})");
    }
}

/// The counts of allocations (on the measuring thread) of `classify`,
/// `cast_many` and `trace_many` (the latter into a `Traces` already grown
/// by the same batch) of the first `n` of 20 copies of the scene's rays.
fn batch_allocations(c: &Complex, rays: &[Ray], n: usize) -> [u64; 3] {
    let rays: Vec<Ray> = rays.iter().cycle().take(n).copied().collect();
    let points: Vec<_> = rays.iter().map(|r| r.at(4.0)).collect();
    let mut owners = vec![None; n];
    let mut hits = vec![None; n];
    let mut traces = complex::Traces::new();
    c.trace_many(&rays, &mut traces);
    let classify = allocation_counter::measure(|| c.classify(&points, &mut owners).expect("lengths match"));
    let cast = allocation_counter::measure(|| c.cast_many(&rays, f64::INFINITY, &mut hits).expect("lengths match"));
    let trace = allocation_counter::measure(|| c.trace_many(&rays, &mut traces));
    [classify.count_total, cast.count_total, trace.count_total]
}

#[test]
fn batch_queries_do_not_allocate_per_query() {
    for transparent_every in [0, 4] {
        let (c, rays) = scene(transparent_every);
        // One chunk each (100 rays): on the calling thread, nothing at all.
        assert_eq!(batch_allocations(&c, &rays, 100), [0; 3], "transparent every {transparent_every}");
        // Many chunks through rayon, measured on the one thread of a pool,
        // which runs them all (the counter counts the measuring thread's
        // allocations): rayon's jobs live on the stack, so again nothing.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool");
        for n in [3_000, 10_000] {
            let counts = pool.install(|| batch_allocations(&c, &rays, n));
            assert_eq!(counts, [0; 3], "{n} queries, transparent every {transparent_every}");
        }
    }
}

/// A block with more non-convex solids than an interval set carries (a
/// plate drilled by 100 holes) keeps its intervals in a heap buffer, taken
/// from a per-thread pool: once the first query on a thread has made it,
/// the queries allocate nothing more.
#[test]
fn large_blocks_allocate_once_per_thread() {
    let mut solids = cuboid([-6.0, -1.0, -6.0], [6.0, 1.0, 6.0]);
    for i in -5..5 {
        for k in -5..5 {
            let m = quadric::Transform::scale_xyz(quadric::nalgebra::Vector3::new(0.3, 1.0, 0.3))
                .expect("finite")
                .then(&translate(i as f64, 0.0, k as f64));
            solids.push(Solid::from(Quadric::tube_y().transformed(&m)).complement());
        }
    }
    let plate = Block::new("plate", solids, Opacity::Transparent, MaterialKey(1)).expect("valid");
    let (c, mut rays) = scene(4);
    // Rays along the plate, through its rows of holes.
    rays.extend((0..200).map(|k| {
        let (y, z, dz) = (-0.9 + 0.009 * k as f64, -5.5 + 0.055 * k as f64, 0.1 * ((k % 7) as f64 - 3.0));
        Ray::new(quadric::nalgebra::Point3::new(-8.0, y, z), quadric::nalgebra::Vector3::new(1.0, 0.0, dz))
            .expect("valid")
    }));
    let mut blocks = c.blocks().to_vec();
    blocks.push(plate);
    let c = Complex::new(blocks, ComplexOptions::default()).expect("valid");
    let mut partition = complex::Partition::default();
    let mut lists = complex::BlockIntervals::new();
    // The case is what it says: the plate spills.
    let plate = complex::BlockId(c.blocks().len() as u32 - 1);
    let spilled = rays
        .iter()
        .filter(|r| {
            c.intervals_into(r, &mut lists);
            lists.get(plate).is_some_and(|ivs| ivs.len() > quadric::IntervalSet::CAPACITY)
        })
        .count();
    assert!(spilled >= 10, "only {spilled} rays meet the plate in more intervals than a set carries");
    let mut run = || {
        let mut n = 0;
        for r in &rays {
            n += usize::from(c.cast_ray(r, f64::INFINITY).is_some());
            n += usize::from(c.occluded(r, 8.0));
            c.partition_into(r, &mut partition);
            c.intervals_into(r, &mut lists);
            n += lists.len();
        }
        n
    };
    // Warm-up: the buffers grow.
    let n = run();
    assert!(n > 100, "the scene should be hit often, got {n}");
    let info = allocation_counter::measure(|| {
        run();
    });
    assert_eq!(info.count_total, 0, "queries allocated after warm-up");
}

/// The scene placed as definitions: a translated 2 × 1 × 2 lattice of its
/// balls and a rotated, scaled instance of all of it, with an own block
/// between them.
fn assembled(transparent_every: usize) -> (Complex, Vec<Ray>) {
    use complex::{Member, Placement};
    use quadric::nalgebra::Vector3;
    use quadric::Transform;
    let (definition, rays) = scene(transparent_every);
    // A lattice's definition is bounded: the scene without its floor.
    let balls = Complex::new(definition.blocks()[..300].to_vec(), ComplexOptions::default()).expect("valid");
    let definition = std::sync::Arc::new(definition);
    let lattice = Placement {
        pitch: Vector3::new(3.0, 0.0, 3.0),
        count: [2, 1, 2],
        ..Placement::instance(
            std::sync::Arc::new(balls),
            Transform::translate(Vector3::new(-1.5, 0.0, -1.5)).expect("finite"),
        )
    };
    let turn = Transform::scale(0.5).expect("finite").then(&Transform::rotate_y_degrees(30.0).expect("finite"));
    let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(1));
    let members = vec![
        Member::Placed(lattice),
        Member::Block(ball.expect("valid")),
        Member::Placed(Placement::instance(definition, turn)),
    ];
    (Complex::assemble(members, ComplexOptions::default()).expect("valid"), rays)
}

#[test]
fn assembled_scenes_do_not_allocate() {
    for transparent_every in [0, 4] {
        let (c, rays) = assembled(transparent_every);
        let mut n = 0;
        let info = allocation_counter::measure(|| n = hits(&c, &rays));
        assert!(n > 50, "the scene should be hit often, got {n}");
        assert_eq!(info.count_total, 0, "cast_ray allocated (transparent every {transparent_every})");
        let info = allocation_counter::measure(|| n = rays.iter().filter(|r| c.occluded(r, 8.0)).count());
        assert_eq!(info.count_total, 0, "occluded allocated (transparent every {transparent_every})");
        let info = allocation_counter::measure(|| {
            for r in rays.chunks_exact(4) {
                std::hint::black_box(c.cast_rays(&[r[0], r[1], r[2], r[3]], f64::INFINITY));
            }
        });
        assert_eq!(info.count_total, 0, "cast_rays allocated (transparent every {transparent_every})");
    }
}
