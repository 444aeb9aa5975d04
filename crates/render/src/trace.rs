//! One ray through the scene, reported in full (like BRL-CAD's `nirt`):
//! every block's interval set, the partition and the first hit.

use std::fmt;

use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;
use serde::Serialize;

use crate::error::Error;
use crate::world::World;

/// A block's interval set along the ray.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlockReport {
    /// 1-based block index (priority order).
    pub index: u32,
    /// The block's name.
    pub name: String,
    /// `[enter, exit]` pairs, `None` (JSON `null`) for an unbounded end.
    pub intervals: Vec<[Option<f64>; 2]>,
}

/// One segment of the partition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SegmentReport {
    /// Start parameter.
    pub start: f64,
    /// End parameter, `None` for `∞`.
    pub end: Option<f64>,
    /// 1-based owner block, `None` for empty space.
    pub block: Option<u32>,
    /// The owner's name.
    pub name: Option<String>,
}

impl SegmentReport {
    /// The report of one of `complex`'s segments.
    pub fn new(complex: &complex::Complex, s: &complex::Segment) -> Self {
        SegmentReport {
            start: s.start,
            end: finite(s.end),
            block: s.owner.map(|id| id.0 + 1),
            name: s.owner.map(|id| complex.block(id).name().to_string()),
        }
    }
}

/// The first hit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HitReport {
    /// Distance along the (unit) ray.
    pub t: f64,
    /// The hit point.
    pub point: [f64; 3],
    /// Outward unit normal of the hit block's surface.
    pub normal: [f64; 3],
    /// 1-based block index.
    pub block: u32,
    /// 1-based solid index within the block.
    pub object: u32,
}

/// Everything `komplex trace` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TraceReport {
    /// Every block's interval set (raw, `λ >= 0`, before the ε rule); in a
    /// scene with instances of more than [`MAX_BLOCKS_LISTED`] blocks, only
    /// those of the blocks the ray meets, after the ε rule.
    pub blocks: Vec<BlockReport>,
    /// The partition of the ray under the priority rule.
    pub segments: Vec<SegmentReport>,
    /// The first event after ε, if any.
    pub hit: Option<HitReport>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// The most blocks of a scene with instances whose intervals `trace` lists
/// one by one, met by the ray or not; beyond, it lists those the ray meets.
pub const MAX_BLOCKS_LISTED: usize = 1 << 16;

/// Traces one ray from `origin` along `direction` (normalised).
pub fn trace(world: &World, origin: [f64; 3], direction: [f64; 3]) -> Result<TraceReport, Error> {
    let ray = Ray::new(Point3::from(Vector3::from(origin)), Vector3::from(direction))
        .map_err(|e| Error::Options(format!("--origin/--direction: {e}")))?;
    let complex = &world.complex;
    let mut set = Vec::new();
    let report = |i: u32, set: &[quadric::Interval]| BlockReport {
        index: i + 1,
        name: complex.block(complex::BlockId(i)).name().to_string(),
        intervals: set.iter().map(|iv| [finite(iv.enter.t), finite(iv.exit.t)]).collect(),
    };
    let blocks = if complex.len() <= MAX_BLOCKS_LISTED || !world.is_instanced() {
        (0..complex.len() as u32)
            .map(|i| {
                complex.block_intervals_into(complex::BlockId(i), &ray, &mut set);
                report(i, &set)
            })
            .collect()
    } else {
        // Too many to list: the blocks the ray meets, after the ε rule.
        let mut met = complex::BlockIntervals::new();
        complex.intervals_into(&ray, &mut met);
        met.iter().map(|(id, set)| report(id.0, set)).collect()
    };
    let partition = complex.partition(&ray);
    let segments = partition.segments.iter().map(|s| SegmentReport::new(complex, s)).collect();
    let hit = complex.cast_ray(&ray, f64::INFINITY).map(|h| HitReport {
        t: h.t,
        point: [h.point.x, h.point.y, h.point.z],
        normal: [h.normal.x, h.normal.y, h.normal.z],
        block: h.block.0 + 1,
        object: h.solid + 1,
    });
    Ok(TraceReport { blocks, segments, hit })
}

fn end(x: Option<f64>, inf: &str) -> String {
    x.map_or_else(|| inf.to_string(), |v| format!("{v:?}"))
}

impl fmt::Display for TraceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "blocks:")?;
        for b in &self.blocks {
            let ivs: Vec<String> =
                b.intervals.iter().map(|[a, z]| format!("[{}, {}]", end(*a, "-inf"), end(*z, "+inf"))).collect();
            let set = if ivs.is_empty() { "(empty)".to_string() } else { ivs.join(" ∪ ") };
            writeln!(f, "  {:>3} {:<20} {}", b.index, b.name, set)?;
        }
        writeln!(f, "segments:")?;
        for s in &self.segments {
            let owner = match (&s.block, &s.name) {
                (Some(i), Some(n)) => format!("block {i} \"{n}\""),
                _ => "(nothing)".to_string(),
            };
            writeln!(f, "  [{:?}, {}] {}", s.start, end(s.end, "+inf"), owner)?;
        }
        match &self.hit {
            None => writeln!(f, "hit: none"),
            Some(h) => writeln!(
                f,
                "hit: t = {:?}\n  point  = ({:?}, {:?}, {:?})\n  normal = ({:?}, {:?}, {:?})\n  block {}, object {}",
                h.t, h.point[0], h.point[1], h.point[2], h.normal[0], h.normal[1], h.normal[2], h.block, h.object
            ),
        }
    }
}
