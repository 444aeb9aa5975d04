//! Blocks: intersections of solids.

use quadric::{Bound, HalfSpace, Interval, IntervalSet, Pieces, Precision, Quadric, Ray, Solid};

use crate::ComplexError;

/// How light passes a block. The kernel only uses it for ownership (docs/model.md §3.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Opacity {
    /// Owns every point it contains.
    Opaque,
    /// Owns a point only where no opaque block and no earlier transparent block does.
    Transparent,
}

/// An opaque key the kernel carries for its user (a material index, say).
/// Overlapping transparent blocks with equal keys act as one medium.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct MaterialKey(pub u32);

/// The index of a block in a [`crate::Complex`], in insertion (= priority) order, from 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BlockId(pub u32);

impl BlockId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// An intersection of solids: `Object_1 ∩ … ∩ Object_m`, with a name, an
/// opacity and a material key.
///
/// ```
/// use complex::{Block, MaterialKey, Opacity};
/// use quadric::{HalfSpace, Quadric, Solid};
/// let capped = Block::new(
///     "post",
///     vec![
///         Solid::from(Quadric::tube_y()),
///         Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -1.0).unwrap()),
///         Solid::from(HalfSpace::new(0.0, -1.0, 0.0, 0.0).unwrap()),
///     ],
///     Opacity::Opaque,
///     MaterialKey(0),
/// ).unwrap();
/// assert_eq!(capped.solids().len(), 3);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    name: String,
    solids: Vec<Solid>,
    opacity: Opacity,
    material: MaterialKey,
    /// Every solid is convex, so a ray meets the block in at most one
    /// interval: [`Block::spans`] then keeps one [`ConvexSpan`] instead of
    /// interval sets.
    convex: bool,
    /// At most `IntervalSet::CAPACITY - 1` non-convex solids: every ray's
    /// set fits an [`IntervalSet`] (`m` non-convex solids give at most
    /// `m + 1` intervals). Larger blocks take a heap buffer.
    fits: bool,
    /// The kernel's precision mode (set by [`Complex::set_precision`](crate::Complex::set_precision)).
    precision: Precision,
}

/// A block's intervals along a ray: without an interval set (and the copies
/// of its fixed-size buffer) when there is at most one.
// Boxing the set would allocate per ray; the big variant is the rare one.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub(crate) enum Spans {
    Empty,
    One(Interval),
    Many(IntervalSet),
}

impl Spans {
    /// The intervals, sorted.
    #[inline]
    pub(crate) fn as_slice(&self) -> &[Interval] {
        match self {
            Spans::Empty => &[],
            Spans::One(iv) => core::slice::from_ref(iv),
            Spans::Many(set) => set.as_slice(),
        }
    }
}

/// Where a query writes one block's intervals at a time, reused from block
/// to block. Two kinds: a bare [`Spans`], for the complexes whose blocks
/// all fit an interval set (every query on them is compiled for it, so the
/// common case carries nothing for the rare one), and a [`SpanBuf`], which
/// adds a heap buffer for the blocks that do not
/// ([`Block::fits_interval_set`]).
pub(crate) trait Scratch {
    /// Whether it can hold a large block's intervals.
    const LARGE: bool;
    fn new() -> Self;
    /// The intervals, sorted.
    fn as_slice(&self) -> &[Interval];
    /// Holds `spans` (a block that fits a set).
    fn set_spans(&mut self, spans: Spans);
    /// Holds the intervals `fill` writes into an empty buffer (a block too
    /// large for a set).
    fn set_large(&mut self, fill: impl FnOnce(&mut Vec<Interval>));
    /// The buffer of a large block's intervals, if it holds one.
    fn large_mut(&mut self) -> Option<&mut Vec<Interval>>;
    /// The [`Spans`] to write a block that fits a set into.
    fn spans_mut(&mut self) -> &mut Spans;
}

impl Scratch for Spans {
    const LARGE: bool = false;

    #[inline(always)]
    fn new() -> Self {
        Spans::Empty
    }

    #[inline(always)]
    fn as_slice(&self) -> &[Interval] {
        Spans::as_slice(self)
    }

