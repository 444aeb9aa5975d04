//! Placed definitions: a complex whose list holds, besides blocks,
//! instances and lattices of other complexes (docs/model.md §3.10). Each
//! definition is built once in its own frame; a query moves the ray into
//! that frame and asks the definition, so memory grows with the unique
//! geometry and the number of placements, not with the expansion.
//!
//! Block ids number the expansion in list order (a lattice's elements with
//! `i` fastest, then `j`, then `k`), so an assembled complex answers every
//! query with the ids, and the priority rule, of its explicit expansion.

use std::sync::Arc;

use quadric::nalgebra::{Point3, Vector3};
use quadric::{Bound, Interval, IntervalSet, Ray, Solid, Transform};

use crate::bvh::{Bvh, RayBoxes};
use crate::point_grid::PointGrid;
use crate::{Aabb, Block, BlockId, Complex, ComplexError, ComplexOptions};

/// One entry of the list [`Complex::assemble`] takes: a block, or a placed
/// definition.
#[derive(Clone, Debug)]
pub enum Member {
    /// A block of the complex itself.
    Block(Block),
    /// An instance or a lattice of another complex.
    Placed(Placement),
}

/// A definition placed once (`count = [1, 1, 1]`) or as a lattice: element
/// `(i, j, k)` is the definition moved by `(i·pitch.x, j·pitch.y,
/// k·pitch.z)`, then by `transform`.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The definition, built once and shared by every placement.
    pub definition: Arc<Complex>,
    /// From the definition's (the lattice's) frame to the frame of the
    /// complex being assembled, applied after the lattice offset.
    pub transform: Transform,
    /// The lattice's spacing along x, y and z (ignored on an axis of count 1).
    pub pitch: Vector3<f64>,
    /// Elements along x, y and z; `[1, 1, 1]` for a single instance.
    pub count: [u32; 3],
}

impl Placement {
    /// The definition placed once by `transform`.
    pub fn instance(definition: Arc<Complex>, transform: Transform) -> Self {
        Placement { definition, transform, pitch: Vector3::zeros(), count: [1, 1, 1] }
    }
}

/// Where a block of an assembled complex comes from ([`Complex::resolve`]).
#[derive(Clone, Debug)]
pub struct Resolved<'a> {
    /// The [`ComplexOptions::key`] of the complex that holds the block in its
    /// own list (the top one, or a definition).
    pub key: u32,
    /// The block's index among that complex's own blocks (its
    /// [`Member::Block`]s, in list order).
    pub own: u32,
    /// The block, in that complex's frame.
    pub block: &'a Block,
    /// From that frame to the world's; `None`: the identity (a block of the
    /// top complex's own list).
    pub to_world: Option<Transform>,
}

/// The visitor of [`Complex::walk_spans`]: a block's id, its intervals along
/// the ray (clipped to its box, before the ε rule) and the walk's bound,
/// which it may lower.
pub(crate) type Visit<'a> = dyn FnMut(u32, &[Interval], &mut f64) + 'a;

/// One placed definition, ready for queries.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    /// The id of the first block of its first element.
    base: u32,
    /// Blocks per element (the definition's [`Complex::len`]).
    stride: u32,
    count: [u32; 3],
    pitch: Vector3<f64>,
    definition: Arc<Complex>,
    /// The definition's (lattice's) frame to this complex's frame.
    transform: Transform,
    /// Its inverse.
    inverse: Transform,
    /// `transform` is a translation only: the ray keeps its direction.
    translation_only: bool,
    /// The definition's box in its frame.
    element_box: Aabb,
    /// How many cells an element's box reaches beyond its own, per axis.
    reach: [i64; 3],
    /// The box of every element, in this complex's frame.
    world_box: Aabb,
}

/// The assembled part of a complex: its own blocks as a flat complex, and
/// the placements, found through a BVH over their boxes.
#[derive(Clone, Debug)]
pub(crate) struct Assembly {
    /// The own blocks, numbered by their place among the own blocks.
    own: Complex,
    /// The id of each own block in the expansion (ascending).
    own_ids: Vec<u32>,
    parts: Vec<Part>,
    /// Bounded parts.
    bvh: Bvh,
    /// Parts with an unbounded box.
    unbounded: Vec<u32>,
    /// Bounded parts by cell, for point queries.
    points: PointGrid,
    len: u32,
    key: u32,
}

