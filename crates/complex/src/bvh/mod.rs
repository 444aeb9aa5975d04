//! A bounding-volume hierarchy over the bounded blocks.
//!
//! Built once with the surface-area heuristic over binned centroids into a
//! binary tree, then collapsed into a tree of four-wide nodes (the
//! collapse of least surface-area cost: see [`Open::Cheapest`]): a node holds
//! the boxes of its (up to) four children lane by lane, so one step tests all
//! four with a few `f64x4` operations (the `wide` crate: AVX where the
//! target has it, plain arrays elsewhere) and reads 256 bytes from four
//! adjacent cache lines; half as many levels as the binary tree. Scenes of
//! [`EIGHT_WIDE_FROM`] bounded blocks or more get eight-wide nodes (two
//! `f64x4` per axis and side, 448 bytes): a third fewer levels, each node
//! read a cost that pays only once the tree is deep. Traversed front to back
//! with a fixed-size stack, so a query never allocates.
//! (`f32` boxes rounded outwards, and a scalar four-wide tree, were measured
//! too and did not pay, see `docs/benchmarks.md`.)

use arrayvec::ArrayVec;
use quadric::Ray;
use wide::{f64x4, CmpGe, CmpGt, CmpLe, CmpLt};

use crate::Aabb;

/// Leaves hold at most this many blocks, except at the depth limit: so a
/// leaf's box is its block's box, and a walk visits exactly the blocks
/// whose own boxes it enters.
const LEAF_SIZE: usize = 1;
/// Number of centroid bins per axis for the SAH.
const BINS: usize = 16;
/// Subtrees of at least this many blocks build their two halves in
/// parallel (see `Binary::build_node`).
const PARALLEL_FROM: usize = 4096;
/// Depth limit of the binary build; the builder makes a leaf before a
/// subtree could get deeper than this.
const MAX_DEPTH: usize = 64;
/// Traversal stack size: the wide tree is at most `MAX_DEPTH / 2` deep
/// (see [`Tree::collapse`] and [`Costs`]), and a step takes one entry and leaves at most
/// eight (`walk` keeps one of them aside as the next, which only lowers the
/// count), so the stack holds at most `7 · depth + 1` entries.
const STACK: usize = 7 * MAX_DEPTH.div_ceil(2) + 1;
/// From this many bounded blocks on, the tree is eight-wide (see the module
/// documentation and `docs/benchmarks.md`: below it the wider node costs
/// small scenes more than the levels it saves).
pub(crate) const EIGHT_WIDE_FROM: usize = 256;

/// A node of the binary build: its box and either two children or a run of
/// blocks.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Lower corner.
    min: [f64; 3],
    /// Upper corner.
    max: [f64; 3],
    /// Inner node: index of its first child in `Binary::nodes` (the second
    /// follows it). Leaf: index of its first entry in `items`.
    start: u32,
    /// Number of blocks in a leaf; 0 for an inner node.
    count: u32,
}

const EMPTY_NODE: Node = Node { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3], start: 0, count: 0 };

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

/// Which inner node the collapse into a wide tree opens next, once the
/// binary node's own two children are open ([`Tree::collapse`]).
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
    /// programming over the binary tree ([`Costs`]). Never dearer
    /// than the other two.
    Cheapest,
}

/// The hierarchy: wide nodes and the block indices the leaves point into.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Nodes,
    items: Vec<u32>,
}

/// A ray prepared for slab tests: the reciprocal direction, and the origin
/// moved by the pad towards each side of a box, so that a box face costs one
/// addition and one product.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes {
    inv: [f64; 3],
    /// `-o - pad` for the lower faces and `-o + pad` for the upper ones: the
    /// ray meets the padded face at `b` where `t = (b + shift) / d`.
    shift_lo: [f64; 3],
    shift_hi: [f64; 3],
}