    #[inline(always)]
    fn set_spans(&mut self, spans: Spans) {
        *self = spans;
    }

    /// Only for a complex that holds no large block: then the intervals fit.
    #[cold]
    fn set_large(&mut self, fill: impl FnOnce(&mut Vec<Interval>)) {
        let mut v = Vec::new();
        fill(&mut v);
        match IntervalSet::from_intervals(v) {
            Ok(set) => *self = Spans::Many(set),
            Err(_) => unreachable!("a block too large for an interval set queried as a small one"),
        }
    }

    #[inline(always)]
    fn large_mut(&mut self) -> Option<&mut Vec<Interval>> {
        None
    }

    #[inline(always)]
    fn spans_mut(&mut self) -> &mut Spans {
        self
    }
}

/// A [`Spans`] and, for the blocks too large for an interval set, a heap
/// buffer, which the queries keep from block to block and hand back to a
/// per-thread pool when done, so that a thread allocates it once, not per
/// query.
#[derive(Debug)]
pub(crate) struct SpanBuf {
    spans: Spans,
    /// Whether the intervals are in `heap` (else in `spans`).
    on_heap: bool,
    heap: Vec<Interval>,
}

thread_local! {
    /// The heap buffer of the last [`SpanBuf`] dropped on this thread.
    static SPILLED: core::cell::Cell<Vec<Interval>> = const { core::cell::Cell::new(Vec::new()) };
}

impl SpanBuf {
    /// The intervals as a set, or `Err` past its capacity.
    pub(crate) fn set(&self) -> Result<IntervalSet, quadric::CapacityError> {
        match &self.spans {
            _ if self.on_heap => IntervalSet::from_intervals(self.heap.iter().copied()),
            Spans::Empty => Ok(IntervalSet::empty()),
            Spans::One(iv) => Ok(IntervalSet::from_interval(iv.enter, iv.exit)),
            Spans::Many(set) => Ok(*set),
        }
    }
}

impl Scratch for SpanBuf {
    const LARGE: bool = true;

    #[inline(always)]
    fn new() -> Self {
        SpanBuf { spans: Spans::Empty, on_heap: false, heap: Vec::new() }
    }

    #[inline]
    fn as_slice(&self) -> &[Interval] {
        if self.on_heap {
            &self.heap
        } else {
            self.spans.as_slice()
        }
    }

    #[inline(always)]
    fn set_spans(&mut self, spans: Spans) {
        self.spans = spans;
        self.on_heap = false;
    }

    /// Into the heap buffer (taken from the thread's pool the first time).
    #[cold]
    fn set_large(&mut self, fill: impl FnOnce(&mut Vec<Interval>)) {
        if self.heap.capacity() == 0 {
            self.heap = SPILLED.with(|c| c.take());
        }
        self.heap.clear();
        fill(&mut self.heap);
        self.on_heap = true;
    }

    #[inline]
    fn large_mut(&mut self) -> Option<&mut Vec<Interval>> {
        self.on_heap.then_some(&mut self.heap)
    }

    #[inline(always)]
    fn spans_mut(&mut self) -> &mut Spans {
        self.on_heap = false;
        &mut self.spans
    }
}

impl Drop for SpanBuf {
    fn drop(&mut self) {
        if self.heap.capacity() != 0 {
            let heap = core::mem::take(&mut self.heap);
            // During a thread's teardown the pool may be gone: then it is freed.
            let _ = SPILLED.try_with(|c| c.set(heap));
        }
    }
}

impl Block {
    /// A block; errors if it has no solids or a solid is not finite. Any
    /// number of solids, convex or not, is allowed (see
    /// [`Block::fits_interval_set`]).
    pub fn new(
        name: impl Into<String>,
        solids: Vec<Solid>,
        opacity: Opacity,
        material: MaterialKey,
    ) -> Result<Self, ComplexError> {
        let name = name.into();
        if solids.is_empty() {
            return Err(ComplexError::EmptyBlock { name });
        }
        for (index, s) in solids.iter().enumerate() {
            let finite = match s {
                Solid::Quadric(q) => q.is_finite(),
                Solid::HalfSpace(h) => h.is_finite(),
            };
            if !finite {
                return Err(ComplexError::NonFinite { name, solid: index });
            }
        }
        let non_convex = solids.iter().filter(|s| s.max_intervals() > 1).count();
        Ok(Block {
            name,
            solids,
            opacity,
            material,
            convex: non_convex == 0,
            fits: non_convex < IntervalSet::CAPACITY,
            precision: Precision::default(),
        })
    }

