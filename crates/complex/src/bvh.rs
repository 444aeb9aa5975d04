//! A bounding-volume hierarchy over the bounded blocks.
//!
//! Built once with the surface-area heuristic over binned centroids; stored
//! flat, the two children of a node side by side in 128 bytes aligned to a
//! cache line (so a step reads both child boxes from two adjacent lines);
//! traversed front to back with a fixed-size stack, so a query never
//! allocates. (`f32` boxes rounded outwards, two nodes per 64-byte line,
//! were measured too: the conversions cost as much as the smaller nodes
//! saved, see `docs/benchmarks.md`.)

use quadric::Ray;

use crate::Aabb;

/// Leaves hold at most this many blocks (unless their centres coincide and
/// the depth limit is reached).
const LEAF_SIZE: usize = 1;
/// Number of centroid bins per axis for the SAH.
const BINS: usize = 16;
/// Traversal stack depth; the builder makes a leaf before a subtree could
/// get deeper than this, so the stack cannot overflow.
pub(crate) const MAX_DEPTH: usize = 64;

/// A node: its box and either two children or a run of blocks.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Lower corner.
    min: [f64; 3],
    /// Upper corner.
    max: [f64; 3],
    /// Inner node: index of its pair of children in `Bvh::pairs`.
    /// Leaf: index of its first entry in `Bvh::items`.
    start: u32,
    /// Number of blocks in a leaf; 0 for an inner node.
    count: u32,
}

const EMPTY_NODE: Node = Node { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], start: 0, count: 0 };

/// Two sibling nodes (112 bytes, padded to 128), aligned to a cache line.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
struct Pair([Node; 2]);

/// The hierarchy: node pairs, and the block indices the leaves point into.
/// Node `n` is `pairs[n / 2].0[n % 2]`; the root is node 0 (its sibling,
/// node 1, is an unused empty node).
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    pairs: Vec<Pair>,
    items: Vec<u32>,
}

/// A ray prepared for slab tests: origin and reciprocal direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes {
    origin: [f64; 3],
    inv: [f64; 3],
    /// How far outside a block's exact box the kernel may put the ends of
    /// the block's intervals: they are accurate to a few ulps of the ray
    /// origin's coordinates, which near a box at the origin (a ray leaving
    /// the plane x = 0 from (0, 4, 12)) is far more than the box's own
    /// widening. Boxes are grown by this much in the slab test.
    pad: f64,
}

