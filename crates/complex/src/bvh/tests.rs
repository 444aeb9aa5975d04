//! The BVH's unit tests: the slab arithmetic against its scalar form, the
//! SAH split against the sweep over every bin, the collapse against brute
//! force and the greedy rules, and the walks against brute force.

use arrayvec::ArrayVec;
use proptest::prelude::*;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;
use wide::{CmpGt, CmpLt};

use super::build::{bounds_of, centroid_bounds, gather_left, sah_split, Entry, Node, BINS};
use super::slab::{greater_or_second, less_or_second, PacketBounds};
use super::*;

/// How a collapse into a wide tree picks each wide node's children: a
/// greedy rule, which opens one inner node at a time once the binary
/// node's own two children are open ([`greedy_children`]), or the build's
/// own collapse. The greedy rules are the oracles the build's collapse is
/// compared with.
#[derive(Clone, Copy, Debug)]
enum Open {
    /// The shallowest (the first of them): the binary tree level by level,
    /// best where the blocks are alike (a grid).
    Shallowest,
    /// The one with the largest box, which a ray most likely enters: best
    /// where sizes vary (a sphereflake's spheres shrink threefold a level).
    Largest,
    /// Not one at a time: the collapse of least surface-area cost among all
    /// that open each wide node's own two binary children, found by dynamic
    /// programming over the binary tree ([`Tree::cheapest`]). Never dearer
    /// than the other two.
    Cheapest,
}

/// The children of the wide node for the binary inner node `n` by a greedy
/// rule: `n`'s own two, then inner ones opened as `open` picks until there
/// are `W`, or only leaves.
fn greedy_children<const W: usize>(nodes: &[Node], n: usize, open: Open) -> ArrayVec<usize, W> {
    let first = nodes[n].start as usize;
    // `(node, binary depth below n)`.
    let mut children = ArrayVec::<_, W>::from_iter([(first, 1), (first + 1, 1)]);
    while children.len() < W {
        let inner = (0..children.len()).filter(|&j| nodes[children[j].0].count == 0);
        let pick = match open {
            Open::Shallowest => inner.min_by_key(|&j| children[j].1),
            Open::Largest => inner
                .map(|j| {
                    let k = &nodes[children[j].0];
                    (j, children[j].1 == 1, half_area(&k.min, &k.max))
                })
                .reduce(|a, b| if (b.1, b.2) > (a.1, a.2) { b } else { a })
                .map(|(j, _, _)| j),
            // `Tree::collapsed_by` takes this one's children from `Tree::cheapest`.
            Open::Cheapest => unreachable!("the cheapest collapse is not greedy"),
        };
        let Some(j) = pick else { break };
        let (c, d) = children.remove(j);
        let c = nodes[c].start as usize;
        children.extend([(c, d + 1), (c + 1, d + 1)]);
    }
    children.into_iter().map(|(c, _)| c).collect()
}

impl<const W: usize, const H: usize> Tree<W, H> {
    /// The wide tree of a binary one whose root is an inner node, collapsed
    /// by `open`, and its cost (see [`Tree::collapsed`]).
    fn collapsed_by(binary: &[Node], open: Open) -> (Self, f64) {
        match open {
            Open::Cheapest => Self::cheapest(binary),
            rule => Self::collapsed(binary, &|n| greedy_children(binary, n, rule)),
        }
    }

    /// The wide tree of a binary one (root: node 0, not empty), collapsed
    /// by `open`.
    fn from_binary_by(binary: &[Node], open: Open) -> Self {
        if binary[0].count > 0 {
            Self::single_leaf(&binary[0])
        } else {
            Self::collapsed_by(binary, open).0
        }
    }
}

/// Panics unless the cheapest collapse of `binary` costs no more than
/// either greedy rule's.
fn assert_cheapest_is_no_dearer<const W: usize, const H: usize>(binary: &[Node]) {
    if binary[0].count > 0 {
        return;
    }
    let cost = Tree::<W, H>::cheapest(binary).1;
    for rule in [Open::Shallowest, Open::Largest] {
        let other = Tree::<W, H>::collapsed_by(binary, rule).1;
        assert!(cost <= other * (1.0 + 1e-12), "{rule:?} costs {other}, the cheapest {cost}");
    }
}

