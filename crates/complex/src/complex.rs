//! The complex: blocks in priority order and the queries on them.

use quadric::nalgebra::{Point3, Vector3};
use quadric::{Bound, Interval, IntervalSet, Ray};

use crate::assembly::{Assembly, Resolved, Visit};
use crate::block::{Scratch, SolidRef, SpanBuf, Spans};
use crate::bounds::block_boxes;
use crate::bvh::{Bvh, RayBoxes, RayBoxes4};
use crate::kernel::Kernel;
use crate::partition::{BlockIntervals, BlockSpans, Event};
use crate::point_grid::PointGrid;
use crate::{Aabb, Block, BlockId, ComplexError};

/// The default ε relative to the scene's size: `ε = DEFAULT_RELATIVE_EPSILON · D`
/// with `D` the diagonal of the box around all bounded blocks (`D = 1` if
/// there are none). Large enough to swallow the rounding error of a hit
/// point (about `10⁻¹⁵ D` away from tangencies), small enough to be invisible.
pub const DEFAULT_RELATIVE_EPSILON: f64 = 1e-9;

/// Options for building a [`Complex`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ComplexOptions {
    /// Intervals contained in `[0, ε]` are no hit. `None`: the default,
    /// [`DEFAULT_RELATIVE_EPSILON`] times the diagonal of the bounded part of
    /// the scene (or `1e-9` if nothing is bounded).
    pub epsilon: Option<f64>,
    /// The precision mode of every query (default
    /// [`quadric::Precision::Accurate`]); [`Complex::set_precision`] changes
    /// it later.
    pub precision: quadric::Precision,
    /// A caller's number for this complex, which [`Complex::resolve`]
    /// reports for the blocks of its own list (default 0).
    pub key: u32,
}

/// What [`Complex::occluded_with`] remembers between rays: the block that
/// stopped the last one (none at first). Only a hint: any value gives the
/// same answers.
///
/// ```
/// use complex::{Block, Complex, ComplexOptions, MaterialKey, Occluder, Opacity};
/// use quadric::nalgebra::{Point3, Vector3};
/// use quadric::{Quadric, Ray, Solid};
/// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(0)).unwrap();
/// let scene = Complex::new(vec![ball], ComplexOptions::default()).unwrap();
/// // Shadow rays of neighbouring points towards one light, one hint for all.
/// let mut hint = Occluder::default();
/// for x in [-0.2, -0.1, 0.0, 0.1, 0.2] {
///     let shadow = Ray::new(Point3::new(x, 0.0, -5.0), Vector3::z()).unwrap();
///     assert!(scene.occluded_with(&shadow, 10.0, &mut hint));
///     assert_eq!(scene.occluded_with(&shadow, 10.0, &mut hint), scene.occluded(&shadow, 10.0));
/// }
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Occluder {
    /// BVH slot of the block.
    slot: Option<u32>,
}

/// The first surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray: a double, so it carries up to `ulp(t)` of
    /// error, which can exceed the ulps of the hit point itself when the ray
    /// starts farther from the world origin than the hit.
    pub t: f64,
    /// The hit point, near `ray.at(t)` but refined onto the surface
    /// ([`quadric::Solid::hit_point`]: within about the float64 rounding
    /// floor of the true hit point; `ray.at(t)` in `Precision::Fast`).
    pub point: Point3<f64>,
    /// Outward unit normal of the hit block's surface (zero where undefined).
    pub normal: Vector3<f64>,
    /// Whether the ray enters the block here (else it leaves it).
    pub entering: bool,
    /// The block whose surface was hit.
    pub block: BlockId,
    /// The index of the solid within the block.
    pub solid: u32,
}

/// An immutable union of blocks in priority order, ready for queries.
///
/// ```
/// use complex::{Block, Complex, ComplexOptions, MaterialKey, Opacity};
/// use quadric::nalgebra::{Point3, Vector3};
/// use quadric::{Quadric, Ray, Solid, Transform};
/// let ball = |x: f64, opacity| {
///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
///     Block::new("ball", vec![Solid::from(Quadric::sphere().transformed(&m))], opacity, MaterialKey(0)).unwrap()
/// };
/// let scene = Complex::new(vec![ball(0.0, Opacity::Transparent), ball(5.0, Opacity::Opaque)], ComplexOptions::default())
///     .unwrap();
/// let ray = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).unwrap();
/// let hit = scene.cast_ray(&ray, f64::INFINITY).unwrap();
/// assert_eq!((hit.t, hit.entering, hit.block.0), (2.0, true, 0));
/// let p = scene.partition(&ray);
/// assert_eq!(p.events.iter().map(|e| e.t).collect::<Vec<_>>(), [2.0, 4.0, 7.0, 9.0]);
/// assert_eq!(scene.contains_point(&Point3::new(5.0, 0.5, 0.0)).map(|b| b.0), Some(1));
/// ```
#[derive(Clone, Debug)]
pub struct Complex {
    blocks: Vec<Block>,
    boxes: Vec<Aabb>,
    /// Bounded, non-empty blocks.
    bvh: Bvh,
    /// The bounded blocks' solids packed in the BVH's leaf order.
    kernel: Kernel,
    /// Each block's slot in `kernel` (`u32::MAX`: none, an unbounded or
    /// empty block): the spawner reads a hit's solid from the packed copy
    /// the ray test just read, not from the block's own heap buffer.
    slot_of: Vec<u32>,
    /// Blocks with an infinite box: tested for every ray.
    unbounded: Vec<u32>,
    /// The bounded blocks by cell, for point queries.
    points: PointGrid,
    epsilon: f64,
    any_transparent: bool,
    /// Some block is too large for an interval set
    /// ([`Block::fits_interval_set`]): the queries then take the scratch
    /// with a heap buffer ([`SpanBuf`]), else the bare [`Spans`].
    large: bool,
    /// Opaque blocks only, each fitting an interval set, no placements:
    /// the common case, tested first.
    plain: bool,
    /// Placed definitions ([`Complex::assemble`]); then `blocks` and the
    /// structures over them are empty and the assembly holds the own blocks.
    assembly: Option<Box<Assembly>>,
    /// [`ComplexOptions::key`].
    key: u32,
}

/// The default ε of a complex whose bounded part lies in `scene`.
pub(crate) fn default_epsilon(scene: &Aabb) -> f64 {
    let diagonal = if scene.is_bounded() { (scene.max - scene.min).norm() } else { 0.0 };
    if diagonal > 0.0 && diagonal.is_finite() {
        DEFAULT_RELATIVE_EPSILON * diagonal
    } else {
        DEFAULT_RELATIVE_EPSILON
    }
}

