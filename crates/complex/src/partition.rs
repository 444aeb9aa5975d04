//! The partition of a ray into segments owned by blocks (docs/model.md §3.5, §3.6): its
//! types, and the priority rule that forms it from the blocks' intervals
//! along the ray ([`Complex::partition`], its segments alone, and its first
//! interface).

use core::cell::RefCell;

use quadric::nalgebra::{Point3, Vector3};
use quadric::{Interval, IntervalSet, Ray};

use crate::{BlockId, Complex, Opacity};

/// A piece `[start, end]` of the ray owned by one block, or by nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Where the segment starts (0 for the first).
    pub start: f64,
    /// Where it ends (`∞` for the last).
    pub end: f64,
    /// The owning block, `None` outside every block.
    pub owner: Option<BlockId>,
}

/// The surface an event lies on: solid `solid` of block `block`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Surface {
    /// The block whose boundary it is.
    pub block: BlockId,
    /// The index of the solid within that block.
    pub solid: u32,
}

/// A change of owner between two consecutive segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Ray parameter of the event.
    pub t: f64,
    /// The point `p + t r`.
    pub point: Point3<f64>,
    /// Owner before the event.
    pub before: Option<BlockId>,
    /// Owner after the event.
    pub after: Option<BlockId>,
    /// The surface: the entry of the new owner if it starts here, else the exit of the old.
    pub surface: Surface,
    /// Whether the ray enters `surface.block` here (else it leaves it).
    pub entering: bool,
    /// Outward unit normal of `surface.block` at the point (away from the
    /// block whose surface it is); zero where undefined (a cone's apex).
    pub normal: Vector3<f64>,
    /// Whether both sides are the same medium (two transparent blocks with
    /// the same material): no refraction happens here.
    pub same_medium: bool,
}

/// The segments of a ray, in order, with the events between them.
/// `events[i]` lies between `segments[i]` and `segments[i + 1]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Partition {
    /// Consecutive segments with different owners, covering `[0, ∞)`.
    pub segments: Vec<Segment>,
    /// The events between consecutive segments.
    pub events: Vec<Event>,
}

impl Partition {
    /// The owner at parameter `t`, if `t` lies in a segment.
    pub fn owner_at(&self, t: f64) -> Option<BlockId> {
        self.segments.iter().find(|s| s.start <= t && t <= s.end).and_then(|s| s.owner)
    }

    /// Empties both lists, keeping their allocations.
    pub fn clear(&mut self) {
        self.segments.clear();
        self.events.clear();
    }
}

/// How many bounded partitions [`Complex::first_interface`] forms, each
/// reaching one interval end further, before it forms the full one.
const BOUNDED_TRIES: usize = 3;

/// Per-thread buffers `partition_into` reuses, so that after the first ray
/// on a thread it allocates only if `out` must grow.
#[derive(Default)]
struct Scratch {
    spans: BlockSpans,
    /// The spans of [`Complex::first_interface`]'s previous try.
    previous: BlockSpans,
    cuts: Vec<f64>,
}

/// The blocks' spans along one ray, stored flat: a block's spans are a run
/// of `intervals`, so collecting a block costs a copy of its few intervals,
/// not of a whole fixed-capacity `IntervalSet` (several hundred bytes,
/// copied two or three times on the way into a vector and again by its
/// sort).
#[derive(Debug, Default)]
pub(crate) struct BlockSpans {
    /// `(block, first interval, count)`, sorted by block once collected.
    blocks: Vec<(BlockId, u32, u32)>,
    intervals: Vec<Interval>,
    /// Scratch of the owners' sweep ([`Owners`]), kept for reuse.
    sweep: Owners,
}

/// The owners of the pieces between cuts by a sweep along the ray, for
/// rays that meet many blocks (a dense lattice of transparent cells):
/// the intervals in order of entry, and the blocks holding the current
/// piece in two heaps by priority (opaque, transparent), whose tops are
/// dropped once their interval has ended. `O(n log n)` where testing every
/// block on every piece is `O(n²)`.
#[derive(Debug, Default)]
struct Owners {
    /// `(enter, exit, block, opaque)` of every interval, sorted by entry.
    entries: Vec<(f64, f64, u32, bool)>,
    /// Opaque blocks entered, the earliest on top, with their exits.
    opaque: std::collections::BinaryHeap<(core::cmp::Reverse<u32>, u64)>,
    /// Transparent blocks entered, likewise.
    transparent: std::collections::BinaryHeap<(core::cmp::Reverse<u32>, u64)>,
}

