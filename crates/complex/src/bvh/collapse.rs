//! The collapse of the binary tree into a wide one: the collapse of least
//! surface-area cost among all that open each wide node's own two binary
//! children, found by dynamic programming over the binary tree ([`Costs`]),
//! each node's cost capped so that huge or infinite boxes keep the sums
//! finite.

use arrayvec::ArrayVec;

use super::build::Node;
use super::{half_area, Tree, Wide};

impl<const W: usize, const H: usize> Tree<W, H> {
    /// The wide tree of a binary one (root: node 0, not empty), the
    /// cheapest collapse ([`Tree::cheapest`]).
    pub(super) fn from_binary(binary: &[Node]) -> Self {
        const { assert!(W == 4 * H && W <= 8) };
        let root = &binary[0];
        if root.count > 0 {
            return Self::single_leaf(root);
        }
        Self::cheapest(binary).0
    }

    /// The tree of a binary one that is a single leaf: one node with one lane.
    pub(super) fn single_leaf(root: &Node) -> Self {
        let mut node = Wide::EMPTY;
        node.set_box(0, &root.min, &root.max);
        node.child[0] = root.start;
        node.count[0] = root.count;
        Tree { nodes: vec![node] }
    }

    /// The collapse of least cost of a binary tree whose root is an inner
    /// node, among all that open each wide node's own two binary children
    /// (see [`Costs`]), and its cost.
    pub(super) fn cheapest(binary: &[Node]) -> (Self, f64) {
        let costs = Costs::<W>::new(binary);
        Self::collapsed(binary, &|x| costs.children(binary, x))
    }

    /// The wide tree of a binary one whose root is an inner node, each wide
    /// node's children picked by `children`, and its cost: the sum of its
    /// nodes' half-areas (see [`Tree::collapse`]).
    pub(super) fn collapsed(binary: &[Node], children: &impl Fn(usize) -> ArrayVec<usize, W>) -> (Self, f64) {
        let mut tree = Tree { nodes: Vec::with_capacity(binary.len() / (W - 1) + 1) };
        let mut cost = 0.0;
        tree.collapse(binary, 0, children, &mut cost);
        (tree, cost)
    }

    /// Appends the wide node for the binary inner node `n`, then those of
    /// its inner descendants; returns its index, and adds to `cost` the
    /// half-areas of the boxes of the nodes it makes (a ray crosses a box
    /// about in proportion to its area: their sum over the root's is the
    /// number of node steps a random ray takes, the surface-area heuristic
    /// of the wide tree). Its children, at most `W`, are the binary nodes
    /// `children(n)` picks below `n` (as [`Costs`] chose them, or, in the
    /// tests, by a greedy rule); `n`'s own two children are always opened:
    /// so every inner child is at least two binary levels below `n`, and the
    /// wide tree is at most `MAX_DEPTH / 2` deep (see `STACK`).
    fn collapse(
        &mut self,
        nodes: &[Node],
        n: usize,
        children: &impl Fn(usize) -> ArrayVec<usize, W>,
        cost: &mut f64,
    ) -> u32 {
        *cost += step_cost(&nodes[n]);
        let me = self.nodes.len();
        self.nodes.push(Wide::EMPTY);
        let mut node = Wide::EMPTY;
        for (lane, c) in children(n).into_iter().enumerate() {
            let k = &nodes[c];
            node.set_box(lane, &k.min, &k.max);
            if k.count > 0 {
                node.child[lane] = k.start;
                node.count[lane] = k.count;
            } else {
                node.child[lane] = self.collapse(nodes, c, children, cost);
            }
        }
        self.nodes[me] = node;
        me as u32
    }
}

/// The least costs of a collapse that opens each wide node's own two
/// binary children, for every binary node `x` (children follow their
/// parent in the binary tree, so one pass from the last node to the first
/// has each node's children done before it):
///
/// - `node[x]`: `x` as a wide node: the half-area of its box plus the least
///   cost of its two children's subtrees, both opened (unless leaves),
///   sharing `W` lanes (`node_split[x]` of them to the first child);
/// - `opened[x][k - 1]`: `x`'s subtree in at most `k` lanes with `x` opened:
///   0 for a leaf (one lane), else the least sum, over the ways to share
///   the `k` lanes (`opened_split[x][k - 1]` to the first child), of its
///   children's subtrees in their lanes, each as cheap as it can be: the
///   child as one lane (a leaf, free; an inner node, `node`), or opened.
///
/// A lane is thus always at least two binary levels below its wide node
/// (see `STACK`). Costs are summed in one order, so on a tie the choice is
/// the first found: the child as one lane before opening it, fewer lanes
/// to the first child first.
struct Costs<const W: usize> {
    node: Vec<f64>,
    node_split: Vec<u8>,
    opened: Vec<[f64; W]>,
    opened_split: Vec<[u8; W]>,
}