/// [`Bvh::build_with`], collapsed by `open`. `None`: the build's own
/// collapse, checked to cost no more than either greedy rule's.
fn build_by(entries: &[(u32, Aabb)], parallel_from: usize, eight: bool, open: Option<Open>) -> Bvh {
    let Some(open) = open else {
        if !entries.is_empty() {
            let binary = Binary::of(entries, parallel_from);
            if eight {
                assert_cheapest_is_no_dearer::<8, 2>(&binary.nodes);
            } else {
                assert_cheapest_is_no_dearer::<4, 1>(&binary.nodes);
            }
        }
        return Bvh::build_with(entries, parallel_from, eight);
    };
    if entries.is_empty() {
        return Bvh::default();
    }
    let binary = Binary::of(entries, parallel_from);
    let nodes = if eight {
        Nodes::Eight(Tree::from_binary_by(&binary.nodes, open))
    } else {
        Nodes::Four(Tree::from_binary_by(&binary.nodes, open))
    };
    Bvh { nodes, items: binary.items }
}

/// The slab tests' lane-wise `a > b ? a : b` and `a < b ? a : b`
/// (one `vmaxpd`/`vminpd` with AVX) are bit for bit the comparison and
/// blend they stand for, on every pair of special values: NaN in either
/// operand and zeros of both signs give `b`.
#[test]
fn lane_max_and_min_keep_the_second_operand_on_nan_and_zeros() {
    let values = [
        f64::NAN,
        -f64::NAN,
        0.0,
        -0.0,
        1.0,
        -1.0,
        f64::MIN_POSITIVE / 2.0,
        f64::MAX,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let bits = |v: f64x4| v.to_array().map(f64::to_bits);
    for chunk in values.chunks(2) {
        for &b in &values {
            let a = f64x4::new([chunk[0], chunk[1], b, -b]);
            let b = f64x4::new([b, b, chunk[0], chunk[1]]);
            assert_eq!(bits(greater_or_second(a, b)), bits(a.cmp_gt(b).blend(a, b)), "{a:?} {b:?}");
            assert_eq!(bits(less_or_second(a, b)), bits(a.cmp_lt(b).blend(a, b)), "{a:?} {b:?}");
        }
    }
    let (nan, one) = (f64x4::splat(f64::NAN), f64x4::splat(1.0));
    assert_eq!(greater_or_second(nan, one).to_array(), [1.0; 4]);
    assert_eq!(bits(less_or_second(f64x4::splat(0.0), f64x4::splat(-0.0))), [(-0.0f64).to_bits(); 4]);
}

/// Rays parallel to slabs (reciprocals `±∞`): inside, on the boundary,
/// outside on either side, along both directions of each axis.
#[test]
fn slab_test_with_axis_parallel_rays() {
    let (min, max) = ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
    let check = |origin: [f64; 3], dir: [f64; 3], expected: bool| {
        let ray = Ray::new(Point3::from(origin), Vector3::from(dir)).expect("valid");
        let rb = RayBoxes::new(&ray);
        let got = rb.enter(&min, &max, 0.0, f64::INFINITY);
        assert_eq!(got.is_some(), expected, "{origin:?} along {dir:?}: {got:?}");
        assert_eq!(lane0::<4, 1>(&rb, &min, &max, 0, 0.0, f64::INFINITY), got, "{origin:?} along {dir:?}: four-wide");
        for lane in [0, 5] {
            let wide = lane0::<8, 2>(&rb, &min, &max, lane, 0.0, f64::INFINITY);
            assert_eq!(wide, got, "{origin:?} along {dir:?}: eight-wide, lane {lane}");
        }
        assert!(got.is_none_or(|t| !t.is_nan()), "{origin:?} along {dir:?}: NaN entry");
    };
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut dir = [0.0; 3];
            dir[axis] = sign;
            // The ray starts 2 units before the box along its axis.
            let start = if sign > 0.0 { -2.0 } else { 3.0 };
            for (off, expected) in [(0.5, true), (0.0, true), (1.0, true), (-0.5, false), (1.5, false)] {
                let mut origin = [0.5; 3];
                origin[axis] = start;
                // Offset across one of the other axes.
                origin[(axis + 1) % 3] = off;
                check(origin, dir, expected);
            }
            // Pointing away from the box: a miss.
            let mut origin = [0.5; 3];
            origin[axis] = if sign > 0.0 { 3.0 } else { -2.0 };
            check(origin, dir, false);
        }
    }
}