impl Complex {
    /// Builds the query structure: a tight box per block and a BVH over the
    /// bounded ones. Blocks keep their order: earlier blocks have priority
    /// (docs/model.md §3.4).
    pub fn new(blocks: Vec<Block>, options: ComplexOptions) -> Result<Self, ComplexError> {
        if blocks.len() as u64 > crate::assembly::MAX_BLOCKS {
            return Err(ComplexError::TooManyBlocks { max: crate::assembly::MAX_BLOCKS as usize });
        }
        if let Some(e) = options.epsilon {
            if !(e.is_finite() && e >= 0.0) {
                return Err(ComplexError::BadEpsilon(e));
            }
        }
        let (boxes, balls) = block_boxes(&blocks);
        let mut bounded = Vec::new();
        let mut unbounded = Vec::new();
        for (i, b) in boxes.iter().enumerate() {
            if b.is_empty() {
                continue; // provably empty: no ray can meet it
            } else if b.is_bounded() {
                bounded.push((i as u32, *b));
            } else {
                unbounded.push(i as u32);
            }
        }
        let epsilon = options
            .epsilon
            .unwrap_or_else(|| default_epsilon(&bounded.iter().fold(Aabb::EMPTY, |a, (_, b)| a.union(b))));
        let bvh = Bvh::build(&bounded);
        let points = PointGrid::new(&bounded);
        let kernel = Kernel::new(bvh.items(), &blocks, &balls);
        let mut slot_of = vec![u32::MAX; blocks.len()];
        for k in 0..kernel.len() as u32 {
            slot_of[kernel.block(k) as usize] = k;
        }
        let any_transparent = blocks.iter().any(Block::is_transparent);
        let large = !blocks.iter().all(Block::fits_interval_set);
        let mut complex = Complex {
            blocks,
            boxes,
            bvh,
            kernel,
            slot_of,
            unbounded,
            points,
            epsilon,
            any_transparent,
            large,
            plain: !any_transparent && !large,
            assembly: None,
            key: options.key,
        };
        if options.precision != quadric::Precision::default() {
            complex.set_precision(options.precision);
        }
        Ok(complex)
    }

    /// The precision mode of the kernel every query uses (default
    /// [`quadric::Precision::Accurate`]; see `docs/quadric.md`, "Precision modes").
    pub fn precision(&self) -> quadric::Precision {
        self.kernel.precision
    }

    /// Sets the precision mode of every query (`cast_ray`, `occluded`,
    /// `partition`, `intervals`, `block_intervals`; `contains_point`
    /// evaluates `f` at the point, the same in every mode).
    pub fn set_precision(&mut self, precision: quadric::Precision) {
        self.kernel.precision = precision;
        for b in &mut self.blocks {
            b.set_precision(precision);
        }
        if let Some(a) = &mut self.assembly {
            a.set_precision(precision);
        }
    }

    /// Makes this (empty) complex the assembly `a` ([`Complex::assemble`]).
    pub(crate) fn set_assembly(&mut self, a: Assembly, any_transparent: bool, large: bool) {
        self.any_transparent = any_transparent;
        self.large = large;
        self.plain = false;
        self.assembly = Some(Box::new(a));
    }

    /// [`Assembly::placing`] of any complex: a flat one's blocks are in place.
    pub(crate) fn placing(&self, id: u32) -> (&Block, crate::assembly::Placing) {
        match &self.assembly {
            None => (&self.blocks[id as usize], crate::assembly::Placing::Identity),
            Some(a) => a.placing(id),
        }
    }

    /// The blocks of the complex's own list in priority order: all its
    /// blocks, unless it was assembled with placed definitions
    /// ([`Complex::assemble`]), whose blocks are found by
    /// [`Complex::block`] and [`Complex::resolve`].
    pub fn blocks(&self) -> &[Block] {
        match &self.assembly {
            None => &self.blocks,
            Some(a) => a.own().blocks(),
        }
    }

    /// The number of blocks, placed definitions expanded: ids run from 0
    /// to `len() - 1`.
    pub fn len(&self) -> usize {
        match &self.assembly {
            None => self.blocks.len(),
            Some(a) => a.len(),
        }
    }

    /// Whether the complex has no blocks.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether definitions are placed in it ([`Complex::assemble`]).
    pub fn is_assembled(&self) -> bool {
        self.assembly.is_some()
    }

    /// The block with this id, in the frame of the complex that lists it
    /// (the world for the blocks of [`Complex::blocks`]; a definition's
    /// frame for a placed one: [`Complex::resolve`] says where it is).
    ///
    /// # Panics
    /// If `id` is not a block of this complex.
    #[inline]
    pub fn block(&self, id: BlockId) -> &Block {
        match &self.assembly {
            None => &self.blocks[id.index()],
            Some(a) => a.block(id.0),
        }
    }