/// How a block is moved from its definition's frame to the world.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Placing {
    Identity,
    Translate(Vector3<f64>),
    General(Transform),
}

/// The most blocks a complex numbers: ids are `u32`, and `u32::MAX` is kept
/// free.
pub(crate) const MAX_BLOCKS: u64 = u32::MAX as u64 - 1;

impl Complex {
    /// Builds a complex from blocks and placed definitions in priority
    /// (list) order. Block ids number the expansion: a block takes one, an
    /// instance as many as its definition holds, a lattice `nx·ny·nz` times
    /// that, its element `(i, j, k)` (`i` fastest) after the one before. A
    /// list of blocks only is [`Complex::new`].
    ///
    /// Errors: [`ComplexError::TooManyBlocks`] beyond `2³² − 2` blocks,
    /// [`ComplexError::BadPlacement`] for a lattice of count 0, a pitch that
    /// is not finite (or not positive on an axis with more than one
    /// element), or an unbounded definition in a lattice of more than one
    /// element; and [`Complex::new`]'s errors for the blocks.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use complex::{Block, Complex, ComplexOptions, MaterialKey, Member, Opacity, Placement};
    /// use quadric::nalgebra::{Point3, Vector3};
    /// use quadric::{Quadric, Ray, Solid, Transform};
    /// let ball = Block::new("ball", vec![Solid::from(Quadric::sphere())], Opacity::Opaque, MaterialKey(0)).unwrap();
    /// let definition = Arc::new(Complex::new(vec![ball], ComplexOptions::default()).unwrap());
    /// let row = Placement { pitch: Vector3::new(3.0, 0.0, 0.0), count: [1000, 1, 1],
    ///                       ..Placement::instance(definition, Transform::identity()) };
    /// let scene = Complex::assemble(vec![Member::Placed(row)], ComplexOptions::default()).unwrap();
    /// assert_eq!(scene.len(), 1000);
    /// let ray = Ray::new(Point3::new(2997.0, 0.0, -5.0), Vector3::z()).unwrap();
    /// let hit = scene.cast_ray(&ray, f64::INFINITY).unwrap();
    /// assert_eq!((hit.block.0, hit.t), (999, 4.0));
    /// ```
    pub fn assemble(members: Vec<Member>, options: ComplexOptions) -> Result<Self, ComplexError> {
        if members.iter().all(|m| matches!(m, Member::Block(_))) {
            let blocks = members
                .into_iter()
                .filter_map(|m| match m {
                    Member::Block(b) => Some(b),
                    Member::Placed(_) => None,
                })
                .collect();
            return Complex::new(blocks, options);
        }
        let mut own = Vec::new();
        let mut own_ids = Vec::new();
        let mut parts = Vec::new();
        let mut next: u64 = 0;
        for (index, member) in members.into_iter().enumerate() {
            match member {
                Member::Block(b) => {
                    own_ids.push(next as u32);
                    own.push(b);
                    next += 1;
                }
                Member::Placed(p) => {
                    let part = Part::new(p, next, index)?;
                    next += u64::from(part.stride) * part.elements();
                    // An empty definition takes no ids: nothing to find.
                    if part.stride > 0 {
                        parts.push(part);
                    }
                }
            }
            if next > MAX_BLOCKS {
                return Err(ComplexError::TooManyBlocks { max: MAX_BLOCKS as usize });
            }
        }
        let mut world = Aabb::EMPTY;
        let mut bounded = Vec::new();
        let mut unbounded = Vec::new();
        for (i, p) in parts.iter().enumerate() {
            if p.world_box.is_empty() {
                continue;
            } else if p.world_box.is_bounded() {
                bounded.push((i as u32, p.world_box));
                world = world.union(&p.world_box);
            } else {
                unbounded.push(i as u32);
            }
        }
        let own = Complex::new(own, ComplexOptions { epsilon: Some(0.0), ..options })?;
        let own_box = own.bounded_aabb();
        world = world.union(&own_box);
        let epsilon = match options.epsilon {
            Some(e) => e,
            None => crate::complex::default_epsilon(&world),
        };
        let any_transparent = own.has_transparent() || parts.iter().any(|p| p.definition.has_transparent());
        let large = own.is_large() || parts.iter().any(|p| p.definition.is_large());
        let assembly = Assembly {
            own,
            own_ids,
            bvh: Bvh::build(&bounded),
            points: PointGrid::new(&bounded),
            parts,
            unbounded,
            len: next as u32,
            key: options.key,
        };
        let mut complex = Complex::new(Vec::new(), ComplexOptions { epsilon: Some(epsilon), ..options })?;
        complex.set_assembly(assembly, any_transparent, large);
        if options.precision != quadric::Precision::default() {
            complex.set_precision(options.precision);
        }
        Ok(complex)
    }
}