/// [`RayBoxes::enter_node`] for a node whose lane `lane` holds the box
/// (the other lanes empty, which must never be entered; those before
/// it hold children, as the collapse fills lanes from the first).
fn lane0<const W: usize, const H: usize>(
    rb: &RayBoxes,
    min: &[f64; 3],
    max: &[f64; 3],
    lane: usize,
    t_min: f64,
    t_max: f64,
) -> Option<f64> {
    let mut node = Wide::<W, H>::EMPTY;
    node.set_box(lane, min, max);
    node.count[..=lane].fill(1);
    let (entry, hits) = rb.enter_node(&node, t_min, t_max);
    assert_eq!(hits & !(1 << lane), 0, "an empty lane was entered");
    (hits & (1 << lane) != 0).then(|| entry[lane / 4].to_array()[lane % 4])
}

fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![-4.0..4.0f64, Just(0.0), Just(1.0), Just(-1.0)]
}

fn ray() -> impl Strategy<Value = Ray> {
    ([coord(), coord(), coord()], [coord(), coord(), coord()])
        .prop_filter_map("zero direction", |(o, d)| Ray::new(Point3::from(o), Vector3::from(d)).ok())
}

/// A box's lower and upper corner.
type Corners = ([f64; 3], [f64; 3]);

/// Four rays for a packet and eight boxes (`None`: an empty lane).
fn packet_and_boxes() -> impl Strategy<Value = ([Ray; 4], Vec<Option<Corners>>)> {
    let scale = prop_oneof![Just(1.0), Just(1e3), Just(1e9)];
    let axis_or_not = || prop_oneof![3 => -1.0..1.0f64, 1 => Just(0.0)];
    let dir = [axis_or_not(), axis_or_not(), axis_or_not()];
    let spread = prop_oneof![Just(0.0), Just(1e-3), Just(1.0)];
    let shared = any::<bool>();
    let jitter = || prop::array::uniform4(prop::array::uniform3(-1.0..1.0f64));
    (scale, [coord(), coord(), coord()], dir, spread, shared, jitter(), jitter())
        .prop_filter_map("zero direction", |(scale, o, d, spread, shared, jitter_o, jitter_d)| {
            let rays: Option<Vec<Ray>> = (0..4)
                .map(|l| {
                    let origin = [0, 1, 2].map(|i| (o[i] + if shared { 0.0 } else { jitter_o[l][i] }) * scale);
                    let dir = [0, 1, 2].map(|i| d[i] + spread * jitter_d[l][i]);
                    Ray::new(Point3::from(origin), Vector3::from(dir)).ok()
                })
                .collect();
            let rays: [Ray; 4] = rays?.try_into().ok()?;
            Some((rays, scale))
        })
        .prop_flat_map(|(rays, scale)| {
            // A box at random (scaled with the origins), or one with a
            // corner on a point of one ray, reaching away or across.
            let one = prop_oneof![
                1 => Just(None),
                2 => boxed().prop_map(move |(lo, hi)| Some((lo.map(|x| x * scale), hi.map(|x| x * scale)))),
                3 => (0..4usize, 0.0..3.0f64, prop::array::uniform3(0.0..2.0f64), prop::array::uniform3(any::<bool>()))
                    .prop_map(move |(l, t, size, below)| {
                        let p = rays[l].at(t * scale);
                        let mut lo = [p.x, p.y, p.z];
                        let mut hi = lo;
                        for i in 0..3 {
                            if below[i] {
                                lo[i] -= size[i] * scale;
                            } else {
                                hi[i] += size[i] * scale;
                            }
                        }
                        Some((lo, hi))
                    }),
            ];
            (Just(rays), prop::collection::vec(one, 8))
        })
}

