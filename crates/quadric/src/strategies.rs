//! Proptest strategies for the kernel's types (cargo feature `proptest`).
//!
//! ```
//! use proptest::prelude::*;
//! use quadric::strategies;
//! proptest!(|(q in strategies::solid(), ray in strategies::ray(10.0))| {
//!     let set = q.intervals(&ray, 0);
//!     prop_assert!(set.is_normalised());
//! });
//! ```

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

use crate::{Bound, HalfSpace, Interval, IntervalSet, Quadric, Ray, Solid, Transform};

/// A finite coordinate in `[-extent, extent]`.
pub fn coordinate(extent: f64) -> impl Strategy<Value = f64> + Clone {
    -extent..=extent
}

/// A point in the cube `[-extent, extent]³`.
pub fn point(extent: f64) -> impl Strategy<Value = Point3<f64>> + Clone {
    (coordinate(extent), coordinate(extent), coordinate(extent)).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// A unit vector, uniform on the sphere.
pub fn unit_vector() -> impl Strategy<Value = Vector3<f64>> + Clone {
    (-1.0f64..=1.0, 0.0f64..core::f64::consts::TAU).prop_map(|(z, phi): (f64, f64)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vector3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

/// A ray with its origin in `[-extent, extent]³` and a uniform direction.
pub fn ray(extent: f64) -> impl Strategy<Value = Ray> + Clone {
    (point(extent), unit_vector()).prop_filter_map("degenerate direction", |(p, d)| Ray::new(p, d).ok())
}

/// A direction that is often axis-aligned or diagonal, with exact zero
/// components of either sign (the `s = 0`, `t = 0` rows of the table and
/// `-0.0` handling), otherwise uniform. Not normalised.
pub fn direction() -> impl Strategy<Value = Vector3<f64>> + Clone {
    let zero = prop_oneof![Just(0.0f64), Just(-0.0f64)];
    let small = prop_oneof![3 => (-2i32..=2).prop_map(f64::from), 1 => zero.clone()];
    prop_oneof![
        unit_vector(),
        (0usize..3, any::<bool>(), zero.clone(), zero).prop_map(|(axis, neg, z1, z2)| {
            let mut v = Vector3::new(z1, z2, z1);
            v[axis] = if neg { -1.0 } else { 1.0 };
            v
        }),
        (small.clone(), small.clone(), small)
            .prop_filter("non-zero", |(x, y, z)| *x != 0.0 || *y != 0.0 || *z != 0.0)
            .prop_map(|(x, y, z)| Vector3::new(x, y, z)),
    ]
}

/// A ray with its origin on the grid of halves in `[-extent, extent]³` and a
/// [`direction`]: rays through centres, along axes, tangent to unit surfaces
/// and lying in them come up often.
pub fn grid_ray(extent: i32) -> impl Strategy<Value = Ray> + Clone {
    let c = (-2 * extent..=2 * extent).prop_map(|i| f64::from(i) / 2.0);
    (c.clone(), c.clone(), c, direction())
        .prop_filter_map("degenerate direction", |(x, y, z, d)| Ray::new(Point3::new(x, y, z), d).ok())
}

/// An exactly representable placement: integer translations, scales by
/// ±2^k (k in -2..=2) per axis, and quarter-turn rotations, so that the
/// moved coefficients are exact and degenerate cases stay degenerate.
pub fn grid_transform() -> impl Strategy<Value = Transform> + Clone {
    let factor = (-2i32..=2, any::<bool>()).prop_map(|(k, neg)| if neg { -(2f64.powi(k)) } else { 2f64.powi(k) });
    let step = prop_oneof![
        (-3i32..=3, -3i32..=3, -3i32..=3).prop_filter_map("finite", |(x, y, z)| {
            Transform::translate(Vector3::new(f64::from(x), f64::from(y), f64::from(z))).ok()
        }),
        (factor.clone(), factor.clone(), factor)
            .prop_filter_map("finite", |(x, y, z)| Transform::scale_xyz(Vector3::new(x, y, z)).ok()),
        (0usize..3, 0i32..4).prop_filter_map("finite", |(axis, k)| {
            let deg = f64::from(90 * k);
            match axis {
                0 => Transform::rotate_x_degrees(deg).ok(),
                1 => Transform::rotate_y_degrees(deg).ok(),
                _ => Transform::rotate_z_degrees(deg).ok(),
            }
        }),
    ];
    proptest::collection::vec(step, 0..4).prop_map(|steps| steps.iter().fold(Transform::identity(), |m, s| m.then(s)))
}

/// An elementary quadric, or a half-space with an axis normal, under a
/// [`grid_transform`], possibly complemented: exact coefficients, so
/// tangent rays and rays in the surface are exactly that.
pub fn grid_solid() -> impl Strategy<Value = Solid> + Clone {
    let plane = (0usize..3, any::<bool>(), -2i32..=2).prop_filter_map("valid", |(axis, neg, d)| {
        let mut n = Vector3::zeros();
        n[axis] = if neg { -1.0 } else { 1.0 };
        HalfSpace::new(n.x, n.y, n.z, f64::from(d)).ok()
    });
    (
        prop_oneof![3 => elementary_quadric().prop_map(Solid::from), 1 => plane.prop_map(Solid::from)],
        grid_transform(),
        any::<bool>(),
    )
        .prop_map(|(q, m, c)| {
            let q = q.transformed(&m);
            if c {
                q.complement()
            } else {
                q
            }
        })
}

/// One elementary step: translation, per-axis scale (factors of magnitude
/// 0.25 … 4, either sign), or a rotation about x, y or z.
pub fn elementary_transform() -> impl Strategy<Value = Transform> + Clone {
    let factor = (0.25f64..4.0, any::<bool>()).prop_map(|(f, neg)| if neg { -f } else { f });
    prop_oneof![
        (coordinate(3.0), coordinate(3.0), coordinate(3.0))
            .prop_filter_map("finite", |(x, y, z)| Transform::translate(Vector3::new(x, y, z)).ok()),
        (factor.clone(), factor.clone(), factor)
            .prop_filter_map("finite", |(x, y, z)| Transform::scale_xyz(Vector3::new(x, y, z)).ok()),
        (0usize..3, -360.0f64..360.0).prop_filter_map("finite", |(axis, deg)| match axis {
            0 => Transform::rotate_x_degrees(deg).ok(),
            1 => Transform::rotate_y_degrees(deg).ok(),
            _ => Transform::rotate_z_degrees(deg).ok(),
        }),
    ]
}

/// A composition of up to four elementary steps.
pub fn transform() -> impl Strategy<Value = Transform> + Clone {
    proptest::collection::vec(elementary_transform(), 0..=4)
        .prop_map(|steps| steps.iter().fold(Transform::identity(), |m, s| m.then(s)))
}

/// One of the elementary quadrics in its unit frame.
pub fn elementary_quadric() -> impl Strategy<Value = Quadric> + Clone {
    prop_oneof![
        Just(Quadric::sphere()),
        Just(Quadric::tube_x()),
        Just(Quadric::tube_y()),
        Just(Quadric::tube_z()),
        Just(Quadric::cone()),
        Just(Quadric::paraboloid()),
        Just(Quadric::hyperboloid_one_sheet()),
        Just(Quadric::hyperboloid_two_sheets()),
    ]
}

/// A quadric from ten random coefficients in `[-2, 2]` (any type: ellipsoids,
/// hyperboloids, degenerate pairs of planes …).
pub fn raw_quadric() -> impl Strategy<Value = Quadric> + Clone {
    proptest::array::uniform10(-2.0f64..2.0).prop_filter_map("finite", |c| Quadric::from_coefficients(c).ok())
}

/// An elementary or raw quadric, possibly complemented, under a random transform.
pub fn quadric() -> impl Strategy<Value = Quadric> + Clone {
    (prop_oneof![3 => elementary_quadric(), 1 => raw_quadric()], transform(), any::<bool>()).prop_map(|(q, m, c)| {
        let q = q.transformed(&m);
        if c {
            q.complement()
        } else {
            q
        }
    })
}

/// A half-space with a random normal through a point in `[-2, 2]³`.
pub fn half_space() -> impl Strategy<Value = HalfSpace> + Clone {
    (unit_vector(), point(2.0))
        .prop_filter_map("zero normal", |(n, p)| HalfSpace::new(n.x, n.y, n.z, -n.dot(&p.coords)).ok())
}

/// A quadric or a half-space.
pub fn solid() -> impl Strategy<Value = Solid> + Clone {
    prop_oneof![3 => quadric().prop_map(Solid::from), 1 => half_space().prop_map(Solid::from)]
}

/// A normalised interval set of up to `max` intervals with ends in
/// `[-10, 10]`, the first possibly starting at `-∞` and the last possibly
/// ending at `+∞`. Ends are drawn from a coarse grid so that coincident ends
/// (the hard case for set laws) are common.
pub fn interval_set(max: usize) -> impl Strategy<Value = IntervalSet> + Clone {
    let max = max.min(IntervalSet::CAPACITY);
    (proptest::collection::vec(-40i32..=40, 0..=2 * max), any::<bool>(), any::<bool>(), 0u32..4).prop_map(
        move |(mut ends, open_low, open_high, solid)| {
            ends.sort_unstable();
            ends.dedup();
            let mut ts: Vec<f64> = ends.iter().map(|&e| f64::from(e) / 4.0).collect();
            if open_low {
                ts.insert(0, f64::NEG_INFINITY);
            }
            if open_high {
                ts.push(f64::INFINITY);
            }
            let intervals =
                ts.chunks_exact(2).take(max).map(|w| Interval::new(Bound::new(w[0], solid), Bound::new(w[1], solid)));
            IntervalSet::from_intervals(intervals).unwrap_or_default()
        },
    )
}
