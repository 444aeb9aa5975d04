//! The complex: blocks in priority order and the queries on them.

use quadric::nalgebra::{Point3, Vector3};
use quadric::{IntervalSet, Ray};

use crate::partition::{Event, Partition, Segment, Surface};
use crate::{Aabb, Block, BlockId, ComplexError, Opacity};

/// Options for building a [`Complex`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ComplexOptions {
    /// Intervals contained in `[0, ε]` are no hit. `None`: `1e-9` times the
    /// size of the bounded part of the scene (at least `1e-9`).
    pub epsilon: Option<f64>,
}

/// The first surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f64,
    /// The hit point.
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
#[derive(Clone, Debug)]
pub struct Complex {
    blocks: Vec<Block>,
    boxes: Vec<Aabb>,
    epsilon: f64,
    any_transparent: bool,
}

impl Complex {
    /// Builds the query structure. Blocks keep their order: earlier blocks
    /// have priority (SPEC §3).
    pub fn new(blocks: Vec<Block>, options: ComplexOptions) -> Result<Self, ComplexError> {
        if blocks.len() >= u32::MAX as usize {
            return Err(ComplexError::TooManyBlocks { max: u32::MAX as usize - 1 });
        }
        let boxes: Vec<Aabb> = blocks.iter().map(|_| Aabb::INFINITE).collect();
        let epsilon = match options.epsilon {
            Some(e) if !(e.is_finite() && e >= 0.0) => return Err(ComplexError::BadEpsilon(e)),
            Some(e) => e,
            None => 1e-9,
        };
        let any_transparent = blocks.iter().any(Block::is_transparent);
        Ok(Complex { blocks, boxes, epsilon, any_transparent })
    }

    /// The blocks in priority order.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// The block with this id.
    pub fn block(&self, id: BlockId) -> &Block {
        &self.blocks[id.index()]
    }

    /// The fault-tolerance ε in use.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// Whether any block is transparent.
    pub fn has_transparent(&self) -> bool {
        self.any_transparent
    }

    /// The box of one block (infinite where unbounded).
    pub fn block_aabb(&self, id: BlockId) -> Aabb {
        self.boxes[id.index()]
    }

    /// The box of the whole complex.
    pub fn aabb(&self) -> Aabb {
        self.boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b))
    }

    /// The interval set of one block along the ray, without the ε rule.
    pub fn block_intervals(&self, id: BlockId, ray: &Ray) -> IntervalSet {
        self.blocks[id.index()].intervals(ray)
    }

    /// The interval set of each block the ray meets, with intervals inside
    /// `[0, ε]` removed, in priority order.
    pub fn intervals(&self, ray: &Ray) -> Vec<(BlockId, IntervalSet)> {
        (0..self.blocks.len())
            .filter_map(|i| {
                let id = BlockId(i as u32);
                let set = self.without_epsilon(self.block_intervals(id, ray));
                (!set.is_empty()).then_some((id, set))
            })
            .collect()
    }

    /// The ε rule (SPEC §3): an interval contained in `[0, ε]` is no hit.
    fn without_epsilon(&self, mut set: IntervalSet) -> IntervalSet {
        let eps = self.epsilon;
        set.retain(|iv| iv.exit.t > eps);
        set
    }

    /// The block that owns `p` under the priority rule, if any.
    pub fn contains_point(&self, p: &Point3<f64>) -> Option<BlockId> {
        owner_of(
            self.blocks
                .iter()
                .enumerate()
                .filter(|(_, b)| b.contains_point(p))
                .map(|(i, b)| (BlockId(i as u32), b.opacity())),
        )
    }

    /// The first event along the ray with `ε < t <= max_t`: the first change
    /// of owner. Events within `ε` of the origin are skipped, so a ray leaving
    /// a surface does not hit it again.
    pub fn cast_ray(&self, ray: &Ray, max_t: f64) -> Option<Hit> {
        let p = self.partition(ray);
        p.events.iter().find(|e| e.t > self.epsilon).filter(|e| e.t <= max_t).map(|e| Hit {
            t: e.t,
            point: e.point,
            normal: e.normal,
            entering: e.entering,
            block: e.surface.block,
            solid: e.surface.solid,
        })
    }

    /// The partition of the ray into owned segments with the events between them.
    pub fn partition(&self, ray: &Ray) -> Partition {
        let mut out = Partition::default();
        self.partition_into(ray, &mut out);
        out
    }

    /// Like [`Complex::partition`], reusing `out`'s allocations.
    pub fn partition_into(&self, ray: &Ray, out: &mut Partition) {
        out.clear();
        let sets = self.intervals(ray);
        let mut cuts: Vec<f64> = vec![0.0];
        for (_, s) in &sets {
            for iv in s.iter() {
                cuts.extend([iv.enter.t, iv.exit.t].into_iter().filter(|t| *t > 0.0 && t.is_finite()));
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        cuts.push(f64::INFINITY);
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let mid = if b.is_finite() { 0.5 * (a + b) } else { a + 1.0 };
            let owner = owner_of(
                sets.iter().filter(|(_, s)| s.contains(mid)).map(|(id, _)| (*id, self.blocks[id.index()].opacity())),
            );
            match out.segments.last_mut() {
                Some(last) if last.owner == owner => last.end = b,
                _ => out.segments.push(Segment { start: a, end: b, owner }),
            }
        }
        for w in out.segments.windows(2) {
            let (s0, s1) = (w[0], w[1]);
            let t = s1.start;
            let set_of = |id: BlockId| sets.iter().find(|(i, _)| *i == id).map(|(_, s)| *s);
            // Prefer the entry of the new owner; else the exit of the old one.
            let entry = s1.owner.and_then(|id| {
                set_of(id)?
                    .iter()
                    .find(|iv| iv.enter.t == t)
                    .and_then(|iv| iv.enter.solid())
                    .map(|solid| (id, solid, true))
            });
            let exit = || {
                s0.owner.and_then(|id| {
                    set_of(id)?
                        .iter()
                        .find(|iv| iv.exit.t == t)
                        .and_then(|iv| iv.exit.solid())
                        .map(|solid| (id, solid, false))
                })
            };
            let Some((block, solid, entering)) = entry.or_else(exit) else { continue };
            let point = ray.at(t);
            let normal =
                self.blocks[block.index()].solids()[solid as usize].normal(&point).unwrap_or_else(Vector3::zeros);
            let medium = |o: Option<BlockId>| {
                o.map(|id| &self.blocks[id.index()]).filter(|b| b.is_transparent()).map(|b| b.material())
            };
            let same_medium = match (s0.owner, s1.owner) {
                (Some(_), Some(_)) => medium(s0.owner).is_some() && medium(s0.owner) == medium(s1.owner),
                _ => false,
            };
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
        }
    }
}

/// The owner among the blocks containing a point (in priority order):
/// the first opaque one, else the first transparent one.
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
