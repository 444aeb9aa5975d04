//! Oracle property tests: random complexes and rays, checked against point
//! membership sampled along the ray (from `Solid::value` alone) and against
//! a brute-force partition over every block.

use complex::{Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity};
use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::{strategies, IntervalSet, Quadric, Ray, Solid};

/// One block: solids, transparent?, material.
pub(crate) type Spec = (Vec<Solid>, bool, u32);

/// Solids flipped where needed so that each contains the origin.
fn through_origin(solids: Vec<Solid>) -> Vec<Solid> {
    let o = Point3::origin();
    solids.into_iter().map(|s| if s.value(&o) > 0.0 { s.complement() } else { s }).collect()
}

fn spec() -> impl Strategy<Value = Spec> {
    let ball = (strategies::transform(), 0.5f64..2.0).prop_map(|(m, r)| {
        Solid::from(Quadric::sphere().transformed(&quadric::Transform::scale(r).expect("finite").then(&m)))
    });
    (
        proptest::option::weighted(0.5, ball),
        proptest::collection::vec(strategies::solid(), 1..=3),
        any::<bool>(),
        0u32..2,
    )
        .prop_map(|(ball, mut solids, transparent, material)| {
            if let Some(b) = ball {
                solids.insert(0, b);
            }
            (solids, transparent, material)
        })
}

/// 3 to 8 blocks, the first three all containing the origin (so at least
/// three overlap there), in shuffled priority.
pub(crate) fn complex_spec() -> impl Strategy<Value = Vec<Spec>> {
    (proptest::collection::vec(spec(), 3..=8), any::<proptest::sample::Index>()).prop_map(|(mut specs, rot)| {
        for s in specs.iter_mut().take(3) {
            s.0 = through_origin(core::mem::take(&mut s.0));
        }
        let k = rot.index(specs.len());
        specs.rotate_left(k);
        specs
    })
}

/// Rays from anywhere in `[-4, 4]³`, half of them aimed near the origin.
pub(crate) fn ray_spec() -> impl Strategy<Value = Ray> {
    (strategies::ray(4.0), strategies::point(0.5), any::<bool>()).prop_map(|(r, target, aim)| {
        if aim {
            Ray::new(r.origin(), target - r.origin()).unwrap_or(r)
        } else {
            r
        }
    })
}

/// `cast_rays` answers every four rays exactly as `cast_ray` answers each:
/// the given rays four at a time (mostly far apart), and for each of them a
/// bundle of four near-parallel rays from its origin, as a camera's
/// neighbouring pixels are (they share most of the walk).
fn packets_agree(c: &Complex, rays: &[Ray], max_t: f64) -> Result<(), TestCaseError> {
    let mut fours: Vec<[Ray; 4]> = rays.chunks_exact(4).map(|r| [r[0], r[1], r[2], r[3]]).collect();
    for r in rays {
        let d = r.direction();
        let nudge = |k: usize| {
            let e = [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::zeros()][k];
            Ray::new(r.origin(), d + 1e-3 * e).unwrap_or(*r)
        };
        fours.push([nudge(0), nudge(1), nudge(2), nudge(3)]);
    }
    for four in &fours {
        let one_by_one = four.each_ref().map(|r| c.cast_ray(r, max_t));
        prop_assert_eq!(c.cast_rays(four, max_t), one_by_one, "max_t = {}", max_t);
    }
    Ok(())
}

pub(crate) fn build(specs: &[Spec]) -> Complex {
    let blocks = specs
        .iter()
        .enumerate()
        .map(|(i, (solids, t, m))| {
            let opacity = if *t { Opacity::Transparent } else { Opacity::Opaque };
            Block::new(format!("b{i}"), solids.clone(), opacity, MaterialKey(*m)).expect("valid block")
        })
        .collect();
    Complex::new(blocks, ComplexOptions::default()).expect("valid complex")
}

/// The owner by docs/model.md §3.4, from membership flags in priority order.
fn oracle_owner(inside: &[bool], transparent: &[bool]) -> Option<BlockId> {
    let pick = |want_transparent: bool| {
        (0..inside.len()).find(|&i| inside[i] && transparent[i] == want_transparent).map(|i| BlockId(i as u32))
    };
    pick(false).or_else(|| pick(true))
}