impl Part {
    fn new(p: Placement, base: u64, index: usize) -> Result<Part, ComplexError> {
        let Placement { definition, transform, pitch, count } = p;
        let bad = |what: String| ComplexError::BadPlacement { index, what };
        if count.contains(&0) {
            return Err(bad(format!("a lattice needs at least one element per axis, got count {count:?}")));
        }
        for a in 0..3 {
            if count[a] > 1 && !(pitch[a].is_finite() && pitch[a] > 0.0) {
                return Err(bad(format!(
                    "the pitch must be finite and > 0 on an axis of several elements, got {}",
                    pitch[a]
                )));
            }
        }
        if !transform.is_finite() {
            return Err(bad("the transform is not finite".into()));
        }
        let stride = definition.len() as u64;
        let elements = count.iter().map(|&n| u64::from(n)).product::<u64>();
        if base + stride.saturating_mul(elements) > MAX_BLOCKS || stride > MAX_BLOCKS {
            return Err(ComplexError::TooManyBlocks { max: MAX_BLOCKS as usize });
        }
        let element_box = definition.aabb();
        if elements > 1 && !element_box.is_empty() && !element_box.is_bounded() {
            return Err(bad("a lattice's definition must be bounded".into()));
        }
        let pitch = Vector3::from_fn(|a, _| if count[a] > 1 { pitch[a] } else { 0.0 });
        let mut reach = [0i64; 3];
        let mut lattice_box = element_box;
        if !element_box.is_empty() {
            for a in 0..3 {
                if count[a] > 1 {
                    let width = (element_box.max[a] - element_box.min[a]) / pitch[a];
                    reach[a] = width.ceil() as i64;
                    lattice_box.max[a] += f64::from(count[a] - 1) * pitch[a];
                }
            }
        }
        let linear = transform.linear();
        let translation_only = *linear == quadric::nalgebra::Matrix3::identity();
        Ok(Part {
            base: base as u32,
            stride: stride as u32,
            count,
            pitch,
            world_box: transformed_box(&lattice_box, &transform),
            inverse: transform.inverse(),
            definition,
            transform,
            translation_only,
            element_box,
            reach,
        })
    }

    fn elements(&self) -> u64 {
        self.count.iter().map(|&n| u64::from(n)).product()
    }

    /// The element's offset in the lattice frame.
    fn offset(&self, [i, j, k]: [u32; 3]) -> Vector3<f64> {
        Vector3::new(f64::from(i) * self.pitch.x, f64::from(j) * self.pitch.y, f64::from(k) * self.pitch.z)
    }

    /// The lattice index of element number `e`.
    fn index(&self, e: u32) -> [u32; 3] {
        let [nx, ny, _] = self.count;
        [e % nx, (e / nx) % ny, e / (nx * ny)]
    }

    /// The element's number from its lattice index.
    fn number(&self, [i, j, k]: [u32; 3]) -> u32 {
        let [nx, ny, _] = self.count;
        (k * ny + j) * nx + i
    }

    /// The ray in the lattice frame and the factor from world to local `t`
    /// (`t_local = s · t_world`); `None` if it is not a ray there.
    fn local_ray(&self, ray: &Ray) -> Option<(Ray, f64)> {
        if self.translation_only {
            let o = ray.origin() - self.transform.translation();
            return Ray::new_unit(o, ray.direction()).ok().map(|r| (r, 1.0));
        }
        let o = self.inverse.apply_point(&ray.origin());
        let d = self.inverse.apply_vector(&ray.direction());
        let s = d.norm();
        (s.is_finite() && s > 0.0).then_some(())?;
        Ray::new(o, d).ok().map(|r| (r, s))
    }

