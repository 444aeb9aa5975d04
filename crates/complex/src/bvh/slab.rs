//! The slab arithmetic of the walks: where a ray enters a box, for one box
//! ([`RayBoxes::enter`]), for a node's children four at a time
//! ([`RayBoxes::enter_node`]), and for four rays at once ([`RayBoxes4`]),
//! each the same operations on the same values, so that every form gives
//! the scalar test's answer to the bit.

use quadric::Ray;
use wide::{f64x4, CmpGe, CmpGt, CmpLe, CmpLt};

use super::Wide;

/// A ray prepared for slab tests: the reciprocal direction, and the origin
/// moved by the pad towards each side of a box, so that a box face costs one
/// addition and one product.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes {
    inv: [f64; 3],
    /// `-o - pad` for the lower faces and `-o + pad` for the upper ones: the
    /// ray meets the padded face at `b` where `t = (b + shift) / d`.
    shift_lo: [f64; 3],
    shift_hi: [f64; 3],
}

impl RayBoxes {
    pub(crate) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin(), ray.direction());
        // How far outside a block's exact box the kernel may put the ends of
        // the block's intervals: they are accurate to a few ulps of the ray
        // origin's coordinates, which near a box at the origin (a ray leaving
        // the plane x = 0 from (0, 4, 12)) is far more than the box's own
        // widening. Boxes are grown by this much in the slab test: about
        // 450 ulps of the origin, as `WIDEN_ABS` in `bounds.rs`.
        let pad = 1e-13 * o.coords.amax();
        let (o, d) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
        let inv = quadric::lanes::recip(d);
        // `-o ∓ pad` is rounded once, by half an ulp of `o`: less than 1/900
        // of the pad, so the slabs hold the box grown by nearly all of it,
        // far beyond the kernel's few ulps. (Folding the product into an
        // FMA, `b / d + shift / d`, would lose the sign of `b - o` on a
        // parallel axis, `∞ - ∞`, and with it every cull along that axis.)
        let shift_lo = o.map(|o| -o - pad);
        let shift_hi = o.map(|o| -o + pad);
        RayBoxes { inv, shift_lo, shift_hi }
    }

    /// The entry parameter of the ray into the closed box within
    /// `[t_min, t_max]`, or `None`. Conservative: rounding in the slab test
    /// is covered by a few ulps of slack, so a point of the box on the ray is
    /// never missed.
    ///
    /// No branch for a ray parallel to a slab: its reciprocal is `±∞`, so the
    /// slab gives `[-∞, ∞]` from inside, `±[∞, ∞]` (a miss) from outside, and
    /// NaN (`0·∞`) from its boundary plane, which fails both comparisons and
    /// leaves the range open (the closed box holds that point).
    ///
    /// [`RayBoxes::enter_node`] is the same arithmetic, lane by lane.
    #[inline(always)]
    pub(crate) fn enter(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> Option<f64> {
        let (t0, t1) = self.clip(min, max, t_min, t_max);
        let slack = 4.0 * f64::EPSILON * t1.abs().max(t0.abs());
        // `t0 = ∞` (a parallel ray outside a slab on its far side) would pass
        // `t0 <= t1 + ∞`: a miss.
        (t0 < f64::INFINITY && t0 <= t1 + slack).then_some(t0 - slack)
    }

    /// The parameter range `[lo, hi]` of the line in the padded box, without
    /// slack or clipping: the same slabs as [`RayBoxes::enter`], whose range
    /// for `[t_min, t_max]` is exactly `[max(t_min, lo), min(t_max, hi)]`. So
    /// a probe `enter(.., t, t)` finds the box for every `t` in `[lo, hi]`,
    /// and so does every node above it (its box holds this one, and the slab
    /// arithmetic is monotone). `lo > hi` when the line misses the box.
    #[inline(always)]
    pub(crate) fn range(&self, min: &[f64; 3], max: &[f64; 3]) -> (f64, f64) {
        self.clip(min, max, f64::NEG_INFINITY, f64::INFINITY)
    }

    /// `[t_min, t_max]` narrowed by the three slabs of the padded box.
    #[inline(always)]
    fn clip(&self, min: &[f64; 3], max: &[f64; 3], t_min: f64, t_max: f64) -> (f64, f64) {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let inv = self.inv[i];
            let a = (min[i] + self.shift_lo[i]) * inv;
            let b = (max[i] + self.shift_hi[i]) * inv;
            let (a, b) = if inv >= 0.0 { (a, b) } else { (b, a) };
            // NaN (∞ - ∞ on an infinite side, 0·∞) fails both tests and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        (t0, t1)
    }

    /// [`RayBoxes::enter`] for the children of a node at once, four at a
    /// time: the entries (group `g`, lane `l` for child `4g + l`), and a bit
    /// per child whose box the ray enters.
    #[inline(always)]
    pub(super) fn enter_node<const W: usize, const H: usize>(
        &self,
        node: &Wide<W, H>,
        t_min: f64,
        t_max: f64,
    ) -> ([f64x4; H], u32) {
        let mut entries = [f64x4::ZERO; H];
        let mut mask = 0;
        for (g, entry) in entries.iter_mut().enumerate() {
            // Lanes are filled from the first: a group whose first lane is
            // unused is empty (most nodes near the leaves of an eight-wide
            // tree have four children or fewer).
            if g > 0 && !node.used(4 * g) {
                break;
            }
            let (mut t0, mut t1) = (f64x4::splat(t_min), f64x4::splat(t_max));
            for i in 0..3 {
                // Broadcast loads: cheaper than keeping four-lane copies per ray.
                let inv = f64x4::splat(self.inv[i]);
                let a = (node.group[g].min[i] + f64x4::splat(self.shift_lo[i])) * inv;
                let b = (node.group[g].max[i] + f64x4::splat(self.shift_hi[i])) * inv;
                let (a, b) = if self.inv[i] >= 0.0 { (a, b) } else { (b, a) };
                // `if a > t0 { t0 = a }` lane by lane: NaN keeps `t0`.
                t0 = greater_or_second(a, t0);
                t1 = less_or_second(b, t1);
            }
            // `t0` and `t1` are never NaN (the caller's bounds are not, and
            // the updates keep a NaN out), so this is the plain lane maximum.
            let slack = f64x4::splat(4.0 * f64::EPSILON) * greater_or_second(t1.abs(), t0.abs());
            let hit = t0.cmp_lt(f64x4::splat(f64::INFINITY)) & t0.cmp_le(t1 + slack);
            *entry = t0 - slack;
            mask |= (hit.move_mask() as u32) << (4 * g);
        }
        (entries, mask)
    }
}