/// Whether `t` is safely away from every solid's surface along the ray: all
/// solids keep a non-zero sign on `[t - δ, t + δ]`.
fn away_from_surfaces(c: &Complex, ray: &Ray, t: f64) -> bool {
    let d = 1e-6 * (1.0 + t);
    c.blocks().iter().flat_map(|b| b.solids()).all(|s| {
        let v = [s.value(&ray.at(t - d)), s.value(&ray.at(t)), s.value(&ray.at(t + d))];
        v.iter().all(|x| *x > 0.0) || v.iter().all(|x| *x < 0.0)
    })
}

/// A brute-force partition: every block's set (no BVH, no boxes), the ε rule,
/// and the owner of each piece between consecutive ends. Returns the change
/// points `(t, before, after)`.
fn brute_events(c: &Complex, ray: &Ray) -> Vec<(f64, Option<BlockId>, Option<BlockId>)> {
    let eps = c.epsilon();
    let sets: Vec<IntervalSet> = (0..c.blocks().len())
        .map(|i| {
            let mut s = c.block_intervals(BlockId(i as u32), ray);
            s.retain(|iv| iv.exit.t > eps);
            s
        })
        .collect();
    let transparent: Vec<bool> = c.blocks().iter().map(Block::is_transparent).collect();
    let mut ends: Vec<f64> = sets
        .iter()
        .flat_map(|s| s.iter().flat_map(|iv| [iv.enter.t, iv.exit.t]))
        .filter(|t| t.is_finite() && *t > 0.0)
        .collect();
    ends.sort_by(f64::total_cmp);
    ends.dedup();
    // The owner of the piece (a, b) between consecutive ends: every
    // interval covers all of it or none of it.
    let owner_of = |a: f64, b: f64| {
        let inside: Vec<bool> = sets.iter().map(|s| s.iter().any(|iv| iv.enter.t <= a && b <= iv.exit.t)).collect();
        oracle_owner(&inside, &transparent)
    };
    let mut out = Vec::new();
    let mut prev = owner_of(0.0, ends.first().copied().unwrap_or(f64::INFINITY));
    for (k, &t) in ends.iter().enumerate() {
        let o = owner_of(t, ends.get(k + 1).copied().unwrap_or(f64::INFINITY));
        if o != prev {
            out.push((t, prev, o));
            prev = o;
        }
    }
    out
}

fn visible(c: &Complex, before: Option<BlockId>, after: Option<BlockId>) -> bool {
    let b = |o: Option<BlockId>| o.map(|id| c.block(id));
    match (b(before), b(after)) {
        (Some(x), Some(y)) if !x.is_transparent() && !y.is_transparent() => false,
        (Some(x), Some(y)) => !(x.is_transparent() && y.is_transparent() && x.material() == y.material()),
        _ => true,
    }
}

proptest! {
    #[test]
    fn partitions_and_hits_agree_with_point_membership(
        specs in complex_spec(),
        rays in proptest::collection::vec(ray_spec(), 6),
    ) {
        agrees_with_membership(&specs, &rays)?;
    }

    /// Many overlapping blocks along each ray: more intervals than the
    /// partition tests block by block, so its owners come from the sweep.
    #[test]
    fn crowded_partitions_agree_with_point_membership(
        specs in crowded_spec(),
        rays in proptest::collection::vec(ray_spec(), 4),
    ) {
        agrees_with_membership(&specs, &rays)?;
    }
}

/// 16 to 28 blocks, every one containing the origin, in random opacity
/// and material: a ray near the origin meets most of them.
fn crowded_spec() -> impl Strategy<Value = Vec<Spec>> {
    proptest::collection::vec(spec(), 16..=28).prop_map(|mut specs| {
        for s in &mut specs {
            s.0 = through_origin(core::mem::take(&mut s.0));
        }
        specs
    })
}