    /// The transform from element `e`'s definition frame to this complex's.
    fn element_transform(&self, e: u32) -> Transform {
        let offset = self.offset(self.index(e));
        if offset == Vector3::zeros() {
            return self.transform;
        }
        match Transform::translate(offset) {
            Ok(t) => t.then(&self.transform),
            Err(_) => self.transform,
        }
    }

    /// Visits the blocks of every element whose box the lattice-frame ray
    /// `local` crosses within `[from, *t_max]` (local `t`), element by
    /// element along the cells of the lattice.
    fn walk_elements(&self, local: &Ray, from: f64, t_max: &mut f64, visit: &mut dyn FnMut(u32, &Ray, &mut f64)) {
        let b = &self.element_box;
        if b.is_empty() {
            return;
        }
        if self.count == [1, 1, 1] {
            return visit(0, local, t_max);
        }
        let o = local.origin();
        let d = local.direction();
        let rb = RayBoxes::new(local);
        let lattice_max = b.max + self.offset([self.count[0] - 1, self.count[1] - 1, self.count[2] - 1]);
        let Some(t0) = rb.enter(&b.min.coords.into(), &lattice_max.coords.into(), from, *t_max) else { return };
        let (_, t1) = rb.range(&b.min.coords.into(), &lattice_max.coords.into());
        // The part of the ray a cell's candidates are taken from is grown
        // by far more than the rounding of the slab tests, so every
        // element whose (padded) box the ray enters in the cell is one.
        let grown = |t: f64| 1e-9 * (1.0 + t.abs());
        let (first, end) = (t0 - grown(t0), t1 + grown(t1));
        // Cells of one pitch from the element box's corner; element `i`
        // reaches cells `i ..= i + reach`. An axis of one element is one cell.
        let last = [0, 1, 2].map(|a| i64::from(self.count[a]) - 1 + self.reach[a]);
        let x = o + d * t0.max(from);
        let mut cell = [0i64; 3];
        let mut next = [f64::INFINITY; 3];
        let mut delta = [f64::INFINITY; 3];
        for a in 0..3 {
            if self.count[a] == 1 {
                continue;
            }
            let u = (x[a] - b.min[a]) / self.pitch[a];
            cell[a] = (u.floor() as i64).clamp(0, last[a]);
            if d[a] != 0.0 {
                let face = b.min[a] + (cell[a] + i64::from(d[a] > 0.0)) as f64 * self.pitch[a];
                next[a] = (face - o[a]) / d[a];
                delta[a] = self.pitch[a] / d[a].abs();
            }
        }
        let mut cell_start = f64::NEG_INFINITY;
        // The previous cell's candidates: along a line, each axis's range
        // slides one way, so the cells where an element is a candidate are
        // consecutive, and it is visited in the first of them.
        #[allow(clippy::reversed_empty_ranges)]
        let mut previous = [1..=0, 1..=0, 1..=0];
        loop {
            let axis = (0..3).min_by(|&p, &q| next[p].total_cmp(&next[q])).unwrap_or(0);
            let step = if d[axis] > 0.0 { 1 } else { -1 };
            // The last cell: the next one is out of the grid, or beyond the
            // lattice's box.
            let leaves =
                next[axis] >= end || next[axis] == f64::INFINITY || !(0..=last[axis]).contains(&(cell[axis] + step));
            let cell_end = if leaves { f64::INFINITY } else { next[axis] };
            // The elements whose boxes meet the ray's stretch in this cell
            // (grown for rounding), from its coordinates at both ends.
            let (t_s, t_e) = (cell_start.max(first), cell_end.min(end).min(*t_max));
            let (t_s, t_e) = (t_s - grown(t_s), t_e + grown(t_e));
            let range = |a: usize| {
                if self.count[a] == 1 {
                    return 0..=0;
                }
                let u = |t: f64| if d[a] == 0.0 { o[a] } else { o[a] + t * d[a] };
                let (x0, x1) = (u(t_s), u(t_e));
                // Element `i` meets `[x_lo, x_hi]` iff `x_lo - max ≤ i·p ≤ x_hi - min`.
                let slack = 1e-6;
                let lo = (x0.min(x1) - b.max[a]) / self.pitch[a] - slack;
                let hi = (x0.max(x1) - b.min[a]) / self.pitch[a] + slack;
                let (lo, hi) = ((lo.ceil() as i64).max(0), (hi.floor() as i64).min(i64::from(self.count[a]) - 1));
                lo..=hi
            };
            let ranges = [range(0), range(1), range(2)];
            for k in ranges[2].clone() {
                for j in ranges[1].clone() {
                    let seen_jk = previous[2].contains(&k) && previous[1].contains(&j);
                    for i in ranges[0].clone() {
                        if seen_jk && previous[0].contains(&i) {
                            continue;
                        }
                        let index = [i as u32, j as u32, k as u32];
                        let offset = self.offset(index);
                        let (lo, hi) = ((b.min + offset).coords.into(), (b.max + offset).coords.into());
                        if rb.enter(&lo, &hi, from, *t_max).is_none() {
                            continue;
                        }
                        let Ok(element) = Ray::new_unit(o - offset, d) else { continue };
                        visit(self.number(index), &element, t_max);
                    }
                }
            }
            previous = ranges;
            if leaves || cell_end > *t_max {
                return;
            }
            cell_start = cell_end;
            cell[axis] += step;
            next[axis] += delta[axis];
        }
    }

