//! # complex — unions of blocks of quadric solids
//!
//! A *complex* is `Block_1 ∪ … ∪ Block_n`, a *block* an intersection of
//! solids from the [`quadric`] crate. This crate answers, for any ray, the
//! first hit with its surface ([`Complex::cast_ray`]), the partition of the
//! ray into segments owned by blocks under the priority rule
//! ([`Complex::partition`]) and point membership ([`Complex::contains_point`]),
//! one at a time or in parallel batches ([`Complex::classify`],
//! [`Complex::cast_many`], [`Complex::trace_many`]), and volumes and
//! overlaps measured by chord lengths ([`Complex::volumes`],
//! [`Complex::overlaps`]).
//! Each block gets a tight, conservative box; a BVH over the bounded blocks
//! keeps queries fast for large scenes. See `docs/complex.md`.
#![deny(missing_docs)]

mod assembly;
mod batch;
mod block;
mod bounds;
mod bvh;
mod complex;
mod error;
mod kernel;
mod partition;
mod point_grid;
pub mod shapes;
mod spawn;
mod volume;

pub use assembly::{Member, Placement, Resolved};
pub use batch::Traces;
pub use block::{Block, BlockId, MaterialKey, Opacity};
pub use bounds::Aabb;
pub use complex::{Complex, ComplexOptions, Hit, Occluder, DEFAULT_RELATIVE_EPSILON};
pub use error::ComplexError;
pub use partition::{BlockIntervals, Event, Partition, Segment, Surface};
/// The kernel's precision modes: `quadric`'s type, re-exported (one type, documented there).
#[doc(no_inline)]
pub use quadric::Precision;
pub use shapes::ShapeError;
pub use spawn::{spawn_origin, Spawner, MARGIN as SPAWN_MARGIN};
pub use volume::{
    BlockVolume, Estimate, GroupVolumes, Overlap, Overlaps, VolumeOptions, Volumes, DEFAULT_VOLUME_TOLERANCE,
};