/// The partition, hits, first interfaces, segments, occlusion and sampled
/// membership of `specs` along `rays`, each against its oracle.
fn agrees_with_membership(specs: &[Spec], rays: &[Ray]) -> Result<(), TestCaseError> {
    let c = build(specs);
    let eps = c.epsilon();
    let transparent: Vec<bool> = c.blocks().iter().map(Block::is_transparent).collect();
    for ray in rays {
        let sets = c.intervals(ray);
        let p = c.partition(ray);

        // Structure: sets normalised; segments cover [0, ∞) in order;
        // one event between each two segments, on a surface of one side.
        for (_, s) in &sets {
            prop_assert!(s.is_normalised());
        }
        prop_assert_eq!(p.segments.first().map(|s| s.start), Some(0.0));
        prop_assert_eq!(p.segments.last().map(|s| s.end), Some(f64::INFINITY));
        prop_assert_eq!(p.events.len() + 1, p.segments.len());
        for (k, e) in p.events.iter().enumerate() {
            let (s0, s1) = (p.segments[k], p.segments[k + 1]);
            prop_assert!(s0.end == s1.start && s1.start == e.t && s0.owner != s1.owner);
            prop_assert!(e.before == s0.owner && e.after == s1.owner);
            let side = if e.entering { e.after } else { e.before };
            prop_assert_eq!(Some(e.surface.block), side);
            prop_assert!(e.t.is_finite() && e.point.iter().all(|x| x.is_finite()));
            let n = e.normal.norm();
            prop_assert!(n == 0.0 || (n - 1.0).abs() < 1e-9);
        }

        // Brute force over every block gives the same events.
        let brute = brute_events(&c, ray);
        let events: Vec<_> = p.events.iter().map(|e| (e.t, e.before, e.after)).collect();
        prop_assert_eq!(&events, &brute);

        // cast_ray is the first visible event after ε, BVH or not.
        let first = brute.iter().find(|(t, b, a)| *t > eps && visible(&c, *b, *a)).map(|x| x.0);
        let hit = c.cast_ray(ray, f64::INFINITY);
        prop_assert_eq!(hit.map(|h| h.t), first);
        if let Some(h) = hit {
            let e = p.events.iter().find(|e| e.t == h.t).expect("the hit is an event");
            prop_assert!(c.is_visible(e));
            prop_assert_eq!((h.block, h.solid, h.entering), (e.surface.block, e.surface.solid, e.entering));
            prop_assert!(c.cast_ray(ray, 0.5 * h.t).is_none() || 0.5 * h.t > h.t);
            prop_assert_eq!(c.cast_ray(ray, h.t).map(|x| x.t), Some(h.t));
        }

        // first_interface is the first change after ε that is not
        // between two transparent blocks of one material, and it is the
        // partition's event there (surface, normal and all).
        let one_medium = |b: Option<BlockId>, a: Option<BlockId>| match (b.map(|i| c.block(i)), a.map(|i| c.block(i))) {
            (Some(x), Some(y)) => x.is_transparent() && y.is_transparent() && x.material() == y.material(),
            _ => false,
        };
        let interface = brute.iter().find(|(t, b, a)| *t > eps && !one_medium(*b, *a)).map(|x| x.0);
        let mut scratch = complex::Partition::default();
        let fi = c.first_interface(ray, &mut scratch);
        prop_assert_eq!(fi.map(|e| e.t), interface);
        if let Some(e) = fi {
            prop_assert_eq!(Some(&e), p.events.iter().find(|x| x.t == e.t));
        }

        // segments_into is the partition's segments, without its events
        // (into a buffer that held another partition).
        let mut segments = p.clone();
        segments.segments.reverse();
        c.segments_into(ray, &mut segments);
        prop_assert_eq!(&segments.segments, &p.segments);
        prop_assert!(segments.events.is_empty());

        // segments_within(max_t) is the partition's segments that start
        // before max_t, the last one ending at or after max_t.
        // (Below ε too: the walk that collects the sets starts at
        // `min(ε, max_t)`.)
        let mut reach: Vec<f64> = vec![-1.0, 0.0, 0.5 * eps, eps, 0.5, 2.0, f64::NAN, f64::INFINITY];
        reach.extend(p.segments.iter().flat_map(|s| [s.start, s.end, 0.5 * (s.start + s.end)]));
        for m in reach {
            let mut within = p.clone();
            c.segments_within(ray, m, &mut within);
            prop_assert!(within.events.is_empty());
            let starting: Vec<_> = p.segments.iter().filter(|s| m.is_nan() || s.start < m).collect();
            prop_assert_eq!(within.segments.len(), starting.len(), "max_t = {}", m);
            for (k, (w, s)) in within.segments.iter().zip(&starting).enumerate() {
                prop_assert_eq!((w.start, w.owner), (s.start, s.owner), "max_t = {}", m);
                if k + 1 < starting.len() {
                    prop_assert_eq!(w.end, s.end, "max_t = {}", m);
                } else {
                    prop_assert!(
                        w.end >= m && s.end >= m || w.end == s.end,
                        "max_t = {}: last ends {} and {}",
                        m,
                        w.end,
                        s.end
                    );
                }
            }
        }

        // occluded is "the first visible event is within max_t".
        let mut limits = vec![f64::INFINITY, 0.5, 3.0, eps];
        if let Some(t) = first {
            limits.extend([t, 0.5 * t, 2.0 * t, t * (1.0 - f64::EPSILON)]);
        }
        let mut occluder = complex::Occluder::default();
        for m in limits {
            let want = first.is_some_and(|t| t <= m);
            prop_assert_eq!(c.occluded(ray, m), want, "max_t = {}", m);
            // The hint of the previous limit, then of this one.
            prop_assert_eq!(c.occluded_with(ray, m, &mut occluder), want, "max_t = {}, carried hint", m);
            prop_assert_eq!(c.occluded_with(ray, m, &mut occluder), want, "max_t = {}, own hint", m);
        }

        // Sampled membership: per-block sets, partition owner, contains_point.
        let horizon = brute.last().map_or(10.0, |e| e.0 + 2.0).min(60.0);
        for k in 0..64 {
            let t = eps + (k as f64 + 0.37) / 64.0 * horizon;
            if !away_from_surfaces(&c, ray, t) {
                continue;
            }
            let x = ray.at(t);
            let inside: Vec<bool> = c.blocks().iter().map(|b| b.solids().iter().all(|s| s.value(&x) <= 0.0)).collect();
            for (i, &inn) in inside.iter().enumerate() {
                let in_set = sets.iter().any(|(id, s)| id.index() == i && s.contains(t));
                prop_assert_eq!(in_set, inn, "block {} at t = {}", i, t);
            }
            let owner = oracle_owner(&inside, &transparent);
            prop_assert_eq!(p.owner_at(t), owner, "owner at t = {}", t);
            prop_assert_eq!(c.contains_point(&x), owner, "contains_point at t = {}", t);
        }
    }
    for m in [f64::INFINITY, 1.0, 0.0] {
        packets_agree(&c, rays, m)?;
    }

    Ok(())
}