impl<const W: usize> Costs<W> {
    fn new(nodes: &[Node]) -> Self {
        let n = nodes.len();
        let mut c = Costs {
            node: vec![f64::INFINITY; n],
            node_split: vec![0; n],
            opened: vec![[f64::INFINITY; W]; n],
            opened_split: vec![[0; W]; n],
        };
        for x in (0..n).rev() {
            if nodes[x].count > 0 {
                c.opened[x] = [0.0; W];
                continue;
            }
            let (l, r) = (nodes[x].start as usize, nodes[x].start as usize + 1);
            for k in 2..=W {
                let mut best = (f64::INFINITY, 0);
                for j in 1..k {
                    let sum = c.lanes(nodes, l, j) + c.lanes(nodes, r, k - j);
                    if sum < best.0 {
                        best = (sum, j);
                    }
                }
                c.opened[x][k - 1] = best.0;
                c.opened_split[x][k - 1] = best.1 as u8;
            }
            let mut best = (f64::INFINITY, 0);
            for j in 1..W {
                let sum = c.opened[l][j - 1] + c.opened[r][W - j - 1];
                if sum < best.0 {
                    best = (sum, j);
                }
            }
            c.node[x] = step_cost(&nodes[x]) + best.0;
            c.node_split[x] = best.1 as u8;
        }
        c
    }

    /// Whether `x`, given `k` lanes, stays one lane (a leaf, or a wide node
    /// of its own) rather than being opened.
    fn one_lane(&self, nodes: &[Node], x: usize, k: usize) -> bool {
        nodes[x].count > 0 || self.node[x] <= self.opened[x][k - 1]
    }

    /// The least cost of `x`'s subtree in at most `k` lanes.
    fn lanes(&self, nodes: &[Node], x: usize, k: usize) -> f64 {
        if nodes[x].count > 0 {
            0.0
        } else {
            self.node[x].min(self.opened[x][k - 1])
        }
    }

    /// The children of the wide node for the binary inner node `x`: its own
    /// two opened, sharing the `W` lanes as `node_split` chose.
    fn children(&self, nodes: &[Node], x: usize) -> ArrayVec<usize, W> {
        let first = nodes[x].start as usize;
        let j = usize::from(self.node_split[x]);
        let mut out = ArrayVec::new();
        self.take_opened(nodes, first, j, &mut out);
        self.take_opened(nodes, first + 1, W - j, &mut out);
        out
    }

    /// Appends the lanes of `x`'s subtree in at most `k` lanes, `x` opened.
    fn take_opened(&self, nodes: &[Node], x: usize, k: usize, out: &mut ArrayVec<usize, W>) {
        if nodes[x].count > 0 {
            out.push(x);
            return;
        }
        let j = usize::from(self.opened_split[x][k - 1]);
        let first = nodes[x].start as usize;
        for (c, k) in [(first, j), (first + 1, k - j)] {
            if self.one_lane(nodes, c, k) {
                out.push(c);
            } else {
                self.take_opened(nodes, c, k, out);
            }
        }
    }
}

/// What a wide node with `node`'s box costs a walk in [`Tree::collapse`]:
/// its half-area, at most [`MAX_STEP_COST`] (so also where it overflows,
/// or is NaN: a flat box infinite along another axis). Sums of these over
/// a tree stay finite and are never NaN, so ∞ in [`Costs`] means only "no
/// way to do it" (an inner node opened into a single lane).
fn step_cost(node: &Node) -> f64 {
    let a = half_area(&node.min, &node.max);
    if a <= MAX_STEP_COST {
        a
    } else {
        MAX_STEP_COST
    }
}

/// See [`step_cost`]: a tree of up to 10¹⁸ nodes sums to under `f64::MAX`.
const MAX_STEP_COST: f64 = 1e290;
