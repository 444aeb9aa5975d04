//! A small complex (1 to 8 blocks of up to 6 fuzzed solids each, opaque or
//! transparent, with material keys), rays and points. Checks: bad blocks and
//! ε are rejected with the right error; no panic; the BVH path
//! (`Complex::intervals`, `contains_point`) equals a brute force over all
//! blocks; every block box holds the block's points; the partition covers
//! `[0, ∞)` in order without gaps, its owners follow the priority rule and its
//! events sit between its segments; `cast_ray` returns the first visible
//! event of the partition in `(ε, max_t]`, with a finite point and normal;
//! `segments_into` gives the partition's segments, `segments_within` those
//! that start before `max_t`, and `first_interface` its first interface.
#![no_main]

use complex::{Block, BlockId, Complex, ComplexError, ComplexOptions, MaterialKey, Occluder, Opacity, Partition};
use komplex_fuzz::{bound, BlockSpec, ComplexInput};
use libfuzzer_sys::fuzz_target;
use quadric::nalgebra::Point3;
use quadric::{IntervalSet, Ray, Solid};

/// How far along a ray the BVH path must agree with the brute force.
const FAR: f64 = 1e100;

/// Whether `ray.at(t)` is within `FAR` of the origin of coordinates.
fn near(ray: &Ray, t: f64) -> bool {
    ray.origin().coords.amax() + t <= FAR
}

fn build_block(i: usize, spec: &BlockSpec) -> Option<Block> {
    let placement = spec.chain.build().ok()?;
    let mut solids = Vec::new();
    for s in &spec.solids {
        solids.push(s.build().ok()?.transformed(&placement));
    }
    let finite = |s: &Solid| match s {
        Solid::Quadric(q) => q.is_finite(),
        Solid::HalfSpace(h) => h.is_finite(),
    };
    let non_convex = solids.iter().filter(|s| s.max_intervals() > 1).count();
    let opacity = if spec.transparent { Opacity::Transparent } else { Opacity::Opaque };
    let block = Block::new(format!("b{i}"), solids.clone(), opacity, MaterialKey(spec.material.into()));
    match &block {
        Err(ComplexError::EmptyBlock { .. }) => assert!(solids.is_empty()),
        Err(ComplexError::NonFinite { solid, .. }) => assert!(!finite(&solids[*solid])),
        Err(e) => panic!("unexpected block error {e}"),
        Ok(b) => {
            assert!(!solids.is_empty() && solids.iter().all(finite));
            assert_eq!(b.fits_interval_set(), non_convex < IntervalSet::CAPACITY);
        }
    }
    block.ok()
}

/// The owner among `(id, opacity)` of the blocks covering a place, in
/// priority order: the first opaque one, else the first transparent one.
fn owner(covering: impl Iterator<Item = BlockId> + Clone, c: &Complex) -> Option<BlockId> {
    covering.clone().find(|id| !c.block(*id).is_transparent()).or_else(|| covering.clone().next())
}

/// `contains_point` by brute force over all blocks.
fn owner_of_point(c: &Complex, p: &Point3<f64>) -> Option<BlockId> {
    if !p.iter().all(|x| x.is_finite()) {
        return None;
    }
    let ids = (0..c.blocks().len() as u32).map(BlockId).filter(|id| c.block(*id).contains_point(p));
    owner(ids, c)
}

fn check_point(c: &Complex, p: &Point3<f64>, accurate: bool) {
    let owner = c.contains_point(p);
    // (Far from the origin or among subnormals, `f` itself over- or underflows.)
    if !(accurate && p.iter().all(|x| bound::moderate(*x))) {
        return;
    }
    assert_eq!(owner, owner_of_point(c, p), "contains_point({p:?})");
    for (i, b) in c.blocks().iter().enumerate() {
        if b.contains_point(p) {
            let bx = c.block_aabb(BlockId(i as u32));
            assert!(bx.contains_point(p), "block {i} holds {p:?} but its box {bx:?} does not");
        }
    }
}

