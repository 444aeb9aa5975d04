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
use crate::bounds::Ball;
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
    /// A ball holding the block, for a cheap reject (see [`Ball`]).
    ball: Ball,
}

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
    half_spaces: Vec<HalfSpace>,
    quadrics: Vec<Quadric>,
    /// The precision mode of every query (`Complex::set_precision`).
    pub(crate) precision: Precision,
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
        // grid's 28 MB of solids took 107 MB of allocations (fresh pages and
        // a copy each time).
        let (mut half_spaces, mut quadrics) = (0, 0);
        for &id in order {
            let block = &blocks[id as usize];
            if packed(block) {
                let q = block.solids().iter().filter(|s| matches!(s, Solid::Quadric(_))).count();
                quadrics += q;
                half_spaces += block.solids().len() - q;
            }
        }
        let mut kernel = Kernel {
            slots: Vec::with_capacity(order.len()),
            half_spaces: Vec::with_capacity(half_spaces),
            quadrics: Vec::with_capacity(quadrics),
            ..Kernel::default()
        };
        for &id in order {
            let block = &blocks[id as usize];
            let solids = block.solids();
            let mut slot = Slot {
                block: id,
                half_space: kernel.half_spaces.len() as u32,
                quadric: kernel.quadrics.len() as u32,
                quadric_mask: 0,
                count: 0,
                ball: Ball::NONE,
            };
            if packed(block) {
                for (i, s) in solids.iter().enumerate() {
                    match s {
                        Solid::HalfSpace(h) => kernel.half_spaces.push(*h),
                        Solid::Quadric(q) => {
                            kernel.quadrics.push(*q);
                            slot.quadric_mask |= 1 << i;
                            if slot.ball.radius == f64::INFINITY {
                                slot.ball = Ball::of(q).unwrap_or(Ball::NONE);
                            }
                        }
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
        let slot = &self.slots[k as usize];
        if slot.count > 0 {
            if slot.ball.radius < f64::INFINITY && self.precision == Precision::Accurate && slot.ball.missed_by(ray) {
                *out = Spans::Empty;
                return;
            }
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
    use quadric::nalgebra::{Point3, Vector3};
    use quadric::{strategies, Transform};

    use super::*;
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
                let mut packed = Spans::Empty;
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
                let mut packed = Spans::Empty;
                kernel.spans_into(0, &ray, std::slice::from_ref(&block), &mut packed);
                let plain = block.spans(&ray);
                prop_assert_eq!(packed.as_slice(), plain.as_slice(), "off {}", off);
            }
        }

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
            let kernel = Kernel::new(&order, &blocks, &block_boxes(&blocks).1);
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
