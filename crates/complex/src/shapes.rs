//! Constructors for common shapes, as the solids of a block: a box, a ball,
//! an ellipsoid, a capped cylinder and a cone frustum between two points,
//! instead of half-spaces and transforms written by hand. Each checks its
//! input and returns a [`ShapeError`] for a degenerate or non-finite one.
//!
//! ```
//! use complex::{shapes, Block, MaterialKey, Opacity};
//! use quadric::nalgebra::{Point3, Vector3};
//! // A rod from (0, 0, 0) to (0, 0, 4) of radius 0.5, and a box around its middle.
//! let rod = shapes::capped_cylinder(Point3::origin(), Point3::new(0.0, 0.0, 4.0), 0.5).unwrap();
//! let rod = Block::new("rod", rod, Opacity::Opaque, MaterialKey(0)).unwrap();
//! assert!(rod.contains_point(&Point3::new(0.4, 0.0, 3.9)));
//! assert!(!rod.contains_point(&Point3::new(0.0, 0.0, 4.1)));
//! let case = shapes::cuboid(Point3::new(-1.0, -1.0, 1.0), Point3::new(1.0, 1.0, 3.0)).unwrap();
//! assert_eq!(case.len(), 6);
//! assert!(shapes::sphere(Point3::origin(), 0.0).is_err());
//! assert!(shapes::capped_cylinder(Point3::origin(), Point3::origin(), 1.0).is_err());
//! ```

use quadric::nalgebra::{Matrix4, Point3, Vector3};
use quadric::{GeometryError, HalfSpace, Quadric, Solid, Transform};

/// Why a shape could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A coordinate or size that is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A radius or extent that must be positive is not.
    #[error("{what} must be > 0, got {value}")]
    NotPositive {
        /// Which input.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// The two points that set an axis or a box coincide (on some axis, for
    /// a box).
    #[error("{what}")]
    Degenerate {
        /// What is degenerate.
        what: &'static str,
    },
    /// Placing the solid failed: it underflows or overflows the doubles
    /// (a ball of radius `1e170`, say).
    #[error(transparent)]
    Geometry(#[from] GeometryError),
}

fn finite_point(p: &Point3<f64>, what: &'static str) -> Result<(), ShapeError> {
    if p.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(ShapeError::NonFinite { what })
    }
}

fn positive(value: f64, what: &'static str) -> Result<f64, ShapeError> {
    if !value.is_finite() {
        return Err(ShapeError::NonFinite { what });
    }
    if value > 0.0 {
        Ok(value)
    } else {
        Err(ShapeError::NotPositive { what, value })
    }
}

/// `n·x <= n·p`: the half-space behind the plane through `p` with outward normal `n`.
fn behind(n: &Vector3<f64>, p: &Point3<f64>) -> Result<Solid, ShapeError> {
    Ok(Solid::from(HalfSpace::new(n.x, n.y, n.z, -n.dot(&p.coords))?))
}

/// The axis-aligned box `[min, max]`: six half-spaces, in the order
/// `x >= min.x`, `x <= max.x`, `y >= min.y`, `y <= max.y`, `z >= min.z`,
/// `z <= max.z` (a hit on a face reports that index).
pub fn cuboid(min: Point3<f64>, max: Point3<f64>) -> Result<Vec<Solid>, ShapeError> {
    finite_point(&min, "cuboid min")?;
    finite_point(&max, "cuboid max")?;
    if (0..3).any(|k| min[k] >= max[k]) {
        return Err(ShapeError::Degenerate { what: "cuboid: min must be below max on every axis" });
    }
    let mut solids = Vec::with_capacity(6);
    for k in 0..3 {
        let mut n = Vector3::zeros();
        n[k] = 1.0;
        solids.push(Solid::from(HalfSpace::new(-n.x, -n.y, -n.z, min[k])?));
        solids.push(Solid::from(HalfSpace::new(n.x, n.y, n.z, -max[k])?));
    }
    Ok(solids)
}

/// The ball of `radius` around `center` (the unit sphere scaled, then
/// moved: the placement `komplex`'s scene format uses).
pub fn sphere(center: Point3<f64>, radius: f64) -> Result<Solid, ShapeError> {
    finite_point(&center, "sphere center")?;
    let r = positive(radius, "sphere radius")?;
    let m = Transform::scale(r)?.then(&Transform::translate(center.coords)?);
    Ok(Solid::from(Quadric::sphere().try_transformed(&m)?))
}

/// The solid ellipsoid with semi-axes `radii` along x, y and z around `center`.
pub fn ellipsoid(center: Point3<f64>, radii: Vector3<f64>) -> Result<Solid, ShapeError> {
    finite_point(&center, "ellipsoid center")?;
    for k in 0..3 {
        positive(radii[k], "ellipsoid radius")?;
    }
    let m = Transform::scale_xyz(radii)?.then(&Transform::translate(center.coords)?);
    Ok(Solid::from(Quadric::sphere().try_transformed(&m)?))
}