#[test]
fn no_nan_from_degenerate_queries() {
    let c = build(&[(vec![Solid::from(Quadric::cone())], false, 0), (vec![Solid::from(Quadric::sphere())], true, 0)]);
    // Through the cone's apex, where the normal is undefined.
    let r = Ray::new(Point3::new(0.0, -5.0, 0.0), Vector3::y()).expect("ray");
    for e in c.partition(&r).events {
        assert!(e.t.is_finite() && e.normal.iter().all(|x| x.is_finite()));
    }
    assert!(c.cast_ray(&r, f64::NAN).is_none());
    assert_eq!(c.contains_point(&Point3::new(f64::NAN, 0.0, 0.0)), None);
}

/// `first_interface` with one block along the ray (read off its intervals,
/// no partition formed) is the partition's first event strictly after ε,
/// including when an end lies exactly at ε, or the ray starts inside.
#[test]
fn first_interface_with_one_block_is_the_first_end_after_epsilon() {
    use crate::common::hs;
    // The slab 1 <= x <= 3, along x from the origin, with ε = 1: the entry at
    // t = ε is no interface, the exit at 3 is.
    let slab = vec![hs(-1.0, 0.0, 0.0, 1.0), hs(1.0, 0.0, 0.0, -3.0)];
    let block = |transparent| {
        let opacity = if transparent { Opacity::Transparent } else { Opacity::Opaque };
        Block::new("slab", slab.clone(), opacity, MaterialKey(0)).expect("valid")
    };
    for transparent in [false, true] {
        for (eps, origin, want) in [
            (1.0, 0.0, Some((3.0, false))),
            (0.5, 0.0, Some((1.0, true))),
            (0.5, 2.0, Some((1.0, false))),
            (1.0, 2.0, None),
            (0.0, 3.5, None),
            (0.0, -1.0, Some((2.0, true))),
        ] {
            let c = Complex::new(vec![block(transparent)], ComplexOptions { epsilon: Some(eps), ..Default::default() })
                .expect("valid");
            let ray = Ray::new(Point3::new(origin, 0.0, 0.0), Vector3::x()).expect("ray");
            let fi = c.first_interface(&ray, &mut complex::Partition::default());
            assert_eq!(fi.map(|e| (e.t, e.entering)), want, "ε = {eps}, from x = {origin}");
            let p = c.partition(&ray);
            assert_eq!(fi, p.events.iter().find(|e| e.t > eps && !e.same_medium).copied());
        }
    }
}