    /// The block's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The solids, in order; a hit reports the index into this slice.
    pub fn solids(&self) -> &[Solid] {
        &self.solids
    }

    /// Opaque or transparent.
    pub fn opacity(&self) -> Opacity {
        self.opacity
    }

    /// Whether the block is transparent.
    pub fn is_transparent(&self) -> bool {
        self.opacity == Opacity::Transparent
    }

    /// The material key.
    pub fn material(&self) -> MaterialKey {
        self.material
    }

    /// Whether `x` lies in every solid.
    pub fn contains_point(&self, x: &quadric::nalgebra::Point3<f64>) -> bool {
        self.solids.iter().all(|s| s.contains_point(x))
    }

    /// The set of `λ >= 0` inside the block: the intersection of its solids'
    /// sets, each end tagged with the index of the solid it lies on. Stops as
    /// soon as the running set is empty (the convex loop of docs/model.md §3.1).
    ///
    /// # Panics
    /// If the set has more than [`IntervalSet::CAPACITY`] intervals, which
    /// only a block with more non-convex solids than that can give (see
    /// [`Block::fits_interval_set`]); [`Block::intervals_into`] takes any block.
    pub fn intervals(&self, ray: &Ray) -> IntervalSet {
        match self.spans(ray).set() {
            Ok(set) => set,
            Err(e) => panic!("block \"{}\": {e}; use Block::intervals_into", self.name),
        }
    }

    /// The intervals of [`Block::intervals`], sorted, written into `out`
    /// (cleared first): for a block of any size, allocating only if `out`
    /// must grow.
    ///
    /// ```
    /// use complex::{Block, MaterialKey, Opacity};
    /// use quadric::nalgebra::{Point3, Vector3};
    /// use quadric::{HalfSpace, Quadric, Ray, Solid, Transform};
    /// // A plate (|y| <= 1) drilled by twelve holes of radius 0.25 along y, at x = 0, 1, ..., 11.
    /// let mut solids = vec![
    ///     Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -1.0).unwrap()),
    ///     Solid::from(HalfSpace::new(0.0, -1.0, 0.0, -1.0).unwrap()),
    /// ];
    /// for k in 0..12 {
    ///     let thin = Transform::scale_xyz(Vector3::new(0.25, 1.0, 0.25)).unwrap();
    ///     let m = thin.then(&Transform::translate(Vector3::new(k as f64, 0.0, 0.0)).unwrap());
    ///     solids.push(Solid::from(Quadric::tube_y().transformed(&m)).complement());
    /// }
    /// let plate = Block::new("plate", solids, Opacity::Opaque, MaterialKey(0)).unwrap();
    /// assert!(!plate.fits_interval_set());
    /// // Along the x axis the ray leaves and re-enters the plate at every hole.
    /// let ray = Ray::new(Point3::new(-1.0, 0.0, 0.0), Vector3::x()).unwrap();
    /// let mut out = Vec::new();
    /// plate.intervals_into(&ray, &mut out);
    /// assert_eq!(out.len(), 13);
    /// assert_eq!((out[0].enter.t, out[0].exit.t), (0.0, 0.75));
    /// ```
    pub fn intervals_into(&self, ray: &Ray, out: &mut Vec<Interval>) {
        out.clear();
        out.extend_from_slice(self.spans(ray).as_slice());
    }

    /// Whether every ray's set fits an [`IntervalSet`], so that
    /// [`Block::intervals`] cannot panic: true for a block with at most
    /// `IntervalSet::CAPACITY - 1` non-convex solids (`m` of them give at
    /// most `m + 1` intervals). Larger blocks are allowed; the queries keep
    /// their sets in a heap buffer.
    pub fn fits_interval_set(&self) -> bool {
        self.fits
    }