impl RayBoxes {
    pub(crate) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin(), ray.direction());
        // How far outside a block's exact box the kernel may put the ends of
        // the block's intervals: they are accurate to a few ulps of the ray
        // origin's coordinates, which near a box at the origin (a ray leaving
        // the plane x = 0 from (0, 4, 12)) is far more than the box's own
        // widening. Boxes are grown by this much in the slab test: about
        // 450 ulps of the origin, as `WIDEN_ABS` in `bounds.rs`.
        let pad = 1e-13 * o.coords.amax();
        let (o, d) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
        let inv = quadric::lanes::recip(d);
        // `-o ∓ pad` is rounded once, by half an ulp of `o`: less than 1/900
        // of the pad, so the slabs hold the box grown by nearly all of it,
        // far beyond the kernel's few ulps. (Folding the product into an
        // FMA, `b / d + shift / d`, would lose the sign of `b - o` on a
        // parallel axis, `∞ - ∞`, and with it every cull along that axis.)
        let shift_lo = o.map(|o| -o - pad);
        let shift_hi = o.map(|o| -o + pad);
        RayBoxes { inv, shift_lo, shift_hi }
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
    ///
    /// [`RayBoxes::enter_node`] is the same arithmetic, lane by lane.
    #[inline(always)]
    pub(crate) fn enter(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> Option<f64> {
        let (t0, t1) = self.clip(min, max, t_min, t_max);
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
        self.clip(min, max, f64::NEG_INFINITY, f64::INFINITY)
    }

    /// `[t_min, t_max]` narrowed by the three slabs of the padded box.
    #[inline(always)]
    fn clip(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> (f64, f64) {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let inv = self.inv[i];
            let a = (min[i] + self.shift_lo[i]) * inv;
            let b = (max[i] + self.shift_hi[i]) * inv;
            let (a, b) = if inv >= 0.0 { (a, b) } else { (b, a) };
            // NaN (∞ - ∞ on an infinite side, 0·∞) fails both tests and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        (t0, t1)
    }

    /// [`RayBoxes::enter`] for the children of a node at once, four at a
    /// time: the entries (group `g`, lane `l` for child `4g + l`), and a bit
    /// per child whose box the ray enters.
    #[inline(always)]
    fn enter_node<const W: usize, const H: usize>(
        &self,
        node: &Wide<W, H>,
        t_min: f64,
        t_max: f64,
    ) -> ([f64x4; H], u32) {
        let mut entries = [f64x4::ZERO; H];
        let mut mask = 0;
        for (g, entry) in entries.iter_mut().enumerate() {
            // Lanes are filled from the first: a group whose first lane is
            // unused is empty (most nodes near the leaves of an eight-wide
            // tree have four children or fewer).
            if g > 0 && !node.used(4 * g) {
                break;
            }
            let (mut t0, mut t1) = (f64x4::splat(t_min), f64x4::splat(t_max));
            for i in 0..3 {
                // Broadcast loads: cheaper than keeping four-lane copies per ray.
                let inv = f64x4::splat(self.inv[i]);
                let a = (node.group[g].min[i] + f64x4::splat(self.shift_lo[i])) * inv;
                let b = (node.group[g].max[i] + f64x4::splat(self.shift_hi[i])) * inv;
                let (a, b) = if self.inv[i] >= 0.0 { (a, b) } else { (b, a) };
                // `if a > t0 { t0 = a }` lane by lane: NaN keeps `t0`.
                t0 = greater_or_second(a, t0);
                t1 = less_or_second(b, t1);
            }
            // `t0` and `t1` are never NaN (the caller's bounds are not, and
            // the updates keep a NaN out), so this is the plain lane maximum.
            let slack = f64x4::splat(4.0 * f64::EPSILON) * greater_or_second(t1.abs(), t0.abs());
            let hit = t0.cmp_lt(f64x4::splat(f64::INFINITY)) & t0.cmp_le(t1 + slack);
            *entry = t0 - slack;
            mask |= (hit.move_mask() as u32) << (4 * g);
        }
        (entries, mask)
    }
}

/// `a > b ? a : b` lane by lane, so `b` where either is NaN (and where
/// both are zeros): the slab tests' "a NaN keeps the bound". With AVX one
/// `vmaxpd`, whose rule this is exactly (Intel's `MAX(SRC1, SRC2)`: `SRC2`
/// for a NaN in either and for two zeros of any sign, else the greater),
/// instead of a comparison and a blend; elsewhere those two.
#[inline(always)]
fn greater_or_second(a: f64x4, b: f64x4) -> f64x4 {
    #[cfg(target_feature = "avx")]
    {
        a.fast_max(b)
    }
    #[cfg(not(target_feature = "avx"))]
    {
        a.cmp_gt(b).blend(a, b)
    }
}

/// `a < b ? a : b` lane by lane: [`greater_or_second`]'s rule the other
/// way (`vminpd` with AVX).
#[inline(always)]
fn less_or_second(a: f64x4, b: f64x4) -> f64x4 {
    #[cfg(target_feature = "avx")]
    {
        a.fast_min(b)
    }
    #[cfg(not(target_feature = "avx"))]
    {
        a.cmp_lt(b).blend(a, b)
    }
}

/// Four rays prepared for slab tests, lane by lane: the [`RayBoxes`] of
/// each, transposed, so that one box is tested against all four at once.
/// Each lane computes exactly what [`RayBoxes::enter_node`] computes for its
/// ray (the same operations on the same values), so a packet walk enters
/// a box for a lane exactly when that ray's own walk would.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes4 {
    inv: [f64x4; 3],
    shift_lo: [f64x4; 3],
    shift_hi: [f64x4; 3],
    /// All ones in the lanes whose `inv >= 0` (the lower face is met first).
    forward: [f64x4; 3],
}

