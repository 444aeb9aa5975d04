//! Batch queries (`classify`, `cast_many`, `trace_many`) answer each query
//! exactly as the single query does, bit for bit, at every batch size and on
//! pools of one and two threads; they allocate nothing per query.

use complex::{BlockId, Complex, ComplexError, Hit, Partition, Segment, Traces};
use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;

use crate::oracle::{build, complex_spec, ray_spec, small_block};

/// Batch sizes: empty, below, at and above a packet of four, and more than
/// one chunk of each query (300 rays: two chunks of rays to cast, three to
/// trace; 1,200 points: two to classify), so the parallel path runs too.
const SIZES: [usize; 6] = [0, 1, 3, 4, 5, 300];

/// The pool of one or two threads, built once for all cases.
fn pool(threads: usize) -> &'static rayon::ThreadPool {
    static POOLS: std::sync::OnceLock<[rayon::ThreadPool; 2]> = std::sync::OnceLock::new();
    let build = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("a thread pool");
    &POOLS.get_or_init(|| [build(1), build(2)])[threads - 1]
}

/// `n` rays from the given ones, cycled, each copy's origin nudged a little
/// so that the batch is not one ray repeated (and four in a row point
/// different ways unless there is one ray: `cast_many` casts them one by one).
fn batch_of(rays: &[Ray], n: usize) -> Vec<Ray> {
    if rays.is_empty() {
        return Vec::new();
    }
    (0..n)
        .map(|i| {
            let r = rays[i % rays.len()];
            let k = (i / rays.len()) as f64;
            Ray::new(r.origin() + 1e-3 * k * Vector3::new(1.0, -0.7, 0.3), r.direction()).unwrap_or(r)
        })
        .collect()
}

/// `n` rays in bundles of four near-parallel rays from one origin, as a
/// camera's neighbouring pixels are: `cast_many` sends them through the
/// packet walk.
fn bundles_of(rays: &[Ray], n: usize) -> Vec<Ray> {
    if rays.is_empty() {
        return Vec::new();
    }
    (0..n)
        .map(|i| {
            let r = rays[(i / 4) % rays.len()];
            let e = [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::zeros()][i % 4];
            Ray::new(r.origin(), r.direction() + 1e-3 * e).unwrap_or(r)
        })
        .collect()
}

/// Four points along each ray, from its origin to past the scene.
fn points_of(rays: &[Ray]) -> Vec<Point3<f64>> {
    (0..4 * rays.len()).map(|i| rays[i / 4].at(0.37 * (i % 23) as f64)).collect()
}

/// A hit as bits, so that `-0.0` and `0.0` differ.
fn hit_bits(h: &Option<Hit>) -> Option<([u64; 7], bool, BlockId, u32)> {
    h.map(|h| {
        let f = [h.t, h.point.x, h.point.y, h.point.z, h.normal.x, h.normal.y, h.normal.z];
        (f.map(f64::to_bits), h.entering, h.block, h.solid)
    })
}

fn segment_bits(s: &Segment) -> (u64, u64, Option<BlockId>) {
    (s.start.to_bits(), s.end.to_bits(), s.owner)
}

/// Every batch query on `rays` (and points along them), on pools of one and
/// two threads, equals the single queries bit for bit.
fn batches_agree(c: &Complex, rays: &[Ray], max_t: f64) -> Result<(), TestCaseError> {
    let points = points_of(rays);
    let want_owners: Vec<_> = points.iter().map(|p| c.contains_point(p)).collect();
    let want_hits: Vec<_> = rays.iter().map(|r| hit_bits(&c.cast_ray(r, max_t))).collect();
    let mut scratch = Partition::default();
    let want_traces: Vec<Vec<_>> = rays
        .iter()
        .map(|r| {
            c.segments_into(r, &mut scratch);
            scratch.segments.iter().map(segment_bits).collect()
        })
        .collect();
    for threads in [1, 2] {
        let (owners, hits, traces) = pool(threads).install(|| {
            let mut owners = vec![Some(BlockId(u32::MAX)); points.len()];
            c.classify(&points, &mut owners).expect("lengths match");
            let mut hits = vec![None; rays.len()];
            c.cast_many(rays, max_t, &mut hits).expect("lengths match");
            let mut traces = Traces::new();
            c.trace_many(rays, &mut traces);
            (owners, hits, traces)
        });
        prop_assert_eq!(&owners, &want_owners, "classify, {} threads", threads);
        let hits: Vec<_> = hits.iter().map(hit_bits).collect();
        prop_assert_eq!(&hits, &want_hits, "cast_many, {} threads, max_t = {}", threads, max_t);
        prop_assert_eq!(traces.len(), rays.len());
        prop_assert_eq!(traces.offsets().len(), rays.len() + 1);
        let got: Vec<Vec<_>> = traces.iter().map(|s| s.iter().map(segment_bits).collect()).collect();
        prop_assert_eq!(&got, &want_traces, "trace_many, {} threads", threads);
    }
    Ok(())
}

