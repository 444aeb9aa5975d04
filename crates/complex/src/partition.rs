//! The partition of a ray into segments owned by blocks (SPEC §3).

use quadric::nalgebra::{Point3, Vector3};

use crate::BlockId;

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
