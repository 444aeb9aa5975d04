//! The walks of the wide tree: front to back for one ray (nearest child
//! first) or in any order (any-hit), four rays at once sharing each node
//! read, and the point visit. Each keeps its pending children on a
//! fixed-size stack ([`STACK`] entries), so a query never allocates.

use arrayvec::ArrayVec;
use wide::{f64x4, CmpLe};

use super::slab::{PacketBounds, RayBoxes, RayBoxes4};
use super::{Tree, STACK};

impl<const W: usize, const H: usize> Tree<W, H> {
    /// [`Bvh::traverse`] (`NEAREST_FIRST`) or [`Bvh::traverse_any`].
    #[inline(always)]
    pub(super) fn walk<const NEAREST_FIRST: bool>(
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
        // zeroed array of this size costs 8 % of a small scene's
        // instructions (`docs/benchmarks.md`).
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
    pub(super) fn traverse4(
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
            // would move their four-lane entries through unaligned stack
            // slots: each move a failed store-to-load forward, 17 % of the
            // packet walk's time on the 100,000-block grid, which callgrind
            // does not show; see `docs/benchmarks.md`.)
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