/// `a > b ? a : b` lane by lane, so `b` where either is NaN (and where
/// both are zeros): the slab tests' "a NaN keeps the bound". With AVX one
/// `vmaxpd`, whose rule this is exactly (Intel's `MAX(SRC1, SRC2)`: `SRC2`
/// for a NaN in either and for two zeros of any sign, else the greater),
/// instead of a comparison and a blend; elsewhere those two.
#[inline(always)]
pub(super) fn greater_or_second(a: f64x4, b: f64x4) -> f64x4 {
    #[cfg(target_feature = "avx")]
    {
        a.fast_max(b)
    }
    #[cfg(not(target_feature = "avx"))]
    {
        a.cmp_gt(b).blend(a, b)
    }
}

/// `a < b ? a : b` lane by lane: [`greater_or_second`]'s rule the other
/// way (`vminpd` with AVX).
#[inline(always)]
pub(super) fn less_or_second(a: f64x4, b: f64x4) -> f64x4 {
    #[cfg(target_feature = "avx")]
    {
        a.fast_min(b)
    }
    #[cfg(not(target_feature = "avx"))]
    {
        a.cmp_lt(b).blend(a, b)
    }
}

/// Four rays prepared for slab tests, lane by lane: the [`RayBoxes`] of
/// each, transposed, so that one box is tested against all four at once.
/// Each lane computes exactly what [`RayBoxes::enter_node`] computes for its
/// ray (the same operations on the same values), so a packet walk enters
/// a box for a lane exactly when that ray's own walk would.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes4 {
    inv: [f64x4; 3],
    shift_lo: [f64x4; 3],
    shift_hi: [f64x4; 3],
    /// All ones in the lanes whose `inv >= 0` (the lower face is met first).
    forward: [f64x4; 3],
}

