//! The binary build: the surface-area heuristic over binned centroids, one
//! block per leaf, the two halves of a large subtree built on two threads
//! (the same tree as one thread builds).

use super::{half_area, LEAF_SIZE, MAX_DEPTH};
use crate::Aabb;

/// Number of centroid bins per axis for the SAH.
pub(super) const BINS: usize = 16;

/// A node of the binary build: its box and either two children or a run of
/// blocks.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    /// Lower corner.
    pub(super) min: [f64; 3],
    /// Upper corner.
    pub(super) max: [f64; 3],
    /// Inner node: index of its first child in `Binary::nodes` (the second
    /// follows it). Leaf: index of its first entry in `items`.
    pub(super) start: u32,
    /// Number of blocks in a leaf; 0 for an inner node.
    pub(super) count: u32,
}

pub(super) const EMPTY_NODE: Node = Node { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], start: 0, count: 0 };

/// The binary tree the builder makes (and `Tree::collapse` turns into the
/// wide one): the two children of an inner node are consecutive.
pub(super) struct Binary {
    pub(super) nodes: Vec<Node>,
    pub(super) items: Vec<u32>,
}

impl Binary {
    /// The binary tree over `entries` (not empty), subtrees of
    /// `parallel_from` blocks or more built on two threads.
    pub(super) fn of(entries: &[(u32, Aabb)], parallel_from: usize) -> Self {
        let mut work: Vec<Entry> = entries
            .iter()
            .map(|(i, b)| Entry {
                index: *i,
                min: [b.min.x, b.min.y, b.min.z],
                max: [b.max.x, b.max.y, b.max.z],
                centre: [0.5 * (b.min.x + b.max.x), 0.5 * (b.min.y + b.max.y), 0.5 * (b.min.z + b.max.z)],
            })
            .collect();
        let mut binary =
            Binary { nodes: Vec::with_capacity(2 * entries.len()), items: Vec::with_capacity(entries.len()) };
        binary.nodes.push(EMPTY_NODE);
        binary.build_node(0, &mut work, 0, parallel_from);
        binary
    }

    /// Fills node `n` with `work`; the two halves of a subtree of at least
    /// `parallel_from` blocks are built on two threads (`rayon::join`), each
    /// into a tree of its own grafted in place after: the same nodes in the
    /// same order as one thread builds.
    fn build_node(&mut self, n: usize, work: &mut [Entry], depth: usize, parallel_from: usize) {
        let (min, max) = bounds_of(work);
        let split = if work.len() <= LEAF_SIZE || depth + 1 >= MAX_DEPTH { None } else { split(work, &min, &max) };
        let start = match split {
            None => {
                let first = self.items.len() as u32;
                self.items.extend(work.iter().map(|e| e.index));
                first
            }
            Some(_) => self.nodes.len() as u32,
        };
        self.nodes[n] = Node { min, max, start, count: if split.is_some() { 0 } else { work.len() as u32 } };
        if let Some(mid) = split {
            self.nodes.extend([EMPTY_NODE; 2]);
            let parallel = work.len() >= parallel_from;
            let (left, right) = work.split_at_mut(mid);
            if parallel {
                let subtree = |work: &mut [Entry]| {
                    // A binary tree over `n` blocks has at most `2n - 1` nodes.
                    let mut nodes = Vec::with_capacity(2 * work.len());
                    nodes.push(EMPTY_NODE);
                    let mut t = Binary { nodes, items: Vec::with_capacity(work.len()) };
                    t.build_node(0, work, depth + 1, parallel_from);
                    t
                };
                let (l, r) = rayon::join(|| subtree(left), || subtree(right));
                self.graft(start as usize, &l);
                self.graft(start as usize + 1, &r);
            } else {
                self.build_node(start as usize, left, depth + 1, parallel_from);
                self.build_node(start as usize + 1, right, depth + 1, parallel_from);
            }
        }
    }

    /// Puts the tree `t` (root: its node 0) at node `n`, its other nodes and
    /// its items after ours, where `build_node(n, ..)` would have put them.
    fn graft(&mut self, n: usize, t: &Binary) {
        // `t`'s node k >= 1 lands at `k - 1 + len`.
        let node_shift = self.nodes.len() as u32 - 1;
        let item_shift = self.items.len() as u32;
        let moved = |mut node: Node| {
            node.start += if node.count == 0 { node_shift } else { item_shift };
            node
        };
        self.nodes[n] = moved(t.nodes[0]);
        self.nodes.extend(t.nodes[1..].iter().map(|&k| moved(k)));
        self.items.extend_from_slice(&t.items);
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Entry {
    pub(super) index: u32,
    pub(super) min: [f64; 3],
    pub(super) max: [f64; 3],
    pub(super) centre: [f64; 3],
}

/// The box of the blocks' boxes.
pub(super) fn bounds_of(work: &[Entry]) -> ([f64; 3], [f64; 3]) {
    span(work, |e| (&e.min, &e.max))
}

/// The box of the blocks' box centres.
pub(super) fn centroid_bounds(work: &[Entry]) -> ([f64; 3], [f64; 3]) {
    span(work, |e| (&e.centre, &e.centre))
}

/// The smallest box holding every entry's `(lower, upper)` corners.
#[inline(always)]
fn span(work: &[Entry], corners: impl Fn(&Entry) -> (&[f64; 3], &[f64; 3])) -> ([f64; 3], [f64; 3]) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for e in work {
        let (lo, hi) = corners(e);
        for i in 0..3 {
            min[i] = min[i].min(lo[i]);
            max[i] = max[i].max(hi[i]);
        }
    }
    (min, max)
}

/// Splits `work` between two children and returns the size of the left
/// part, or `None` for a leaf (at most [`LEAF_SIZE`] blocks): the cheapest
/// binned SAH split; if the centres coincide (no SAH split separates them),
/// small boxes to one side and large to the other, so that a ray missing
/// the small ones skips them. A split is made even where the SAH would
/// price a leaf of two blocks lower: one block per leaf keeps the walks
/// exact, and the wide collapse absorbs the extra level.
fn split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
    if work.len() <= LEAF_SIZE {
        return None;
    }
    sah_split(work, min, max).or_else(|| {
        work.sort_unstable_by(|a, b| half_area(&a.min, &a.max).total_cmp(&half_area(&b.min, &b.max)));
        Some(work.len() / 2)
    })
}

