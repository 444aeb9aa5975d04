//! Per-block ray data in BVH leaf order, laid out for the cache.
//!
//! A block's solids live in its own heap buffer, as `Solid` values sized for
//! the larger quadric; reaching them from a BVH leaf takes three dependent
//! cache misses per block (leaf entry, `Block`, solids) and, for a rotated
//! box, thirteen cache lines of solids. Here the blocks of one leaf are
//! neighbours: a slot per block in leaf order, and the half-spaces (as
//! faces) and quadrics of consecutive slots packed in two arrays in the same
//! order, so a leaf reads a few consecutive lines of each. Two opposite
//! half-spaces in a row (a box's faces on one axis, a cylinder's caps) are
//! packed as one slab ([`Face`]), and consecutive faces around the same
//! reference point (a box's three slabs) share the ray's re-basing
//! ([`Rebased`]).

use quadric::{HalfSpace, Precision, Quadric, Ray, Rebased, Solid};

use crate::block::{ConvexSpan, Scratch, SolidRef, Spans};
use crate::bounds::Ball;
use crate::Block;

/// One block in leaf order.
#[derive(Clone, Copy, Debug)]
struct Slot {
    block: u32,
    /// Index of the block's first face in `Kernel::faces`.
    face: u32,
    /// Index of its first quadric in `Kernel::quadrics`.
    quadric: u32,
    /// Bit `i` set: solid `i` is a quadric, else a half-space.
    quadric_mask: u32,
    /// Bit `i` set: half-space `i` and the next solid, its opposite, are
    /// one face (a slab).
    pair_mask: u32,
    /// Number of solids; 0: not packed (non-convex, or more than 32 solids),
    /// answered by [`Block::spans`].
    count: u32,
    /// A ball holding the block, for a cheap reject (see [`Ball`]).
    ball: Ball,
}

/// A packed half-space and, where the slot's `pair_mask` says so, its
/// opposite `-n·(x - o) + opposite <= 0`, the block's next solid: one slab,
/// whose two intervals [`HalfSpace::slab_intervals`] finds for little more
/// than the cost of one, in 64 bytes instead of 112: one cache line, to
/// which it is aligned (unaligned, most faces would straddle two). The
/// opposite itself, which only its hits and `Precision::Fast` read, is
/// kept apart, in `Kernel::seconds`.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
struct Face {
    half_space: HalfSpace,
    opposite: f64,
}

// One line, no padding: a half-space and the opposite's offset fill it.
const _: () = assert!(core::mem::size_of::<Face>() == 64);

/// A packed quadric on whole cache lines: 192 bytes, three lines, where
/// an array of plain `Quadric`s (aligned to 8 or 16 bytes) puts most of
/// them across four.
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
struct Lines(Quadric);

/// The slot's ball ([`crate::bounds::Ball`]): the ball around one of the
/// block's solids that is an axis-aligned ellipsoid (every sphere, and
/// every ellipsoid scaled along the axes and moved), else the one the
/// block's box came with (`bounds::block_bounds`: around a bounded
/// polyhedron such as a rotated box of six half-spaces, or around a capped
/// cylinder), each grown far beyond rounding. A ray whose line passes it by
/// more than a further margin meets none of the block's points, and its
/// interval from the kernel is empty too: the kernel puts its ends within a
/// few ulps of the true ones even where the ray grazes the surface, far
/// inside the margins (`1e-6` of the radius and `1e-12` of the distance),
/// so the reject answers what the solids would, without reading them. No
/// ball: an infinite radius, which rejects nothing.
impl Ball {
    const NONE: Ball = Ball { centre: [0.0; 3], radius: f64::INFINITY };