    /// Visits the blocks of this part that the (this complex's frame) ray
    /// crosses within `[from, *t_max]`, with their ids and `t` in this
    /// complex's frame.
    fn walk(&self, ray: &Ray, from: f64, t_max: &mut f64, visit: &mut Visit) {
        let Some((local, s)) = self.local_ray(ray) else { return };
        // Local bounds are grown by a few ulps: `t · s` rounded must not
        // cut off a box entered at the bound itself.
        let grow = if s == 1.0 { 1.0 } else { 1.0 + 4.0 * f64::EPSILON };
        let mut buf = Scaled::default();
        let (base, stride) = (self.base, self.stride);
        let mut world_max = *t_max;
        let mut local_max = *t_max * s * grow;
        {
            let mut element = |e: u32, ray: &Ray, local_max: &mut f64| {
                let first = base + e * stride;
                self.definition.walk_spans(ray, from * s, local_max, &mut |i, spans, local_max| {
                    visit(first + i, buf.scaled(spans, s), &mut world_max);
                    let bound = world_max * s * grow;
                    if bound < *local_max {
                        *local_max = bound;
                    }
                });
            };
            self.walk_elements(&local, from * s, &mut local_max, &mut element);
        }
        *t_max = world_max;
    }
}

/// The intervals of one block with `t` divided by a factor, in a buffer
/// that grows once (only placements that scale or rotate need it).
struct Scaled {
    stack: [Interval; IntervalSet::CAPACITY],
    heap: Vec<Interval>,
}

impl Default for Scaled {
    fn default() -> Self {
        Scaled { stack: [Interval::new(Bound::free(0.0), Bound::free(0.0)); IntervalSet::CAPACITY], heap: Vec::new() }
    }
}

impl Scaled {
    fn scaled<'a>(&'a mut self, spans: &'a [Interval], s: f64) -> &'a [Interval] {
        if s == 1.0 {
            return spans;
        }
        let scale = |iv: &Interval| {
            let mut iv = *iv;
            iv.enter.t /= s;
            iv.exit.t /= s;
            iv
        };
        if spans.len() <= self.stack.len() {
            for (out, iv) in self.stack.iter_mut().zip(spans) {
                *out = scale(iv);
            }
            return &self.stack[..spans.len()];
        }
        self.heap.clear();
        self.heap.extend(spans.iter().map(scale));
        &self.heap
    }
}

/// A conservative box of `b` moved by `m`: the box of its eight corners,
/// grown by a few ulps of their size for the rounding of the transform.
fn transformed_box(b: &Aabb, m: &Transform) -> Aabb {
    if b.is_empty() {
        return Aabb::EMPTY;
    }
    if !b.is_bounded() {
        // An unbounded box stays unbounded on every axis the transform mixes it into.
        if *m.linear() == quadric::nalgebra::Matrix3::identity() {
            let t = m.translation();
            return Aabb { min: b.min + t, max: b.max + t };
        }
        return Aabb {
            min: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
            max: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        };
    }
    let mut out = Aabb::EMPTY;
    for c in 0..8 {
        let p = Point3::new(
            if c & 1 == 0 { b.min.x } else { b.max.x },
            if c & 2 == 0 { b.min.y } else { b.max.y },
            if c & 4 == 0 { b.min.z } else { b.max.z },
        );
        let q = m.apply_point(&p);
        out = out.union(&Aabb { min: q, max: q });
    }
    let pad = 1e-12 * (out.max - out.min).amax().max(out.max.coords.amax()).max(out.min.coords.amin().abs());
    Aabb { min: out.min - Vector3::repeat(pad), max: out.max + Vector3::repeat(pad) }
}