/// The hint of `occluded_with`: kept while the same block stops the rays,
/// dropped by a ray nothing stops, and never a different answer.
#[test]
fn occluder_remembers_the_block_that_stopped_the_last_ray() {
    let ball = |x: f64| {
        let at = quadric::Transform::translate(Vector3::new(x, 0.0, 0.0)).expect("finite");
        Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&at))], Opacity::Opaque, MaterialKey(0))
            .expect("valid")
    };
    let c = Complex::new(vec![ball(-4.0), ball(4.0)], ComplexOptions::default()).expect("valid");
    let towards = |x: f64, y: f64| Ray::new(Point3::new(x, y, -5.0), Vector3::z()).expect("ray");
    let mut occluder = complex::Occluder::default();
    assert!(c.occluded_with(&towards(4.0, 0.0), 10.0, &mut occluder));
    let first = occluder;
    assert_ne!(first, complex::Occluder::default(), "the blocker is remembered");
    // Stopped by the same ball: the hint stays.
    assert!(c.occluded_with(&towards(4.2, 0.1), 10.0, &mut occluder));
    assert_eq!(occluder, first);
    // Stopped by the other ball: the hint moves to it.
    assert!(c.occluded_with(&towards(-4.0, 0.0), 10.0, &mut occluder));
    assert_ne!(occluder, first);
    assert_ne!(occluder, complex::Occluder::default());
    // Too short to reach it, then missing both: no answer changes, and a ray
    // nothing stops drops the hint.
    assert!(!c.occluded_with(&towards(-4.0, 0.0), 3.0, &mut occluder));
    assert!(!c.occluded_with(&towards(0.0, 0.0), 10.0, &mut occluder));
    assert_eq!(occluder, complex::Occluder::default());
}

/// A small bounded block (ball, capped tube or cube of size 0.1–0.5) placed
/// at random in `[-3, 3]³`, opaque or transparent with one of two materials.
pub(crate) fn small_block() -> impl Strategy<Value = Spec> {
    use crate::common::{cuboid, hs, post};
    let shape = prop_oneof![
        Just(vec![Solid::from(Quadric::sphere())]),
        Just(post(0.0, 0.0, 1.0, -1.0, 1.0)),
        Just(cuboid([-1.0; 3], [1.0; 3])),
        Just(vec![Solid::from(Quadric::cone()), hs(0.0, -1.0, 0.0, 0.2), hs(0.0, 1.0, 0.0, -1.0)]),
    ];
    (shape, strategies::transform(), 0.05f64..0.25, strategies::point(3.0), any::<bool>(), 0u32..2).prop_map(
        |(shape, m, size, at, transparent, material)| {
            let m = quadric::Transform::scale(size)
                .expect("finite")
                .then(&m)
                .then(&quadric::Transform::translate(at.coords).expect("finite"));
            (shape.iter().map(|s| s.transformed(&m)).collect(), transparent, material)
        },
    )
}

/// The first visible change of owner after ε, by brute force.
fn brute_first(c: &Complex, ray: &Ray) -> Option<(f64, Option<BlockId>, Option<BlockId>)> {
    brute_events(c, ray).into_iter().find(|(t, b, a)| *t > c.epsilon() && visible(c, *b, *a))
}