impl RayBoxes {
    pub(crate) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin(), ray.direction());
        // About 450 ulps of the origin, as `WIDEN_ABS` in `bounds.rs`.
        let pad = 1e-13 * o.coords.amax();
        RayBoxes { origin: [o.x, o.y, o.z], inv: [1.0 / d.x, 1.0 / d.y, 1.0 / d.z], pad }
    }

    /// The entry parameter of the ray into the closed box within
    /// `[t_min, t_max]`, or `None`. Conservative: rounding in the slab test
    /// is covered by a few ulps of slack, so a point of the box on the ray is
    /// never missed.
    ///
    /// No branch for a ray parallel to a slab: its reciprocal is `±∞`, so the
    /// slab gives `[-∞, ∞]` from inside, `±[∞, ∞]` (a miss) from outside, and
    /// NaN (`0·∞`) from its boundary plane, which fails both comparisons and
    /// leaves the range open (the closed box holds that point).
    #[inline(always)]
    pub(crate) fn enter(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> Option<f64> {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let inv = self.inv[i];
            let a = (min[i] - self.pad - self.origin[i]) * inv;
            let b = (max[i] + self.pad - self.origin[i]) * inv;
            let (a, b) = if inv >= 0.0 { (a, b) } else { (b, a) };
            // NaN (∞ - ∞ on an infinite side, 0·∞) fails both tests and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        let slack = 4.0 * f64::EPSILON * t1.abs().max(t0.abs());
        // `t0 = ∞` (a parallel ray outside a slab on its far side) would pass
        // `t0 <= t1 + ∞`: a miss.
        (t0 < f64::INFINITY && t0 <= t1 + slack).then_some(t0 - slack)
    }

    /// The parameter range `[lo, hi]` of the line in the padded box, without
    /// slack or clipping: the same slabs as [`RayBoxes::enter`], whose range
    /// for `[t_min, t_max]` is exactly `[max(t_min, lo), min(t_max, hi)]`. So
    /// a probe `enter(.., t, t)` finds the box for every `t` in `[lo, hi]`,
    /// and so does every node above it (its box holds this one, and the slab
    /// arithmetic is monotone). `lo > hi` when the line misses the box.
    #[inline(always)]
    pub(crate) fn range(&self, min: &[f64; 3], max: &[f64; 3]) -> (f64, f64) {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in 0..3 {
            let inv = self.inv[i];
            let a = (min[i] - self.pad - self.origin[i]) * inv;
            let b = (max[i] + self.pad - self.origin[i]) * inv;
            let (a, b) = if inv >= 0.0 { (a, b) } else { (b, a) };
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        (t0, t1)
    }

    /// [`RayBoxes::enter`] for a node's box.
    #[inline(always)]
    fn enter_node(&self, node: &Node, t_min: f64, t_max: f64) -> Option<f64> {
        self.enter(&node.min, &node.max, t_min, t_max)
    }
}

impl Bvh {
    /// Builds the hierarchy over `(index, box)` pairs; every box must be bounded.
    pub(crate) fn build(entries: &[(u32, Aabb)]) -> Self {
        let mut bvh = Bvh { pairs: Vec::with_capacity(entries.len() / LEAF_SIZE + 1), items: Vec::new() };
        if entries.is_empty() {
            return bvh;
        }
        let mut work: Vec<Entry> = entries
            .iter()
            .map(|(i, b)| Entry {
                index: *i,
                min: [b.min.x, b.min.y, b.min.z],
                max: [b.max.x, b.max.y, b.max.z],
                centre: [0.5 * (b.min.x + b.max.x), 0.5 * (b.min.y + b.max.y), 0.5 * (b.min.z + b.max.z)],
            })
            .collect();
        bvh.items.reserve(entries.len());
        bvh.pairs.push(Pair([EMPTY_NODE; 2]));
        bvh.build_node(0, &mut work, 0);
        bvh
    }

    #[inline(always)]
    fn node(&self, n: u32) -> &Node {
        &self.pairs[(n / 2) as usize].0[(n % 2) as usize]
    }

    fn node_mut(&mut self, n: u32) -> &mut Node {
        &mut self.pairs[(n / 2) as usize].0[(n % 2) as usize]
    }

    /// Fills node `n` with `work`.
    fn build_node(&mut self, n: u32, work: &mut [Entry], depth: usize) {
        let (min, max) = bounds_of(work);
        let split = if work.len() <= LEAF_SIZE || depth + 1 >= MAX_DEPTH { None } else { split(work, &min, &max) };
        let start = match split {
            None => {
                let first = self.items.len() as u32;
                self.items.extend(work.iter().map(|e| e.index));
                first
            }
            Some(_) => self.pairs.len() as u32,
        };
        *self.node_mut(n) = Node { min, max, start, count: if split.is_some() { 0 } else { work.len() as u32 } };
        if let Some(mid) = split {
            self.pairs.push(Pair([EMPTY_NODE; 2]));
            let (left, right) = work.split_at_mut(mid);
            self.build_node(2 * start, left, depth + 1);
            self.build_node(2 * start + 1, right, depth + 1);
        }
    }

    /// The block indices in leaf order (a leaf's blocks are consecutive).
    pub(crate) fn items(&self) -> &[u32] {
        &self.items
    }

    /// Visits the blocks whose boxes the ray crosses within `[t_min, *t_max]`,
    /// nearest box first, calling `visit(k, box_entry, t_max)` with `k` the
    /// position in [`Bvh::items`]; `visit` may lower `*t_max` to cut off
    /// everything farther away (early exit).
    #[inline]
    pub(crate) fn traverse(
        &self,
        ray: &RayBoxes,
        t_min: f64,
        t_max: &mut f64,
        mut visit: impl FnMut(u32, f64, &mut f64),
    ) {
        if self.pairs.is_empty() {
            return;
        }
        let Some(t) = ray.enter_node(self.node(0), t_min, *t_max) else { return };
        // Two plain arrays: zeroing them is a short memset, where an array of
        // `(u32, f64)` pairs was zeroed field by field on every query.
        let mut stack_node = [0u32; MAX_DEPTH + 1];
        let mut stack_t = [0.0f64; MAX_DEPTH + 1];
        stack_t[0] = t;
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let (n, t_enter) = (stack_node[top], stack_t[top]);
            if t_enter > *t_max {
                continue;
            }
            let node = self.node(n);
            if node.count > 0 {
                for k in node.start..node.start + node.count {
                    visit(k, t_enter, t_max);
                }
                continue;
            }
            let pair = &self.pairs[node.start as usize].0;
            let (l, r) = (2 * node.start, 2 * node.start + 1);
            let tl = ray.enter_node(&pair[0], t_min, *t_max);
            let tr = ray.enter_node(&pair[1], t_min, *t_max);
            // Push the farther child first so the nearer one is popped next.
            let mut push = |node: u32, t: f64| {
                stack_node[top] = node;
                stack_t[top] = t;
                top += 1;
            };
            match (tl, tr) {
                (Some(a), Some(b)) if a <= b => {
                    push(r, b);
                    push(l, a);
                }
                (Some(a), Some(b)) => {
                    push(l, a);
                    push(r, b);
                }
                (Some(a), None) => push(l, a),
                (None, Some(b)) => push(r, b),
                (None, None) => {}
            }
        }
    }

    /// Visits the blocks whose boxes contain `p`.
    pub(crate) fn visit_point(&self, p: &[f64; 3], mut visit: impl FnMut(u32)) {
        if self.pairs.is_empty() {
            return;
        }
        let mut stack = [0u32; MAX_DEPTH + 1];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let n = stack[top];
            let node = self.node(n);
            if !(0..3).all(|i| node.min[i] <= p[i] && p[i] <= node.max[i]) {
                continue;
            }
            if node.count > 0 {
                let first = node.start as usize;
                for &item in &self.items[first..first + node.count as usize] {
                    visit(item);
                }
            } else {
                stack[top] = 2 * node.start;
                stack[top + 1] = 2 * node.start + 1;
                top += 2;
            }
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    index: u32,
    min: [f64; 3],
    max: [f64; 3],
    centre: [f64; 3],
}

fn bounds_of(work: &[Entry]) -> ([f64; 3], [f64; 3]) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for e in work {
        for i in 0..3 {
            min[i] = min[i].min(e.min[i]);
            max[i] = max[i].max(e.max[i]);
        }
    }
    (min, max)
}

