//! Rays `p + λ r` with a unit direction, so that `λ` is a distance.

use nalgebra::{Point3, Vector3};

use crate::GeometryError;

/// A ray `origin + λ · direction`, `λ >= 0`, with `|direction| = 1`.
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use quadric::Ray;
/// let ray = Ray::new(Point3::origin(), Vector3::new(0.0, 0.0, -2.0)).unwrap();
/// assert_eq!(ray.at(3.0), Point3::new(0.0, 0.0, -3.0));
/// assert!(Ray::new(Point3::origin(), Vector3::zeros()).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    origin: Point3<f64>,
    direction: Vector3<f64>,
}

impl Ray {
    /// How far from 1 `|r|²` may be for [`Ray::new_unit`] to keep `r`: 16
    /// ulps of 1. A vector divided by its computed length has `|r|²` within
    /// a few ulps of 1 (each component rounded twice, the sum of squares
    /// three times), as [`Ray::new`]'s result has.
    pub const UNIT_TOLERANCE: f64 = 16.0 * f64::EPSILON;

    /// A ray from `origin` along `direction`, which is normalised.
    ///
    /// Errors if either is not finite or the direction is zero.
    pub fn new(origin: Point3<f64>, direction: Vector3<f64>) -> Result<Self, GeometryError> {
        if !origin.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the ray origin" });
        }
        if !direction.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the ray direction" });
        }
        // Scale first so that tiny or huge directions normalise without
        // underflow or overflow.
        let m = direction.amax();
        if m == 0.0 {
            return Err(GeometryError::ZeroDirection);
        }
        let d = crate::lanes::div(&direction, m);
        Ok(Ray { origin, direction: crate::lanes::div(&d, d.norm()) })
    }

    /// Four rays from one `origin` (a camera's neighbouring pixels), each
    /// exactly `Ray::new(origin, directions[k])`: the four normalisations
    /// run lane by lane in four-wide instructions, one chain of two
    /// divisions and a square root for all four instead of four chains
    /// (the longest-latency work of a camera ray's setup). Each lane does
    /// `new`'s operations in `new`'s order, and IEEE 754 rounds each lane
    /// as it rounds a scalar, so the rays are the same bit for bit.
    ///
    /// Errors per ray like [`Ray::new`].
    ///
    /// ```
    /// use nalgebra::{Point3, Vector3};
    /// use quadric::Ray;
    /// let o = Point3::new(1.0, 2.0, 3.0);
    /// let d = [Vector3::new(1.0, 2.0, -2.0), Vector3::x(), Vector3::new(0.3, -0.1, 7.0), Vector3::zeros()];
    /// let rays = Ray::new4(o, &d);
    /// for k in 0..4 {
    ///     assert_eq!(rays[k], Ray::new(o, d[k]));
    /// }
    /// ```
    pub fn new4(origin: Point3<f64>, directions: &[Vector3<f64>; 4]) -> [Result<Self, GeometryError>; 4] {
        use wide::f64x4;
        let m = directions.map(|d| d.amax());
        let finite = origin.iter().chain(directions.iter().flat_map(|d| d.iter())).all(|c| c.is_finite());
        // A zero or non-finite direction (never a camera's): the scalar
        // path, with its errors.
        if !finite || m.contains(&0.0) {
            return directions.map(|d| Ray::new(origin, d));
        }
        let lane = |i: usize| f64x4::new(directions.map(|d| d[i]));
        let m = f64x4::new(m);
        let (x, y, z) = (lane(0) / m, lane(1) / m, lane(2) / m);
        // `Vector3::norm`: `sqrt((x² + y²) + z²)`, no fused operations.
        let n = (x * x + y * y + z * z).sqrt();
        let (x, y, z) = ((x / n).to_array(), (y / n).to_array(), (z / n).to_array());
        [0, 1, 2, 3].map(|k| Ok(Ray { origin, direction: Vector3::new(x[k], y[k], z[k]) }))
    }

    /// A ray along a direction the caller has already normalised (a light
    /// direction `v / |v|`): kept as it is where `|direction|²` is 1 to
    /// within [`Ray::UNIT_TOLERANCE`], which saves [`Ray::new`]'s two divisions
    /// and square root (a long chain ahead of every secondary ray); any other
    /// direction is normalised as `new` does. Either way the direction is
    /// a unit vector to within a few ulps, as `new`'s is.
    ///
    /// Errors like [`Ray::new`].
    ///
    /// ```
    /// use nalgebra::{Point3, Vector3};
    /// use quadric::Ray;
    /// let v = Vector3::new(1.0, 2.0, -2.0);
    /// let unit = v / v.norm();
    /// assert_eq!(Ray::new_unit(Point3::origin(), unit).unwrap().direction(), unit);
    /// // Not a unit vector: normalised.
    /// assert_eq!(Ray::new_unit(Point3::origin(), v).unwrap(), Ray::new(Point3::origin(), v).unwrap());
    /// ```
    #[inline]
    pub fn new_unit(origin: Point3<f64>, direction: Vector3<f64>) -> Result<Self, GeometryError> {
        let square = direction.norm_squared();
        // Also false for a NaN or infinite component (their square is not
        // near 1), which `new` then reports.
        if (square - 1.0).abs() <= Self::UNIT_TOLERANCE && origin.iter().all(|c| c.is_finite()) {
            return Ok(Ray { origin, direction });
        }
        Ray::new(origin, direction)
    }

    /// The ray origin `p`.
    #[inline]
    pub fn origin(&self) -> Point3<f64> {
        self.origin
    }

    /// The unit direction `r`.
    #[inline]
    pub fn direction(&self) -> Vector3<f64> {
        self.direction
    }

    /// The point `p + λ r`.
    #[inline]
    pub fn at(&self, lambda: f64) -> Point3<f64> {
        Point3::new(
            lambda.mul_add(self.direction.x, self.origin.x),
            lambda.mul_add(self.direction.y, self.origin.y),
            lambda.mul_add(self.direction.z, self.origin.z),
        )
    }

    /// The same line traversed the other way, starting at `at(lambda)`.
    ///
    /// `lambda` must be finite and small enough for `at(lambda)` to be
    /// finite; [`try_reversed_at`](Self::try_reversed_at) checks that.
    pub fn reversed_at(&self, lambda: f64) -> Ray {
        Ray { origin: self.at(lambda), direction: -self.direction }
    }

    /// [`reversed_at`](Self::reversed_at), checked: an error if the new
    /// origin `at(lambda)` is not finite.
    ///
    /// ```
    /// use nalgebra::{Point3, Vector3};
    /// use quadric::Ray;
    /// let ray = Ray::new(Point3::origin(), Vector3::x()).unwrap();
    /// assert_eq!(ray.try_reversed_at(2.0).unwrap().origin(), Point3::new(2.0, 0.0, 0.0));
    /// assert!(ray.try_reversed_at(f64::INFINITY).is_err());
    /// ```
    pub fn try_reversed_at(&self, lambda: f64) -> Result<Ray, GeometryError> {
        let origin = self.at(lambda);
        if !origin.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the reversed ray's origin" });
        }
        Ok(Ray { origin, direction: -self.direction })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn component() -> impl Strategy<Value = f64> {
        prop_oneof![-1e3..1e3f64, -1e-150..1e-150f64, -1e150..1e150f64, Just(0.0)]
    }

    proptest! {
        /// A normalised direction is kept bit for bit; any other is
        /// normalised exactly as `Ray::new` does; both are unit vectors.
        #[test]
        fn new_unit_keeps_unit_vectors_and_normalises_the_rest(
            x in component(), y in component(), z in component(), o in prop::array::uniform3(-1e9..1e9f64),
        ) {
            let (o, v) = (Point3::from(o), Vector3::new(x, y, z));
            prop_assume!(v.amax() > 0.0);
            let plain = Ray::new(o, v).expect("a finite, nonzero direction");
            let unit = plain.direction();
            prop_assert_eq!(Ray::new_unit(o, unit).expect("a unit direction").direction(), unit);
            let scaled = Ray::new_unit(o, v).expect("a finite, nonzero direction");
            if (v.norm_squared() - 1.0).abs() > Ray::UNIT_TOLERANCE {
                prop_assert_eq!(scaled, plain);
            }
            prop_assert!((scaled.direction().norm() - 1.0).abs() <= 8.0 * f64::EPSILON);
        }
    }

    proptest! {
        /// Four rays at once are `Ray::new`'s four, bit for bit (and its
        /// errors, for a zero or non-finite lane).
        #[test]
        fn new4_is_new_four_times(
            d in prop::array::uniform4(prop::array::uniform3(component())),
            o in prop::array::uniform3(-1e9..1e9f64),
            bad in 0..6usize,
        ) {
            let o = Point3::from(o);
            let mut d = d.map(Vector3::from);
            if bad == 4 {
                d[1] = Vector3::new(0.0, f64::NAN, 1.0);
            }
            for (k, ray) in Ray::new4(o, &d).into_iter().enumerate() {
                let want = Ray::new(o, d[k]);
                match (&ray, &want) {
                    (Ok(a), Ok(b)) => {
                        let bits = |r: &Ray| r.direction().map(f64::to_bits);
                        prop_assert_eq!(bits(a), bits(b));
                        prop_assert_eq!(a.origin(), b.origin());
                    }
                    _ => prop_assert_eq!(ray, want),
                }
            }
            if bad == 5 {
                let far = Point3::new(f64::INFINITY, 0.0, 0.0);
                prop_assert!(Ray::new4(far, &d).iter().all(Result::is_err));
            }
        }
    }

    #[test]
    fn new_unit_rejects_what_new_rejects() {
        let o = Point3::origin();
        assert_eq!(Ray::new_unit(o, Vector3::zeros()), Err(GeometryError::ZeroDirection));
        assert!(Ray::new_unit(o, Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
        assert!(Ray::new_unit(o, Vector3::new(1.0, f64::INFINITY, 0.0)).is_err());
        assert!(Ray::new_unit(Point3::new(f64::INFINITY, 0.0, 0.0), Vector3::x()).is_err());
    }
}