/// Above this many intervals the owners come from the sweep.
const SWEEP_FROM: usize = 16;

impl BlockSpans {
    pub(crate) fn clear(&mut self) {
        self.blocks.clear();
        self.intervals.clear();
    }

    /// Adds block `id`'s intervals that reach past `eps` (the ε rule: an
    /// interval inside `[0, ε]` is no hit), if there are any (with none,
    /// an empty entry if `keep_empty`: it records that the block was
    /// looked at).
    #[inline]
    pub(crate) fn push(&mut self, id: BlockId, intervals: &[Interval], eps: f64, keep_empty: bool) -> &[Interval] {
        let first = self.intervals.len();
        // Sorted and disjoint: the intervals ending by ε are a prefix.
        let keep = intervals.iter().position(|iv| iv.exit.t > eps).unwrap_or(intervals.len());
        self.intervals.extend_from_slice(&intervals[keep..]);
        let n = self.intervals.len() - first;
        if n > 0 || keep_empty {
            self.blocks.push((id, first as u32, n as u32));
        }
        &self.intervals[first..]
    }

    /// Priority order: by block id.
    pub(crate) fn sort(&mut self) {
        self.blocks.sort_unstable_by_key(|b| b.0);
    }

    pub(crate) fn len(&self) -> usize {
        self.blocks.len()
    }

    /// Each block's spans, in priority order.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (BlockId, &[Interval])> + '_ {
        self.blocks.iter().map(|&(id, first, n)| (id, &self.intervals[first as usize..(first + n) as usize]))
    }

    /// The one block with intervals, `Some(None)` if no block has any,
    /// `None` if several have (the one-block shortcuts of the partition).
    fn lone(&self) -> Option<Option<(BlockId, &[Interval])>> {
        let mut blocks = self.iter().filter(|(_, ivs)| !ivs.is_empty());
        let lone = blocks.next();
        blocks.next().is_none().then_some(lone)
    }

    /// Block `id`'s intervals, if it has any.
    pub(crate) fn get(&self, id: BlockId) -> Option<&[Interval]> {
        let k = self.blocks.binary_search_by_key(&id, |b| b.0).ok()?;
        let (_, first, n) = self.blocks[k];
        Some(&self.intervals[first as usize..(first + n) as usize])
    }

    /// As a vector of interval sets (the public form of
    /// [`Complex::intervals`]), or `Err` naming a block whose set is past
    /// an interval set's capacity.
    pub(crate) fn to_vec(&self) -> Result<Vec<(BlockId, IntervalSet)>, BlockId> {
        self.iter()
            .map(|(id, ivs)| Ok((id, IntervalSet::from_intervals(ivs.iter().copied()).map_err(|_| id)?)))
            .collect()
    }

    /// As lists (the Certified tie settlement's form).
    fn to_lists(&self) -> Vec<(BlockId, Vec<Interval>)> {
        self.iter().map(|(id, ivs)| (id, ivs.to_vec())).collect()
    }

    /// Replaces the spans by the lists `sets` (sorted by block).
    fn assign(&mut self, sets: &[(BlockId, Vec<Interval>)]) {
        self.clear();
        for (id, set) in sets {
            self.push(*id, set, f64::NEG_INFINITY, false);
        }
    }
}

/// Every block's intervals along one ray, as [`Complex::intervals_into`]
/// writes them: reusable, so that after the first rays it allocates
/// nothing, and for blocks of any size (a block's intervals are a slice,
/// not an [`IntervalSet`] of fixed capacity).
///
/// ```
/// use complex::{Block, BlockId, BlockIntervals, Complex, ComplexOptions, MaterialKey, Opacity};
/// use quadric::nalgebra::{Point3, Vector3};
/// use quadric::{Quadric, Ray, Solid};
/// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(0)).unwrap();
/// let scene = Complex::new(vec![ball], ComplexOptions::default()).unwrap();
/// let mut out = BlockIntervals::new();
/// for y in [0.0, 0.5, 2.0] {
///     let ray = Ray::new(Point3::new(0.0, y, -5.0), Vector3::z()).unwrap();
///     scene.intervals_into(&ray, &mut out);
///     let blocks: Vec<BlockId> = out.iter().map(|(id, _)| id).collect();
///     assert_eq!(blocks.len(), usize::from(y < 1.0));
///     if let Some(ivs) = out.get(BlockId(0)) {
///         assert_eq!(ivs.len(), 1);
///         assert!(ivs[0].enter.t > 3.9 && ivs[0].exit.t < 6.1);
///     }
/// }
/// ```
#[derive(Debug, Default)]
pub struct BlockIntervals {
    spans: BlockSpans,
}