/// A rigid motion taking the y axis to the line through `a` along the unit
/// vector `d` (and the origin to `a`).
fn onto_axis(a: &Point3<f64>, d: &Vector3<f64>) -> Result<Transform, ShapeError> {
    // A unit vector across `d`, from the axis `d` is least along.
    let k = (0..3).min_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs())).unwrap_or(0);
    let mut e = Vector3::zeros();
    e[k] = 1.0;
    let u = d.cross(&e).normalize();
    let w = u.cross(d);
    #[rustfmt::skip]
    let m = Matrix4::new(
        u.x, d.x, w.x, a.x,
        u.y, d.y, w.y, a.y,
        u.z, d.z, w.z, a.z,
        0.0, 0.0, 0.0, 1.0,
    );
    Ok(Transform::from_matrix(&m)?)
}

/// The unit axis from `a` to `b` and its length.
fn axis(a: &Point3<f64>, b: &Point3<f64>, what: &'static str) -> Result<(Vector3<f64>, f64), ShapeError> {
    finite_point(a, what)?;
    finite_point(b, what)?;
    let v = b - a;
    let length = v.norm();
    if !(length > 0.0 && length.is_finite()) {
        return Err(ShapeError::Degenerate { what });
    }
    Ok((v / length, length))
}

/// The cylinder of `radius` around the segment from `a` to `b`, capped by
/// the planes through `a` and `b` at right angles to it: the infinite tube,
/// then the cap at `b`, then the cap at `a`.
pub fn capped_cylinder(a: Point3<f64>, b: Point3<f64>, radius: f64) -> Result<Vec<Solid>, ShapeError> {
    let (d, _) = axis(&a, &b, "capped cylinder: the two ends must differ (and be finite)")?;
    let r = positive(radius, "cylinder radius")?;
    let m = Transform::scale_xyz(Vector3::new(r, 1.0, r))?.then(&onto_axis(&a, &d)?);
    let tube = Solid::from(Quadric::tube_y().try_transformed(&m)?);
    Ok(vec![tube, behind(&d, &b)?, behind(&-d, &a)?])
}