    /// The ball of `q` if it is an ellipsoid with a diagonal `A`:
    /// `f = Σ aᵢ(dᵢ + wᵢ/aᵢ)² - K` with `d = x - c` and
    /// `K = Σ wᵢ²/aᵢ - k`, so the solid lies within `sqrt(K / min aᵢ)` of
    /// `m = c - w/a` (exactly, for the stored coefficients).
    fn of(q: &Quadric) -> Option<Ball> {
        let (c, a, w, k) = q.local_parts();
        let off_diagonal = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)];
        if off_diagonal.iter().any(|&(i, j)| a[(i, j)] != 0.0) {
            return None;
        }
        let d = [a[(0, 0)], a[(1, 1)], a[(2, 2)]];
        if !d.iter().all(|&x| x > 0.0 && x.is_finite()) || !k.is_finite() {
            return None;
        }
        let shift = [0, 1, 2].map(|i| w[i] / d[i]);
        let centre = [0, 1, 2].map(|i| c[i] - shift[i]);
        let terms: f64 = (0..3).map(|i| w[i] * shift[i]).sum();
        // `K` and `K / min aᵢ` to a few ulps of the terms they are formed
        // from; grown by far more.
        let level = terms - k + 1e-12 * (terms.abs() + k.abs());
        let r2 = level / d.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let spread = (0..3).fold(0.0f64, |m, i| m.max(c[i].abs()).max(shift[i].abs()));
        let radius = r2.max(0.0).sqrt() * (1.0 + 1e-6) + 1e-12 * spread;
        (radius.is_finite() && centre.iter().all(|x| x.is_finite())).then_some(Ball { centre, radius })
    }

    /// Whether the ray's line passes the ball by more than a margin for
    /// the rounding of this test (`1e-12` of the distance to the centre).
    #[inline(always)]
    fn missed_by(&self, ray: &Ray) -> bool {
        let (o, r) = (ray.origin(), ray.direction());
        let d = [self.centre[0] - o.x, self.centre[1] - o.y, self.centre[2] - o.z];
        let t = d[0] * r.x + d[1] * r.y + d[2] * r.z;
        let e = [d[0] - t * r.x, d[1] - t * r.y, d[2] - t * r.z];
        let far = d[0].abs().max(d[1].abs()).max(d[2].abs());
        let reach = self.radius + 1e-12 * far;
        e[0] * e[0] + e[1] * e[1] + e[2] * e[2] > reach * reach
    }
}

/// The packed solids of the bounded blocks, in BVH leaf order.
#[derive(Clone, Debug, Default)]
pub(crate) struct Kernel {
    slots: Vec<Slot>,
    faces: Vec<Face>,
    /// Each face's opposite, if it holds one, else its own half-space again.
    seconds: Vec<HalfSpace>,
    quadrics: Vec<Lines>,
    /// The precision mode of every query (`Complex::set_precision`).
    pub(crate) precision: Precision,
}

/// The faces of a block's solids in order: `(i, h, opposite)` for each
/// half-space `h` at `i`, with the next solid and its offset if that is its
/// opposite ([`HalfSpace::opposite_offset`]), which the face then holds too.
fn faces_of(solids: &[Solid]) -> impl Iterator<Item = (usize, &HalfSpace, Option<(&HalfSpace, f64)>)> {
    let mut next = 0;
    std::iter::from_fn(move || {
        while next < solids.len() {
            let i = next;
            next += 1;
            if let Solid::HalfSpace(h) = &solids[i] {
                let opposite = match solids.get(i + 1) {
                    Some(Solid::HalfSpace(o)) => h.opposite_offset(o).map(|d| (o, d)),
                    _ => None,
                };
                next += usize::from(opposite.is_some());
                return Some((i, h, opposite));
            }
        }
        None
    })
}