/// Per axis, bounds over the four rays of a packet, from which
/// [`RayBoxes4::cull`] finds, for all the children of a node at once, a
/// lower bound of every ray's entry and an upper bound of its exit (see
/// there): the least and greatest reciprocal, and the shifts that give the
/// smallest entry and the largest exit (`-∞` and `+∞` on an axis where the
/// rays' reciprocals are not all finite or do not all have one sign: no
/// bound there).
#[derive(Clone, Copy, Debug)]
struct PacketBounds {
    inv_min: [f64; 3],
    inv_max: [f64; 3],
    /// Added to the face met first: `min shift_lo` going forward, `max
    /// shift_hi` going backward.
    entry_shift: [f64; 3],
    /// Added to the face met last: `max shift_hi` forward, `min shift_lo`
    /// backward.
    exit_shift: [f64; 3],
    forward: [bool; 3],
}

impl PacketBounds {
    /// No bound on any axis.
    const NONE: PacketBounds = PacketBounds {
        inv_min: [1.0; 3],
        inv_max: [1.0; 3],
        entry_shift: [f64::NEG_INFINITY; 3],
        exit_shift: [f64::INFINITY; 3],
        forward: [true; 3],
    };

    /// The bounds of the four rays of `rays`.
    fn new(rays: &RayBoxes4) -> Self {
        let mut b = PacketBounds::NONE;
        for i in 0..3 {
            let inv = rays.inv[i].to_array();
            let forward = inv.iter().all(|&v| v >= 0.0);
            if !(inv.iter().all(|v| v.is_finite()) && (forward || inv.iter().all(|&v| v < 0.0))) {
                continue;
            }
            let lo = rays.shift_lo[i].to_array().iter().fold(f64::INFINITY, |m, &v| m.min(v));
            let hi = rays.shift_hi[i].to_array().iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
            b.inv_min[i] = inv.iter().fold(f64::INFINITY, |m, &v| m.min(v));
            b.inv_max[i] = inv.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
            (b.entry_shift[i], b.exit_shift[i]) = if forward { (lo, hi) } else { (hi, lo) };
            b.forward[i] = forward;
        }
        b
    }
}

impl RayBoxes4 {
    pub(crate) fn new(rays: &[RayBoxes; 4]) -> Self {
        let lanes = |f: &dyn Fn(&RayBoxes) -> f64| f64x4::new([f(&rays[0]), f(&rays[1]), f(&rays[2]), f(&rays[3])]);
        let inv = [0, 1, 2].map(|i| lanes(&|r| r.inv[i]));
        RayBoxes4 {
            inv,
            shift_lo: [0, 1, 2].map(|i| lanes(&|r| r.shift_lo[i])),
            shift_hi: [0, 1, 2].map(|i| lanes(&|r| r.shift_hi[i])),
            forward: inv.map(|v| v.cmp_ge(f64x4::splat(0.0))),
        }
    }

