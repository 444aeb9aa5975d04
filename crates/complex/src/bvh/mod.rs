//! A bounding-volume hierarchy over the bounded blocks.
//!
//! Built once with the surface-area heuristic over binned centroids into a
//! binary tree ([`build`]), then collapsed into a tree of four-wide nodes
//! (the collapse of least surface-area cost, [`collapse`]): a node holds the
//! boxes of its (up to) four children lane by lane, so one step tests all
//! four with a few `f64x4` operations ([`slab`]; the `wide` crate: AVX where
//! the target has it, plain arrays elsewhere) and reads 256 bytes from four
//! adjacent cache lines; half as many levels as the binary tree. Scenes of
//! [`EIGHT_WIDE_FROM`] bounded blocks or more get eight-wide nodes (two
//! `f64x4` per axis and side, 448 bytes): a third fewer levels, each node
//! read a cost that pays only once the tree is deep. Traversed front to back
//! with a fixed-size stack, so a query never allocates ([`tree_walks`]).
//! Boxes stay `f64` and their test four-lane: `f32` boxes rounded outwards
//! and a scalar four-wide tree are slower (see `docs/benchmarks.md`).

use wide::f64x4;

use crate::Aabb;

mod build;
mod collapse;
mod slab;
#[cfg(test)]
mod tests;
// Not `walk`: rustc hands LLVM the functions sorted by mangled name, and
// the queries' inlined walks take fewer instructions when the walks'
// symbols sort before `Bvh`'s, as a module name of ten letters or more
// does (`10tree_walks` < `3Bvh` < `4walk`). Named `walk`, the release
// build renders the table scene with 1.0 % more instructions and the
// glass scene with 0.45 % more (callgrind, `scripts/compare-builds.sh
// --instructions`).
mod tree_walks;

use build::Binary;
pub(crate) use slab::{RayBoxes, RayBoxes4};

/// Leaves hold at most this many blocks, except at the depth limit: so a
/// leaf's box is its block's box, and a walk visits exactly the blocks
/// whose own boxes it enters.
const LEAF_SIZE: usize = 1;
/// Subtrees of at least this many blocks build their two halves in
/// parallel (see `Binary::build_node`).
const PARALLEL_FROM: usize = 4096;
/// Depth limit of the binary build; the builder makes a leaf before a
/// subtree could get deeper than this.
const MAX_DEPTH: usize = 64;
/// Traversal stack size: the wide tree is at most `MAX_DEPTH / 2` deep
/// (see [`Tree::collapse`] and `collapse::Costs`), and a step takes one
/// entry and leaves at most eight (`walk` keeps one of them aside as the
/// next, which only lowers the count), so the stack holds at most
/// `7 · depth + 1` entries.
const STACK: usize = 7 * MAX_DEPTH.div_ceil(2) + 1;
/// From this many bounded blocks on, the tree is eight-wide (see the module
/// documentation and `docs/benchmarks.md`: below it the wider node costs
/// small scenes more than the levels it saves).
pub(crate) const EIGHT_WIDE_FROM: usize = 256;

/// Four children's boxes lane by lane, per axis: 192 bytes, three lines.
#[derive(Clone, Copy, Debug)]
struct Group {
    min: [f64x4; 3],
    max: [f64x4; 3],
}

/// Up to `W = 4H` children: their boxes lane by lane (`H` groups of four
/// children, each group's boxes in lines of their own, so that a walk that
/// skips an empty group does not load it), and what each child is. An
/// unused lane has the empty box (`min = +∞`, `max = -∞`), which no slab
/// test enters. Four-wide: 224 bytes, eight-wide: 448, aligned to lines.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
struct Wide<const W: usize, const H: usize> {
    group: [Group; H],
    /// Inner child: its index in `Tree::nodes`. Leaf: its first position in
    /// `Bvh::items`.
    child: [u32; W],
    /// Blocks in a leaf child; 0 for an inner child (and an unused lane).
    count: [u32; W],
}

/// A wide tree: its nodes, the root first.
#[derive(Clone, Debug, Default)]
struct Tree<const W: usize, const H: usize> {
    nodes: Vec<Wide<W, H>>,
}

/// The tree of a scene, four- or eight-wide by its size.
#[derive(Clone, Debug)]
enum Nodes {
    Four(Tree<4, 1>),
    Eight(Tree<8, 2>),
}

impl Default for Nodes {
    fn default() -> Self {
        Nodes::Four(Tree::default())
    }
}

/// Runs `$body` with `$t` bound to the tree, whichever its width (each
/// width's walk compiled on its own).
macro_rules! with_tree {
    ($nodes:expr, $t:ident => $body:expr) => {
        match $nodes {
            Nodes::Four($t) => $body,
            Nodes::Eight($t) => $body,
        }
    };
}

/// The hierarchy: wide nodes and the block indices the leaves point into.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Nodes,
    items: Vec<u32>,
}