    /// [`Block::intervals`] without building a set for a convex block.
    pub(crate) fn spans(&self, ray: &Ray) -> SpanBuf {
        let mut spans = <SpanBuf as Scratch>::new();
        self.spans_into(ray, &mut spans);
        spans
    }

    /// [`Block::spans`] written into `out`: a convex block writes at most
    /// one interval, and only the general case a whole set. (Returning the
    /// enum instead costs a copy of its full 272 bytes wherever it is
    /// passed on, whatever the variant.)
    #[inline(always)]
    pub(crate) fn spans_into<S: Scratch>(&self, ray: &Ray, out: &mut S) {
        if self.convex {
            let solids = self.solids.iter().map(SolidRef::from);
            if let Some(spans) = convex_spans(ray, solids, self.precision) {
                out.set_spans(spans);
                return;
            }
        }
        self.spans_rare_into(ray, out);
    }

    /// `*out = self.spans_general(ray)`, out of line: the rare case.
    #[cold]
    #[inline(never)]
    pub(crate) fn spans_general_into(&self, ray: &Ray, out: &mut Spans) {
        *out = self.spans_general(ray);
    }

    /// The intervals of a block that is not convex (or whose convex test
    /// failed): [`Block::spans_general_into`] for a block that fits a set,
    /// else the heap path (which a bare [`Spans`] scratch, used only where
    /// no block is large, compiles away).
    #[inline(always)]
    pub(crate) fn spans_rare_into<S: Scratch>(&self, ray: &Ray, out: &mut S) {
        if S::LARGE && !self.fits {
            return out.set_large(|heap| self.spans_large(ray, heap));
        }
        self.spans_general_into(ray, out.spans_mut());
    }

    /// The precision mode its sets are computed in.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Sets the precision mode of [`Block::intervals`].
    pub fn set_precision(&mut self, precision: Precision) {
        self.precision = precision;
    }

    /// Whether every solid is convex.
    pub(crate) fn is_convex(&self) -> bool {
        self.convex
    }

    /// Intersection of interval sets, for blocks with non-convex solids.
    pub(crate) fn spans_general(&self, ray: &Ray) -> Spans {
        if self.precision == Precision::Certified {
            return Spans::Many(self.certified_set(ray));
        }
        let mut acc = IntervalSet::everything().clip(0.0, f64::INFINITY);
        for (i, s) in self.solids.iter().enumerate() {
            let i = i as u32;
            acc = match s {
                Solid::HalfSpace(h) => {
                    let (enter, exit) = h.interval_with(ray, i, self.precision);
                    acc.intersect_interval(enter, exit)
                }
                Solid::Quadric(q) => {
                    let set = q.intervals_with(ray, i, self.precision);
                    // Within capacity: checked in `Block::new`.
                    acc.intersect(&set).unwrap_or_default()
                }
            };
            if acc.is_empty() {
                break;
            }
        }
        Spans::Many(acc)
    }

    /// [`Block::spans_general`] for a block too large for an interval set:
    /// the same intersection, solid by solid in block order with the same
    /// comparisons (on equal `t` the running set's end is kept), into `acc`
    /// (empty on entry), a buffer that grows as needed. In
    /// [`Precision::Certified`] each solid's set is first settled against
    /// the running set as [`Block::certified_set`] does.
    fn spans_large(&self, ray: &Ray, acc: &mut Vec<Interval>) {
        acc.push(Interval::new(Bound::free(0.0), Bound::free(f64::INFINITY)));
        for (i, s) in self.solids.iter().enumerate() {
            let i = i as u32;
            let set: IntervalSet = match s {
                _ if self.precision == Precision::Certified => {
                    settle_ties(ray, &self.solids, i as usize, &s.intervals_certified(ray, i), acc)
                }
                Solid::HalfSpace(h) => {
                    let (enter, exit) = h.interval_with(ray, i, self.precision);
                    IntervalSet::from_interval(enter, exit)
                }
                Solid::Quadric(q) => q.pieces_with(ray, i, self.precision).into(),
            };
            intersect_in_place(acc, set.as_slice());
            if acc.is_empty() {
                break;
            }
        }
    }
}