/// A box at random, or now and then one reaching to ±1e308 or ±∞ along
/// some axes (its half-area overflows to ∞, or is ∞·0 = NaN if it is
/// also flat): a scene may hold such blocks, and the collapse must
/// still give every wide node at most `W` lanes.
fn boxed_or_huge() -> impl Strategy<Value = ([f64; 3], [f64; 3])> {
    let reach = || prop_oneof![3 => Just(None), 1 => Just(Some(1e308)), 1 => Just(Some(f64::INFINITY))];
    prop_oneof![
        4 => boxed(),
        1 => (boxed(), [reach(), reach(), reach()]).prop_map(|((mut lo, mut hi), reach)| {
            for i in 0..3 {
                if let Some(r) = reach[i] {
                    (lo[i], hi[i]) = (-r, r);
                }
            }
            (lo, hi)
        }),
    ]
}

fn boxed() -> impl Strategy<Value = ([f64; 3], [f64; 3])> {
    let size = || prop_oneof![0.0..3.0f64, Just(0.0)];
    ([coord(), coord(), coord()], [size(), size(), size()])
        .prop_map(|(lo, size)| (lo, [lo[0] + size[0], lo[1] + size[1], lo[2] + size[2]]))
}

/// The SAH split by the plain sweep: every bin of every axis swept, each
/// axis binned in a pass of its own (`sah_split` bins the three axes in one
/// pass and sweeps only the non-empty bins): the oracle of
/// `sah_split_is_the_sweep_over_every_bin`.
fn sah_split_every_bin(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
    let (cmin, cmax) = centroid_bounds(work);
    let parent = half_area(min, max);
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, bins on the left)
    for axis in 0..3 {
        let extent = cmax[axis] - cmin[axis];
        // Also skips NaN extents.
        if extent.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            continue;
        }
        let mut count = [0usize; BINS];
        let mut bmin = [[f64::INFINITY; 3]; BINS];
        let mut bmax = [[f64::NEG_INFINITY; 3]; BINS];
        let scale = BINS as f64 / extent;
        for e in work.iter() {
            let b = (((e.centre[axis] - cmin[axis]) * scale) as usize).min(BINS - 1);
            count[b] += 1;
            for i in 0..3 {
                bmin[b][i] = bmin[b][i].min(e.min[i]);
                bmax[b][i] = bmax[b][i].max(e.max[i]);
            }
        }
        // Sweep from the right to get the right-hand areas, then from the left.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let (mut rmin, mut rmax, mut rc) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], 0);
        for b in (1..BINS).rev() {
            for i in 0..3 {
                rmin[i] = rmin[i].min(bmin[b][i]);
                rmax[i] = rmax[i].max(bmax[b][i]);
            }
            rc += count[b];
            right_area[b] = if rc > 0 { half_area(&rmin, &rmax) } else { 0.0 };
            right_count[b] = rc;
        }
        let (mut lmin, mut lmax, mut lc) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], 0);
        for b in 0..BINS - 1 {
            for i in 0..3 {
                lmin[i] = lmin[i].min(bmin[b][i]);
                lmax[i] = lmax[i].max(bmax[b][i]);
            }
            lc += count[b];
            let rcount = right_count[b + 1];
            if lc == 0 || rcount == 0 {
                continue;
            }
            let cost = 0.125 + (lc as f64 * half_area(&lmin, &lmax) + rcount as f64 * right_area[b + 1]) / parent;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    // A degenerate parent (zero area) makes every cost NaN or ∞; any split
    // found still separates the centres.
    let (_, axis, bins_left) = best?;
    let extent = cmax[axis] - cmin[axis];
    let scale = BINS as f64 / extent;
    let goes_left = |e: &Entry| (((e.centre[axis] - cmin[axis]) * scale) as usize).min(BINS - 1) < bins_left;
    let i = gather_left(work, goes_left);
    (i > 0 && i < work.len()).then_some(i)
}