    /// Where block `id` comes from: the complex listing it (by its
    /// [`ComplexOptions::key`]), its place among that complex's own blocks,
    /// and the transform from that complex's frame to this one's.
    ///
    /// # Panics
    /// If `id` is not a block of this complex.
    pub fn resolve(&self, id: BlockId) -> Resolved<'_> {
        match &self.assembly {
            None => Resolved { key: self.key, own: id.0, block: &self.blocks[id.index()], to_world: None },
            Some(a) => a.resolve(id.0),
        }
    }

    pub(crate) fn is_large(&self) -> bool {
        self.large
    }

    /// Every block whose box the ray crosses within `[from, *t_max]`, with
    /// its intervals clipped to its box (before the ε rule) and `t` in this
    /// complex's frame; `visit` may lower `*t_max`. The walk of placed
    /// definitions, which ask their definitions through it.
    pub(crate) fn walk_spans(&self, ray: &Ray, from: f64, t_max: &mut f64, visit: &mut Visit) {
        match &self.assembly {
            Some(a) => a.walk(ray, from, t_max, visit),
            None if self.large => self.walk_flat::<SpanBuf>(ray, from, t_max, visit),
            None => self.walk_flat::<Spans>(ray, from, t_max, visit),
        }
    }

    fn walk_flat<S: Scratch>(&self, ray: &Ray, from: f64, t_max: &mut f64, visit: &mut Visit) {
        let rb = RayBoxes::new(ray);
        let mut scratch = S::new();
        for i in self.unbounded_crossed(&rb, from, *t_max) {
            visit(i, self.block_spans(i, ray, &rb, &mut scratch), t_max);
        }
        self.bvh.traverse(&rb, from, t_max, |k, _, t_max| {
            visit(self.kernel.block(k), self.slot_spans(k, ray, &rb, &mut scratch), t_max)
        });
    }

    /// Calls `f` with every block containing `p`, in no particular order.
    pub(crate) fn for_each_containing(&self, p: &Point3<f64>, f: &mut dyn FnMut(u32, &Block)) {
        if let Some(a) = &self.assembly {
            return a.for_each_containing(p, f);
        }
        let others = self.points.wide_blocks().iter().chain(&self.unbounded);
        for &i in self.points.cell_blocks(p).iter().chain(others) {
            let b = &self.blocks[i as usize];
            if self.boxes[i as usize].contains_point(p) && b.contains_point(p) {
                f(i, b);
            }
        }
    }

    /// [`Complex::block_intervals_into`] by raw id, for the assembly.
    pub(crate) fn block_spans_into(&self, id: u32, ray: &Ray, out: &mut Vec<Interval>) {
        match &self.assembly {
            Some(a) => a.block_spans_into(id, ray, out),
            None => self.block_intervals_into(BlockId(id), ray, out),
        }
    }

    /// The visits of a query's walk to placed definitions: nothing for a
    /// flat complex.
    #[inline(always)]
    fn walk_placed(&self, ray: &Ray, from: f64, t_max: &mut f64, visit: &mut Visit) {
        if let Some(a) = &self.assembly {
            a.walk(ray, from, t_max, visit);
        }
    }

    /// The fault-tolerance ε in use.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Whether any block is transparent.
    pub fn has_transparent(&self) -> bool {
        self.any_transparent
    }

    /// Solid `solid` of block `id`: the packed copy if the block has one,
    /// else the block's own; `None` if either index is out of range.
    pub(crate) fn solid_ref(&self, id: BlockId, solid: u32) -> Option<SolidRef<'_>> {
        if self.assembly.is_some() {
            return None;
        }
        let slot = self.slot_of.get(id.index()).filter(|&&k| k != u32::MAX);
        let packed = slot.and_then(|&k| self.kernel.solid(k, solid));
        packed.or_else(|| self.blocks.get(id.index())?.solids().get(solid as usize).map(SolidRef::from))
    }

    /// The box of one block: conservative (it holds every point of the
    /// block), tight for bounded blocks, infinite on the axes where the block
    /// is unbounded, [`Aabb::EMPTY`] for a block shown to be empty.
    pub fn block_aabb(&self, id: BlockId) -> Aabb {
        match &self.assembly {
            None => self.boxes[id.index()],
            Some(a) => a.block_aabb(id.0),
        }
    }

    /// The box of the whole complex.
    pub fn aabb(&self) -> Aabb {
        match &self.assembly {
            None => self.boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b)),
            Some(a) => a.aabb(),
        }
    }

    /// The box of the bounded blocks.
    pub(crate) fn bounded_aabb(&self) -> Aabb {
        self.boxes.iter().filter(|b| b.is_bounded()).fold(Aabb::EMPTY, |a, b| a.union(b))
    }

    /// The solid `solid` of block `id` in this complex's frame, for a
    /// placed block (`None` for the others, whose own solids are in this
    /// frame, or an index out of range).
    pub(crate) fn placed_solid(&self, id: BlockId, solid: u32) -> Option<quadric::Solid> {
        self.assembly.as_ref()?.world_solid(id.0, solid)
    }

    /// The interval set of one block along the ray as every query sees it,
    /// without the ε rule: [`Block::intervals`] clipped to the part of the
    /// ray inside the block's box ([`Complex::block_aabb`], grown by a few
    /// hundred ulps of the ray origin). The box is conservative in exact
    /// arithmetic, so the clip removes only what the kernel put outside the
    /// block by rounding (a sliver of a degenerate quadric, a crossing of a
    /// half-space whose reference point is far away); an end moved by the
    /// clip lies on the box and is tagged with a solid the ray is outside
    /// of there (see `docs/complex.md`, "One set per block and ray").
    ///
    /// # Panics
    /// If the set has more than [`IntervalSet::CAPACITY`] intervals, which
    /// only a block with more non-convex solids than that can give (see
    /// [`Block::fits_interval_set`]); [`Complex::block_intervals_into`]
    /// takes any block.
    pub fn block_intervals(&self, id: BlockId, ray: &Ray) -> IntervalSet {
        if let Some(a) = &self.assembly {
            let mut out = Vec::new();
            a.block_spans_into(id.0, ray, &mut out);
            return match IntervalSet::from_intervals(out.iter().copied()) {
                Ok(set) => set,
                Err(e) => panic!("block \"{}\": {e}; use Complex::block_intervals_into", self.block(id).name()),
            };
        }
        let mut scratch = <SpanBuf as Scratch>::new();
        self.block_intervals_in(id, ray, &mut scratch);
        match scratch.set() {
            Ok(set) => set,
            Err(e) => panic!("block \"{}\": {e}; use Complex::block_intervals_into", self.blocks[id.index()].name()),
        }
    }

    /// The intervals of [`Complex::block_intervals`], sorted, written into
    /// `out` (cleared first): for a block of any size, allocating only if
    /// `out` must grow.
    pub fn block_intervals_into(&self, id: BlockId, ray: &Ray, out: &mut Vec<Interval>) {
        if let Some(a) = &self.assembly {
            return a.block_spans_into(id.0, ray, out);
        }
        let mut scratch = <SpanBuf as Scratch>::new();
        self.block_intervals_in(id, ray, &mut scratch);
        out.clear();
        out.extend_from_slice(scratch.as_slice());
    }

    fn block_intervals_in(&self, id: BlockId, ray: &Ray, scratch: &mut SpanBuf) {
        if !self.boxes[id.index()].is_empty() {
            self.block_spans(id.0, ray, &RayBoxes::new(ray), scratch);
        }
    }

    /// The intervals of the block in BVH slot `k`, clipped to its box: the
    /// one place every query of a bounded block reads its intervals from.
    /// They are written into `scratch` (one per query, reused for every
    /// block) and read from there: a [`Spans`] value passed on by value is a
    /// 272-byte copy, whatever its variant.
    #[inline(always)]
    fn slot_spans<'s, S: Scratch>(&self, k: u32, ray: &Ray, rb: &RayBoxes, scratch: &'s mut S) -> &'s [Interval] {
        self.kernel.spans_into(k, ray, &self.blocks, scratch);
        self.clip_to_box(self.kernel.block(k), scratch, ray, rb);
        scratch.as_slice()
    }

    /// The intervals of block `i`, clipped to its box (for unbounded
    /// blocks), like [`Complex::slot_spans`].
    #[inline]
    fn block_spans<'s, S: Scratch>(&self, i: u32, ray: &Ray, rb: &RayBoxes, scratch: &'s mut S) -> &'s [Interval] {
        self.blocks[i as usize].spans_into(ray, scratch);
        self.clip_to_box(i, scratch, ray, rb);
        scratch.as_slice()
    }

    /// `spans` within the range `[lo, hi]` where the ray is in block `i`'s
    /// padded box, the same range the box probes of the queries test: so
    /// every `t` of a block's spans is found by a probe at `t`, and the
    /// partition and `cast_ray` see the same spans. The common case (nothing outside) is two
    /// comparisons after the slab test.
    #[inline(always)]
    fn clip_to_box<S: Scratch>(&self, i: u32, spans: &mut S, ray: &Ray, rb: &RayBoxes) {
        let s = spans.as_slice();
        let (Some(first), Some(last)) = (s.first(), s.last()) else { return };
        let b = &self.boxes[i as usize];
        let (lo, hi) = rb.range(&b.min.coords.into(), &b.max.coords.into());
        if first.enter.t >= lo && last.exit.t <= hi {
            return;
        }
        self.clip_spans(i, spans, lo, hi, ray);
    }

    /// The cold part of [`Complex::clip_to_box`]: an end moved to `lo` or
    /// `hi` keeps the solid the kernel tagged it with; a free end (the ray
    /// origin, or infinity) takes the first solid the ray is outside of
    /// there (the box face is near that solid's surface), else solid 0.
    #[cold]
    #[inline(never)]
    fn clip_spans<S: Scratch>(&self, i: u32, spans: &mut S, lo: f64, hi: f64, ray: &Ray) {
        let solids = self.blocks[i as usize].solids();
        let tag = |b: Bound, t: f64| {
            let x = ray.at(t);
            let solid = b.solid().or_else(|| solids.iter().position(|s| s.value(&x) > 0.0).map(|k| k as u32));
            Bound::new(t, solid.unwrap_or(0))
        };
        let clip = |iv: &Interval| {
            let enter = if iv.enter.t < lo { tag(iv.enter, lo) } else { iv.enter };
            let exit = if iv.exit.t > hi { tag(iv.exit, hi) } else { iv.exit };
            (enter.t < exit.t).then_some(Interval::new(enter, exit))
        };
        if let Some(heap) = spans.large_mut() {
            // A large block's intervals, clipped in place.
            let mut n = 0;
            for k in 0..heap.len() {
                if let Some(iv) = clip(&heap[k]) {
                    heap[n] = iv;
                    n += 1;
                }
            }
            heap.truncate(n);
            return;
        }
        let mut out = [Interval::new(Bound::free(0.0), Bound::free(0.0)); IntervalSet::CAPACITY];
        let mut n = 0;
        for iv in spans.as_slice() {
            if let Some(iv) = clip(iv) {
                out[n] = iv;
                n += 1;
            }
        }
        spans.set_spans(match &out[..n] {
            [] => Spans::Empty,
            [iv] => Spans::One(*iv),
            // At most as many intervals as the block had: within capacity.
            many => Spans::Many(IntervalSet::from_intervals(many.iter().copied()).unwrap_or_default()),
        });
    }

    /// The interval set of each block the ray meets, with intervals inside
    /// `[0, ε]` removed, in priority order. A vector per call:
    /// [`Complex::intervals_into`] gives the same intervals into a reusable
    /// [`BlockIntervals`], for blocks of any size.
    ///
    /// # Panics
    /// If a block's set has more than [`IntervalSet::CAPACITY`] intervals,
    /// which only a block with more non-convex solids than that can give
    /// (see [`Block::fits_interval_set`]).
    pub fn intervals(&self, ray: &Ray) -> Vec<(BlockId, IntervalSet)> {
        let mut out = BlockSpans::default();
        self.collect_spans(ray, f64::INFINITY, &mut out);
        match out.to_vec() {
            Ok(sets) => sets,
            Err(id) => {
                panic!("block \"{}\": {}; use Complex::intervals_into", self.block(id).name(), quadric::CapacityError)
            }
        }
    }

    /// [`Complex::intervals`] written into `out` (cleared first): each
    /// block the ray meets with its intervals after the ε rule, in priority
    /// order. Allocates only while `out` grows (and once per thread for a
    /// block too large for an interval set).
    pub fn intervals_into(&self, ray: &Ray, out: &mut BlockIntervals) {
        self.collect_spans(ray, f64::INFINITY, out.spans_mut());
    }

    /// The non-empty spans (after the ε rule) of the blocks whose boxes the ray
    /// crosses before `max_t`, sorted by block id.
    ///
    /// The walk starts at `min(ε, max_t)`, not at 0: a block whose padded
    /// box the ray has left by then (the one a secondary ray leaves, if
    /// thin) has its intervals clipped to that box ([`Complex::clip_to_box`],
    /// the same slabs as the walk's), so they all end before ε and the ε
    /// rule would remove every one of them. The spans are the same.
    pub(crate) fn collect_spans(&self, ray: &Ray, max_t: f64, out: &mut BlockSpans) {
        match (self.assembly.is_some(), self.large) {
            (true, _) => self.collect_spans_in::<Spans, true>(ray, max_t, out),
            (false, true) => self.collect_spans_in::<SpanBuf, false>(ray, max_t, out),
            (false, false) => self.collect_spans_in::<Spans, false>(ray, max_t, out),
        }
    }

    /// [`Complex::collect_spans`] with scratch `S` (see [`Scratch`]).
    #[inline(always)]
    fn collect_spans_in<S: Scratch, const P: bool>(&self, ray: &Ray, max_t: f64, out: &mut BlockSpans) {
        out.clear();
        let eps = self.epsilon;
        let mut push = |i: u32, spans: &[Interval]| {
            out.push(BlockId(i), spans, eps, false);
        };
        let rb = RayBoxes::new(ray);
        let from = if max_t < eps { max_t } else { eps };
        let mut t_max = max_t;
        let mut scratch = S::new();
        self.bvh.traverse_any(&rb, from, &mut t_max, |k, _, _| {
            push(self.kernel.block(k), self.slot_spans(k, ray, &rb, &mut scratch))
        });
        for i in self.unbounded_crossed(&rb, from, max_t) {
            push(i, self.block_spans(i, ray, &rb, &mut scratch));
        }
        if P {
            self.walk_placed(ray, from, &mut t_max, &mut |i, spans, _| push(i, spans));
        }
        out.sort();
    }

    /// Like [`Complex::collect_spans`] with no bound, but the walk stops at
    /// the first interval end `T` after `after` among the blocks visited,
    /// which it returns (`∞` if there is none): every block with an
    /// interval meeting `[0, T]` is collected (its padded box is entered by
    /// `T`), possibly with some farther ones. Every block visited gets an
    /// entry, empty or not; those found in `previous` (the same ray's
    /// spans, collected this way) are copied from it.
    pub(crate) fn collect_spans_to_first_end(
        &self,
        ray: &Ray,
        after: f64,
        out: &mut BlockSpans,
        previous: Option<&BlockSpans>,
    ) -> f64 {
        match (self.assembly.is_some(), self.large) {
            (true, _) => self.collect_spans_to_first_end_in::<Spans, true>(ray, after, out, previous),
            (false, true) => self.collect_spans_to_first_end_in::<SpanBuf, false>(ray, after, out, previous),
            (false, false) => self.collect_spans_to_first_end_in::<Spans, false>(ray, after, out, previous),
        }
    }

    /// [`Complex::collect_spans_to_first_end`] with scratch `S` (see [`Scratch`]).
    #[inline(always)]
    fn collect_spans_to_first_end_in<S: Scratch, const P: bool>(
        &self,
        ray: &Ray,
        after: f64,
        out: &mut BlockSpans,
        previous: Option<&BlockSpans>,
    ) -> f64 {
        out.clear();
        let eps = self.epsilon;
        let mut push = |i: u32, intervals: &[Interval], t_max: &mut f64| {
            for iv in out.push(BlockId(i), intervals, eps, true) {
                for e in [iv.enter.t, iv.exit.t] {
                    if e > after && e < *t_max {
                        *t_max = e;
                    }
                }
            }
        };
        let known = |i: u32| previous.and_then(|p| p.get(BlockId(i)));
        let rb = RayBoxes::new(ray);
        let mut t_max = f64::INFINITY;
        let mut scratch = S::new();
        for i in self.unbounded_crossed(&rb, 0.0, f64::INFINITY) {
            match known(i) {
                Some(ivs) => push(i, ivs, &mut t_max),
                None => push(i, self.block_spans(i, ray, &rb, &mut scratch), &mut t_max),
            }
        }
        self.bvh.traverse(&rb, 0.0, &mut t_max, |k, _, t_max| {
            let i = self.kernel.block(k);
            match known(i) {
                Some(ivs) => push(i, ivs, t_max),
                None => push(i, self.slot_spans(k, ray, &rb, &mut scratch), t_max),
            }
        });
        if P {
            self.walk_placed(ray, 0.0, &mut t_max, &mut |i, spans, t_max| match known(i) {
                Some(ivs) => push(i, ivs, t_max),
                None => push(i, spans, t_max),
            });
        }
        out.sort();
        t_max
    }

    /// The unbounded blocks whose boxes the ray crosses within `[t_min, t_max]`.
    fn unbounded_crossed<'a>(&'a self, rb: &'a RayBoxes, t_min: f64, t_max: f64) -> impl Iterator<Item = u32> + 'a {
        self.unbounded.iter().copied().filter(move |&i| {
            let b = &self.boxes[i as usize];
            rb.enter(&b.min.coords.into(), &b.max.coords.into(), t_min, t_max).is_some()
        })
    }

    /// The block that owns `p` under the priority rule, if any: the first
    /// opaque block containing it, else the first transparent one.
    pub fn contains_point(&self, p: &Point3<f64>) -> Option<BlockId> {
        if !p.iter().all(|c| c.is_finite()) {
            return None;
        }
        let (mut opaque, mut transparent) = (u32::MAX, u32::MAX);
        if let Some(a) = &self.assembly {
            a.for_each_containing(p, &mut |i, b| {
                let best = if b.is_transparent() { &mut transparent } else { &mut opaque };
                *best = (*best).min(i);
            });
            return [opaque, transparent].into_iter().find(|&i| i != u32::MAX).map(BlockId);
        }
        // The cell's blocks come in ascending order: the first opaque one
        // holding `p` owns it, whatever follows.
        for &i in self.points.cell_blocks(p) {
            let b = &self.blocks[i as usize];
            if !self.boxes[i as usize].contains_point(p) {
                continue;
            }
            if !b.is_transparent() {
                if b.contains_point(p) {
                    opaque = i;
                    break;
                }
            } else if transparent == u32::MAX && b.contains_point(p) {
                transparent = i;
            }
        }
        for &i in self.points.wide_blocks().iter().chain(&self.unbounded) {
            let b = &self.blocks[i as usize];
            let best = if b.is_transparent() { &mut transparent } else { &mut opaque };
            if i < *best && self.boxes[i as usize].contains_point(p) && b.contains_point(p) {
                *best = i;
            }
        }
        [opaque, transparent].into_iter().find(|&i| i != u32::MAX).map(BlockId)
    }

    /// Every block that contains `p`, in priority order, into `out` (its
    /// previous contents replaced): each block with
    /// [`Block::contains_point`], found through the BVH as
    /// [`Complex::contains_point`] finds its owner (the first opaque block
    /// of the list, else its first). Two or more blocks mean that `p` lies
    /// where blocks overlap. Empty for a non-finite `p`; allocates only
    /// when `out` must grow.
    ///
    /// ```
    /// use complex::{Block, BlockId, Complex, ComplexOptions, MaterialKey, Opacity};
    /// use quadric::nalgebra::{Point3, Vector3};
    /// use quadric::{Quadric, Solid, Transform};
    /// let ball = |x: f64| {
    ///     let m = Transform::translate(Vector3::new(x, 0.0, 0.0)).unwrap();
    ///     let solid = Solid::from(Quadric::sphere().transformed(&m));
    ///     Block::new("ball", vec![solid], Opacity::Opaque, MaterialKey(0)).unwrap()
    /// };
    /// let scene = Complex::new(vec![ball(0.0), ball(1.0)], ComplexOptions::default()).unwrap();
    /// let mut inside = Vec::new();
    /// scene.blocks_containing(&Point3::new(0.5, 0.0, 0.0), &mut inside);
    /// assert_eq!(inside, [BlockId(0), BlockId(1)]);
    /// scene.blocks_containing(&Point3::new(1.8, 0.0, 0.0), &mut inside);
    /// assert_eq!(inside, [BlockId(1)]);
    /// scene.blocks_containing(&Point3::new(5.0, 0.0, 0.0), &mut inside);
    /// assert!(inside.is_empty());
    /// ```
    pub fn blocks_containing(&self, p: &Point3<f64>, out: &mut Vec<BlockId>) {
        out.clear();
        if !p.iter().all(|c| c.is_finite()) {
            return;
        }
        if let Some(a) = &self.assembly {
            a.for_each_containing(p, &mut |i, _| out.push(BlockId(i)));
            out.sort_unstable();
            return;
        }
        let holds = |i: u32| self.boxes[i as usize].contains_point(p) && self.blocks[i as usize].contains_point(p);
        out.extend(self.points.cell_blocks(p).iter().copied().filter(|&i| holds(i)).map(BlockId));
        let cell = out.len();
        let others = self.points.wide_blocks().iter().chain(&self.unbounded);
        out.extend(others.copied().filter(|&i| holds(i)).map(BlockId));
        // The cell's blocks come in order; the wide and unbounded ones join them.
        if out.len() > cell {
            out.sort_unstable();
        }
    }

    /// Whether an event is an interface a renderer sees: the medium changes
    /// there. Events between two opaque blocks (inside opaque matter) and
    /// between two transparent blocks of the same material are not.
    pub fn is_visible(&self, event: &Event) -> bool {
        let opaque = |o: Option<BlockId>| o.is_some_and(|id| !self.block(id).is_transparent());
        let inside_opaque = opaque(event.before) && opaque(event.after);
        !(event.same_medium || inside_opaque)
    }

    /// The first surface along the ray with `ε < t <= max_t`: the first
    /// visible event of [`Complex::partition`] (see [`Complex::is_visible`]).
    /// Events within `ε` of the origin are skipped, so a ray leaving a
    /// surface does not hit it again.
    ///
    /// Without transparent blocks this is the first point after `ε` where the
    /// ray crosses the boundary of the union of the blocks: the nearest entry,
    /// found front to back through the BVH with early exit, or, for a ray
    /// that starts inside, the exit from the connected run of blocks it
    /// starts in. No partition is built and nothing is allocated.
    pub fn cast_ray(&self, ray: &Ray, max_t: f64) -> Option<Hit> {
        // Also rejects a NaN `max_t`.
        if max_t.partial_cmp(&self.epsilon) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        if self.plain {
            return self.cast_opaque::<Spans, false>(ray, max_t);
        }
        self.cast_ray_other(ray, max_t)
    }

    /// [`Complex::cast_ray`] of a complex with transparent or large blocks,
    /// out of line (the common case's function stays as small as it was).
    #[inline(never)]
    fn cast_ray_other(&self, ray: &Ray, max_t: f64) -> Option<Hit> {
        if self.assembly.is_some() {
            return match self.any_transparent {
                false => self.cast_opaque::<Spans, true>(ray, max_t),
                true => self.cast_general::<Spans, true>(ray, max_t),
            };
        }
        match (self.any_transparent, self.large) {
            (false, _) => self.cast_opaque::<SpanBuf, false>(ray, max_t),
            (true, false) => self.cast_general::<Spans, false>(ray, max_t),
            (true, true) => self.cast_general::<SpanBuf, false>(ray, max_t),
        }
    }

    /// Whether anything stops the ray in `(ε, max_t]`: exactly
    /// `self.cast_ray(ray, max_t).is_some()`, but for opaque complexes an
    /// any-hit query: the first block entry found within `max_t` ends the
    /// search, with no nearest-hit ordering and no normal. Meant for shadow
    /// rays, which need only a yes or no.
    pub fn occluded(&self, ray: &Ray, max_t: f64) -> bool {
        self.occluded_with(ray, max_t, &mut Occluder::default())
    }

    /// [`Complex::occluded`], trying first the block that stopped the
    /// previous ray given the same `occluder` (shadow rays of neighbouring
    /// pixels towards one light are mostly stopped by the same block), and
    /// remembering the one that stops this ray. The answer is exactly
    /// `occluded`'s whatever `occluder` holds (the block tried first only
    /// ends the search for an entry sooner); keep one per light and thread.
    pub fn occluded_with(&self, ray: &Ray, max_t: f64, occluder: &mut Occluder) -> bool {
        if max_t.partial_cmp(&self.epsilon) != Some(core::cmp::Ordering::Greater) {
            return false;
        }
        if self.plain {
            return self.occluded_opaque::<Spans, false>(ray, max_t, occluder);
        }
        self.occluded_other(ray, max_t, occluder)
    }

    /// [`Complex::occluded_with`] of a complex with transparent or large
    /// blocks, out of line.
    #[inline(never)]
    fn occluded_other(&self, ray: &Ray, max_t: f64, occluder: &mut Occluder) -> bool {
        if self.assembly.is_some() {
            return match self.any_transparent {
                false => self.occluded_opaque::<Spans, true>(ray, max_t, occluder),
                true => self.cast_general::<Spans, true>(ray, max_t).is_some(),
            };
        }
        match (self.any_transparent, self.large) {
            (false, _) => self.occluded_opaque::<SpanBuf, false>(ray, max_t, occluder),
            (true, false) => self.cast_general::<Spans, false>(ray, max_t).is_some(),
            (true, true) => self.cast_general::<SpanBuf, false>(ray, max_t).is_some(),
        }
    }

    /// [`Complex::occluded_with`] of a complex of opaque blocks, with
    /// scratch `S` (see [`Scratch`]).
    #[inline(always)]
    fn occluded_opaque<S: Scratch, const P: bool>(&self, ray: &Ray, max_t: f64, occluder: &mut Occluder) -> bool {
        let eps = self.epsilon;
        let rb = RayBoxes::new(ray);
        // One walk answers both questions: is the ray inside the union just
        // after ε (then the answer is whether that run ends within `max_t`),
        // and does it enter a block in `(ε, max_t]` (then, from outside, it
        // is stopped: the nearest entry is one, and every entry is at or
        // after it). Once an entry is found only the inside-probe is left:
        // `t_max = ε` keeps just the boxes that hold the ray at ε.
        let mut run_end = eps;
        let mut found = false;
        let mut look = |spans: &[Interval], t_max: &mut f64| {
            let mut enters = false;
            for iv in spans {
                if iv.enter.t <= eps {
                    if eps < iv.exit.t {
                        run_end = run_end.max(iv.exit.t);
                    }
                } else if iv.enter.t <= max_t {
                    found = true;
                    enters = true;
                    *t_max = eps;
                }
            }
            enters
        };
        let mut t_max = max_t;
        let mut scratch = S::new();
        // The block that stopped the previous ray: if it stops this one
        // too, the walk below is the inside-probe only. (Looking at a block
        // twice changes nothing: `look` only raises `run_end` and sets
        // `found`.)
        let tried = occluder.slot.filter(|&k| (k as usize) < self.kernel.len());
        let hint_stops = tried.is_some_and(|k| look(self.slot_spans(k, ray, &rb, &mut scratch), &mut t_max));
        for i in self.unbounded_crossed(&rb, eps, max_t) {
            look(self.block_spans(i, ray, &rb, &mut scratch), &mut t_max);
        }
        let mut stopper = None;
        self.bvh.traverse_any(&rb, eps, &mut t_max, |k, _, t_max| {
            if look(self.slot_spans(k, ray, &rb, &mut scratch), t_max) && stopper.is_none() {
                stopper = Some(k);
            }
        });
        if P {
            self.walk_placed(ray, eps, &mut t_max, &mut |_, spans, t_max| {
                look(spans, t_max);
            });
        }
        // Keep the hint while it stops the rays, else the block that did.
        occluder.slot = if hint_stops { tried } else { stopper };
        if run_end > eps {
            return self.run_exit::<S, P>(ray, &rb, run_end, max_t).is_some();
        }
        found
    }

    /// `cast_ray` with transparent blocks: walks the ends of the blocks'
    /// intervals in order from ε, keeping the owner, until the owner changes
    /// visibly. Each step is one front-to-back BVH query for the next end
    /// (with early exit) and one for the blocks covering the ray just after
    /// it; nothing is stored, so nothing is allocated.
    fn cast_general<S: Scratch, const P: bool>(&self, ray: &Ray, max_t: f64) -> Option<Hit> {
        let rb = RayBoxes::new(ray);
        let mut tau = self.epsilon;
        let mut before = self.owner_after::<S, P>(ray, &rb, tau);
        loop {
            let t = self.next_end::<S, P>(ray, &rb, tau, max_t)?;
            let after = self.owner_after::<S, P>(ray, &rb, t);
            if after != before {
                if self.visible_change(before, after) {
                    if let Some(hit) = self.event_hit::<S>(ray, &rb, t, before, after) {
                        return Some(hit);
                    }
                }
                before = after;
            }
            tau = t;
        }
    }

    /// The owner of the ray just after `t`: the blocks with an interval
    /// `enter <= t < exit`, by the priority rule.
    fn owner_after<S: Scratch, const P: bool>(&self, ray: &Ray, rb: &RayBoxes, t: f64) -> Option<BlockId> {
        let (mut opaque, mut transparent) = (u32::MAX, u32::MAX);
        let mut consider = |i: u32, spans: &[Interval]| {
            let best = if self.block(BlockId(i)).is_transparent() { &mut transparent } else { &mut opaque };
            if i < *best && spans.iter().any(|iv| iv.enter.t <= t && t < iv.exit.t) {
                *best = i;
            }
        };
        let mut t_hi = t;
        let mut scratch = S::new();
        self.bvh.traverse_any(rb, t, &mut t_hi, |k, _, _| {
            consider(self.kernel.block(k), self.slot_spans(k, ray, rb, &mut scratch))
        });
        for i in self.unbounded_crossed(rb, t, t) {
            consider(i, self.block_spans(i, ray, rb, &mut scratch));
        }
        if P {
            self.walk_placed(ray, t, &mut t_hi, &mut |i, spans, _| consider(i, spans));
        }
        [opaque, transparent].into_iter().find(|&i| i != u32::MAX).map(BlockId)
    }

    /// The smallest finite end of any block's interval in `(tau, max_t]`.
    fn next_end<S: Scratch, const P: bool>(&self, ray: &Ray, rb: &RayBoxes, tau: f64, max_t: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        let mut consider = |spans: &[Interval], t_max: &mut f64| {
            for iv in spans {
                for e in [iv.enter.t, iv.exit.t] {
                    if e > tau && e <= *t_max && e.is_finite() && best.is_none_or(|b| e < b) {
                        best = Some(e);
                        *t_max = e;
                    }
                }
            }
        };
        let mut t_max = max_t;
        let mut scratch = S::new();
        for i in self.unbounded_crossed(rb, tau, max_t) {
            consider(self.block_spans(i, ray, rb, &mut scratch), &mut t_max);
        }
        self.bvh
            .traverse(rb, tau, &mut t_max, |k, _, t_max| consider(self.slot_spans(k, ray, rb, &mut scratch), t_max));
        if P {
            self.walk_placed(ray, tau, &mut t_max, &mut |_, spans, t_max| consider(spans, t_max));
        }
        best
    }

    /// Whether a change of owner from `before` to `after` is an interface
    /// (see [`Complex::is_visible`]).
    fn visible_change(&self, before: Option<BlockId>, after: Option<BlockId>) -> bool {
        let (Some(b), Some(a)) = (before, after) else { return true };
        let (b, a) = (self.block(b), self.block(a));
        match (b.is_transparent(), a.is_transparent()) {
            (false, false) => false,
            (true, true) => b.material() != a.material(),
            _ => true,
        }
    }

    /// The hit at a change of owner at `t`: the entry of the new owner if it
    /// starts there, else the exit of the old one (as in the partition).
    fn event_hit<S: Scratch>(
        &self,
        ray: &Ray,
        rb: &RayBoxes,
        t: f64,
        before: Option<BlockId>,
        after: Option<BlockId>,
    ) -> Option<Hit> {
        if self.assembly.is_some() {
            return self.placed_event_hit(ray, t, before, after);
        }
        let entry = after.and_then(|id| {
            let mut scratch = S::new();
            let spans = self.block_spans(id.0, ray, rb, &mut scratch);
            let solid = spans.iter().find(|iv| iv.enter.t == t)?.enter.solid()?;
            Some(self.hit(ray, t, id.0, solid, true))
        });
        entry.or_else(|| {
            let id = before?;
            let mut scratch = S::new();
            let spans = self.block_spans(id.0, ray, rb, &mut scratch);
            let solid = spans.iter().find(|iv| iv.exit.t == t)?.exit.solid()?;
            Some(self.hit(ray, t, id.0, solid, false))
        })
    }

    /// [`Complex::event_hit`] in an assembly: the block's spans from a walk
    /// probing the boxes that hold the ray at `t`.
    fn placed_event_hit(&self, ray: &Ray, t: f64, before: Option<BlockId>, after: Option<BlockId>) -> Option<Hit> {
        let end = |id: BlockId, entering: bool| {
            let mut solid = None;
            let mut t_hi = t;
            self.walk_placed(ray, t, &mut t_hi, &mut |i, spans, _| {
                if i == id.0 {
                    let end = spans.iter().map(|iv| if entering { iv.enter } else { iv.exit }).find(|b| b.t == t);
                    solid = solid.or(end.and_then(|b| b.solid()));
                }
            });
            solid.map(|solid| self.hit(ray, t, id.0, solid, entering))
        };
        after.and_then(|id| end(id, true)).or_else(|| end(before?, false))
    }

    /// `cast_ray` for complexes of opaque blocks only.
    fn cast_opaque<S: Scratch, const P: bool>(&self, ray: &Ray, max_t: f64) -> Option<Hit> {
        let eps = self.epsilon;
        let rb = RayBoxes::new(ray);
        // One front-to-back walk with early exit finds the nearest entry
        // after ε (lowest block id on ties: the owner after the event) and
        // whether the ray is inside the union just after ε: then the answer
        // is the end of the run of overlapping intervals it is in. The boxes
        // holding the ray at ε enter at or before ε, before any entry found,
        // so the shrinking `t_max` never cuts them off.
        let mut nearest = Nearest::new(eps);
        let mut t_max = max_t;
        let mut scratch = S::new();
        for i in self.unbounded_crossed(&rb, eps, max_t) {
            nearest.consider(i, None, self.block_spans(i, ray, &rb, &mut scratch), &mut t_max);
        }
        self.bvh.traverse(&rb, eps, &mut t_max, |k, _, t_max| {
            nearest.consider(self.kernel.block(k), Some(k), self.slot_spans(k, ray, &rb, &mut scratch), t_max)
        });
        if P {
            self.walk_placed(ray, eps, &mut t_max, &mut |i, spans, t_max| nearest.consider(i, None, spans, t_max));
        }
        self.nearest_hit::<S, P>(ray, &rb, &nearest, max_t)
    }

    /// [`Complex::cast_ray`] of four rays, for coherent rays such as a
    /// camera's neighbouring pixels: in a complex of opaque blocks the four
    /// share one walk of the BVH (each node is read once for all of them);
    /// each answer is exactly `cast_ray`'s for its ray.
    pub fn cast_rays(&self, rays: &[Ray; 4], max_t: f64) -> [Option<Hit>; 4] {
        // With a block too large for an interval set, one ray at a time.
        if !self.plain || max_t.partial_cmp(&self.epsilon) != Some(core::cmp::Ordering::Greater) {
            return rays.each_ref().map(|r| self.cast_ray(r, max_t));
        }
        let eps = self.epsilon;
        let rbs = rays.each_ref().map(RayBoxes::new);
        let mut nearest = [Nearest::new(eps); 4];
        let mut t_max = [max_t; 4];
        let mut scratch = Spans::Empty;
        for (lane, ray) in rays.iter().enumerate() {
            for i in self.unbounded_crossed(&rbs[lane], eps, max_t) {
                let spans = self.block_spans(i, ray, &rbs[lane], &mut scratch);
                nearest[lane].consider(i, None, spans, &mut t_max[lane]);
            }
        }
        self.bvh.traverse4(&RayBoxes4::new(&rbs), 0b1111, eps, &mut t_max, |k, lane, t_max| {
            let spans = self.slot_spans(k, &rays[lane], &rbs[lane], &mut scratch);
            nearest[lane].consider(self.kernel.block(k), Some(k), spans, &mut t_max[lane]);
        });
        [0, 1, 2, 3].map(|lane| self.nearest_hit::<Spans, false>(&rays[lane], &rbs[lane], &nearest[lane], max_t))
    }

    /// The hit a [`Nearest`] search found: the exit of the run the ray
    /// starts in, else the nearest entry.
    fn nearest_hit<S: Scratch, const P: bool>(
        &self,
        ray: &Ray,
        rb: &RayBoxes,
        nearest: &Nearest,
        max_t: f64,
    ) -> Option<Hit> {
        if nearest.run_end > self.epsilon {
            return self.run_exit::<S, P>(ray, rb, nearest.run_end, max_t);
        }
        let (t, block, solid, slot) = nearest.best?;
        // The normal from the packed copy of the solid, which the test just
        // read (the block's own copy is likely out of the caches by now).
        let (point, normal) = match slot.and_then(|k| self.kernel.solid(k, solid)) {
            Some(SolidRef::HalfSpace(h)) => (self.refined(ray, t, |t| h.hit_point(ray, t)), h.normal()),
            Some(SolidRef::Quadric(q)) => {
                let point = self.refined(ray, t, |t| q.hit_point(ray, t));
                (point, q.normal(&point).unwrap_or_else(Vector3::zeros))
            }
            None => return Some(self.hit(ray, t, block, solid, true)),
        };
        Some(Hit { t, point, normal, entering: true, block: BlockId(block), solid })
    }

    /// The exit from the run of overlapping intervals containing `(ε, run_end]`.
    fn run_exit<S: Scratch, const P: bool>(
        &self,
        ray: &Ray,
        rb: &RayBoxes,
        mut run_end: f64,
        max_t: f64,
    ) -> Option<Hit> {
        loop {
            let mut next = run_end;
            // The lowest block id whose interval ends exactly at `next`: the
            // owner just before the exit.
            let mut owner: Option<(u32, u32)> = None;
            let mut extend = |i: u32, spans: &[Interval]| {
                for iv in spans {
                    if iv.enter.t <= run_end && iv.exit.t >= next {
                        if iv.exit.t > next {
                            next = iv.exit.t;
                            owner = None;
                        }
                        if owner.is_none_or(|(o, _)| i < o) {
                            owner = Some((i, iv.exit.solid));
                        }
                    }
                }
            };
            let mut t_hi = run_end;
            let mut scratch = S::new();
            self.bvh.traverse_any(rb, self.epsilon, &mut t_hi, |k, _, _| {
                extend(self.kernel.block(k), self.slot_spans(k, ray, rb, &mut scratch))
            });
            for i in self.unbounded_crossed(rb, self.epsilon, run_end) {
                extend(i, self.block_spans(i, ray, rb, &mut scratch));
            }
            if P {
                self.walk_placed(ray, self.epsilon, &mut t_hi, &mut |i, spans, _| extend(i, spans));
            }
            if next > run_end {
                if next > max_t {
                    return None;
                }
                run_end = next;
                continue;
            }
            let (block, solid) = owner?;
            if !(run_end.is_finite() && run_end <= max_t) {
                return None;
            }
            return Some(self.hit(ray, run_end, block, solid, false));
        }
    }

    fn hit(&self, ray: &Ray, t: f64, block: u32, solid: u32, entering: bool) -> Hit {
        if let Some(a) = &self.assembly {
            let (b, placing) = a.placing(block);
            let (point, normal) = match placing {
                // Moved only: the point on the solid where it is defined,
                // moved back (a translation keeps the normal).
                crate::assembly::Placing::Translate(v) => {
                    match (b.solids().get(solid as usize), Ray::new_unit(ray.origin() - v, ray.direction())) {
                        (Some(s), Ok(local)) => {
                            let point = self.refined(&local, t, |t| s.hit_point(&local, t));
                            (point + v, s.normal(&point).unwrap_or_else(Vector3::zeros))
                        }
                        _ => (ray.at(t), Vector3::zeros()),
                    }
                }
                _ => match a.world_solid(block, solid) {
                    Some(s) => {
                        let point = self.refined(ray, t, |t| s.hit_point(ray, t));
                        (point, s.normal(&point).unwrap_or_else(Vector3::zeros))
                    }
                    None => (ray.at(t), Vector3::zeros()),
                },
            };
            return Hit { t, point, normal, entering, block: BlockId(block), solid };
        }
        let point = self.hit_point(ray, t, BlockId(block), solid);
        let normal = self.normal(BlockId(block), solid, &point);
        Hit { t, point, normal, entering, block: BlockId(block), solid }
    }

    /// The hit point at the crossing `t` of `solid`'s surface: refined onto
    /// the surface ([`quadric::Solid::hit_point`]) except in
    /// [`quadric::Precision::Fast`], where it is `ray.at(t)`.
    pub(crate) fn hit_point(&self, ray: &Ray, t: f64, block: BlockId, solid: u32) -> Point3<f64> {
        if self.assembly.is_some() {
            return match self.placed_solid(block, solid) {
                Some(s) => self.refined(ray, t, |t| s.hit_point(ray, t)),
                None => ray.at(t),
            };
        }
        match self.blocks[block.index()].solids().get(solid as usize) {
            Some(s) => self.refined(ray, t, |t| s.hit_point(ray, t)),
            None => ray.at(t),
        }
    }

    #[inline(always)]
    fn refined(&self, ray: &Ray, t: f64, refine: impl FnOnce(f64) -> Point3<f64>) -> Point3<f64> {
        if self.kernel.precision == quadric::Precision::Fast {
            ray.at(t)
        } else {
            refine(t)
        }
    }

    pub(crate) fn normal(&self, block: BlockId, solid: u32, point: &Point3<f64>) -> Vector3<f64> {
        if self.assembly.is_some() {
            return self.placed_solid(block, solid).and_then(|s| s.normal(point)).unwrap_or_else(Vector3::zeros);
        }
        self.blocks[block.index()]
            .solids()
            .get(solid as usize)
            .and_then(|s| s.normal(point))
            .unwrap_or_else(Vector3::zeros)
    }
}