/// Per axis, bounds over the four rays of a packet, from which
/// [`RayBoxes4::cull`] finds, for all the children of a node at once, a
/// lower bound of every ray's entry and an upper bound of its exit (see
/// there): the least and greatest reciprocal, and the shifts that give the
/// smallest entry and the largest exit (`-∞` and `+∞` on an axis where the
/// rays' reciprocals are not all finite or do not all have one sign: no
/// bound there).
#[derive(Clone, Copy, Debug)]
pub(super) struct PacketBounds {
    inv_min: [f64; 3],
    inv_max: [f64; 3],
    /// Added to the face met first: `min shift_lo` going forward, `max
    /// shift_hi` going backward.
    entry_shift: [f64; 3],
    /// Added to the face met last: `max shift_hi` forward, `min shift_lo`
    /// backward.
    exit_shift: [f64; 3],
    forward: [bool; 3],
}

impl PacketBounds {
    /// No bound on any axis.
    pub(super) const NONE: PacketBounds = PacketBounds {
        inv_min: [1.0; 3],
        inv_max: [1.0; 3],
        entry_shift: [f64::NEG_INFINITY; 3],
        exit_shift: [f64::INFINITY; 3],
        forward: [true; 3],
    };

    /// The bounds of the four rays of `rays`.
    pub(super) fn new(rays: &RayBoxes4) -> Self {
        let mut b = PacketBounds::NONE;
        for i in 0..3 {
            let inv = rays.inv[i].to_array();
            let forward = inv.iter().all(|&v| v >= 0.0);
            if !(inv.iter().all(|v| v.is_finite()) && (forward || inv.iter().all(|&v| v < 0.0))) {
                continue;
            }
            let lo = rays.shift_lo[i].to_array().iter().fold(f64::INFINITY, |m, &v| m.min(v));
            let hi = rays.shift_hi[i].to_array().iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
            b.inv_min[i] = inv.iter().fold(f64::INFINITY, |m, &v| m.min(v));
            b.inv_max[i] = inv.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
            (b.entry_shift[i], b.exit_shift[i]) = if forward { (lo, hi) } else { (hi, lo) };
            b.forward[i] = forward;
        }
        b
    }
}

impl RayBoxes4 {
    pub(crate) fn new(rays: &[RayBoxes; 4]) -> Self {
        let lanes = |f: &dyn Fn(&RayBoxes) -> f64| f64x4::new([f(&rays[0]), f(&rays[1]), f(&rays[2]), f(&rays[3])]);
        let inv = [0, 1, 2].map(|i| lanes(&|r| r.inv[i]));
        RayBoxes4 {
            inv,
            shift_lo: [0, 1, 2].map(|i| lanes(&|r| r.shift_lo[i])),
            shift_hi: [0, 1, 2].map(|i| lanes(&|r| r.shift_hi[i])),
            forward: inv.map(|v| v.cmp_ge(f64x4::splat(0.0))),
        }
    }