/// Boxes on a coarse lattice (coincident centres, flat and equal boxes,
/// empty bins) or anywhere.
fn entries() -> impl Strategy<Value = Vec<Entry>> {
    let coord = prop_oneof![(-4i32..4).prop_map(|k| f64::from(k) * 0.5), -10.0..10.0f64];
    let corner = [coord.clone(), coord.clone(), coord];
    prop::collection::vec((corner.clone(), corner), 2..80).prop_map(|boxes| {
        boxes
            .into_iter()
            .enumerate()
            .map(|(k, (a, b))| {
                let min = [0, 1, 2].map(|i| a[i].min(b[i]));
                let max = [0, 1, 2].map(|i| a[i].max(b[i]));
                let centre = [0, 1, 2].map(|i| 0.5 * (min[i] + max[i]));
                Entry { index: k as u32, min, max, centre }
            })
            .collect()
    })
}

proptest! {
    /// The split and the order it leaves the blocks in are the ones the
    /// sweep over every bin gives.
    #[test]
    fn sah_split_is_the_sweep_over_every_bin(work in entries()) {
        let (min, max) = bounds_of(&work);
        let (mut a, mut b) = (work.clone(), work);
        let split_a = sah_split(&mut a, &min, &max);
        let split_b = sah_split_every_bin(&mut b, &min, &max);
        prop_assert_eq!(split_a, split_b);
        prop_assert_eq!(a.iter().map(|e| e.index).collect::<Vec<_>>(), b.iter().map(|e| e.index).collect::<Vec<_>>());
    }

    /// The wide slab tests are the scalar one lane by lane, to the bit
    /// (parallel axes, flat boxes and boxes through the origin included).
    #[test]
    fn wide_lanes_are_the_scalar_test(
        ray in ray(), b in boxed(), t_min in 0.0..2.0f64, extra in 0.0..5.0f64, lane in 0..8usize,
    ) {
        let rb = RayBoxes::new(&ray);
        for t_max in [t_min + extra, f64::INFINITY] {
            let scalar = rb.enter(&b.0, &b.1, t_min, t_max).map(f64::to_bits);
            let four = lane0::<4, 1>(&rb, &b.0, &b.1, lane % 4, t_min, t_max);
            let eight = lane0::<8, 2>(&rb, &b.0, &b.1, lane, t_min, t_max);
            prop_assert_eq!(scalar, four.map(f64::to_bits));
            prop_assert_eq!(scalar, eight.map(f64::to_bits));
        }
    }

    /// The packet cull of an eight-wide node keeps every child that one
    /// of the active rays enters by its own test (`enter_child`, each
    /// lane the scalar test to the bit): four rays from one point or
    /// from four, near each other or not, near the origin or far from
    /// it, parallel to axes or not; boxes placed at random or through
    /// a point of one of the rays (where only the slack lets the ray
    /// in), empty lanes included.
    #[test]
    fn packet_cull_keeps_every_child_a_ray_enters(
        (rays, boxes) in packet_and_boxes(),
        t_min in prop_oneof![Just(0.0), 0.0..2.0f64],
        t_max in prop::array::uniform4(prop_oneof![Just(f64::INFINITY), 0.0..50.0f64]),
        lanes in 1..16u32,
    ) {
        let rbs = rays.each_ref().map(RayBoxes::new);
        let packet = RayBoxes4::new(&rbs);
        let mut node = Wide::<8, 2>::EMPTY;
        for (c, b) in boxes.iter().enumerate() {
            if let Some((lo, hi)) = b {
                node.set_box(c, lo, hi);
            }
        }
        let t_max = t_max.map(|t| t.max(t_min));
        let reach = (0..4).filter(|l| lanes & (1 << l) != 0).fold(f64::NEG_INFINITY, |m, l| m.max(t_max[l]));
        let kept = RayBoxes4::cull(&PacketBounds::new(&packet), &node, t_min, reach);
        for c in 0..8 {
            let (_, hits) = packet.enter_child(&node, c, f64x4::splat(t_min), f64x4::new(t_max));
            if hits & lanes != 0 {
                prop_assert!(kept & (1 << c) != 0, "child {} entered by lanes {:#b} but culled", c, hits & lanes);
            }
        }
    }

    /// The cheapest collapse costs what the least of every possible
    /// choice of lanes costs, and no more than a greedy rule's.
    #[test]
    fn cheapest_collapse_is_the_least_of_all(boxes in prop::collection::vec(boxed(), 2..12)) {
        let entries: Vec<(u32, Aabb)> = boxes
            .iter()
            .enumerate()
            .map(|(i, (lo, hi))| (i as u32, Aabb { min: Point3::from(*lo), max: Point3::from(*hi) }))
            .collect();
        let binary = Binary::of(&entries, PARALLEL_FROM).nodes;
        prop_assume!(binary[0].count == 0);
        for w in [4, 8] {
            let want = brute_cost(&binary, 0, w);
            let (got, other) = if w == 4 {
                let (t, cost) = Tree::<4, 1>::collapsed_by(&binary, Open::Cheapest);
                prop_assert!((tree_cost(&t) - cost).abs() <= 1e-9 * cost);
                (cost, Tree::<4, 1>::collapsed_by(&binary, Open::Shallowest).1)
            } else {
                let (t, cost) = Tree::<8, 2>::collapsed_by(&binary, Open::Cheapest);
                prop_assert!((tree_cost(&t) - cost).abs() <= 1e-9 * cost);
                (cost, Tree::<8, 2>::collapsed_by(&binary, Open::Largest).1)
            };
            prop_assert!((got - want).abs() <= 1e-9 * want, "{}-wide: {} but the least is {}", w, got, want);
            prop_assert!(got <= other * (1.0 + 1e-12));
        }
    }

    /// The collapsed tree, four- and eight-wide, by any rule, visits exactly the
    /// blocks whose own boxes the ray enters (no early exit).
    #[test]
    fn tree_visits_what_brute_force_does(
        boxes in prop::collection::vec(boxed_or_huge(), 1..60), ray in ray(), eight: bool,
        others in [ray(), ray(), ray()],
        open in prop_oneof![Just(None), Just(Some(Open::Shallowest)), Just(Some(Open::Largest))],
    ) {
        let entries: Vec<(u32, Aabb)> = boxes
            .iter()
            .enumerate()
            .map(|(i, (lo, hi))| (i as u32, Aabb { min: Point3::from(*lo), max: Point3::from(*hi) }))
            .collect();
        let bvh = build_by(&entries, PARALLEL_FROM, eight, open);
        prop_assert_eq!(matches!(bvh.nodes, Nodes::Eight(_)), eight);
        let rb = RayBoxes::new(&ray);
        let mut seen = Vec::new();
        let mut t_max = f64::INFINITY;
        bvh.traverse(&rb, 0.0, &mut t_max, |k, _, _| seen.push(bvh.items()[k as usize]));
        seen.sort_unstable();
        let expected: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| rb.enter(&boxes[i as usize].0, &boxes[i as usize].1, 0.0, f64::INFINITY).is_some())
            .collect();
        // Inner boxes hold their children, so nothing is culled early;
        // a leaf is visited once.
        prop_assert_eq!(&seen, &expected);
        // The any-hit walk visits the same blocks in its own order.
        let mut any = Vec::new();
        let mut t_max = f64::INFINITY;
        bvh.traverse_any(&rb, 0.0, &mut t_max, |k, _, _| any.push(bvh.items()[k as usize]));
        any.sort_unstable();
        prop_assert_eq!(&any, &expected);
        // So does each lane of a packet walk (of this ray and three
        // others), through the eight-wide tree's cull and nodes with
        // unused lanes.
        let rays = [ray, others[0], others[1], others[2]];
        let rbs = rays.map(|r| RayBoxes::new(&r));
        let mut lanes = vec![Vec::new(); 4];
        let mut t_max = [f64::INFINITY; 4];
        bvh.traverse4(&RayBoxes4::new(&rbs), 0b1111, 0.0, &mut t_max, |k, lane, _| {
            lanes[lane].push(bvh.items()[k as usize])
        });
        for (lane, rb) in rbs.iter().enumerate() {
            lanes[lane].sort_unstable();
            let expected: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| rb.enter(&boxes[i as usize].0, &boxes[i as usize].1, 0.0, f64::INFINITY).is_some())
                .collect();
            prop_assert_eq!(&lanes[lane], &expected, "lane {}", lane);
        }
    }
}