/// The search state of [`Complex::cast_opaque`] for one ray: the nearest
/// entry after ε so far (lowest block id on ties) and the end of the run of
/// intervals holding the ray at ε. The result depends only on which blocks
/// are considered, not on their order.
#[derive(Clone, Copy, Debug)]
struct Nearest {
    eps: f64,
    run_end: f64,
    /// `(t, block, solid, BVH slot)`.
    best: Option<(f64, u32, u32, Option<u32>)>,
}

impl Nearest {
    fn new(eps: f64) -> Self {
        Nearest { eps, run_end: eps, best: None }
    }

    /// Takes block `i`'s intervals (from BVH slot `k`, if bounded) into
    /// account, lowering `t_max` to a nearer entry.
    #[inline(always)]
    fn consider(&mut self, i: u32, k: Option<u32>, spans: &[Interval], t_max: &mut f64) {
        let eps = self.eps;
        let mut entry = None;
        for iv in spans {
            if iv.enter.t <= eps {
                if eps < iv.exit.t {
                    self.run_end = self.run_end.max(iv.exit.t);
                }
            } else if entry.is_none() && iv.enter.t > eps {
                entry = Some(iv);
            }
        }
        if let Some(iv) = entry {
            let t = iv.enter.t;
            if t <= *t_max && self.best.is_none_or(|(bt, bi, _, _)| t < bt || (t == bt && i < bi)) {
                self.best = Some((t, i, iv.enter.solid, k));
                *t_max = t;
            }
        }
    }
}