/// Every query agrees with brute force over every block on a large scene
/// (see the tests below).
fn large_scene_agrees(specs: Vec<Spec>, rays: &[Ray], all_opaque: bool) -> Result<(), TestCaseError> {
    let specs: Vec<Spec> = specs.into_iter().map(|(s, t, m)| (s, t && !all_opaque, m)).collect();
    let c = build(&specs);
    let mut occluder = complex::Occluder::default();
    for ray in rays {
        let brute = brute_first(&c, ray);
        let hit = c.cast_ray(ray, f64::INFINITY);
        prop_assert_eq!(hit.map(|h| h.t), brute.map(|b| b.0));
        if let (Some(h), Some((_, before, after))) = (hit, brute) {
            prop_assert_eq!(Some(h.block), if h.entering { after } else { before });
        }
        for m in [f64::INFINITY, 1.0, 4.0, brute.map_or(1.0, |b| b.0)] {
            let want = brute.is_some_and(|b| b.0 <= m);
            prop_assert_eq!(c.occluded(ray, m), want, "max_t = {}", m);
            // With the hint of the previous ray (another ray's blocker,
            // or none), then with this ray's own blocker as the hint.
            prop_assert_eq!(c.occluded_with(ray, m, &mut occluder), want, "max_t = {}, carried hint", m);
            prop_assert_eq!(c.occluded_with(ray, m, &mut occluder), want, "max_t = {}, own hint", m);
        }
        let events: Vec<_> = c.partition(ray).events.iter().map(|e| (e.t, e.before, e.after)).collect();
        prop_assert_eq!(events, brute_events(&c, ray));
        // The point probe, at points of the ray away from every surface.
        let transparent: Vec<bool> = c.blocks().iter().map(Block::is_transparent).collect();
        for k in 0..8 {
            let t = 0.01 + (k as f64 + 0.37) * 0.75;
            if !away_from_surfaces(&c, ray, t) {
                continue;
            }
            let x = ray.at(t);
            let inside: Vec<bool> = c.blocks().iter().map(|b| b.solids().iter().all(|s| s.value(&x) <= 0.0)).collect();
            prop_assert_eq!(c.contains_point(&x), oracle_owner(&inside, &transparent), "contains_point at t = {}", t);
        }
    }
    packets_agree(&c, rays, f64::INFINITY)?;
    packets_agree(&c, &rays[..8], 2.0)?;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 16).max(8)))]

    /// With a few hundred blocks the BVH is deep; it must find exactly the
    /// hits brute force over every block finds, with and without
    /// transparency. (Below 256 blocks the tree is four-wide.)
    #[test]
    fn bvh_agrees_with_brute_force_on_large_scenes(
        specs in proptest::collection::vec(small_block(), 150..256),
        rays in proptest::collection::vec(ray_spec(), 40),
        all_opaque in any::<bool>(),
    ) {
        large_scene_agrees(specs, &rays, all_opaque)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 64).max(4)))]

    /// The same with more blocks than the eight-wide tree starts from
    /// (256): its walks, the packet walk and the point probe.
    #[test]
    fn eight_wide_bvh_agrees_with_brute_force(
        specs in proptest::collection::vec(small_block(), 300..400),
        rays in proptest::collection::vec(ray_spec(), 24),
        all_opaque in any::<bool>(),
    ) {
        large_scene_agrees(specs, &rays, all_opaque)?;
    }
}

#[test]
fn a_complex_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Complex>();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 16).max(8)))]

    /// `contains_point` (the point grid, its list of blocks too wide for a
    /// cell, the unbounded blocks) finds the owner that membership in every
    /// block and the priority rule give, on scenes of small blocks with a
    /// few big and unbounded ones among them.
    #[test]
    fn point_owner_agrees_with_membership_with_big_blocks(
        specs in proptest::collection::vec(small_block(), 60..200),
        big in proptest::collection::vec((0usize..3, any::<bool>(), 0usize..200), 1..4),
        points in proptest::collection::vec(strategies::point(3.5), 300),
    ) {
        use crate::common::{cuboid, hs};
        let mut specs = specs;
        for (kind, transparent, at) in big {
            let solids = match kind {
                0 => cuboid([-3.0, -3.0, -0.5], [3.0, 3.0, 0.5]),
                1 => vec![Solid::from(Quadric::sphere().transformed(&quadric::Transform::scale(2.5).expect("finite")))],
                _ => vec![hs(0.3, 1.0, -0.2, 0.1)],
            };
            specs.insert(at.min(specs.len()), (solids, transparent, 0));
        }
        let c = build(&specs);
        let transparent: Vec<bool> = c.blocks().iter().map(Block::is_transparent).collect();
        for x in &points {
            let inside: Vec<bool> = c.blocks().iter().map(|b| b.contains_point(x)).collect();
            prop_assert_eq!(c.contains_point(x), oracle_owner(&inside, &transparent), "at {:?}", x);
        }
    }
}