    /// A bit for each child of `node` that one of the four rays (whose
    /// bounds are `b`) may enter within `[t_min, t_max]` (`t_max`: the
    /// largest of the lanes' that count): every child some ray enters by
    /// [`RayBoxes4::enter_child`] has its bit, so testing only those gives
    /// the same answers. One test for all four rays, the children four at a
    /// time, instead of a test per child for the four rays: in an
    /// eight-wide node a packet enters few of the eight.
    ///
    /// Why no child a ray enters is culled: on an axis with bounds, every
    /// ray's reciprocal `v` is finite, of one sign, in `[inv_min, inv_max]`,
    /// and its face plus shift is at least `P` (the face met first plus
    /// `entry_shift`, rounded: rounding is monotone). So its entry on that
    /// axis, the rounded `(face + shift)·v`, is at least the rounded `P·v`,
    /// which is monotone in `v` for a fixed `P`: at least the smaller of
    /// `P·inv_min` and `P·inv_max`. So `T0`, the largest of these bounds and
    /// `t_min`, is at most every ray's `t0`; likewise `T1`, from the exit
    /// faces, at least every ray's `t1`. A ray enters only if `t0 <= t1 +
    /// slack` with `slack = 4ε·max(|t0|, |t1|)`; with `M = max(|T0|, |T1|)`,
    /// `S = 16ε·M` covers that slack where `|t0|, |t1| <= 3.99 M`, and
    /// where one of them is larger the gap between them is far wider than
    /// its slack (the larger is then positive and above `3.99 M` for `t0`,
    /// negative and below `-3.99 M` for `t1`). So `T0 > T1 + S` means no
    /// ray enters. NaN (an empty lane: `∞ - ∞`; an axis without bounds)
    /// fails every comparison and culls nothing.
    #[inline(always)]
    fn cull<const W: usize, const H: usize>(b: &PacketBounds, node: &Wide<W, H>, t_min: f64, t_max: f64) -> u32 {
        let mut mask = 0;
        for g in 0..H {
            let (mut t0, mut t1) = (f64x4::splat(t_min), f64x4::splat(t_max));
            for i in 0..3 {
                let (first, last) = if b.forward[i] {
                    (node.group[g].min[i], node.group[g].max[i])
                } else {
                    (node.group[g].max[i], node.group[g].min[i])
                };
                let p = first + f64x4::splat(b.entry_shift[i]);
                let q = last + f64x4::splat(b.exit_shift[i]);
                let (v0, v1) = (f64x4::splat(b.inv_min[i]), f64x4::splat(b.inv_max[i]));
                let (p0, p1) = (p * v0, p * v1);
                let (q0, q1) = (q * v0, q * v1);
                let enter = less_or_second(p0, p1);
                let exit = greater_or_second(q0, q1);
                // NaN keeps the bound as it was.
                t0 = greater_or_second(enter, t0);
                t1 = less_or_second(exit, t1);
            }
            // Never NaN, as in `enter_node`: the plain lane maximum.
            let s = f64x4::splat(16.0 * f64::EPSILON) * greater_or_second(t0.abs(), t1.abs());
            let culled = t0.cmp_gt(t1 + s);
            mask |= (!(culled.move_mask() as u32) & 0b1111) << (4 * g);
        }
        mask
    }

    /// Child `c` of `node` against the four rays: their entries and a bit
    /// per ray that enters it within its `[t_min, t_max]`.
    #[inline(always)]
    fn enter_child<const W: usize, const H: usize>(
        &self,
        node: &Wide<W, H>,
        c: usize,
        t_min: f64x4,
        t_max: f64x4,
    ) -> (f64x4, u32) {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let lo = f64x4::splat(node.group[c / 4].min[i].as_array_ref()[c % 4]);
            let hi = f64x4::splat(node.group[c / 4].max[i].as_array_ref()[c % 4]);
            let a = (lo + self.shift_lo[i]) * self.inv[i];
            let b = (hi + self.shift_hi[i]) * self.inv[i];
            let (a, b) = (self.forward[i].blend(a, b), self.forward[i].blend(b, a));
            t0 = greater_or_second(a, t0);
            t1 = less_or_second(b, t1);
        }
        // Never NaN, as in `RayBoxes::enter_node`: the plain lane maximum.
        let slack = f64x4::splat(4.0 * f64::EPSILON) * greater_or_second(t1.abs(), t0.abs());
        let hit = t0.cmp_lt(f64x4::splat(f64::INFINITY)) & t0.cmp_le(t1 + slack);
        (t0 - slack, hit.move_mask() as u32)
    }
}

impl Bvh {
    /// Builds the hierarchy over `(index, box)` pairs; every box must be
    /// bounded. Eight-wide from [`EIGHT_WIDE_FROM`] pairs on, else four-wide.
    pub(crate) fn build(entries: &[(u32, Aabb)]) -> Self {
        Self::build_with(entries, PARALLEL_FROM, entries.len() >= EIGHT_WIDE_FROM, None)
    }