    /// A bit for each child of `node` that one of the four rays (whose
    /// bounds are `b`) may enter within `[t_min, t_max]` (`t_max`: the
    /// largest of the lanes' that count): every child some ray enters by
    /// [`RayBoxes4::enter_child`] has its bit, so testing only those gives
    /// the same answers. One test for all four rays, the children four at a
    /// time, instead of a test per child for the four rays: in an
    /// eight-wide node a packet enters few of the eight.
    ///
    /// Why no child a ray enters is culled: on an axis with bounds, every
    /// ray's reciprocal `v` is finite, of one sign, in `[inv_min, inv_max]`,
    /// and its face plus shift is at least `P` (the face met first plus
    /// `entry_shift`, rounded: rounding is monotone). So its entry on that
    /// axis, the rounded `(face + shift)·v`, is at least the rounded `P·v`,
    /// which is monotone in `v` for a fixed `P`: at least the smaller of
    /// `P·inv_min` and `P·inv_max`. So `T0`, the largest of these bounds and
    /// `t_min`, is at most every ray's `t0`; likewise `T1`, from the exit
    /// faces, at least every ray's `t1`. A ray enters only if `t0 <= t1 +
    /// slack` with `slack = 4ε·max(|t0|, |t1|)`; with `M = max(|T0|, |T1|)`,
    /// `S = 16ε·M` covers that slack where `|t0|, |t1| <= 3.99 M`, and
    /// where one of them is larger the gap between them is far wider than
    /// its slack (the larger is then positive and above `3.99 M` for `t0`,
    /// negative and below `-3.99 M` for `t1`). So `T0 > T1 + S` means no
    /// ray enters. NaN (an empty lane: `∞ - ∞`; an axis without bounds)
    /// fails every comparison and culls nothing.
    #[inline(always)]
    pub(super) fn cull<const W: usize, const H: usize>(
        b: &PacketBounds,
        node: &Wide<W, H>,
        t_min: f64,
        t_max: f64,
    ) -> u32 {
        let mut mask = 0;
        for g in 0..H {
            let (mut t0, mut t1) = (f64x4::splat(t_min), f64x4::splat(t_max));
            for i in 0..3 {
                let (first, last) = if b.forward[i] {
                    (node.group[g].min[i], node.group[g].max[i])
                } else {
                    (node.group[g].max[i], node.group[g].min[i])
                };
                let p = first + f64x4::splat(b.entry_shift[i]);
                let q = last + f64x4::splat(b.exit_shift[i]);
                let (v0, v1) = (f64x4::splat(b.inv_min[i]), f64x4::splat(b.inv_max[i]));
                let (p0, p1) = (p * v0, p * v1);
                let (q0, q1) = (q * v0, q * v1);
                let enter = less_or_second(p0, p1);
                let exit = greater_or_second(q0, q1);
                // NaN keeps the bound as it was.
                t0 = greater_or_second(enter, t0);
                t1 = less_or_second(exit, t1);
            }
            // Never NaN, as in `enter_node`: the plain lane maximum.
            let s = f64x4::splat(16.0 * f64::EPSILON) * greater_or_second(t0.abs(), t1.abs());
            let culled = t0.cmp_gt(t1 + s);
            mask |= (!(culled.move_mask() as u32) & 0b1111) << (4 * g);
        }
        mask
    }

    /// Child `c` of `node` against the four rays: their entries and a bit
    /// per ray that enters it within its `[t_min, t_max]`.
    #[inline(always)]
    pub(super) fn enter_child<const W: usize, const H: usize>(
        &self,
        node: &Wide<W, H>,
        c: usize,
        t_min: f64x4,
        t_max: f64x4,
    ) -> (f64x4, u32) {
        let (mut t0, mut t1) = (t_min, t_max);
        for i in 0..3 {
            let lo = f64x4::splat(node.group[c / 4].min[i].as_array_ref()[c % 4]);
            let hi = f64x4::splat(node.group[c / 4].max[i].as_array_ref()[c % 4]);
            let a = (lo + self.shift_lo[i]) * self.inv[i];
            let b = (hi + self.shift_hi[i]) * self.inv[i];
            let (a, b) = (self.forward[i].blend(a, b), self.forward[i].blend(b, a));
            t0 = greater_or_second(a, t0);
            t1 = less_or_second(b, t1);
        }
        // Never NaN, as in `RayBoxes::enter_node`: the plain lane maximum.
        let slack = f64x4::splat(4.0 * f64::EPSILON) * greater_or_second(t1.abs(), t0.abs());
        let hit = t0.cmp_lt(f64x4::splat(f64::INFINITY)) & t0.cmp_le(t1 + slack);
        (t0 - slack, hit.move_mask() as u32)
    }
}
