//! Axis-aligned boxes, possibly infinite.

use quadric::nalgebra::Point3;
use quadric::Ray;

/// An axis-aligned box `[min, max]`; coordinates may be `±∞` for unbounded blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lower corner.
    pub min: Point3<f64>,
    /// The upper corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// The box covering all of space.
    pub const INFINITE: Aabb = Aabb {
        min: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        max: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
    };

    /// The empty box.
    pub const EMPTY: Aabb = Aabb {
        min: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        max: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    };

    /// Whether the box is empty.
    pub fn is_empty(&self) -> bool {
        (0..3).any(|i| self.min[i] > self.max[i])
    }

    /// Whether every coordinate is finite (and the box is not empty).
    pub fn is_bounded(&self) -> bool {
        !self.is_empty() && self.min.iter().chain(self.max.iter()).all(|c| c.is_finite())
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.inf(&other.min), max: self.max.sup(&other.max) }
    }

    /// The intersection of both.
    pub fn intersection(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.sup(&other.min), max: self.max.inf(&other.max) }
    }

    /// Whether `p` lies in the closed box.
    pub fn contains_point(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|i| self.min[i] <= p[i] && p[i] <= self.max[i])
    }

    /// The parameter range `[t0, t1]` (clipped to `[0, max_t]`) where the
    /// ray is inside the box, or `None`. Conservative: never misses a point
    /// of the box the ray passes through.
    #[inline]
    pub fn ray_range(&self, ray: &Ray, max_t: f64) -> Option<(f64, f64)> {
        let o = ray.origin();
        let d = ray.direction();
        let (mut t0, mut t1) = (0.0f64, max_t);
        for i in 0..3 {
            if d[i] == 0.0 {
                if o[i] < self.min[i] || o[i] > self.max[i] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d[i];
            let (mut a, mut b) = ((self.min[i] - o[i]) * inv, (self.max[i] - o[i]) * inv);
            if a > b {
                core::mem::swap(&mut a, &mut b);
            }
            // NaN (∞ - ∞ on an infinite box side) compares false and leaves the range open.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
        }
        // Widen by a few ulps so rounding in the slab test never drops a grazing hit.
        let slack = 4.0 * f64::EPSILON * t1.abs().max(t0.abs());
        (t0 <= t1 + slack).then_some((t0, t1))
    }
}
