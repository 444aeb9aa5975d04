//! Per-block ray data in BVH leaf order, laid out for the cache.
//!
//! A block's solids live in its own heap buffer, as `Solid` values sized for
//! the larger quadric; reaching them from a BVH leaf took three dependent
//! cache misses per block (leaf entry, `Block`, solids) and, for a rotated
//! box, thirteen cache lines of solids. Here the blocks of one leaf are
//! neighbours: a slot per block in leaf order, and the half-spaces and
//! quadrics of consecutive slots packed in two arrays in the same order, so a
//! leaf reads a few consecutive lines of each.

use quadric::{HalfSpace, Precision, Quadric, Ray, Solid};

use crate::block::{convex_spans, SolidRef, Spans};
use crate::Block;

/// One block in leaf order.
#[derive(Clone, Copy, Debug)]
struct Slot {
    block: u32,
    /// Index of the block's first half-space in `Kernel::half_spaces`.
    half_space: u32,
    /// Index of its first quadric in `Kernel::quadrics`.
    quadric: u32,
    /// Bit `i` set: solid `i` is a quadric, else a half-space.
    quadric_mask: u32,
    /// Number of solids; 0: not packed (non-convex, or more than 32 solids),
    /// answered by [`Block::spans`].
    count: u32,
}

/// The packed solids of the bounded blocks, in BVH leaf order.
#[derive(Clone, Debug, Default)]
pub(crate) struct Kernel {
    slots: Vec<Slot>,
    half_spaces: Vec<HalfSpace>,
    quadrics: Vec<Quadric>,
    /// The precision mode of every query (`Complex::set_precision`).
    pub(crate) precision: Precision,
}

impl Kernel {
    /// Packs `blocks[order[k]]` into slot `k`.
    pub(crate) fn new(order: &[u32], blocks: &[Block]) -> Self {
        let mut kernel = Kernel { slots: Vec::with_capacity(order.len()), ..Kernel::default() };
        for &id in order {
            let block = &blocks[id as usize];
            let solids = block.solids();
            let mut slot = Slot {
                block: id,
                half_space: kernel.half_spaces.len() as u32,
                quadric: kernel.quadrics.len() as u32,
                quadric_mask: 0,
                count: 0,
            };
            if block.is_convex() && solids.len() <= 32 {
                for (i, s) in solids.iter().enumerate() {
                    match s {
                        Solid::HalfSpace(h) => kernel.half_spaces.push(*h),
                        Solid::Quadric(q) => {
                            kernel.quadrics.push(*q);
                            slot.quadric_mask |= 1 << i;
                        }
                    }
                }
                slot.count = solids.len() as u32;
            }
            kernel.slots.push(slot);
        }
        kernel
    }

    /// The number of slots (bounded blocks).
    #[inline(always)]
    pub(crate) fn len(&self) -> usize {
        self.slots.len()
    }

    /// The block in slot `k`.
    #[inline(always)]
    pub(crate) fn block(&self, k: u32) -> u32 {
        self.slots[k as usize].block
    }

    /// Solid `i` of the block in slot `k`, if the slot is packed.
    #[inline]
    pub(crate) fn solid(&self, k: u32, i: u32) -> Option<SolidRef<'_>> {
        let slot = self.slots[k as usize];
        if i >= slot.count {
            return None;
        }
        // The solids before `i` of the same kind come first in their array.
        let below = slot.quadric_mask & ((1u32 << i) - 1);
        Some(if slot.quadric_mask & (1 << i) != 0 {
            SolidRef::Quadric(&self.quadrics[(slot.quadric + below.count_ones()) as usize])
        } else {
            SolidRef::HalfSpace(&self.half_spaces[(slot.half_space + i - below.count_ones()) as usize])
        })
    }

    /// The intervals along the ray of the block in slot `k`, written into
    /// `out`: exactly [`Block::spans`], read from the packed solids. (Written
    /// in place, like [`Block::spans_into`]: a convex block writes at most
    /// one interval, not a 272-byte enum.)
    #[inline(always)]
    pub(crate) fn spans_into(&self, k: u32, ray: &Ray, blocks: &[Block], out: &mut Spans) {
        let slot = self.slots[k as usize];
        if slot.count > 0 {
            let (mut h, mut q) = (slot.half_space as usize, slot.quadric as usize);
            let solids = (0..slot.count).map(|i| {
                if slot.quadric_mask & (1 << i) != 0 {
                    q += 1;
                    SolidRef::Quadric(&self.quadrics[q - 1])
                } else {
                    h += 1;
                    SolidRef::HalfSpace(&self.half_spaces[h - 1])
                }
            });
            if let Some(spans) = convex_spans(ray, solids, self.precision) {
                *out = spans;
                return;
            }
        }
        blocks[slot.block as usize].spans_general_into(ray, out);
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use quadric::strategies;

    use super::*;
    use crate::{MaterialKey, Opacity};

    proptest! {
        /// Every slot answers exactly what its block answers, solid tags included.
        #[test]
        fn packed_blocks_answer_like_their_blocks(
            blocks in proptest::collection::vec(proptest::collection::vec(strategies::solid(), 1..=5), 1..12),
            order_seed in any::<u64>(),
            rays in proptest::collection::vec(strategies::ray(4.0), 8),
        ) {
            let blocks: Vec<Block> = blocks
                .into_iter()
                .map(|s| Block::new("b", s, Opacity::Opaque, MaterialKey(0)).expect("valid"))
                .collect();
            // Any order of the blocks, as a BVH's leaves would give.
            let mut order: Vec<u32> = (0..blocks.len() as u32).collect();
            order.rotate_left((order_seed % blocks.len() as u64) as usize);
            let kernel = Kernel::new(&order, &blocks);
            for ray in &rays {
                for k in 0..order.len() as u32 {
                    let id = kernel.block(k);
                    prop_assert_eq!(id, order[k as usize]);
                    let mut packed = Spans::Empty;
                    kernel.spans_into(k, ray, &blocks, &mut packed);
                    let plain = blocks[id as usize].spans(ray);
                    prop_assert_eq!(packed.as_slice(), plain.as_slice());
                }
            }
            for k in 0..order.len() as u32 {
                let block = &blocks[kernel.block(k) as usize];
                for (i, s) in block.solids().iter().enumerate() {
                    let same = match (kernel.solid(k, i as u32), s) {
                        (Some(SolidRef::HalfSpace(a)), Solid::HalfSpace(b)) => a == b,
                        (Some(SolidRef::Quadric(a)), Solid::Quadric(b)) => a == b,
                        // Only blocks the kernel does not pack have no packed solids.
                        (None, _) => !block.is_convex(),
                        _ => false,
                    };
                    prop_assert!(same, "slot {} solid {}", k, i);
                }
            }
        }
    }
}