impl Assembly {
    /// Visits every block whose box the ray crosses within `[from, *t_max]`.
    pub(crate) fn walk(&self, ray: &Ray, from: f64, t_max: &mut f64, visit: &mut Visit) {
        if !self.own_ids.is_empty() {
            let own_ids = &self.own_ids;
            self.own.walk_spans(ray, from, t_max, &mut |i, spans, t_max| visit(own_ids[i as usize], spans, t_max));
        }
        if let [part] = &self.parts[..] {
            // One placement (a lattice, say): its walk tests its own box.
            return part.walk(ray, from, t_max, visit);
        }
        let rb = RayBoxes::new(ray);
        for &p in &self.unbounded {
            let b = &self.parts[p as usize].world_box;
            if rb.enter(&b.min.coords.into(), &b.max.coords.into(), from, *t_max).is_some() {
                self.parts[p as usize].walk(ray, from, t_max, visit);
            }
        }
        let items = self.bvh.items();
        self.bvh.traverse(&rb, from, t_max, |k, _, t_max| {
            self.parts[items[k as usize] as usize].walk(ray, from, t_max, visit)
        });
    }

    pub(crate) fn len(&self) -> usize {
        self.len as usize
    }

    pub(crate) fn own(&self) -> &Complex {
        &self.own
    }

    /// The part holding id `id`, if it is not an own block.
    fn part_of(&self, id: u32) -> Result<&Part, u32> {
        if let Ok(k) = self.own_ids.binary_search(&id) {
            return Err(k as u32);
        }
        let k = self.parts.partition_point(|p| p.base <= id);
        Ok(&self.parts[k - 1])
    }

    /// The block `id` of the expansion, in its definition's frame.
    pub(crate) fn block(&self, id: u32) -> &Block {
        match self.part_of(id) {
            Err(own) => &self.own.blocks()[own as usize],
            Ok(p) => p.definition.block(BlockId((id - p.base) % p.stride)),
        }
    }