impl BlockIntervals {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// Each block the ray meets (after the ε rule) with its intervals,
    /// sorted, in priority order.
    pub fn iter(&self) -> impl Iterator<Item = (BlockId, &[Interval])> + '_ {
        self.spans.iter()
    }

    /// Block `id`'s intervals, if the ray meets it.
    pub fn get(&self, id: BlockId) -> Option<&[Interval]> {
        self.spans.get(id)
    }

    /// How many blocks the ray meets.
    pub fn len(&self) -> usize {
        self.spans.len()
    }

    /// Whether the ray meets no block.
    pub fn is_empty(&self) -> bool {
        self.spans.len() == 0
    }

    /// Empties the list, keeping its allocations.
    pub fn clear(&mut self) {
        self.spans.clear();
    }

    pub(crate) fn spans_mut(&mut self) -> &mut BlockSpans {
        &mut self.spans
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

impl Complex {
    /// The partition of the ray into owned segments with the events between them.
    pub fn partition(&self, ray: &Ray) -> Partition {
        let mut out = Partition::default();
        self.partition_into(ray, &mut out);
        out
    }

    /// Like [`Complex::partition`], reusing `out`'s allocations (and
    /// per-thread scratch buffers): only blocks whose boxes the ray crosses
    /// are visited.
    pub fn partition_into(&self, ray: &Ray, out: &mut Partition) {
        self.partition_with(ray, f64::INFINITY, f64::INFINITY, out);
    }

    /// The segments of [`Complex::partition`] alone, into `out.segments`
    /// (`out.events` is left empty): no hit points or normals are computed.
    /// What a shadow ray needs to weigh the media between a point and a
    /// light. Allocates only as [`Complex::partition_into`] does.
    pub fn segments_into(&self, ray: &Ray, out: &mut Partition) {
        self.partition_with(ray, f64::INFINITY, f64::NEG_INFINITY, out);
    }

    /// The segments of [`Complex::partition`] that start before `max_t`,
    /// into `out.segments` (`out.events` is left empty): the same starts and
    /// owners, and the same ends except the last one's, which lies at or
    /// after `max_t` but may differ from the partition's. Only the blocks
    /// whose boxes the ray crosses before `max_t` are visited, so a shadow
    /// ray towards a light costs nothing beyond the light. Every segment that
    /// starts before `max_t` is determined by those blocks: each of its
    /// owners' intervals, and each interval end below `max_t`, reaches into
    /// `[0, max_t)`. (In [`quadric::Precision::Certified`], which settles
    /// near ties between the ends of any two blocks, every block is visited.)
    /// A NaN `max_t` reads as `∞` ([`Complex::segments_into`]); for
    /// `max_t <= 0` the list is empty.
    pub fn segments_within(&self, ray: &Ray, max_t: f64, out: &mut Partition) {
        if max_t.is_nan() || max_t == f64::INFINITY {
            return self.segments_into(ray, out);
        }
        // Certified settles near ties between the ends of different blocks,
        // a block beyond `max_t` included: it takes them all.
        let reach = if self.precision() == quadric::Precision::Certified { f64::INFINITY } else { max_t };
        self.partition_with(ray, reach, f64::NEG_INFINITY, out);
        let keep = out.segments.iter().take_while(|s| s.start < max_t).count();
        out.segments.truncate(keep);
    }

    /// The partition formed from the blocks whose boxes the ray crosses
    /// before `reach`, with its events up to `until` (see
    /// `partition_of_spans`).
    fn partition_with(&self, ray: &Ray, reach: f64, until: f64, out: &mut Partition) {
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut s) => {
                let Scratch { spans, cuts, .. } = &mut *s;
                self.partition_core(ray, reach, (spans, cuts), until, Events::All, out);
            }
            Err(_) => {
                self.partition_core(ray, reach, (&mut BlockSpans::default(), &mut Vec::new()), until, Events::All, out)
            }
        });
    }

    /// The first event of [`Complex::partition`] after ε where the medium
    /// changes (`t > ε` and not [`Event::same_medium`]): exactly
    /// `partition(ray).events.iter().find(|e| e.t > ε && !e.same_medium)`,
    /// what a renderer stops at or refracts through. The partition is first
    /// formed only from the blocks whose boxes the ray enters by the first
    /// interval end `T` after ε (the BVH walk stops there): its events up to
    /// `T` are those of the full partition, since every block with an
    /// interval reaching into `[0, T]` is among them. If none of those
    /// events qualifies, the next try reaches to the next interval end
    /// after `T`; after a few tries the full partition is formed. `out` is scratch: it
    /// is left holding a prefix of the partition's segments and, of its
    /// events, only the one returned (the hit points and normals of the
    /// events before it are not computed), or nothing (when at most
    /// one block has intervals past ε the answer is read off that block's
    /// intervals, and no partition is formed). Allocates only as
    /// [`Complex::partition_into`] does.
    pub fn first_interface(&self, ray: &Ray, out: &mut Partition) -> Option<Event> {
        let eps = self.epsilon();
        // `Events::FirstInterface` forms no event but the answer (`t > ε`,
        // not within one medium), so the answer is the first event formed.
        let found = |out: &Partition| out.events.first().copied();
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut s) => {
                let Scratch { spans, previous, cuts } = &mut *s;
                let mut after = eps;
                for attempt in 0..BOUNDED_TRIES {
                    // A retry meets the blocks of the last try again: their
                    // spans are taken from it, not computed anew. (Not in
                    // Certified, whose settlement may have moved them.)
                    let reuse = attempt > 0 && self.precision() != quadric::Precision::Certified;
                    if reuse {
                        core::mem::swap(spans, previous);
                    }
                    let until = self.collect_spans_to_first_end(ray, after, spans, reuse.then_some(&*previous));
                    if attempt == 0 && self.precision() != quadric::Precision::Certified {
                        if let Some(answer) = self.lone_interface(ray, spans) {
                            out.clear();
                            return answer;
                        }
                    }
                    self.partition_of_spans(ray, spans, cuts, until, Events::FirstInterface, out);
                    // Events are formed only up to `until`, where they are
                    // exact. With `until = ∞` nothing was cut off.
                    let e = found(out);
                    if e.is_some() || until == f64::INFINITY {
                        return e;
                    }
                    after = until;
                }
                self.partition_core(ray, f64::INFINITY, (spans, cuts), f64::INFINITY, Events::FirstInterface, out);
                found(out)
            }
            Err(_) => {
                let buffers = (&mut BlockSpans::default(), &mut Vec::new());
                self.partition_core(ray, f64::INFINITY, buffers, f64::INFINITY, Events::FirstInterface, out);
                found(out)
            }
        })
    }

    /// [`Complex::first_interface`] when at most one block has intervals
    /// past ε (most rays of a glass scene: one leaving a glass body, one
    /// seeing a single wall), read off that block's intervals without
    /// forming the partition: `Some(answer)`, or `None` where the general
    /// path must decide. With one block `B` the owners alternate between
    /// nothing and `B`, each end is a change of owner (the intervals are
    /// disjoint and never touch), and no change is within one medium; the
    /// partition's event at an end `t > 0` is `B`'s entry or exit there if
    /// the end is tagged with a solid, and none otherwise. So the answer is
    /// the first end after ε: `None` if it is infinite (the ray stays in
    /// `B`), the event formed exactly as `partition_of_spans` forms it if it
    /// is tagged, the general path if it is not.
    fn lone_interface(&self, ray: &Ray, spans: &BlockSpans) -> Option<Option<Event>> {
        let Some((block, intervals)) = spans.lone()? else { return Some(None) };
        let eps = self.epsilon();
        let (bound, entering) =
            intervals.iter().flat_map(|iv| [(iv.enter, true), (iv.exit, false)]).find(|(b, _)| b.t > eps)?;
        if !bound.t.is_finite() {
            return Some(None);
        }
        let solid = bound.solid()?;
        let point = self.hit_point(ray, bound.t, block, solid);
        let (before, after) = if entering { (None, Some(block)) } else { (Some(block), None) };
        Some(Some(Event {
            t: bound.t,
            point,
            before,
            after,
            surface: Surface { block, solid },
            entering,
            normal: self.normal(block, solid, &point),
            same_medium: false,
        }))
    }

    /// The segments of the partition formed from `spans` (collected by
    /// [`Complex::collect_spans`] with no bound: then exactly
    /// [`Complex::segments_into`]'s), for callers that also read the spans.
    pub(crate) fn segments_of_spans(
        &self,
        ray: &Ray,
        spans: &mut BlockSpans,
        cuts: &mut Vec<f64>,
        out: &mut Partition,
    ) {
        self.partition_of_spans(ray, spans, cuts, f64::NEG_INFINITY, Events::All, out);
    }

    /// [`Complex::partition_with`], with caller-provided buffers for the
    /// spans and cuts.
    fn partition_core(
        &self,
        ray: &Ray,
        reach: f64,
        (spans, cuts): (&mut BlockSpans, &mut Vec<f64>),
        until: f64,
        events: Events,
        out: &mut Partition,
    ) {
        self.collect_spans(ray, reach, spans);
        self.partition_of_spans(ray, spans, cuts, until, events, out);
    }

    /// The partition formed from `spans` (sorted by block id), its events
    /// only up to `until` (the segments up to the first one past it; all of
    /// them, and no events, for `until = -∞`), and of those only the ones
    /// `events` asks for.
    fn partition_of_spans(
        &self,
        ray: &Ray,
        spans: &mut BlockSpans,
        cuts: &mut Vec<f64>,
        until: f64,
        events: Events,
        out: &mut Partition,
    ) {
        out.clear();
        // The segments alone (a shadow ray's query), with at most one block:
        // they alternate between nothing and the block at its interval
        // ends, read off directly (the cuts below would give the same).
        if until == f64::NEG_INFINITY && lone_segments(spans, &mut out.segments) {
            return;
        }
        let gather = |spans: &BlockSpans, cuts: &mut Vec<f64>| {
            cuts.clear();
            cuts.push(0.0);
            for iv in &spans.intervals {
                cuts.extend([iv.enter.t, iv.exit.t].into_iter().filter(|t| *t > 0.0 && t.is_finite()));
            }
            cuts.sort_unstable_by(f64::total_cmp);
        };
        gather(spans, cuts);
        // Certified: ends of different blocks that their bounds cannot order
        // are ordered exactly (a cold path, only when two ends are close).
        if self.precision() == quadric::Precision::Certified
            && spans.len() > 1
            && cuts.windows(2).any(|w| w[1] - w[0] <= crate::block::NEAR_TIE * w[1].abs())
        {
            let mut moved = spans.to_lists();
            if crate::block::settle_block_ties(ray, if self.is_assembled() { &[] } else { self.blocks() }, &mut moved) {
                spans.assign(&moved);
                gather(spans, cuts);
            }
        }
        cuts.dedup();
        // Past `until` only the first cut is needed: it ends the segment
        // after an event at `until`.
        if until > f64::NEG_INFINITY {
            if let Some(k) = cuts.iter().position(|&c| c > until) {
                cuts.truncate(k + 1);
            }
        }
        cuts.push(f64::INFINITY);
        if spans.intervals.len() > SWEEP_FROM {
            self.owners_by_sweep(spans, cuts, out);
        } else {
            for w in cuts.windows(2) {
                let (a, b) = (w[0], w[1]);
                // No end lies strictly inside (a, b), so each interval covers all
                // of it or none. (A midpoint test would fail between adjacent floats.)
                let owner = owner_of(
                    spans
                        .iter()
                        .filter(|(_, s)| s.iter().any(|iv| iv.enter.t <= a && b <= iv.exit.t))
                        .map(|(id, _)| (id, self.block(id).opacity())),
                );
                push_segment(out, a, b, owner);
            }
        }
        let spans_of = |id: BlockId| spans.get(id);
        for w in out.segments.windows(2) {
            let (s0, s1) = (w[0], w[1]);
            let t = s1.start;
            if t > until {
                break;
            }
            // Prefer the entry of the new owner; else the exit of the old one.
            let entry = s1.owner.and_then(|id| {
                spans_of(id)?
                    .iter()
                    .find(|iv| iv.enter.t == t)
                    .and_then(|iv| iv.enter.solid())
                    .map(|solid| (id, solid, true))
            });
            let exit = || {
                s0.owner.and_then(|id| {
                    spans_of(id)?
                        .iter()
                        .find(|iv| iv.exit.t == t)
                        .and_then(|iv| iv.exit.solid())
                        .map(|solid| (id, solid, false))
                })
            };
            let Some((block, solid, entering)) = entry.or_else(exit) else { continue };
            let medium =
                |o: Option<BlockId>| o.map(|id| self.block(id)).filter(|b| b.is_transparent()).map(|b| b.material());
            let same_medium = medium(s0.owner).is_some() && medium(s0.owner) == medium(s1.owner);
            let interface = t > self.epsilon() && !same_medium;
            if events == Events::FirstInterface && !interface {
                continue;
            }
            // The hit point's refinement and the normal: the event's dearest part.
            let point = self.hit_point(ray, t, block, solid);
            let normal = self.normal(block, solid, &point);
            out.events.push(Event {
                t,
                point,
                before: s0.owner,
                after: s1.owner,
                surface: Surface { block, solid },
                entering,
                normal,
                same_medium,
            });
            if events == Events::FirstInterface {
                break;
            }
        }
    }
}