impl Block {
    /// [`Precision::Certified`]: the intersection of the solids' certified
    /// sets, with ties between solids settled exactly. Before solid `i`'s
    /// set meets the running set, each of its ends that lies within the two
    /// certified bounds of an end of an earlier solid `j` is ordered against
    /// it by [`Solid::compare_roots`] (exact): an exact tie takes the earlier
    /// end's value (so the intersection keeps the earlier solid's end, and
    /// an interval closing on a tie is empty, as in the exact reference),
    /// and a strict order the doubles got wrong is restored by one ulp.
    /// Outside those near-ties (the usual case) it is the float
    /// intersection.
    fn certified_set(&self, ray: &Ray) -> IntervalSet {
        let mut acc = IntervalSet::everything().clip(0.0, f64::INFINITY);
        for (i, s) in self.solids.iter().enumerate() {
            let own = s.intervals_certified(ray, i as u32);
            let set = settle_ties(ray, &self.solids, i, &own, acc.as_slice());
            // Within capacity: checked in `Block::new`.
            acc = acc.intersect(&set).unwrap_or_default();
            if acc.is_empty() {
                break;
            }
        }
        acc
    }
}

/// `acc ∩ other` into `acc`, as `IntervalSet::intersect` forms it (where two
/// ends coincide the end of `acc` is kept; touching results merge), for a
/// running set of any length: the result is appended after `acc`'s
/// intervals, which are then dropped.
fn intersect_in_place(acc: &mut Vec<Interval>, other: &[Interval]) {
    let n = acc.len();
    let (mut i, mut j) = (0, 0);
    while i < n && j < other.len() {
        let (x, y) = (acc[i], other[j]);
        let enter = if y.enter.t > x.enter.t { y.enter } else { x.enter };
        let exit = if y.exit.t < x.exit.t { y.exit } else { x.exit };
        // Empty, inverted or NaN intervals are dropped, as by `IntervalSet`.
        if enter.t.partial_cmp(&exit.t) == Some(core::cmp::Ordering::Less) {
            match acc[n..].last_mut() {
                Some(last) if enter.t <= last.exit.t => {
                    if exit.t > last.exit.t {
                        last.exit = exit;
                    }
                }
                _ => acc.push(Interval::new(enter, exit)),
            }
        }
        if x.exit.t <= y.exit.t {
            i += 1;
        } else {
            j += 1;
        }
    }
    acc.drain(..n);
}

/// The root of `certified` nearest to `t`, as (index, bound of `t`'s
/// distance from the true root).
fn nearest_root(certified: &quadric::CertifiedIntervals, t: f64) -> Option<(usize, f64)> {
    let (k, r) = certified.roots().iter().enumerate().min_by(|a, b| (a.1.t - t).abs().total_cmp(&(b.1.t - t).abs()))?;
    Some((k, r.error + (r.t - t).abs()))
}

/// Solid `i`'s certified set with each end that the bounds cannot order
/// against an end of `acc` (ends of solids `< i`) moved to its exact place
/// relative to it (see [`Block::certified_set`]).
#[cold]
fn settle_ties(
    ray: &Ray,
    solids: &[Solid],
    i: usize,
    own: &quadric::CertifiedIntervals,
    acc: &[Interval],
) -> IntervalSet {
    let near = |a: f64, b: f64, bound: f64| (a - b).abs() <= bound;
    let mut out = [Interval::new(Bound::free(0.0), Bound::free(0.0)); IntervalSet::CAPACITY];
    let n = own.set.len();
    out[..n].copy_from_slice(own.set.as_slice());
    let mut moved = false;
    for iv in out[..n].iter_mut() {
        for end in [&mut iv.enter, &mut iv.exit] {
            let Some((k, e_own)) = end.solid().and_then(|_| nearest_root(own, end.t)) else { continue };
            for other in acc.iter().flat_map(|a| [a.enter, a.exit]) {
                let Some(j) = other.solid() else { continue };
                // Certified bounds are at most 2⁻²⁰ relative (else settled
                // exactly, one ulp): a cheap filter before the other's bound.
                if !near(end.t, other.t, e_own + 4e-6 * other.t.abs()) {
                    continue;
                }
                let Some(theirs) = solids.get(j as usize) else { continue };
                let cert = theirs.intervals_certified(ray, j);
                let Some((m, e_other)) = nearest_root(&cert, other.t) else { continue };
                if !near(end.t, other.t, e_own + e_other) {
                    continue;
                }
                let Some(t) = settled(end.t, other.t, theirs.compare_roots(m, &solids[i], k, ray)) else { continue };
                moved |= t != end.t;
                end.t = t;
            }
        }
    }
    if !moved {
        return own.set;
    }
    rebuilt(&out[..n], own.set)
}