impl Kernel {
    /// Packs `blocks[order[k]]` into slot `k`. `balls[i]`: a ball holding
    /// block `i` from [`crate::bounds::block_boxes`] (missing entries: none),
    /// kept where the block has no axis-aligned ellipsoid of its own.
    pub(crate) fn new(order: &[u32], blocks: &[Block], balls: &[Option<Ball>]) -> Self {
        // Convex blocks of at most 32 solids are packed; others are answered
        // by `Block::spans`.
        let packed = |block: &Block| block.is_convex() && block.solids().len() <= 32;
        // The arrays' sizes up front: grown by doubling, the 100,000-block
        // grid's 28 MB of solids would take 107 MB of allocations (fresh
        // pages and a copy each time).
        let (mut faces, mut quadrics) = (0, 0);
        for &id in order {
            let block = &blocks[id as usize];
            if packed(block) {
                quadrics += block.solids().iter().filter(|s| matches!(s, Solid::Quadric(_))).count();
                faces += faces_of(block.solids()).count();
            }
        }
        let mut kernel = Kernel {
            slots: Vec::with_capacity(order.len()),
            faces: Vec::with_capacity(faces),
            seconds: Vec::with_capacity(faces),
            quadrics: Vec::with_capacity(quadrics),
            ..Kernel::default()
        };
        for &id in order {
            let block = &blocks[id as usize];
            let solids = block.solids();
            let mut slot = Slot {
                block: id,
                face: kernel.faces.len() as u32,
                quadric: kernel.quadrics.len() as u32,
                quadric_mask: 0,
                pair_mask: 0,
                count: 0,
                ball: Ball::NONE,
            };
            if packed(block) {
                for (i, s) in solids.iter().enumerate() {
                    if let Solid::Quadric(q) = s {
                        kernel.quadrics.push(Lines(*q));
                        slot.quadric_mask |= 1 << i;
                        if slot.ball.radius == f64::INFINITY {
                            slot.ball = Ball::of(q).unwrap_or(Ball::NONE);
                        }
                    }
                }
                for (i, h, opposite) in faces_of(solids) {
                    let (second, d) = opposite.unwrap_or((h, 0.0));
                    kernel.faces.push(Face { half_space: *h, opposite: d });
                    kernel.seconds.push(*second);
                    if opposite.is_some() {
                        slot.pair_mask |= 1 << i;
                    }
                }
                slot.count = solids.len() as u32;
                if let (f64::INFINITY, Some(&Some(ball))) = (slot.ball.radius, balls.get(id as usize)) {
                    slot.ball = ball;
                }
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
    #[inline(always)]
    pub(crate) fn solid(&self, k: u32, i: u32) -> Option<SolidRef<'_>> {
        let slot = self.slots[k as usize];
        if i >= slot.count {
            return None;
        }
        let below = (1u32 << i) - 1;
        Some(if slot.quadric_mask & (1 << i) != 0 {
            // The quadrics before `i` come first in their array.
            SolidRef::Quadric(&self.quadrics[(slot.quadric + (slot.quadric_mask & below).count_ones()) as usize].0)
        } else {
            // One face for each half-space before `i` that is not a slab's second.
            let seconds = slot.pair_mask << 1;
            let f = (slot.face + (!slot.quadric_mask & below).count_ones() - (seconds & below).count_ones()) as usize;
            SolidRef::HalfSpace(if seconds & (1 << i) != 0 { &self.seconds[f - 1] } else { &self.faces[f].half_space })
        })
    }

    /// The intervals along the ray of the block in slot `k`, written into
    /// `out`: exactly [`Block::spans`], read from the packed solids. (Written
    /// in place, like [`Block::spans_into`]: a convex block writes at most
    /// one interval, not a 272-byte enum.)
    #[inline(always)]
    pub(crate) fn spans_into<S: Scratch>(&self, k: u32, ray: &Ray, blocks: &[Block], out: &mut S) {
        let slot = &self.slots[k as usize];
        if slot.count > 0 {
            let spans = match self.precision {
                Precision::Accurate => {
                    if slot.ball.radius < f64::INFINITY && slot.ball.missed_by(ray) {
                        out.set_spans(Spans::Empty);
                        return;
                    }
                    self.packed_spans::<false>(slot, ray)
                }
                Precision::Fast => self.packed_spans::<true>(slot, ray),
                // Ties between solids are settled exactly on the general path.
                _ => None,
            };
            if let Some(spans) = spans {
                out.set_spans(spans);
                return;
            }
        }
        blocks[slot.block as usize].spans_rare_into(ray, out);
    }

    /// [`convex_spans`](crate::block::convex_spans) from the packed
    /// solids, in [`Precision::Fast`] or [`Precision::Accurate`]: the same
    /// intervals met in the same order; `None` if a quadric gave more than
    /// one interval after all. In `Accurate` a slab's two at once, and the
    /// ray re-based once for consecutive faces around one reference point;
    /// in `Fast`, which evaluates at the ray's origin, one at a time.
    #[inline(always)]
    fn packed_spans<const FAST: bool>(&self, slot: &Slot, ray: &Ray) -> Option<Spans> {
        let precision = if FAST { Precision::Fast } else { Precision::Accurate };
        let (mut span, mut f, mut q) = (ConvexSpan::ALL, slot.face as usize, slot.quadric as usize);
        let mut at: Option<([u64; 3], Rebased)> = None;
        let mut i = 0;
        while i < slot.count {
            let non_empty = if slot.quadric_mask & (1 << i) != 0 {
                q += 1;
                span.narrow_pieces(&self.quadrics[q - 1].0.pieces_with(ray, i, precision))?
            } else {
                let Face { half_space: h, opposite } = &self.faces[f];
                f += 1;
                let pair = slot.pair_mask & (1 << i) != 0;
                if FAST {
                    let (e, x) = h.interval_with(ray, i, precision);
                    span.narrow(e, x)
                        && (!pair || {
                            i += 1;
                            let (e, x) = self.seconds[f - 1].interval_with(ray, i, precision);
                            span.narrow(e, x)
                        })
                } else {
                    let o = h.reference_point();
                    let key = [o.x.to_bits(), o.y.to_bits(), o.z.to_bits()];
                    let rebased = match at {
                        Some((same, rebased)) if same == key => rebased,
                        _ => at.insert((key, Rebased::new(ray, &o))).1,
                    };
                    if pair {
                        let [(e0, x0), (e1, x1)] = h.slab_intervals(*opposite, ray, &rebased, i);
                        i += 1;
                        span.narrow(e0, x0) && span.narrow(e1, x1)
                    } else {
                        let (e, x) = h.interval_rebased(ray, &rebased, i);
                        span.narrow(e, x)
                    }
                }
            };
            if !non_empty {
                return Some(Spans::Empty);
            }
            i += 1;
        }
        Some(span.spans())
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use quadric::nalgebra::{Point3, Vector3};
    use quadric::{strategies, Transform};

    use super::*;
    use crate::block::SpanBuf;
    use crate::bounds::block_boxes;
    use crate::{MaterialKey, Opacity};

    /// An axis-aligned ellipsoid (the unit sphere scaled along the axes and
    /// moved, as scenes build them), possibly far from the origin, with a
    /// sphere's radius for aiming rays at it.
    fn ellipsoid() -> impl Strategy<Value = (Quadric, f64)> {
        // Mostly spheres, whose ball is the solid itself (grown by 1e-6).
        let axis = || prop_oneof![3 => Just(1.0), 1 => 0.2..3.0f64];
        let place = prop_oneof![Just(0.0), -5.0..5.0f64, -1e9..1e9f64];
        ([axis(), axis(), axis()], [place.clone(), place.clone(), place], 1e-3..1e3f64).prop_map(|(s, at, size)| {
            let m = Transform::scale_xyz(Vector3::from(s).scale(size))
                .expect("finite")
                .then(&Transform::translate(Vector3::from(at)).expect("finite"));
            (Quadric::sphere().transformed(&m), size * s.iter().fold(0.0f64, |m, x| m.max(*x)))
        })
    }

    /// An axis-aligned ellipsoid from its coefficients, with linear terms:
    /// `Σ aᵢxᵢ² + 2gᵢxᵢ + k` (centre `-g/a`, stored around the origin).
    fn ellipsoid_from_coefficients() -> impl Strategy<Value = Quadric> {
        let a = || 1e-3..1e3f64;
        let g = || prop_oneof![Just(0.0), -1e3..1e3f64];
        ([a(), a(), a()], [g(), g(), g()], 0.01..10.0f64).prop_map(|(a, g, level)| {
            // k below Σ gᵢ²/aᵢ, so that the ellipsoid is not empty.
            let k = (0..3).map(|i| g[i] * g[i] / a[i]).sum::<f64>() - level;
            Quadric::from_coefficients([a[0], a[1], a[2], 0.0, 0.0, 0.0, g[0], g[1], g[2], k]).expect("finite")
        })
    }

    /// A box of half sizes `e`, or a cylinder of radius `e[0]` and half
    /// height `e[1]` along y capped by two planes, turned about x and y and
    /// moved (near the origin or far from it), as scenes build them: the
    /// block, and the points of it farthest from its middle (the box's
    /// corners, points of the cylinder's rims) placed by the same transform,
    /// independently of how the kernel's ball is found.
    fn turned_block() -> impl Strategy<Value = (Block, Point3<f64>, Vec<Point3<f64>>)> {
        let place = prop_oneof![Just(0.0), -5.0..5.0f64, -1e9..1e9f64];
        (
            any::<bool>(),
            [0.05..2.0f64, 0.05..2.0, 0.05..2.0],
            0.0..360.0f64,
            0.0..360.0f64,
            [place.clone(), place.clone(), place],
        )
            .prop_map(|(cylinder, e, ax, ay, at)| {
                let m = Transform::rotate_x_degrees(ax)
                    .and_then(|r| Ok(r.then(&Transform::rotate_y_degrees(ay)?)))
                    .and_then(|r| Ok(r.then(&Transform::translate(Vector3::from(at))?)))
                    .expect("finite");
                let plane = |a: f64, b: f64, c: f64, d: f64| {
                    Solid::from(HalfSpace::new(a, b, c, d).expect("valid").transformed(&m))
                };
                let (solids, local): (Vec<Solid>, Vec<Point3<f64>>) = if cylinder {
                    let tube = Quadric::tube_y()
                        .transformed(&Transform::scale_xyz(Vector3::new(e[0], 1.0, e[0])).expect("finite"));
                    let rims = (0..16).flat_map(|k| {
                        let a = f64::from(k) * std::f64::consts::PI / 8.0;
                        [1.0, -1.0].map(|y| Point3::new(e[0] * a.cos(), y * e[1], e[0] * a.sin()))
                    });
                    (
                        vec![
                            Solid::from(tube.transformed(&m)),
                            plane(0.0, 1.0, 0.0, -e[1]),
                            plane(0.0, -1.0, 0.0, -e[1]),
                        ],
                        rims.collect(),
                    )
                } else {
                    let faces = (0..3).flat_map(|i| {
                        [1.0, -1.0].map(|sign| {
                            let mut n = [0.0; 3];
                            n[i] = sign;
                            plane(n[0], n[1], n[2], -e[i])
                        })
                    });
                    let corners = (0..8).map(|k: u32| {
                        let sign = |bit: u32| if k & (1 << bit) != 0 { 1.0 } else { -1.0 };
                        Point3::new(sign(0) * e[0], sign(1) * e[1], sign(2) * e[2])
                    });
                    (faces.collect(), corners.collect())
                };
                let block = Block::new("turned", solids, Opacity::Opaque, MaterialKey(0)).expect("valid");
                (block, m.apply_point(&Point3::origin()), local.iter().map(|p| m.apply_point(p)).collect())
            })
    }

    /// Blocks with opposite half-spaces in a row: a box's three slabs, or a
    /// tube between two caps, each possibly with a lone half-space (around a
    /// reference point of its own) or a sphere among them, axis-aligned or
    /// turned, near the origin or far.
    fn slab_solids() -> impl Strategy<Value = Vec<Solid>> {
        let slab = (0usize..3, -0.5f64..-0.05, -0.5f64..-0.05).prop_map(|(axis, d0, d1)| {
            let mut n = [0.0; 3];
            n[axis] = 1.0;
            vec![
                Solid::from(HalfSpace::new(n[0], n[1], n[2], d0).expect("valid")),
                Solid::from(HalfSpace::new(-n[0], -n[1], -n[2], d1).expect("valid")),
            ]
        });
        let extra = prop_oneof![
            Just(vec![]),
            Just(vec![Solid::from(Quadric::tube_y())]),
            Just(vec![Solid::from(Quadric::sphere())]),
            // Around a reference point of its own, so not re-based with the slabs.
            (strategies::half_space(), strategies::point(1.0)).prop_filter_map("finite", |(h, p)| {
                Some(vec![Solid::from(h.transformed(&Transform::translate(p.coords).ok()?))])
            }),
        ];
        let far = prop_oneof![Just(0.0), Just(1e3), Just(1e8)];
        (
            proptest::collection::vec(slab, 1..=3),
            extra,
            0usize..4,
            strategies::transform(),
            far,
            strategies::unit_vector(),
        )
            .prop_filter_map("finite", |(slabs, extra, at, m, far, dir)| {
                let mut solids: Vec<Solid> = slabs.into_iter().flatten().collect();
                let at = at.min(solids.len());
                solids.splice(at..at, extra);
                let m = m.then(&Transform::translate(dir * far).ok()?);
                Some(solids.iter().map(|s| s.transformed(&m)).collect())
            })
    }

    fn half_space_bits(h: &HalfSpace) -> Vec<u64> {
        let (n, o, v) = (h.normal_vector(), h.reference_point(), h.vector());
        n.iter().chain(o.iter()).chain(v.iter()).map(|x| x.to_bits()).collect()
    }

    fn span_bits(s: &SpanBuf) -> Vec<(u64, Option<u32>, u64, Option<u32>)> {
        s.as_slice()
            .iter()
            .map(|iv| (iv.enter.t.to_bits(), iv.enter.solid(), iv.exit.t.to_bits(), iv.exit.solid()))
            .collect()
    }

    /// The kernel of one block, with the ball its box came with.
    fn one_slot(block: &Block) -> Kernel {
        let blocks = std::slice::from_ref(block);
        Kernel::new(&[0], blocks, &block_boxes(blocks).1)
    }

    #[test]
    fn balls_are_kept_where_they_are_smaller_than_the_box() {
        let cube = |m: &Transform| {
            let faces = (0..3).flat_map(|i| {
                [1.0, -1.0].map(|sign| {
                    let mut n = [0.0; 3];
                    n[i] = sign;
                    Solid::from(HalfSpace::new(n[0], n[1], n[2], -1.0).expect("valid").transformed(m))
                })
            });
            Block::new("cube", faces.collect(), Opacity::Opaque, MaterialKey(0)).expect("valid")
        };
        let turned = Transform::rotate_x_degrees(30.0)
            .expect("finite")
            .then(&Transform::rotate_y_degrees(40.0).expect("finite"));
        // Turned, the cube's box grows past its ball; upright, its ball
        // (radius √3) is larger than its box, and rejects nothing more.
        let ball = one_slot(&cube(&turned)).slots[0].ball;
        assert!((ball.radius - 3f64.sqrt()).abs() < 1e-5 && ball.centre.iter().all(|c| c.abs() < 1e-9), "{ball:?}");
        assert_eq!(one_slot(&cube(&Transform::identity())).slots[0].ball.radius, f64::INFINITY);
        // A long upright cylinder: its ball is far larger than its box.
        let pole = vec![
            Solid::from(
                Quadric::tube_y().transformed(&Transform::scale_xyz(Vector3::new(0.1, 1.0, 0.1)).expect("finite")),
            ),
            Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -2.0).expect("valid")),
            Solid::from(HalfSpace::new(0.0, -1.0, 0.0, -2.0).expect("valid")),
        ];
        let pole = Block::new("pole", pole, Opacity::Opaque, MaterialKey(0)).expect("valid");
        assert_eq!(one_slot(&pole).slots[0].ball.radius, f64::INFINITY);
    }

    proptest! {
        /// A turned box's corners and a turned capped cylinder's rims lie in
        /// the ball the kernel keeps for it, which is centred on the block.
        #[test]
        fn the_ball_of_a_turned_block_holds_its_farthest_points((block, middle, far) in turned_block()) {
            let ball = one_slot(&block).slots[0].ball;
            if ball.radius < f64::INFINITY {
                let c = Point3::from(ball.centre);
                prop_assert!((c - middle).norm() <= 1e-9 * ball.radius + 1e-12 * middle.coords.amax(), "centre {:?}, middle {:?}", c, middle);
                for p in &far {
                    prop_assert!((p - c).norm() <= ball.radius, "{:?} is {} from the centre, radius {}", p, (p - c).norm(), ball.radius);
                }
            }
        }

        /// Rays across a turned block's farthest points, just inside the
        /// block (where the ball is tightest) and just outside it, at right
        /// angles to the radius there (so that the line comes nearest the
        /// ball's centre at that point): the reject answers exactly what the
        /// solids do.
        #[test]
        fn the_ball_of_a_turned_block_rejects_only_rays_the_solids_miss(
            (block, _, far) in turned_block(),
            aims in proptest::collection::vec((0usize..32, strategies::unit_vector(), prop_oneof![-1e-3..1e-3f64, -1e-6..1e-6f64, -1e-9..1e-9f64], 0.5..1e3f64), 16),
        ) {
            let kernel = one_slot(&block);
            let ball = kernel.slots[0].ball;
            let c = Point3::from(ball.centre);
            for (k, dir, inside, back) in &aims {
                let v = far[k % far.len()];
                let radial = v - c;
                // A direction at right angles to the radius.
                let Some(across) = dir.cross(&radial).try_normalize(1e-9) else { continue };
                let aim = c + radial * (1.0 - inside);
                let Ok(ray) = Ray::new(aim - across * (back * radial.norm()), across) else { continue };
                let mut packed = <SpanBuf as Scratch>::new();
                kernel.spans_into(0, &ray, std::slice::from_ref(&block), &mut packed);
                let plain = block.spans(&ray);
                prop_assert_eq!(packed.as_slice(), plain.as_slice(), "inside by {}", inside);
            }
        }

        /// Every point of an axis-aligned ellipsoid lies in its ball, with
        /// linear terms too.
        #[test]
        fn the_ball_of_coefficients_holds_its_ellipsoid(q in ellipsoid_from_coefficients(), dirs in proptest::collection::vec(strategies::ray(1.0), 16)) {
            let ball = Ball::of(&q).expect("an ellipsoid");
            let c = Point3::from(ball.centre);
            prop_assert!(q.value(&c) <= 0.0, "the centre {:?} is outside", c);
            for ray in &dirs {
                let probe = Ray::new(c, ray.direction()).expect("valid");
                for iv in q.intervals(&probe, 0).iter() {
                    prop_assert!(iv.exit.t.is_finite() && iv.exit.t <= ball.radius, "{} beyond {}", iv.exit.t, ball.radius);
                }
            }
        }

        /// Every point of an axis-aligned ellipsoid lies in its ball.
        #[test]
        fn the_ball_holds_its_ellipsoid((q, _) in ellipsoid(), dirs in proptest::collection::vec(strategies::ray(1.0), 16)) {
            let ball = Ball::of(&q).expect("an ellipsoid");
            let c = Point3::from(ball.centre);
            for ray in &dirs {
                // The ellipsoid's far point along each direction from the
                // ball's centre, found by the solver itself.
                let probe = Ray::new(c, ray.direction()).expect("valid");
                for iv in q.intervals(&probe, 0).iter() {
                    if iv.exit.t.is_finite() {
                        prop_assert!(iv.exit.t <= ball.radius, "{} beyond {}", iv.exit.t, ball.radius);
                    }
                }
            }
        }

        /// Rays aimed to pass an ellipsoid's ball at distances around its
        /// radius (grazing a sphere's surface within 1e-13 … 1e-2 of it,
        /// either side, beyond the ball's margin of 1e-6 and within it):
        /// the reject answers exactly what the solids do.
        #[test]
        fn the_ball_rejects_only_rays_the_solids_miss(
            (q, size) in ellipsoid(),
            cap in proptest::option::of(-0.5..0.5f64),
            aims in proptest::collection::vec((strategies::ray(1.0), -2.0..2.0f64, prop_oneof![-1e-2..1e-2f64, -1e-4..1e-4f64, -3e-6..3e-6f64, -1e-12..1e-12f64], 1.0..1e4f64), 16),
        ) {
            let mut solids = vec![Solid::from(q)];
            if let Some(h) = cap {
                let c = Ball::of(&q).expect("an ellipsoid").centre;
                solids.push(Solid::from(HalfSpace::new(0.0, 1.0, 0.0, -(c[1] + h * size)).expect("valid")));
            }
            let block = Block::new("b", solids, Opacity::Opaque, MaterialKey(0)).expect("valid");
            let blocks = std::slice::from_ref(&block);
            let kernel = Kernel::new(&[0], blocks, &block_boxes(blocks).1);
            let ball = kernel.slots[0].ball;
            prop_assert!(ball.radius.is_finite());
            for (dir, along, off, back) in &aims {
                // A line at distance `radius · (1 + off)` from the centre.
                let r = dir.direction();
                let side = r.cross(&Vector3::new(0.3, 0.5, 0.7)).try_normalize(1e-6).unwrap_or_else(|| r.cross(&Vector3::x()).normalize());
                let rho = ball.radius * (1.0 + off) / (1.0 + 1e-6);
                let foot = Point3::from(ball.centre) + side * rho + r * (along * size);
                let Ok(ray) = Ray::new(foot - r * (back * size), r) else { continue };
                let mut packed = <SpanBuf as Scratch>::new();
                kernel.spans_into(0, &ray, std::slice::from_ref(&block), &mut packed);
                let plain = block.spans(&ray);
                prop_assert_eq!(packed.as_slice(), plain.as_slice(), "off {}", off);
            }
        }

        /// Every slot answers exactly what its block answers, bit for bit and
        /// solid tags included, in both modes the kernel packs for; and gives
        /// back each solid bit for bit. The blocks are random solids, and
        /// boxes and capped tubes whose opposite faces are packed as slabs
        /// (the axis-aligned ones have normals with zeros of either sign),
        /// near the origin and far from it.
        #[test]
        fn packed_blocks_answer_like_their_blocks(
            blocks in proptest::collection::vec(
                prop_oneof![proptest::collection::vec(strategies::solid(), 1..=5), slab_solids()],
                1..12,
            ),
            order_seed in any::<u64>(),
            rays in proptest::collection::vec(strategies::ray(4.0), 8),
        ) {
            let mut blocks: Vec<Block> = blocks
                .into_iter()
                .map(|s| Block::new("b", s, Opacity::Opaque, MaterialKey(0)).expect("valid"))
                .collect();
            // Any order of the blocks, as a BVH's leaves would give.
            let mut order: Vec<u32> = (0..blocks.len() as u32).collect();
            order.rotate_left((order_seed % blocks.len() as u64) as usize);
            let mut kernel = Kernel::new(&order, &blocks, &block_boxes(&blocks).1);
            // Rays through each block's reference point too, so that far
            // blocks are met.
            let mut rays = rays;
            for b in &blocks {
                if let Some(Solid::HalfSpace(h)) = b.solids().iter().find(|s| s.is_half_space()) {
                    let o = h.reference_point();
                    rays.extend(rays.clone().iter().filter_map(|r| Ray::new(o - r.direction() * 3.0 + (r.origin().coords * 0.1), r.direction()).ok()).take(4));
                }
            }
            for precision in [Precision::Accurate, Precision::Fast] {
                kernel.precision = precision;
                blocks.iter_mut().for_each(|b| b.set_precision(precision));
                for ray in &rays {
                    for k in 0..order.len() as u32 {
                        let id = kernel.block(k);
                        prop_assert_eq!(id, order[k as usize]);
                        let mut packed = <SpanBuf as Scratch>::new();
                        kernel.spans_into(k, ray, &blocks, &mut packed);
                        let plain = blocks[id as usize].spans(ray);
                        prop_assert_eq!(span_bits(&packed), span_bits(&plain), "{:?} slot {} ray {:?}", precision, k, ray);
                    }
                }
            }
            for k in 0..order.len() as u32 {
                let block = &blocks[kernel.block(k) as usize];
                for (i, s) in block.solids().iter().enumerate() {
                    let same = match (kernel.solid(k, i as u32), s) {
                        (Some(SolidRef::HalfSpace(a)), Solid::HalfSpace(b)) => half_space_bits(a) == half_space_bits(b),
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
