//! The table of docs/model.md §3.8: a top and four legs, the union of five blocks.

use complex::Complex;
use quadric::nalgebra::Point3;

use crate::common::*;

const LEGS: [(f64, f64); 4] = [(-0.9, -0.5), (0.9, -0.5), (-0.9, 0.5), (0.9, 0.5)];

/// The top `[-1, 1] × [0.95, 1] × [-0.6, 0.6]` and legs of radius 0.05 from
/// the floor `y = 0` to the top, at `x = ±0.9`, `z = ±0.5`.
pub fn table() -> Complex {
    let mut blocks = vec![block("top", cuboid([-1.0, 0.95, -0.6], [1.0, 1.0, 0.6]), O, 0)];
    for (i, (x, z)) in LEGS.iter().enumerate() {
        blocks.push(block(&format!("leg{i}"), post(*x, *z, 0.05, 0.0, 0.95), O, 1));
    }
    complex(blocks)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-7 * (1.0 + b.abs())
}

/// Casts a ray and checks the hit's distance, block and outward normal.
fn check(o: [f64; 3], d: [f64; 3], expected: Option<(f64, &str, [f64; 3])>) {
    let c = table();
    let got = c.cast_ray(&ray(o, d), f64::INFINITY);
    match (got, expected) {
        (None, None) => {}
        (Some(h), Some((t, block, n))) => {
            assert!(close(h.t, t), "t {} != {t}", h.t);
            assert_eq!(name(&c, h.block), block);
            assert!((0..3).all(|i| close(h.normal[i], n[i])), "normal {:?} != {n:?}", h.normal);
            assert!(h.entering);
        }
        (got, expected) => panic!("ray {o:?} {d:?}: got {got:?}, expected {expected:?}"),
    }
}

#[test]
fn rays_hit_the_top_the_legs_or_nothing() {
    check([0.0, 3.0, 0.0], [0.0, -1.0, 0.0], Some((2.0, "top", [0.0, 1.0, 0.0])));
    check([0.0, 0.97, 3.0], [0.0, 0.0, -1.0], Some((2.4, "top", [0.0, 0.0, 1.0])));
    // From the side at mid height, through the legs at z = 0.5.
    check([-3.0, 0.5, 0.5], [1.0, 0.0, 0.0], Some((2.05, "leg2", [-1.0, 0.0, 0.0])));
    check([3.0, 0.5, -0.5], [-1.0, 0.0, 0.0], Some((2.05, "leg1", [1.0, 0.0, 0.0])));
    // Between the legs under the top: nothing.
    check([-3.0, 0.5, 0.0], [1.0, 0.0, 0.0], None);
    // From below the floor, up into a leg's bottom cap.
    check([0.9, -1.0, 0.5], [0.0, 1.0, 0.0], Some((1.0, "leg3", [0.0, -1.0, 0.0])));
    // Looking away from the table.
    check([0.0, 3.0, 0.0], [0.0, 1.0, 0.0], None);
}

#[test]
fn points_belong_to_the_top_or_a_leg() {
    let c = table();
    let owner = |p: [f64; 3]| c.contains_point(&Point3::new(p[0], p[1], p[2])).map(|id| name(&c, id).to_owned());
    assert_eq!(owner([0.0, 0.97, 0.0]).as_deref(), Some("top"));
    assert_eq!(owner([0.9, 0.4, 0.5]).as_deref(), Some("leg3"));
    assert_eq!(owner([0.0, 0.5, 0.0]), None);
    assert_eq!(owner([0.9, 1.1, 0.5]), None);
}

#[test]
fn the_table_has_a_tight_box() {
    let c = table();
    let b = c.aabb();
    let (min, max) = ([-1.0, 0.0, -0.6], [1.0, 1.0, 0.6]);
    assert!((0..3).all(|i| close(b.min[i], min[i]) && close(b.max[i], max[i])), "{b:?}");
    let leg = c.block_aabb(complex::BlockId(4));
    assert!(close(leg.min.x, 0.85) && close(leg.max.x, 0.95) && close(leg.min.z, 0.45) && close(leg.max.z, 0.55));
    assert!(close(leg.min.y, 0.0) && close(leg.max.y, 0.95), "{leg:?}");
}