fn check_partition(c: &Complex, ray: &Ray, sets: &[(BlockId, IntervalSet)]) -> Partition {
    let p = c.partition(ray);
    let segs = &p.segments;
    assert!(!segs.is_empty(), "no segments");
    assert_eq!(segs[0].start, 0.0, "{segs:?}");
    assert_eq!(segs[segs.len() - 1].end, f64::INFINITY, "{segs:?}");
    for s in segs {
        assert!(s.start < s.end, "empty or NaN segment in {segs:?}");
    }
    for w in segs.windows(2) {
        assert_eq!(w[0].end, w[1].start, "gap or overlap in {segs:?}");
        assert_ne!(w[0].owner, w[1].owner, "equal owners not merged in {segs:?}");
    }
    // Owners by the priority rule, from the brute-force sets, in the middle
    // of each segment (where it has a middle between floats).
    for s in segs {
        let t = if s.end.is_finite() { 0.5 * s.start + 0.5 * s.end } else { 2.0 * s.start + 1.0 };
        if s.start < t && t < s.end {
            let ids = sets.iter().filter(|(_, set)| set.contains(t)).map(|(id, _)| *id);
            assert_eq!(s.owner, owner(ids, c), "owner of {s:?} (sets {sets:?})");
        }
    }
    assert_eq!(p.events.len(), segs.len() - 1, "events do not sit between segments: {p:?}");
    for (e, w) in p.events.iter().zip(segs.windows(2)) {
        assert_eq!((e.t, e.before, e.after), (w[1].start, w[0].owner, w[1].owner), "{e:?}");
        assert!(e.t.is_finite(), "{e:?}");
        // (`p + t r` overflows only for points beyond 1e308.)
        assert!(!near(ray, e.t) || e.point.iter().all(|x| x.is_finite()), "{e:?}");
        assert!(e.normal.iter().all(|x| x.is_finite()), "{e:?}");
        let set = sets.iter().find(|(id, _)| *id == e.surface.block).map(|(_, s)| s);
        let on_end = set.is_some_and(|s| s.iter().any(|iv| (if e.entering { iv.enter } else { iv.exit }).t == e.t));
        assert!(on_end, "event {e:?} is not an end of its block's set");
    }
    p
}

fn check_cast(c: &Complex, ray: &Ray, max_t: f64, p: &Partition, accurate: bool) {
    let hit = c.cast_ray(ray, max_t);
    let eps = c.epsilon();
    let expected = p.events.iter().find(|e| e.t > eps && c.is_visible(e)).filter(|e| e.t <= max_t);
    if let Some(h) = &hit {
        assert!(h.t.is_finite() && h.t > eps && h.t <= max_t, "hit at {} (ε = {eps:e}, max_t = {max_t})", h.t);
        assert!(!near(ray, h.t) || h.point.iter().all(|x| x.is_finite()), "{h:?}");
        assert!(h.normal.iter().all(|x| x.is_finite()), "{h:?}");
    }
    if !accurate {
        return;
    }
    // (Only within the accurate range; see `FAR`.)
    let got = hit.map(|h| (h.t, h.block, h.solid, h.entering)).filter(|h| h.0 <= FAR);
    let want = expected.map(|e| (e.t, e.surface.block, e.surface.solid, e.entering)).filter(|e| e.0 <= FAR);
    assert_eq!(got, want, "cast_ray(max_t = {max_t}) against the partition {p:?}");
}