impl Bvh {
    /// Builds the hierarchy over `(index, box)` pairs; every box must be
    /// bounded. Eight-wide from [`EIGHT_WIDE_FROM`] pairs on, else four-wide.
    pub(crate) fn build(entries: &[(u32, Aabb)]) -> Self {
        Self::build_with(entries, PARALLEL_FROM, entries.len() >= EIGHT_WIDE_FROM)
    }

    /// [`Bvh::build`], with subtrees of `parallel_from` blocks or more built
    /// on two threads, eight-wide if `eight`.
    fn build_with(entries: &[(u32, Aabb)], parallel_from: usize, eight: bool) -> Self {
        if entries.is_empty() {
            return Bvh::default();
        }
        let binary = Binary::of(entries, parallel_from);
        let nodes = if eight {
            Nodes::Eight(Tree::from_binary(&binary.nodes))
        } else {
            Nodes::Four(Tree::from_binary(&binary.nodes))
        };
        Bvh { nodes, items: binary.items }
    }

    /// The block indices in leaf order (a leaf's blocks are consecutive).
    pub(crate) fn items(&self) -> &[u32] {
        &self.items
    }

    /// Visits the blocks whose boxes the ray crosses within `[t_min, *t_max]`,
    /// nearest box first, calling `visit(k, box_entry, t_max)` with `k` the
    /// position in [`Bvh::items`]; `visit` may lower `*t_max` to cut off
    /// everything farther away (early exit). A leaf holds one block, except
    /// at the depth limit, where a leaf is visited whole when the ray
    /// crosses its box (a block whose own box the ray misses then has an
    /// empty set after the clip to its box).
    #[inline]
    pub(crate) fn traverse(&self, ray: &RayBoxes, t_min: f64, t_max: &mut f64, visit: impl FnMut(u32, f64, &mut f64)) {
        with_tree!(&self.nodes, t => t.walk::<true>(ray, t_min, t_max, visit))
    }

    /// [`Bvh::traverse`] in no particular order, for any-hit queries: the
    /// same blocks (less those `visit` cuts off), without sorting the
    /// children a node step enters.
    #[inline]
    pub(crate) fn traverse_any(
        &self,
        ray: &RayBoxes,
        t_min: f64,
        t_max: &mut f64,
        visit: impl FnMut(u32, f64, &mut f64),
    ) {
        with_tree!(&self.nodes, t => t.walk::<false>(ray, t_min, t_max, visit))
    }

    /// [`Bvh::traverse`] for four rays at once, the lanes in `active`:
    /// each node is read once for all of them. `visit(k, lane, t_max)` is
    /// called for every block whose box lane `lane`'s ray crosses within
    /// `[t_min, t_max[lane]]` (and may lower `t_max[lane]`), so each lane
    /// visits at least the blocks its own [`Bvh::traverse`] visits: every
    /// block its walk enters with the final `t_max`, and the boxes that hold
    /// it at `t_min`. Children are taken nearest first by the nearest entry
    /// among the lanes that enter them.
    #[inline]
    pub(crate) fn traverse4(
        &self,
        rays: &RayBoxes4,
        active: u32,
        t_min: f64,
        t_max: &mut [f64; 4],
        visit: impl FnMut(u32, usize, &mut [f64; 4]),
    ) {
        with_tree!(&self.nodes, t => t.traverse4(rays, active, t_min, t_max, visit))
    }
}

impl<const W: usize, const H: usize> Wide<W, H> {
    /// Child `lane` as a stack entry: `child | count << 32`.
    #[inline(always)]
    fn entry(&self, lane: usize) -> u64 {
        u64::from(self.child[lane]) | u64::from(self.count[lane]) << 32
    }

    /// Whether `lane` holds a child. The collapse fills lanes from the
    /// first, so the first unused lane ends the children. An unused lane
    /// has child 0 and count 0: node 0 is the root, no node's child, and a
    /// leaf has at least one block.
    #[inline(always)]
    fn used(&self, lane: usize) -> bool {
        self.child[lane] | self.count[lane] != 0
    }

    const EMPTY: Self = Wide {
        group: [Group { min: [f64x4::new([f64::INFINITY; 4]); 3], max: [f64x4::new([f64::NEG_INFINITY; 4]); 3] }; H],
        child: [0; W],
        count: [0; W],
    };

    fn set_box(&mut self, lane: usize, min: &[f64; 3], max: &[f64; 3]) {
        let g = lane / 4;
        for i in 0..3 {
            let (mut lo, mut hi) = (self.group[g].min[i].to_array(), self.group[g].max[i].to_array());
            lo[lane % 4] = min[i];
            hi[lane % 4] = max[i];
            self.group[g].min[i] = f64x4::new(lo);
            self.group[g].max[i] = f64x4::new(hi);
        }
    }
}

/// Half the surface area of the box `[min, max]`: the surface-area
/// heuristic's measure of how likely a ray is to cross it.
fn half_area(min: &[f64; 3], max: &[f64; 3]) -> f64 {
    let d = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}