/// Which events [`Complex::partition_of_spans`] forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Events {
    /// Every event (up to `until`): the partition's.
    All,
    /// Only the first after ε where the medium changes, the answer of
    /// [`Complex::first_interface`] (`t > ε`, not [`Event::same_medium`]);
    /// the others' hit points and normals are not computed.
    FirstInterface,
}

/// The segments of the partition when at most one block has intervals
/// (sorted, disjoint, never touching, each ending after 0): empty space up
/// to each entry after 0, the block up to its exit, empty space after the
/// last finite exit. `false`, with `segments` untouched, for more blocks.
fn lone_segments(spans: &BlockSpans, segments: &mut Vec<Segment>) -> bool {
    let Some(lone) = spans.lone() else { return false };
    let mut cursor = 0.0;
    if let Some((id, intervals)) = lone {
        for iv in intervals {
            if iv.enter.t > cursor {
                segments.push(Segment { start: cursor, end: iv.enter.t, owner: None });
                cursor = iv.enter.t;
            }
            segments.push(Segment { start: cursor, end: iv.exit.t, owner: Some(id) });
            cursor = iv.exit.t;
        }
    }
    if cursor < f64::INFINITY {
        segments.push(Segment { start: cursor, end: f64::INFINITY, owner: None });
    }
    true
}