/// The two-thread build gives the same tree as one thread, node for node.
#[test]
fn parallel_build_is_the_sequential_one() {
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let entries: Vec<(u32, Aabb)> = (0..6000)
        .map(|i| {
            let c = [next() * 100.0, next() * 100.0, next() * 100.0];
            let r = 0.1 + next();
            (i, Aabb { min: Point3::new(c[0] - r, c[1] - r, c[2] - r), max: Point3::new(c[0] + r, c[1] + r, c[2] + r) })
        })
        .collect();
    for eight in [false, true] {
        let (one, two) = (build_by(&entries, usize::MAX, eight, None), build_by(&entries, 64, eight, None));
        assert_eq!(one.items, two.items);
        match (&one.nodes, &two.nodes) {
            (Nodes::Four(a), Nodes::Four(b)) => same_tree(a, b),
            (Nodes::Eight(a), Nodes::Eight(b)) => same_tree(a, b),
            _ => panic!("the widths differ"),
        }
    }
    // The size decides the width.
    assert!(matches!(Bvh::build(&entries).nodes, Nodes::Eight(_)));
    assert!(matches!(Bvh::build(&entries[..EIGHT_WIDE_FROM - 1]).nodes, Nodes::Four(_)));
}

/// The build keeps the collapse of lower cost: level by level for a
/// grid of like boxes, the largest boxes first for a sphereflake's
/// spheres, whose sizes shrink threefold a level (where the two rules
/// give different trees, so the choice is seen).
#[test]
fn the_build_keeps_the_cheaper_collapse() {
    let cube = |c: [f64; 3], r: f64| Aabb {
        min: Point3::new(c[0] - r, c[1] - r, c[2] - r),
        max: Point3::new(c[0] + r, c[1] + r, c[2] + r),
    };
    let grid: Vec<(u32, Aabb)> =
        (0..1000u32).map(|i| (i, cube([f64::from(i % 10), f64::from(i / 10 % 10), f64::from(i / 100)], 0.3))).collect();
    // Spheres of radius 1, 1/3, 1/9, 1/27 around their parents.
    let mut flake = vec![cube([0.0; 3], 1.0)];
    let mut level = vec![([0.0; 3], 1.0)];
    for _ in 0..3 {
        let mut next = vec![];
        for (c, r) in level {
            for k in 0..9 {
                let a = f64::from(k) * 0.7;
                let child = (
                    [c[0] + 1.34 * r * a.cos(), c[1] + 1.34 * r * a.sin(), c[2] + 0.2 * r * f64::from(k % 3)],
                    r / 3.0,
                );
                flake.push(cube(child.0, child.1));
                next.push(child);
            }
        }
        level = next;
    }
    let flake: Vec<(u32, Aabb)> = flake.into_iter().enumerate().map(|(i, b)| (i as u32, b)).collect();
    for (entries, cheaper) in [(&grid, Open::Shallowest), (&flake, Open::Largest)] {
        let trees = [None, Some(Open::Shallowest), Some(Open::Largest)]
            .map(|open| build_by(entries, PARALLEL_FROM, true, open));
        let [Nodes::Eight(chosen), Nodes::Eight(shallow), Nodes::Eight(large)] = trees.map(|b| b.nodes) else {
            panic!("not eight-wide");
        };
        assert_ne!(tree_cost(&shallow), tree_cost(&large), "the rules give the same tree");
        let (best, other) = match cheaper {
            Open::Shallowest => (shallow, large),
            Open::Largest => (large, shallow),
            Open::Cheapest => unreachable!(),
        };
        assert!(tree_cost(&best) < tree_cost(&other), "{cheaper:?} is not the cheaper rule here");
        // The build's collapse costs less than either rule's on both.
        assert!(tree_cost(&chosen) < tree_cost(&best), "{} against {}", tree_cost(&chosen), tree_cost(&best));
        let Nodes::Eight(cheapest) = build_by(entries, PARALLEL_FROM, true, Some(Open::Cheapest)).nodes else {
            panic!("not eight-wide");
        };
        same_tree(&chosen, &cheapest);
    }
}