/// The set of `intervals` (in any order; empty ones dropped, touching ones
/// merged), or `fallback` past capacity. Unlike
/// `IntervalSet::from_intervals` it does not allocate: a union per interval.
fn rebuilt(intervals: &[Interval], fallback: IntervalSet) -> IntervalSet {
    let mut acc = IntervalSet::empty();
    for iv in intervals {
        match acc.union(&IntervalSet::from_interval(iv.enter, iv.exit)) {
            Ok(set) => acc = set,
            Err(_) => return fallback,
        }
    }
    acc
}

/// [`rebuilt`] for a list of any length: the same set where it fits an
/// interval set; past that (a large block's) `intervals` sorted by entry
/// (ties in input order) and merged where they overlap or touch, the earlier
/// end kept on ties, as `IntervalSet::from_intervals` merges.
fn rebuilt_list(intervals: &[Interval], fallback: &[Interval]) -> Vec<Interval> {
    if intervals.len() <= IntervalSet::CAPACITY && fallback.len() <= IntervalSet::CAPACITY {
        let fallback = IntervalSet::from_intervals(fallback.iter().copied()).unwrap_or_default();
        return rebuilt(intervals, fallback).as_slice().to_vec();
    }
    let mut sorted: Vec<Interval> = intervals.iter().copied().filter(|iv| iv.enter.t < iv.exit.t).collect();
    sorted.sort_by(|x, y| x.enter.t.total_cmp(&y.enter.t));
    let mut out: Vec<Interval> = Vec::with_capacity(sorted.len());
    for iv in sorted {
        match out.last_mut() {
            Some(last) if iv.enter.t <= last.exit.t => {
                if iv.exit.t > last.exit.t {
                    last.exit = iv.exit;
                }
            }
            _ => out.push(iv),
        }
    }
    out
}

/// A relative distance within which two ends may be a tie their certified
/// bounds cannot order: each bound is at most 2⁻²⁰ of its root (else the
/// root was settled exactly, to an ulp), so two ends farther apart than
/// this (relative to the larger) are ordered by their doubles.
pub(crate) const NEAR_TIE: f64 = 4e-6;

