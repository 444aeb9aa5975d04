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