proptest! {
    // Each case runs some 600 rays through every query on two pools and
    // through each single query: a thirty-second of the usual count (31
    // cases at CI's 1,000) keeps the suite's time.
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 32).max(8)))]

    /// On 3 to 8 overlapping blocks, opaque and transparent, in shuffled
    /// priority: every batch size, both pools, the single queries' answers.
    #[test]
    fn batch_queries_equal_single_queries(
        specs in complex_spec(),
        rays in proptest::collection::vec(ray_spec(), 1..12),
        max_t in prop_oneof![Just(f64::INFINITY), 0.5f64..6.0],
    ) {
        let c = build(&specs);
        for n in SIZES {
            batches_agree(&c, &batch_of(&rays, n), max_t)?;
            batches_agree(&c, &bundles_of(&rays, n), max_t)?;
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 32).max(4)))]

    /// On 150 to 250 small blocks (a deep BVH, rays that miss most blocks),
    /// all opaque (the packet walk of `cast_rays`) or some transparent.
    #[test]
    fn batch_queries_equal_single_queries_on_large_scenes(
        specs in proptest::collection::vec(small_block(), 150..250),
        rays in proptest::collection::vec(ray_spec(), 16),
        all_opaque in any::<bool>(),
    ) {
        let specs: Vec<_> = specs.into_iter().map(|(s, t, m)| (s, t && !all_opaque, m)).collect();
        let c = build(&specs);
        batches_agree(&c, &batch_of(&rays, 1000), f64::INFINITY)?;
        batches_agree(&c, &bundles_of(&rays, 1000), f64::INFINITY)?;
    }
}

#[test]
fn a_batch_with_too_few_or_too_many_answer_slots_is_an_error() {
    let c = build(&[(crate::common::cuboid([-1.0; 3], [1.0; 3]), false, 0)]);
    let rays = batch_of(&[crate::common::ray([-3.0, 0.0, 0.0], [1.0, 0.0, 0.0])], 5);
    let points = &points_of(&rays)[..5];
    for answers in [0, 4, 6] {
        let mismatch = Err(ComplexError::LengthMismatch { queries: 5, answers });
        let mut owners = vec![Some(BlockId(7)); answers];
        assert_eq!(c.classify(points, &mut owners), mismatch);
        assert!(owners.iter().all(|o| *o == Some(BlockId(7))), "classify wrote into a mismatched slice");
        let mut hits = vec![None; answers];
        assert_eq!(c.cast_many(&rays, f64::INFINITY, &mut hits), mismatch);
        assert!(hits.iter().all(Option::is_none), "cast_many wrote into a mismatched slice");
    }
    assert_eq!(
        ComplexError::LengthMismatch { queries: 5, answers: 4 }.to_string(),
        "a batch of 5 queries needs 5 answer slots, got 4"
    );
}

#[test]
fn traces_reused_for_a_smaller_batch_hold_only_that_batch() {
    let c = build(&[(crate::common::cuboid([-1.0; 3], [1.0; 3]), true, 0)]);
    let rays = batch_of(&[crate::common::ray([-3.0, 0.0, 0.0], [1.0, 0.0, 0.0])], 700);
    let mut reused = Traces::new();
    assert!(reused.is_empty() && reused.ray(0).is_none());
    c.trace_many(&rays, &mut reused);
    for n in [3, 0, 700, 1] {
        c.trace_many(&rays[..n], &mut reused);
        let mut fresh = Traces::new();
        c.trace_many(&rays[..n], &mut fresh);
        assert_eq!(reused, fresh, "{n} rays");
        assert_eq!((reused.len(), reused.offsets().len()), (n, n + 1));
        assert_eq!(reused.ray(n), None);
        assert_eq!(reused.segments().len(), 3 * n, "in, through and out of the box");
    }
}