    /// [`Bvh::build`], with subtrees of `parallel_from` blocks or more built
    /// on two threads, eight-wide if `eight`, collapsed by `open` (`None`:
    /// the cheapest collapse, see [`Tree::from_binary`]).
    fn build_with(entries: &[(u32, Aabb)], parallel_from: usize, eight: bool, open: Option<Open>) -> Self {
        if entries.is_empty() {
            return Bvh::default();
        }
        let binary = Binary::of(entries, parallel_from);
        let nodes = if eight {
            Nodes::Eight(Tree::from_binary(&binary.nodes, open))
        } else {
            Nodes::Four(Tree::from_binary(&binary.nodes, open))
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

    /// Visits the blocks whose boxes contain `p` (at the depth limit, every
    /// block of a leaf whose box contains it; see [`Bvh::traverse`]).
    pub(crate) fn visit_point(&self, p: &[f64; 3], visit: impl FnMut(u32)) {
        with_tree!(&self.nodes, t => t.visit_point(&self.items, p, visit))
    }
}

impl<const W: usize, const H: usize> Tree<W, H> {
    /// The wide tree of a binary one (root: node 0, not empty), collapsed
    /// by `open` (`None`: [`Open::Cheapest`]; with debug assertions, checked
    /// to cost no more than the other two rules).
    fn from_binary(binary: &[Node], open: Option<Open>) -> Self {
        const { assert!(W == 4 * H && W <= 8) };
        let root = &binary[0];
        if root.count > 0 {
            // A single leaf: one node with one lane.
            let mut node = Wide::EMPTY;
            node.set_box(0, &root.min, &root.max);
            node.child[0] = root.start;
            node.count[0] = root.count;
            return Tree { nodes: vec![node] };
        }
        let (tree, cost) = Self::collapsed(binary, open.unwrap_or(Open::Cheapest));
        if cfg!(debug_assertions) && open.is_none() {
            for rule in [Open::Shallowest, Open::Largest] {
                let other = Self::collapsed(binary, rule).1;
                debug_assert!(cost <= other * (1.0 + 1e-12), "{rule:?} costs {other}, the cheapest {cost}");
            }
        }
        tree
    }

    /// The wide tree of a binary one whose root is an inner node, opened by
    /// `open`, and its cost: the sum of its nodes' half-areas (see
    /// [`Tree::collapse`]).
    fn collapsed(binary: &[Node], open: Open) -> (Self, f64) {
        let mut tree = Tree { nodes: Vec::with_capacity(binary.len() / (W - 1) + 1) };
        let mut cost = 0.0;
        if let Open::Cheapest = open {
            let costs = Costs::<W>::new(binary);
            tree.collapse(binary, 0, &|x| costs.children(binary, x), &mut cost);
        } else {
            tree.collapse(binary, 0, &|n| greedy_children(binary, n, open), &mut cost);
        }
        (tree, cost)
    }

    /// Appends the wide node for the binary inner node `n`, then those of
    /// its inner descendants; returns its index, and adds to `cost` the
    /// half-areas of the boxes of the nodes it makes (a ray crosses a box
    /// about in proportion to its area: their sum over the root's is the
    /// number of node steps a random ray takes, the surface-area heuristic
    /// of the wide tree). Its children, at most `W`, are the binary nodes
    /// `children(n)` picks below `n` (by a greedy rule, or as [`Costs`]
    /// chose them); `n`'s own two children are always opened: so every
    /// inner child is at least two binary levels below `n`, and the wide
    /// tree is at most `MAX_DEPTH / 2` deep (see `STACK`).
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

    /// [`Bvh::traverse`] (`NEAREST_FIRST`) or [`Bvh::traverse_any`].
    #[inline(always)]
    fn walk<const NEAREST_FIRST: bool>(
        &self,
        ray: &RayBoxes,
        t_min: f64,
        t_max: &mut f64,
        mut visit: impl FnMut(u32, f64, &mut f64),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        // Entries are `child | count << 32` (count 0: an inner node) and the
        // parameter where the ray enters it. An `ArrayVec` is not zeroed: a
        // zeroed array of this size cost 8 % of a small scene's instructions.
        let mut stack: ArrayVec<(u64, f64), STACK> = ArrayVec::new();
        // The next entry to take, kept out of the stack: a step that enters
        // children goes on with one of them without pushing and popping it.
        let mut next = Some((0u64, t_min));
        while let Some((r, t_enter)) = next.take().or_else(|| stack.pop()) {
            if t_enter > *t_max {
                continue;
            }
            let (child, count) = (r as u32, (r >> 32) as u32);
            if count > 0 {
                for k in child..child + count {
                    visit(k, t_enter, t_max);
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let (entry, mut hits) = ray.enter_node(node, t_min, *t_max);
            let entry = |lane: usize| entry[lane / 4].as_array_ref()[lane % 4];
            if !NEAREST_FIRST {
                if hits != 0 {
                    let lane = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    next = Some((node.entry(lane), entry(lane)));
                }
                while hits != 0 {
                    let lane = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    stack.push((node.entry(lane), entry(lane)));
                }
                continue;
            }
            // The children entered, nearest first (insertion into at most
            // `W` places), pushed farthest first so the nearest pops next.
            let mut order = [(0.0f64, 0u64); W];
            let mut n = 0;
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                insert_nearest(&mut order, &mut n, (entry(lane), node.entry(lane)));
            }
            // Cannot overflow: see `STACK`.
            for &(t, r) in order[1..n.max(1)].iter().rev() {
                stack.push((r, t));
            }
            if n > 0 {
                next = Some((order[0].1, order[0].0));
            }
        }
    }

    /// [`Bvh::traverse4`].
    #[inline(always)]
    fn traverse4(
        &self,
        rays: &RayBoxes4,
        active: u32,
        t_min: f64,
        t_max: &mut [f64; 4],
        mut visit: impl FnMut(u32, usize, &mut [f64; 4]),
    ) {
        if self.nodes.is_empty() || active == 0 {
            return;
        }
        let t_min4 = f64x4::splat(t_min);
        // Only eight-wide walks cull (see below).
        let bounds = if H > 1 { PacketBounds::new(rays) } else { PacketBounds::NONE };
        // `(child | count << 32, lanes)` and each lane's entry.
        let mut stack: ArrayVec<(u64, u32, f64x4), STACK> = ArrayVec::new();
        // The next entry, kept out of the stack as in `walk`.
        let mut next = Some((0, active, t_min4));
        while let Some((r, lanes, t_enter)) = next.take().or_else(|| stack.pop()) {
            // `t_enter <= t_max` lane by lane (entries are never NaN).
            let lanes = lanes & (t_enter.cmp_le(f64x4::new(*t_max)).move_mask() as u32);
            if lanes == 0 {
                continue;
            }
            let (child, count) = (r as u32, (r >> 32) as u32);
            if count > 0 {
                for k in child..child + count {
                    let mut todo = lanes;
                    while todo != 0 {
                        let lane = todo.trailing_zeros() as usize;
                        todo &= todo - 1;
                        if t_enter.as_array_ref()[lane] <= t_max[lane] {
                            visit(k, lane, t_max);
                        }
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let t_max4 = f64x4::new(*t_max);
            // Only `(key, child)` pairs are sorted; the children's entries
            // stay where they were computed. (Sorting whole stack entries
            // moved their four-lane entries through unaligned stack slots:
            // each move a failed store-to-load forward, 17 % of the packet
            // walk's time on the 100,000-block grid, invisible to callgrind.)
            let mut entries = [f64x4::ZERO; W];
            let mut masks = [0u32; W];
            let mut order = [(0.0f64, 0usize); W];
            let mut n = 0;
            let mut child = |c: usize| {
                let (entry, hits) = rays.enter_child(node, c, t_min4, t_max4);
                let hits = hits & lanes;
                if hits == 0 {
                    return;
                }
                // The nearest entry among the lanes that enter.
                let e = entry.to_array();
                let key = (0..4).filter(|l| hits & (1 << l) != 0).fold(f64::INFINITY, |m, l| m.min(e[l]));
                entries[c] = entry;
                masks[c] = hits;
                insert_nearest(&mut order, &mut n, (key, c));
            };
            if H == 1 {
                // A four-wide node's four children cost the packet test
                // about what the cull would: each is tested.
                (0..W).for_each(child);
            } else {
                // The lanes are filled from the first, so the first unused
                // one ends the children. (The cull keeps unused lanes, see
                // there; most nodes near the leaves of an eight-wide tree
                // have four children or fewer.)
                let reach = (0..4).filter(|l| lanes & (1 << l) != 0).fold(f64::NEG_INFINITY, |m, l| m.max(t_max[l]));
                let mut maybe = RayBoxes4::cull(&bounds, node, t_min, reach);
                while maybe != 0 {
                    let c = maybe.trailing_zeros() as usize;
                    maybe &= maybe - 1;
                    if !node.used(c) {
                        break;
                    }
                    child(c);
                }
            }
            // Cannot overflow: see `STACK`.
            for &(_, c) in order[1..n.max(1)].iter().rev() {
                stack.push((node.entry(c), masks[c], entries[c]));
            }
            if n > 0 {
                let c = order[0].1;
                next = Some((node.entry(c), masks[c], entries[c]));
            }
        }
    }

    /// [`Bvh::visit_point`], with the leaves pointing into `items`.
    fn visit_point(&self, items: &[u32], p: &[f64; 3], mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: ArrayVec<u32, STACK> = ArrayVec::new();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            for lane in 0..W {
                let inside = (0..3).all(|i| {
                    let (lo, hi) = (
                        node.group[lane / 4].min[i].as_array_ref()[lane % 4],
                        node.group[lane / 4].max[i].as_array_ref()[lane % 4],
                    );
                    lo <= p[i] && p[i] <= hi
                });
                if !inside {
                    continue;
                }
                let (child, count) = (node.child[lane], node.count[lane]);
                if count > 0 {
                    for &item in &items[child as usize..(child + count) as usize] {
                        visit(item);
                    }
                } else {
                    stack.push(child);
                }
            }
        }
    }
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
            // `Tree::collapsed` takes this one's children from `Costs`.
            Open::Cheapest => unreachable!("the cheapest collapse is not greedy"),
        };
        let Some(j) = pick else { break };
        let (c, d) = children.remove(j);
        let c = nodes[c].start as usize;
        children.extend([(c, d + 1), (c + 1, d + 1)]);
    }
    children.into_iter().map(|(c, _)| c).collect()
}

/// The least costs of [`Open::Cheapest`], for every binary node `x`
/// (children follow their parent in the binary tree, so one pass from the
/// last node to the first has each node's children done before it):
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
/// A lane is thus always at least two binary levels below its wide node,
/// as with the other rules (see `STACK`). Costs are summed in one order
/// whatever the rule, so on a tie the choice is the first found: the child
/// as one lane before opening it, fewer lanes to the first child first.
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

/// Inserts `item` into the first `*n` entries of `order`, kept sorted by
/// their first field (nearest entry first; at most `N` children).
#[inline(always)]
fn insert_nearest<T: Copy, const N: usize>(order: &mut [(f64, T); N], n: &mut usize, item: (f64, T)) {
    let mut j = *n;
    while j > 0 && order[j - 1].0 > item.0 {
        order[j] = order[j - 1];
        j -= 1;
    }
    order[j] = item;
    *n += 1;
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

/// The binary tree the builder makes (and [`Tree::collapse`] turns into the
/// wide one): the two children of an inner node are consecutive.
struct Binary {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

impl Binary {
    /// The binary tree over `entries` (not empty), subtrees of
    /// `parallel_from` blocks or more built on two threads.
    fn of(entries: &[(u32, Aabb)], parallel_from: usize) -> Self {
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
struct Entry {
    index: u32,
    min: [f64; 3],
    max: [f64; 3],
    centre: [f64; 3],
}

/// The box of the blocks' boxes.
fn bounds_of(work: &[Entry]) -> ([f64; 3], [f64; 3]) {
    span(work, |e| (&e.min, &e.max))
}

/// The box of the blocks' box centres.
fn centroid_bounds(work: &[Entry]) -> ([f64; 3], [f64; 3]) {
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

fn half_area(min: &[f64; 3], max: &[f64; 3]) -> f64 {
    let d = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// Partitions `work` for two children and returns the size of the left
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
fn sah_split(work: &mut [Entry], min: &[f64; 3], max: &[f64; 3]) -> Option<usize> {
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
            if best.map_or(true, |(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    // A degenerate parent (zero area) makes every cost NaN or ∞; any split
    // found still separates the centres.
    let (_, axis, bins_left) = best?;
    let goes_left = |e: &Entry| bin(e, axis) < bins_left;
    let i = partition(work, goes_left);
    (i > 0 && i < work.len()).then_some(i)
}

/// Moves the entries that go left to the front, in place, and returns
/// their number.
fn partition(work: &mut [Entry], goes_left: impl Fn(&Entry) -> bool) -> usize {
    let mut i = 0;
    for j in 0..work.len() {
        if goes_left(&work[j]) {
            work.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use quadric::nalgebra::{Point3, Vector3};

    use super::*;

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
            assert_eq!(
                lane0::<4, 1>(&rb, &min, &max, 0, 0.0, f64::INFINITY),
                got,
                "{origin:?} along {dir:?}: four-wide"
            );
            for lane in [0, 5] {
                let wide = lane0::<8, 2>(&rb, &min, &max, lane, 0.0, f64::INFINITY);
                assert_eq!(wide, got, "{origin:?} along {dir:?}: eight-wide, lane {lane}");
            }
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

    /// The SAH split as it was before its sweeps skipped empty bins (every
    /// bin of every axis swept, each axis binned in a pass of its own): the
    /// oracle of `sah_split_is_the_sweep_over_every_bin`.
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
                if best.map_or(true, |(c, _, _)| cost < c) {
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
        let i = partition(work, goes_left);
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
                    let (t, cost) = Tree::<4, 1>::collapsed(&binary, Open::Cheapest);
                    prop_assert!((tree_cost(&t) - cost).abs() <= 1e-9 * cost);
                    (cost, Tree::<4, 1>::collapsed(&binary, Open::Shallowest).1)
                } else {
                    let (t, cost) = Tree::<8, 2>::collapsed(&binary, Open::Cheapest);
                    prop_assert!((tree_cost(&t) - cost).abs() <= 1e-9 * cost);
                    (cost, Tree::<8, 2>::collapsed(&binary, Open::Largest).1)
                };
                prop_assert!((got - want).abs() <= 1e-9 * want, "{}-wide: {} but the least is {}", w, got, want);
                prop_assert!(got <= other * (1.0 + 1e-12));
            }
        }

        /// The collapsed tree, four- and eight-wide, by any rule, visits exactly the
        /// blocks whose own boxes the ray enters (no early exit), and
        /// `visit_point` exactly those whose boxes hold the point.
        #[test]
        fn tree_visits_what_brute_force_does(
            boxes in prop::collection::vec(boxed_or_huge(), 1..60), ray in ray(), p in [coord(), coord(), coord()], eight: bool,
            others in [ray(), ray(), ray()],
            open in prop_oneof![Just(None), Just(Some(Open::Shallowest)), Just(Some(Open::Largest))],
        ) {
            let entries: Vec<(u32, Aabb)> = boxes
                .iter()
                .enumerate()
                .map(|(i, (lo, hi))| (i as u32, Aabb { min: Point3::from(*lo), max: Point3::from(*hi) }))
                .collect();
            let bvh = Bvh::build_with(&entries, PARALLEL_FROM, eight, open);
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
            let mut inside = Vec::new();
            bvh.visit_point(&p, |i| inside.push(i));
            inside.sort_unstable();
            let holds = |(lo, hi): &([f64; 3], [f64; 3])| (0..3).all(|i| lo[i] <= p[i] && p[i] <= hi[i]);
            let expected: Vec<u32> = (0..boxes.len() as u32).filter(|&i| holds(&boxes[i as usize])).collect();
            prop_assert_eq!(inside, expected);
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
                (
                    i,
                    Aabb {
                        min: Point3::new(c[0] - r, c[1] - r, c[2] - r),
                        max: Point3::new(c[0] + r, c[1] + r, c[2] + r),
                    },
                )
            })
            .collect();
        for eight in [false, true] {
            let (one, two) =
                (Bvh::build_with(&entries, usize::MAX, eight, None), Bvh::build_with(&entries, 64, eight, None));
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
        let grid: Vec<(u32, Aabb)> = (0..1000u32)
            .map(|i| (i, cube([f64::from(i % 10), f64::from(i / 10 % 10), f64::from(i / 100)], 0.3)))
            .collect();
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
                .map(|open| Bvh::build_with(entries, PARALLEL_FROM, true, open));
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
            let Nodes::Eight(cheapest) = Bvh::build_with(entries, PARALLEL_FROM, true, Some(Open::Cheapest)).nodes
            else {
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
}