fuzz_target!(|input: ComplexInput| {
    let blocks: Vec<Block> = input.blocks.iter().enumerate().filter_map(|(i, b)| build_block(i, b)).collect();
    let epsilon = input.epsilon.map(|e| e.value());
    let c = Complex::new(blocks, ComplexOptions { epsilon, ..Default::default() });
    let eps_ok = epsilon.map_or(true, |e| e.is_finite() && e >= 0.0);
    assert_eq!(c.is_ok(), eps_ok, "ε = {epsilon:?}: {:?}", c.as_ref().err());
    let Ok(c) = c else { return };
    // Exact agreement between the BVH path and the brute force, and between
    // `cast_ray` and the partition, is promised where the kernel is accurate:
    // coefficients of moderate size. (A half-space normal of 1e-319 has a few
    // significant bits; its computed crossing lies outside its exact box.)
    let accurate = c.blocks().iter().all(|b| b.solids().iter().all(bound::moderate_solid));
    assert!(c.epsilon().is_finite() && c.epsilon() >= 0.0);

    for p in &input.points {
        check_point(&c, &p.point(), accurate);
    }
    // Carried from cast to cast, as the renderer carries it between the
    // shadow rays of one light: any hint gives `occluded`'s answers.
    let mut occluder = Occluder::default();
    for cast in &input.casts {
        let Ok(ray) = cast.ray.build() else { continue };
        // The BVH and box culling against every block.
        let brute: Vec<(BlockId, IntervalSet)> = (0..c.blocks().len() as u32)
            .map(BlockId)
            .map(|id| {
                let mut set = c.block_intervals(id, &ray);
                assert!(set.is_normalised(), "block {id:?}: {set:?}");
                set.retain(|iv| iv.exit.t > c.epsilon());
                (id, set)
            })
            .filter(|(_, set)| !set.is_empty())
            .collect();
        let sets = c.intervals(&ray);
        // A block the boxes cull may differ from the brute force only beyond
        // the range where the kernel promises accuracy (docs/model.md §7.3, "Range": coordinates up
        // to about 1e150; a ray with a direction component of 1e-270 meets
        // spurious roots near 1e273, where `s = r·Ar` underflows).
        let mut k = 0;
        for (id, set) in &brute {
            if sets.get(k).is_some_and(|(i, _)| i == id) {
                assert_eq!(&sets[k].1, set, "block {id:?}: the BVH path and the brute force differ");
                k += 1;
            } else if accurate && ray.origin().coords.amax() <= FAR {
                let near = set.clip(0.0, FAR);
                assert!(near.is_empty(), "block {id:?} culled, but it holds {near:?} of the ray (all: {set:?})");
            }
        }
        assert_eq!(k, sets.len(), "Complex::intervals holds blocks the brute force does not: {sets:?} vs {brute:?}");

        let partition = check_partition(&c, &ray, &sets);
        check_cast(&c, &ray, cast.max_t.value(), &partition, accurate);
        check_cast(&c, &ray, f64::INFINITY, &partition, accurate);

        // `occluded` is `cast_ray(..).is_some()`, with or without the hint
        // of the previous cast, and with this cast's own blocker as the hint.
        for max_t in [cast.max_t.value(), f64::INFINITY] {
            let stopped = c.cast_ray(&ray, max_t).is_some();
            assert_eq!(c.occluded(&ray, max_t), stopped, "occluded(max_t = {max_t})");
            assert_eq!(c.occluded_with(&ray, max_t, &mut occluder), stopped, "occluded_with, carried hint");
            assert_eq!(c.occluded_with(&ray, max_t, &mut occluder), stopped, "occluded_with, own hint");
        }

        // The partition's segments alone (shadow rays), and its first
        // interface formed from a bounded partition (camera rays).
        let mut scratch = Partition::default();
        c.segments_into(&ray, &mut scratch);
        assert_eq!(scratch.segments, partition.segments, "segments_into against the partition");
        assert!(scratch.events.is_empty(), "segments_into left events: {scratch:?}");
        // Up to `max_t`: the segments that start before it, the last one
        // ending at or after it.
        let max_t = cast.max_t.value();
        c.segments_within(&ray, max_t, &mut scratch);
        let starting: Vec<_> = partition.segments.iter().filter(|s| max_t.is_nan() || s.start < max_t).collect();
        assert_eq!(scratch.segments.len(), starting.len(), "segments_within({max_t}) against {partition:?}");
        for (k, (w, s)) in scratch.segments.iter().zip(&starting).enumerate() {
            assert_eq!((w.start, w.owner), (s.start, s.owner), "segments_within({max_t}) against {partition:?}");
            let last = k + 1 == starting.len();
            assert!(
                w.end == s.end || last && w.end >= max_t && s.end >= max_t,
                "segments_within({max_t}): {w:?}, {s:?}"
            );
        }
        assert!(scratch.events.is_empty(), "segments_within left events: {scratch:?}");
        let first = c.first_interface(&ray, &mut scratch);
        if accurate && ray.origin().coords.amax() <= FAR {
            let want = partition.events.iter().find(|e| e.t > c.epsilon() && !e.same_medium);
            assert_eq!(first.as_ref(), want, "first_interface against the partition {partition:?}");
        }

        // Points along the ray: in each set's intervals and at every segment's middle.
        for (_, set) in &sets {
            for iv in set {
                let t = if iv.exit.t.is_finite() { 0.5 * iv.enter.t + 0.5 * iv.exit.t } else { iv.enter.t + 1.0 };
                check_point(&c, &ray.at(t), accurate);
            }
        }
        for s in &partition.segments {
            if s.end.is_finite() {
                check_point(&c, &ray.at(0.5 * s.start + 0.5 * s.end), accurate);
            }
        }
    }
});