/// The owner among the blocks containing a point (in priority order):
/// the first opaque one, else the first transparent one.
/// Appends the piece `[a, b]` of `owner`, merged into the last segment if
/// it has the same owner.
fn push_segment(out: &mut Partition, a: f64, b: f64, owner: Option<BlockId>) {
    match out.segments.last_mut() {
        Some(last) if last.owner == owner => last.end = b,
        _ => out.segments.push(Segment { start: a, end: b, owner }),
    }
}

impl Complex {
    /// The segments between consecutive `cuts` (sorted, without repeats,
    /// ending with ∞), owned as [`owner_of`] says, by a sweep ([`Owners`]):
    /// an interval covers the piece `[a, b]` when it was entered by `a` and
    /// is left no earlier than `b`, as no end lies strictly between.
    fn owners_by_sweep(&self, spans: &mut BlockSpans, cuts: &[f64], out: &mut Partition) {
        let BlockSpans { blocks, intervals, sweep } = spans;
        sweep.entries.clear();
        for &(id, first, n) in blocks.iter() {
            let opaque = self.block(id).opacity() == Opacity::Opaque;
            for iv in &intervals[first as usize..(first + n) as usize] {
                sweep.entries.push((iv.enter.t, iv.exit.t, id.0, opaque));
            }
        }
        sweep.entries.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        sweep.opaque.clear();
        sweep.transparent.clear();
        let mut next = 0;
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            while let Some(&(enter, exit, id, opaque)) = sweep.entries.get(next) {
                if enter > a {
                    break;
                }
                let heap = if opaque { &mut sweep.opaque } else { &mut sweep.transparent };
                heap.push((core::cmp::Reverse(id), exit.to_bits()));
                next += 1;
            }
            // Pieces only move on, so an interval that ends before `b` is
            // done for good.
            for heap in [&mut sweep.opaque, &mut sweep.transparent] {
                while heap.peek().is_some_and(|&(_, exit)| f64::from_bits(exit) < b) {
                    heap.pop();
                }
            }
            let top =
                |h: &std::collections::BinaryHeap<(core::cmp::Reverse<u32>, u64)>| h.peek().map(|t| BlockId(t.0 .0));
            let owner = top(&sweep.opaque).or_else(|| top(&sweep.transparent));
            push_segment(out, a, b, owner);
        }
    }
}

fn owner_of(containing: impl Iterator<Item = (BlockId, Opacity)>) -> Option<BlockId> {
    let mut first_transparent = None;
    for (id, opacity) in containing {
        match opacity {
            Opacity::Opaque => return Some(id),
            Opacity::Transparent => {
                first_transparent.get_or_insert(id);
            }
        }
    }
    first_transparent
}
