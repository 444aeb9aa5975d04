//! A bounding-volume hierarchy over the bounded blocks.
//!
//! Built once with the surface-area heuristic over binned centroids; stored
//! flat (a node's left child follows it, the right child is indexed), and
//! traversed front to back with a fixed-size stack, so a query never
//! allocates.

use quadric::Ray;

use crate::Aabb;

/// Leaves hold at most this many blocks.
const LEAF_SIZE: usize = 4;
/// Number of centroid bins per axis for the SAH.
const BINS: usize = 16;
/// Traversal stack depth; the builder makes a leaf before a subtree could
/// get deeper than this, so the stack cannot overflow.
pub(crate) const MAX_DEPTH: usize = 64;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: [f64; 3],
    max: [f64; 3],
    /// Inner node: index of the right child (the left is the next node).
    /// Leaf: index of its first entry in `Bvh::items`.
    start: u32,
    /// Number of blocks in a leaf; 0 for an inner node.
    count: u32,
}

/// The hierarchy: nodes, and the block indices the leaves point into.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
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
    #[inline(always)]
    pub(crate) fn enter(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> Option<f64> {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let inv = self.inv[i];
            if inv.is_infinite() {
                // Parallel to the slab: inside it or never.
                if self.origin[i] < min[i] - self.pad || self.origin[i] > max[i] + self.pad {
                    return None;
                }
                continue;
            }
            let a = (min[i] - self.pad - self.origin[i]) * inv;
            let b = (max[i] + self.pad - self.origin[i]) * inv;
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // NaN (∞ - ∞ on an infinite side) fails both tests and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        let slack = 4.0 * f64::EPSILON * t1.abs().max(t0.abs());
        (t0 <= t1 + slack).then_some(t0 - slack)
    }
}

impl Bvh {
    /// Builds the hierarchy over `(index, box)` pairs; every box must be bounded.
    pub(crate) fn build(entries: &[(u32, Aabb)]) -> Self {
        let mut bvh = Bvh { nodes: Vec::with_capacity(2 * entries.len() / LEAF_SIZE + 1), items: Vec::new() };
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
        bvh.build_node(&mut work, 0);
        bvh
    }

    fn build_node(&mut self, work: &mut [Entry], depth: usize) -> usize {
        let (min, max) = bounds_of(work);
        let at = self.nodes.len();
        self.nodes.push(Node { min, max, start: 0, count: 0 });
        let split = if work.len() <= LEAF_SIZE || depth + 1 >= MAX_DEPTH { None } else { sah_split(work, &min, &max) };
        match split {
            None => {
                self.nodes[at].start = self.items.len() as u32;
                self.nodes[at].count = work.len() as u32;
                self.items.extend(work.iter().map(|e| e.index));
            }
            Some(mid) => {
                let (left, right) = work.split_at_mut(mid);
                self.build_node(left, depth + 1);
                let r = self.build_node(right, depth + 1);
                self.nodes[at].start = r as u32;
            }
        }
        at
    }

    /// Visits the blocks whose boxes the ray crosses within `[t_min, *t_max]`,
    /// nearest box first, calling `visit(block, box_entry, t_max)`; `visit`
    /// may lower `*t_max` to cut off everything farther away (early exit).
    #[inline]
    pub(crate) fn traverse(
        &self,
        ray: &RayBoxes,
        t_min: f64,
        t_max: &mut f64,
        mut visit: impl FnMut(u32, f64, &mut f64),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [(0u32, 0.0f64); MAX_DEPTH + 1];
        let mut top = 0usize;
        let root = &self.nodes[0];
        let Some(t) = ray.enter(&root.min, &root.max, t_min, *t_max) else { return };
        stack[0] = (0, t);
        top += 1;
        while top > 0 {
            top -= 1;
            let (n, t_enter) = stack[top];
            if t_enter > *t_max {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let first = node.start as usize;
                for &item in &self.items[first..first + node.count as usize] {
                    visit(item, t_enter, t_max);
                }
                continue;
            }
            let (l, r) = (n + 1, node.start);
            let (ln, rn) = (&self.nodes[l as usize], &self.nodes[r as usize]);
            let tl = ray.enter(&ln.min, &ln.max, t_min, *t_max);
            let tr = ray.enter(&rn.min, &rn.max, t_min, *t_max);
            // Push the farther child first so the nearer one is popped next.
            let mut push = |node: u32, t: f64| {
                stack[top] = (node, t);
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
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; MAX_DEPTH + 1];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let n = stack[top];
            let node = &self.nodes[n as usize];
            if !(0..3).all(|i| node.min[i] <= p[i] && p[i] <= node.max[i]) {
                continue;
            }
            if node.count > 0 {
                let first = node.start as usize;
                for &item in &self.items[first..first + node.count as usize] {
                    visit(item);
                }
            } else {
                stack[top] = n + 1;
                stack[top + 1] = node.start;
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

/// Partitions `work` by the cheapest binned SAH split and returns the size
/// of the left part, or `None` if a leaf is cheaper (or no split separates).
fn sah_split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
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
        return None;
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
    (i > 0 && i < work.len()).then_some(i)
}