/// Every set of lanes `x`'s subtree can give a wide node above it: `x`
/// itself (if `may_be_lane`, or a leaf), or one of its first child's
/// sets beside one of its second's, at most `w` lanes in all.
fn cuts(nodes: &[Node], x: usize, may_be_lane: bool, w: usize) -> Vec<Vec<usize>> {
    if nodes[x].count > 0 {
        return vec![vec![x]];
    }
    let mut all = if may_be_lane { vec![vec![x]] } else { vec![] };
    let first = nodes[x].start as usize;
    for a in cuts(nodes, first, true, w) {
        for b in cuts(nodes, first + 1, true, w) {
            if a.len() + b.len() <= w {
                all.push([a.clone(), b].concat());
            }
        }
    }
    all
}

/// The least cost of the wide node for `x` and everything below it, by
/// trying every set of lanes (its own two children opened).
fn brute_cost(nodes: &[Node], x: usize, w: usize) -> f64 {
    let first = nodes[x].start as usize;
    let mut best = f64::INFINITY;
    for a in cuts(nodes, first, false, w) {
        for b in cuts(nodes, first + 1, false, w) {
            if a.len() + b.len() <= w {
                let below: f64 =
                    a.iter().chain(&b).filter(|&&c| nodes[c].count == 0).map(|&c| brute_cost(nodes, c, w)).sum();
                best = best.min(below);
            }
        }
    }
    half_area(&nodes[x].min, &nodes[x].max) + best
}