/// [`Precision::Certified`] ties between the ends of *different blocks*
/// in the partition (docs/model.md §3.5), settled as [`Block::certified_set`] settles
/// those between solids: each end of a later block's set (in `sets`,
/// sorted by block id = priority) that lies within the two certified
/// bounds of an end of an earlier block is ordered against it by
/// [`Solid::compare_roots`] (exact). An exact tie takes the earlier
/// block's double, so the partition has one cut there and the priority
/// rule picks the owner (as `reference::csg::ExactPartition`); a strict
/// order the doubles got wrong is restored by one ulp. Returns whether an
/// end moved. A cold path: the caller enters it only when two ends lie
/// within [`NEAR_TIE`] of each other.
#[cold]
pub(crate) fn settle_block_ties(ray: &Ray, blocks: &[Block], sets: &mut [(crate::BlockId, Vec<Interval>)]) -> bool {
    let near = |a: f64, b: f64, bound: f64| (a - b).abs() <= bound;
    // The solid an end lies on and the index and bound of its root.
    let root_of = |block: &Block, end: &Bound| -> Option<(Solid, usize, f64)> {
        let s = end.solid()?;
        let solid = *block.solids().get(s as usize)?;
        let (k, e) = nearest_root(&solid.intervals_certified(ray, s), end.t)?;
        Some((solid, k, e))
    };
    let mut moved_any = false;
    for later in 1..sets.len() {
        let (earlier, rest) = sets.split_at_mut(later);
        let (id, set) = &mut rest[0];
        let Some(block) = blocks.get(id.index()) else { continue };
        let mut out = set.clone();
        let mut moved = false;
        for iv in out.iter_mut() {
            for end in [&mut iv.enter, &mut iv.exit] {
                // Found only when a near end is met (the root is recomputed).
                let mut own = None;
                for (other_id, other_set) in earlier.iter() {
                    let Some(other_block) = blocks.get(other_id.index()) else { continue };
                    for other in other_set.iter().flat_map(|a| [a.enter, a.exit]) {
                        if other.solid().is_none() || !near(end.t, other.t, NEAR_TIE * end.t.abs().max(other.t.abs())) {
                            continue;
                        }
                        if own.is_none() {
                            own = root_of(block, end);
                        }
                        let Some((mine, k, e_own)) = own else { continue };
                        let Some((theirs, m, e_other)) = root_of(other_block, &other) else { continue };
                        if !near(end.t, other.t, e_own + e_other) {
                            continue;
                        }
                        let Some(t) = settled(end.t, other.t, theirs.compare_roots(m, &mine, k, ray)) else {
                            continue;
                        };
                        moved |= t != end.t;
                        end.t = t;
                    }
                }
            }
        }
        if moved {
            // Moved by ulps: rebuilt (an interval closed by the move is
            // dropped, two that now touch are merged).
            *set = rebuilt_list(&out, set);
            moved_any = true;
        }
    }
    moved_any
}

/// The next double above (`up`) or below finite `x` (`f64::next_up` needs
/// a newer Rust than the MSRV).
fn adjacent(x: f64, up: bool) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    f64::from_bits(if (x > 0.0) == up { bits + 1 } else { bits - 1 })
}

/// A solid of a block, wherever it is stored.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SolidRef<'a> {
    HalfSpace(&'a HalfSpace),
    Quadric(&'a Quadric),
}

impl<'a> From<&'a Solid> for SolidRef<'a> {
    fn from(s: &'a Solid) -> Self {
        match s {
            Solid::HalfSpace(h) => SolidRef::HalfSpace(h),
            Solid::Quadric(q) => SolidRef::Quadric(q),
        }
    }
}

/// The intervals of a block of convex solids, given in block order: their
/// running intersection as one [`ConvexSpan`], narrowed by the same
/// comparisons in the same order as `IntervalSet::intersect` (on equal `t`
/// the earlier solid's end is kept), so the bounds and their solid tags
/// are those of [`Block::intervals`]' set path. `None` if a quadric gave
/// more than one interval after all, or in `Precision::Certified` (then the
/// caller takes the general path, which settles ties between solids
/// exactly).
#[inline(always)]
pub(crate) fn convex_spans<'a>(
    ray: &Ray,
    solids: impl Iterator<Item = SolidRef<'a>>,
    precision: Precision,
) -> Option<Spans> {
    if precision == Precision::Certified {
        // Ties between solids are settled exactly on the general path.
        return None;
    }
    let mut span = ConvexSpan::ALL;
    for (i, s) in solids.enumerate() {
        let non_empty = match s {
            SolidRef::HalfSpace(h) => {
                let (e, x) = h.interval_with(ray, i as u32, precision);
                span.narrow(e, x)
            }
            SolidRef::Quadric(q) => span.narrow_pieces(&q.pieces_with(ray, i as u32, precision))?,
        };
        if !non_empty {
            return Some(Spans::Empty);
        }
    }
    Some(span.spans())
}

/// The span of a convex block along a ray: the running intersection of its
/// solids' intervals, given in block order, one span narrowed solid by
/// solid. Two bounds, narrowed by the same comparisons in the same order as
/// `IntervalSet::intersect` (on equal `t` the earlier solid's end is kept).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConvexSpan {
    enter: Bound,
    exit: Bound,
}