/// The cone frustum around the segment from `a` to `b`, of radius `radius_a`
/// at `a` and `radius_b` at `b` (one of them may be 0: a cone with its tip
/// there), capped at both ends: the double cone through the two rims, then
/// the cap at `b`, then the cap at `a`. Equal radii give
/// [`capped_cylinder`].
pub fn frustum(a: Point3<f64>, b: Point3<f64>, radius_a: f64, radius_b: f64) -> Result<Vec<Solid>, ShapeError> {
    let (d, length) = axis(&a, &b, "frustum: the two ends must differ (and be finite)")?;
    for (r, what) in [(radius_a, "frustum radius_a"), (radius_b, "frustum radius_b")] {
        if !r.is_finite() {
            return Err(ShapeError::NonFinite { what });
        }
        if r < 0.0 {
            return Err(ShapeError::NotPositive { what, value: r });
        }
    }
    if radius_a == radius_b {
        return capped_cylinder(a, b, positive(radius_a, "frustum radius")?);
    }
    // The radius grows by `slope` per unit along the axis; the apex is
    // where it reaches 0.
    let slope = (radius_b - radius_a) / length;
    let apex = a - d * (radius_a / slope);
    let m = Transform::scale_xyz(Vector3::new(1.0, 1.0 / slope.abs(), 1.0))?.then(&onto_axis(&apex, &d)?);
    let cone = Solid::from(Quadric::cone().try_transformed(&m)?);
    Ok(vec![cone, behind(&d, &b)?, behind(&-d, &a)?])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Block, MaterialKey, Opacity};

    /// A tiny deterministic generator (xorshift), for sample points.
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        fn point(&mut self, r: f64) -> Point3<f64> {
            Point3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
        }
    }

    /// `solids` as a block against `margin`, an analytic signed distance-like
    /// margin (positive inside), at random points in a box of half-width
    /// `r` around `centre`; points within `1e-9` of the boundary are skipped. Returns how
    /// many points were inside (so a test can see both sides were met).
    fn agree(
        solids: Vec<Solid>,
        (centre, r): (Point3<f64>, f64),
        rng: &mut Rng,
        margin: impl Fn(&Point3<f64>) -> f64,
    ) -> usize {
        let block = Block::new("shape", solids, Opacity::Opaque, MaterialKey(0)).expect("valid");
        let mut inside = 0;
        for _ in 0..4000 {
            let p = centre + rng.point(r).coords;
            let m = margin(&p);
            if m.abs() < 1e-9 {
                continue;
            }
            assert_eq!(block.contains_point(&p), m > 0.0, "{p:?}, margin {m}");
            inside += usize::from(m > 0.0);
        }
        assert!((20..=3980).contains(&inside), "{inside} of 4000 points inside: the samples miss a side");
        inside
    }

    /// The distance of `p` from the line through `a` along unit `d`, and
    /// its coordinate along it.
    fn radial(p: &Point3<f64>, a: &Point3<f64>, d: &Vector3<f64>) -> (f64, f64) {
        let v = p - a;
        let s = v.dot(d);
        ((v - d * s).norm(), s)
    }

    #[test]
    fn constructors_match_analytic_membership() {
        let mut rng = Rng(0x5EED_1234_5678_9ABC);
        for _ in 0..5 {
            let (lo, hi) = (rng.point(1.0), rng.point(1.0));
            let (min, max) = (lo.inf(&hi) - Vector3::repeat(0.3), lo.sup(&hi) + Vector3::repeat(0.3));
            let o = Point3::origin();
            agree(cuboid(min, max).expect("valid"), (o, 2.0), &mut rng, |p| {
                (0..3).map(|k| (p[k] - min[k]).min(max[k] - p[k])).fold(f64::INFINITY, f64::min)
            });
            let (c, r) = (rng.point(0.5), rng.range(0.5, 1.5));
            agree(vec![sphere(c, r).expect("valid")], (o, 2.0), &mut rng, |p| r - (p - c).norm());
            let radii = Vector3::new(rng.range(0.3, 1.5), rng.range(0.3, 1.5), rng.range(0.3, 1.5));
            agree(vec![ellipsoid(c, radii).expect("valid")], (o, 2.0), &mut rng, |p| {
                1.0 - (p - c).component_div(&radii).norm_squared()
            });
            let a = rng.point(1.0);
            let b = a + rng.point(1.0).coords.normalize() * rng.range(0.5, 2.0);
            let (d, length) = ((b - a).normalize(), (b - a).norm());
            let around = (a + (b - a) / 2.0, length / 2.0 + 1.2);
            let r = rng.range(0.3, 0.8);
            agree(capped_cylinder(a, b, r).expect("valid"), around, &mut rng, |p| {
                let (rho, s) = radial(p, &a, &d);
                (r - rho).min(s).min(length - s)
            });
            let (ra, rb) = (rng.range(0.0, 1.0), rng.range(0.4, 1.0));
            agree(frustum(a, b, ra, rb).expect("valid"), around, &mut rng, |p| {
                let (rho, s) = radial(p, &a, &d);
                // Distance-like: the radius at `s` minus the distance, scaled
                // to stay comparable where the cone is steep.
                let at = ra + (rb - ra) * s / length;
                ((at - rho) / (1.0 + ((rb - ra) / length).powi(2)).sqrt()).min(s).min(length - s)
            });
        }
    }

    #[test]
    fn degenerate_input_is_refused() {
        let o = Point3::origin();
        let x = Point3::new(1.0, 0.0, 0.0);
        let nan = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(matches!(cuboid(o, Point3::new(1.0, 0.0, 1.0)), Err(ShapeError::Degenerate { .. })));
        assert!(matches!(cuboid(nan, x), Err(ShapeError::NonFinite { .. })));
        assert!(matches!(sphere(o, -1.0), Err(ShapeError::NotPositive { .. })));
        assert!(matches!(sphere(o, f64::INFINITY), Err(ShapeError::NonFinite { .. })));
        assert!(matches!(sphere(o, 1e170), Err(ShapeError::Geometry(GeometryError::Underflow { .. }))));
        assert!(sphere(o, 1e-170).is_err());
        assert!(matches!(ellipsoid(o, Vector3::new(1.0, 0.0, 1.0)), Err(ShapeError::NotPositive { .. })));
        assert!(matches!(capped_cylinder(x, x, 1.0), Err(ShapeError::Degenerate { .. })));
        assert!(matches!(capped_cylinder(o, x, 0.0), Err(ShapeError::NotPositive { .. })));
        assert!(matches!(frustum(o, x, 0.0, 0.0), Err(ShapeError::NotPositive { .. })));
        assert!(matches!(frustum(o, x, -1.0, 1.0), Err(ShapeError::NotPositive { .. })));
        assert!(matches!(frustum(o, nan, 1.0, 2.0), Err(ShapeError::NonFinite { .. })));
        // Equal radii: the capped cylinder.
        assert_eq!(frustum(o, x, 0.5, 0.5), capped_cylinder(o, x, 0.5));
    }
}