fn half_area(min: &[f64; 3], max: &[f64; 3]) -> f64 {
    let d = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// Partitions `work` for two children and returns the size of the left
/// part, or `None` for a leaf: the cheapest binned SAH split; if the centres
/// coincide (no SAH split separates them) and the leaf would be big, small
/// boxes to one side and large to the other, so that a ray missing the
/// small ones skips them.
fn split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
    match sah_split(work, min, max) {
        Some(SahSplit::Split(mid)) => Some(mid),
        Some(SahSplit::Leaf) => None,
        None if work.len() > LEAF_SIZE => {
            work.sort_unstable_by(|a, b| half_area(&a.min, &a.max).total_cmp(&half_area(&b.min, &b.max)));
            Some(work.len() / 2)
        }
        None => None,
    }
}

enum SahSplit {
    Split(usize),
    Leaf,
}

/// Partitions `work` by the cheapest binned SAH split and returns the size
/// of the left part, or `Leaf` if a leaf is cheaper; `None` if no split
/// separates the centres.
fn sah_split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<SahSplit> {
    let mut cmin = [f64::INFINITY; 3];
    let mut cmax = [f64::NEG_INFINITY; 3];
    for e in work.iter() {
        for i in 0..3 {
            cmin[i] = cmin[i].min(e.centre[i]);
            cmax[i] = cmax[i].max(e.centre[i]);
        }
    }
    let parent = half_area(min, max);
    // Cost of a leaf relative to one traversal step: testing a block costs
    // about as much as a few box tests.
    let leaf_cost = work.len() as f64;
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
            if best.map_or(true, |(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    let (cost, axis, bins_left) = best?;
    // A degenerate parent (zero area) makes every cost NaN or ∞: split anyway
    // when the leaf would be big, to keep leaves small.
    if cost.is_finite() && cost >= leaf_cost && work.len() <= 2 * LEAF_SIZE {
        return Some(SahSplit::Leaf);
    }
    let extent = cmax[axis] - cmin[axis];
    let scale = BINS as f64 / extent;
    let goes_left = |e: &Entry| (((e.centre[axis] - cmin[axis]) * scale) as usize).min(BINS - 1) < bins_left;
    // In-place partition.
    let mut i = 0;
    for j in 0..work.len() {
        if goes_left(&work[j]) {
            work.swap(i, j);
            i += 1;
        }
    }
    (i > 0 && i < work.len()).then_some(SahSplit::Split(i))
}

#[cfg(test)]
mod tests {
    use quadric::nalgebra::{Point3, Vector3};

    use super::*;

    /// Rays parallel to slabs (reciprocals `±∞`): inside, on the boundary,
    /// outside on either side, along both directions of each axis.
    #[test]
    fn slab_test_with_axis_parallel_rays() {
        let (min, max) = ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        let check = |origin: [f64; 3], dir: [f64; 3], expected: bool| {
            let ray = Ray::new(Point3::from(origin), Vector3::from(dir)).expect("valid");
            let got = RayBoxes::new(&ray).enter(&min, &max, 0.0, f64::INFINITY);
            assert_eq!(got.is_some(), expected, "{origin:?} along {dir:?}: {got:?}");
            assert!(got.map_or(true, |t| !t.is_nan()), "{origin:?} along {dir:?}: NaN entry");
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
}
