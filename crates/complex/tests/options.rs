//! Building a complex: its options take effect from the start, and a
//! complex of no blocks is a well-formed empty one.

use complex::{Complex, ComplexOptions};
use quadric::nalgebra::Point3;
use quadric::{Precision, Quadric, Solid, Transform};

use crate::common::*;

/// Overlapping balls and a box, opaque and transparent.
fn blocks() -> Vec<complex::Block> {
    let ball = |x: f64| {
        let m = Transform::scale(0.7).expect("finite").then(&translate(x, 0.0, 0.0));
        vec![Solid::from(Quadric::sphere().transformed(&m))]
    };
    vec![
        block("a", ball(0.0), T, 1),
        block("b", ball(0.5), O, 2),
        block("c", cuboid([-0.2, -1.0, -1.0], [0.2, 1.0, 1.0]), T, 3),
    ]
}

#[test]
fn the_precision_option_is_the_precision_set_after_building() {
    for precision in [Precision::Fast, Precision::Accurate, Precision::Certified] {
        let built = Complex::new(blocks(), ComplexOptions { precision, ..Default::default() }).expect("valid");
        let mut set = complex(blocks());
        set.set_precision(precision);
        assert_eq!(built.precision(), precision);
        for k in 0..200 {
            let a = f64::from(k) * 0.1;
            let r = ray([3.0 * a.cos(), 0.3 * a.sin(), 2.0 * a.sin()], [-a.cos(), 0.01 * f64::from(k % 7), -a.sin()]);
            assert_eq!(built.cast_ray(&r, f64::INFINITY), set.cast_ray(&r, f64::INFINITY), "{precision:?} ray {k}");
            assert_eq!(built.partition(&r), set.partition(&r), "{precision:?} ray {k}");
        }
    }
}

#[test]
fn a_complex_of_no_blocks_is_empty_everywhere() {
    let c = Complex::new(Vec::new(), ComplexOptions::default()).expect("an empty complex is valid");
    assert!(c.aabb().is_empty());
    assert_eq!(c.aabb().center(), None);
    assert!(c.epsilon().is_finite() && c.epsilon() > 0.0);
    let r = ray([0.0, 0.0, 5.0], [0.0, 0.0, -1.0]);
    assert_eq!(c.cast_ray(&r, f64::INFINITY), None);
    assert!(!c.occluded(&r, f64::INFINITY));
    assert_eq!(c.contains_point(&Point3::origin()), None);
    let p = c.partition(&r);
    assert!(p.events.is_empty());
    assert!(p.segments.iter().all(|s| s.owner.is_none()), "{:?}", p.segments);
}
