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

    #[test]
    fn new_unit_rejects_what_new_rejects() {
        let o = Point3::origin();
        assert_eq!(Ray::new_unit(o, Vector3::zeros()), Err(GeometryError::ZeroDirection));
        assert!(Ray::new_unit(o, Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
        assert!(Ray::new_unit(o, Vector3::new(1.0, f64::INFINITY, 0.0)).is_err());
        assert!(Ray::new_unit(Point3::new(f64::INFINITY, 0.0, 0.0), Vector3::x()).is_err());
    }
}