/// The sum of the half-areas of a tree's node boxes (the union of each
/// node's lanes), as [`Tree::collapse`] adds them up.
fn tree_cost<const W: usize, const H: usize>(t: &Tree<W, H>) -> f64 {
    t.nodes
        .iter()
        .map(|node| {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for lane in 0..W {
                for i in 0..3 {
                    let (a, b) = (
                        node.group[lane / 4].min[i].as_array_ref()[lane % 4],
                        node.group[lane / 4].max[i].as_array_ref()[lane % 4],
                    );
                    if a <= b {
                        lo[i] = lo[i].min(a);
                        hi[i] = hi[i].max(b);
                    }
                }
            }
            half_area(&lo, &hi)
        })
        .sum()
}

fn same_tree<const W: usize, const H: usize>(a: &Tree<W, H>, b: &Tree<W, H>) {
    assert_eq!(a.nodes.len(), b.nodes.len());
    for (a, b) in a.nodes.iter().zip(&b.nodes) {
        assert_eq!((a.child, a.count), (b.child, b.count));
        for i in 0..3 {
            for g in 0..H {
                assert_eq!(a.group[g].min[i].to_array(), b.group[g].min[i].to_array());
                assert_eq!(a.group[g].max[i].to_array(), b.group[g].max[i].to_array());
            }
        }
    }
}