impl ConvexSpan {
    /// The whole ray, `[0, ∞)`.
    pub(crate) const ALL: ConvexSpan = ConvexSpan { enter: Bound::free(0.0), exit: Bound::free(f64::INFINITY) };

    /// Narrows to the next solid's interval `[e, x]`; `false` once empty.
    #[inline(always)]
    pub(crate) fn narrow(&mut self, e: Bound, x: Bound) -> bool {
        if e.t > self.enter.t {
            self.enter = e;
        }
        if x.t < self.exit.t {
            self.exit = x;
        }
        // Not less (equal, greater or NaN): empty, like `IntervalSet`.
        self.enter.t.partial_cmp(&self.exit.t) == Some(core::cmp::Ordering::Less)
    }

    /// Narrows to a convex solid's pieces: `Some(false)` once empty (no
    /// piece, or an empty span), `None` if there are two pieces after all.
    #[inline(always)]
    pub(crate) fn narrow_pieces(&mut self, pieces: &Pieces) -> Option<bool> {
        match *pieces.as_slice() {
            [] => Some(false),
            [iv] => Some(self.narrow(iv.enter, iv.exit)),
            _ => None,
        }
    }

    /// The interval, non-empty as long as every [`ConvexSpan::narrow`] said so.
    #[inline(always)]
    pub(crate) fn spans(self) -> Spans {
        Spans::One(Interval::new(self.enter, self.exit))
    }
}

/// Where an end at `end` goes once it is ordered exactly against another
/// solid's end at `other` (`order`: the other root against this one): onto
/// `other` on an exact tie, one ulp to the right side of it where the doubles
/// got a strict order wrong; `None` where the doubles already agree or the
/// comparison could not be made.
fn settled(end: f64, other: f64, order: Option<core::cmp::Ordering>) -> Option<f64> {
    match order {
        Some(core::cmp::Ordering::Equal) => Some(other),
        Some(core::cmp::Ordering::Less) if end <= other => Some(adjacent(other, true)),
        Some(core::cmp::Ordering::Greater) if end >= other => Some(adjacent(other, false)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use quadric::{strategies, Precision, Solid};

    use super::*;

    proptest! {
        /// The large blocks' path (a growable buffer) and the interval
        /// sets' path form the same intersection, bit for bit and tag for
        /// tag, wherever both can: on blocks that fit a set, in every
        /// precision mode.
        #[test]
        fn the_heap_path_forms_the_sets_intersection(
            solids in proptest::collection::vec(strategies::solid(), 1..=7),
            rays in proptest::collection::vec(strategies::ray(3.0), 8),
        ) {
            let mut block = Block::new("b", solids, Opacity::Opaque, MaterialKey(0)).expect("finite");
            prop_assume!(block.fits);
            for precision in [Precision::Accurate, Precision::Fast, Precision::Certified] {
                block.set_precision(precision);
                for ray in &rays {
                    let set = block.spans_general(ray);
                    let mut heap = Vec::new();
                    block.spans_large(ray, &mut heap);
                    let mut buf = <SpanBuf as Scratch>::new();
                    buf.set_spans(set);
                    prop_assert_eq!(buf.as_slice(), &heap[..], "{:?} {:?}", precision, ray);
                }
            }
        }
    }

    /// Seven non-convex solids fit a set (at most eight intervals), eight do not.
    #[test]
    fn eight_non_convex_solids_make_a_large_block() {
        let hollow = |k: u32| {
            Solid::from(quadric::Quadric::sphere())
                .complement()
                .transformed(&quadric::Transform::scale(0.1 * f64::from(k + 1)).expect("finite"))
        };
        let solids: Vec<Solid> = (0..8).map(hollow).collect();
        let block = Block::new("b", solids[..7].to_vec(), Opacity::Opaque, MaterialKey(0)).expect("finite");
        assert!(block.fits_interval_set());
        let block = Block::new("b", solids, Opacity::Opaque, MaterialKey(0)).expect("finite");
        assert!(!block.fits_interval_set());
    }
}