    /// [`Complex::resolve`] of an assembly.
    pub(crate) fn resolve(&self, id: u32) -> Resolved<'_> {
        match self.part_of(id) {
            Err(own) => Resolved { key: self.key, own, block: &self.own.blocks()[own as usize], to_world: None },
            Ok(p) => {
                let rel = id - p.base;
                let inner = p.definition.resolve(BlockId(rel % p.stride));
                let outer = p.element_transform(rel / p.stride);
                let to_world = match inner.to_world {
                    Some(t) => t.then(&outer),
                    None => outer,
                };
                Resolved { to_world: Some(to_world), ..inner }
            }
        }
    }

    /// Calls `f` with every block containing `p` (in no particular order).
    pub(crate) fn for_each_containing(&self, p: &Point3<f64>, f: &mut dyn FnMut(u32, &Block)) {
        let own_ids = &self.own_ids;
        self.own.for_each_containing(p, &mut |i, block| f(own_ids[i as usize], block));
        let mut part = |k: u32| {
            let part = &self.parts[k as usize];
            if !part.world_box.contains_point(p) {
                return;
            }
            let q = if part.translation_only { p - part.transform.translation() } else { part.inverse.apply_point(p) };
            let b = &part.element_box;
            let mut range = [0u32..=0, 0..=0, 0..=0];
            for a in 0..3 {
                if part.count[a] > 1 {
                    let u_lo = ((q[a] - b.max[a]) / part.pitch[a]).floor() - 1.0;
                    let u_hi = ((q[a] - b.min[a]) / part.pitch[a]).floor() + 1.0;
                    let n = f64::from(part.count[a] - 1);
                    if u_hi < 0.0 || u_lo > n {
                        return;
                    }
                    range[a] = (u_lo.max(0.0) as u32)..=(u_hi.min(n) as u32);
                }
            }
            let [ri, rj, rk] = range;
            for k in rk {
                for j in rj.clone() {
                    for i in ri.clone() {
                        let index = [i, j, k];
                        let local = q - part.offset(index);
                        if !b.contains_point(&local) {
                            continue;
                        }
                        let first = part.base + part.number(index) * part.stride;
                        part.definition.for_each_containing(&local, &mut |id, block| f(first + id, block));
                    }
                }
            }
        };
        for &k in self.points.cell_blocks(p).iter().chain(self.points.wide_blocks()).chain(&self.unbounded) {
            part(k);
        }
    }

    /// The solid `solid` of block `id`, placed in the world; `None` if
    /// either index is out of range.
    pub(crate) fn world_solid(&self, id: u32, solid: u32) -> Option<Solid> {
        let (block, placing) = self.placing(id);
        let s = block.solids().get(solid as usize)?;
        Some(match placing {
            Placing::Identity => *s,
            Placing::Translate(v) => s.translated(&v),
            Placing::General(m) => s.transformed(&m),
        })
    }

    /// Block `id` and how it is placed: [`Assembly::resolve`]'s transform,
    /// kept a translation (summed level by level) while every level is one.
    pub(crate) fn placing(&self, id: u32) -> (&Block, Placing) {
        match self.part_of(id) {
            Err(own) => (&self.own.blocks()[own as usize], Placing::Identity),
            Ok(p) => {
                let rel = id - p.base;
                let (block, inner) = p.definition.placing(rel % p.stride);
                let e = rel / p.stride;
                let outer = match (inner, p.translation_only) {
                    (Placing::Identity, true) => Placing::Translate(p.offset(p.index(e)) + p.transform.translation()),
                    (Placing::Translate(v), true) => {
                        Placing::Translate(v + p.offset(p.index(e)) + p.transform.translation())
                    }
                    (Placing::Identity, false) => Placing::General(p.element_transform(e)),
                    (Placing::Translate(v), false) => match Transform::translate(v) {
                        Ok(t) => Placing::General(t.then(&p.element_transform(e))),
                        Err(_) => Placing::General(p.element_transform(e)),
                    },
                    (Placing::General(m), _) => Placing::General(m.then(&p.element_transform(e))),
                };
                (block, outer)
            }
        }
    }

    /// The box of block `id` in the world.
    pub(crate) fn block_aabb(&self, id: u32) -> Aabb {
        match self.part_of(id) {
            Err(own) => self.own.block_aabb(BlockId(own)),
            Ok(p) => {
                let rel = id - p.base;
                let inner = p.definition.block_aabb(BlockId(rel % p.stride));
                transformed_box(&inner, &p.element_transform(rel / p.stride))
            }
        }
    }

    /// The box of the whole assembly.
    pub(crate) fn aabb(&self) -> Aabb {
        self.parts.iter().fold(self.own.aabb(), |a, p| a.union(&p.world_box))
    }

    /// The intervals of block `id` along the ray as every query sees them
    /// (clipped to its box in its definition's frame), into `out`.
    pub(crate) fn block_spans_into(&self, id: u32, ray: &Ray, out: &mut Vec<Interval>) {
        out.clear();
        match self.part_of(id) {
            Err(own) => self.own.block_intervals_into(BlockId(own), ray, out),
            Ok(p) => {
                let rel = id - p.base;
                let Some((local, s)) = p.local_ray(ray) else { return };
                let offset = p.offset(p.index(rel / p.stride));
                let Ok(element) = Ray::new_unit(local.origin() - offset, local.direction()) else { return };
                p.definition.block_spans_into(rel % p.stride, &element, out);
                for iv in out.iter_mut() {
                    iv.enter.t /= s;
                    iv.exit.t /= s;
                }
            }
        }
    }

    /// Sets the precision of the own blocks and of every definition (each
    /// shared definition is copied once, so sharing survives).
    pub(crate) fn set_precision(&mut self, precision: quadric::Precision) {
        self.own.set_precision(precision);
        let mut done: Vec<(*const Complex, Arc<Complex>)> = Vec::new();
        for part in &mut self.parts {
            let key = Arc::as_ptr(&part.definition);
            if let Some((_, new)) = done.iter().find(|(k, _)| *k == key) {
                part.definition = new.clone();
                continue;
            }
            if part.definition.precision() != precision {
                let mut copy = (*part.definition).clone();
                copy.set_precision(precision);
                part.definition = Arc::new(copy);
            }
            done.push((key, part.definition.clone()));
        }
    }
}