/// Partitions `work` by the cheapest binned SAH split and returns the size
/// of the left part; `None` if no split separates the centres.
///
/// The three axes are binned in one pass over `work`, and each axis's
/// sweeps visit only its non-empty bins: a candidate after an empty bin
/// costs exactly what the candidate before it did (the same blocks on
/// either side), and only a strictly cheaper candidate replaces the best,
/// so skipping it changes nothing. Small subtrees, most of the nodes, fill
/// only a few of the bins.
pub(super) fn sah_split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
    let (cmin, cmax) = centroid_bounds(work);
    let parent = half_area(min, max);
    // Also skips NaN extents.
    let open = |axis: usize| (cmax[axis] - cmin[axis]).partial_cmp(&0.0) == Some(core::cmp::Ordering::Greater);
    if !(open(0) || open(1) || open(2)) {
        return None;
    }
    let scale = [0, 1, 2].map(|axis| BINS as f64 / (cmax[axis] - cmin[axis]));
    // `as u32` saturates as `as usize` does (NaN to 0), so with the clamp
    // to the last bin both give the same bin, at fewer instructions.
    let bin =
        |e: &Entry, axis: usize| (((e.centre[axis] - cmin[axis]) * scale[axis]) as u32).min(BINS as u32 - 1) as usize;
    let mut count = [[0u32; BINS]; 3];
    let mut bmin = [[[f64::INFINITY; 3]; BINS]; 3];
    let mut bmax = [[[f64::NEG_INFINITY; 3]; BINS]; 3];
    for e in work.iter() {
        for axis in 0..3 {
            // A closed axis's bins are filled but not read.
            let b = bin(e, axis);
            count[axis][b] += 1;
            for i in 0..3 {
                bmin[axis][b][i] = bmin[axis][b][i].min(e.min[i]);
                bmax[axis][b][i] = bmax[axis][b][i].max(e.max[i]);
            }
        }
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, bins on the left)
    for axis in (0..3).filter(|&axis| open(axis)) {
        let (count, bmin, bmax) = (&count[axis], &bmin[axis], &bmax[axis]);
        let mut full = [0usize; BINS];
        let mut n = 0;
        for (b, &c) in count.iter().enumerate() {
            if c > 0 {
                full[n] = b;
                n += 1;
            }
        }
        // Sweep from the right to get the right-hand areas (`right[k]`: of
        // the bins from `full[k]` on), then from the left.
        let mut right = [(0.0, 0u32); BINS];
        let (mut rmin, mut rmax, mut rc) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], 0);
        for k in (1..n).rev() {
            let b = full[k];
            for i in 0..3 {
                rmin[i] = rmin[i].min(bmin[b][i]);
                rmax[i] = rmax[i].max(bmax[b][i]);
            }
            rc += count[b];
            right[k] = (half_area(&rmin, &rmax), rc);
        }
        let (mut lmin, mut lmax, mut lc) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], 0);
        for k in 0..n.saturating_sub(1) {
            let b = full[k];
            for i in 0..3 {
                lmin[i] = lmin[i].min(bmin[b][i]);
                lmax[i] = lmax[i].max(bmax[b][i]);
            }
            lc += count[b];
            let (right_area, rcount) = right[k + 1];
            let cost = 0.125 + (f64::from(lc) * half_area(&lmin, &lmax) + f64::from(rcount) * right_area) / parent;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    // A degenerate parent (zero area) makes every cost NaN or ∞; any split
    // found still separates the centres.
    let (_, axis, bins_left) = best?;
    let goes_left = |e: &Entry| bin(e, axis) < bins_left;
    let i = gather_left(work, goes_left);
    (i > 0 && i < work.len()).then_some(i)
}

/// Moves the entries that go left to the front, in place, and returns
/// their number.
pub(super) fn gather_left(work: &mut [Entry], goes_left: impl Fn(&Entry) -> bool) -> usize {
    let mut i = 0;
    for j in 0..work.len() {
        if goes_left(&work[j]) {
            work.swap(i, j);
            i += 1;
        }
    }
    i
}
