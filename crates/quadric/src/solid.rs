//! The common type of quadric solids and half-spaces.

use nalgebra::{Point3, Vector3};

use crate::{GeometryError, HalfSpace, IntervalSet, Quadric, Ray, Transform};

/// A solid a block is built from: a quadric or a half-space (each of which
/// may already be a complement, since both complement exactly).
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use quadric::{Quadric, Ray, Solid};
/// let outside = Solid::from(Quadric::sphere()).complement();
/// let ray = Ray::new(Point3::new(-3.0, 0.0, 0.0), Vector3::x()).unwrap();
/// // The outside of a ball is non-convex: two pieces along this ray.
/// assert_eq!(outside.intervals(&ray, 0).len(), 2);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Solid {
    /// `[x;1]ᵀ Q [x;1] <= 0`.
    Quadric(Quadric),
    /// `a x + b y + c z + d <= 0`.
    HalfSpace(HalfSpace),
}

impl From<Quadric> for Solid {
    fn from(q: Quadric) -> Self {
        Solid::Quadric(q)
    }
}

impl From<HalfSpace> for Solid {
    fn from(h: HalfSpace) -> Self {
        Solid::HalfSpace(h)
    }
}

impl Solid {
    /// The closure of the other side (exact: `-Q` or `-q`).
    pub fn complement(&self) -> Self {
        match self {
            Solid::Quadric(q) => Solid::Quadric(q.complement()),
            Solid::HalfSpace(h) => Solid::HalfSpace(h.complement()),
        }
    }

    /// The solid moved by `m`.
    pub fn transformed(&self, m: &Transform) -> Self {
        match self {
            Solid::Quadric(q) => Solid::Quadric(q.transformed(m)),
            Solid::HalfSpace(h) => Solid::HalfSpace(h.transformed(m)),
        }
    }

    /// The solid moved by `v` ([`Quadric::translated`] for a quadric;
    /// the same solid as `transformed` by the translation).
    pub fn translated(&self, v: &Vector3<f64>) -> Self {
        match self {
            Solid::Quadric(q) => Solid::Quadric(q.translated(v)),
            Solid::HalfSpace(h) => match Transform::translate(*v) {
                Ok(m) => Solid::HalfSpace(h.transformed(&m)),
                Err(_) => *self,
            },
        }
    }

    /// The solid moved by `m`, checked: an error if a coefficient overflows
    /// or a part of the solid underflows ([`Quadric::try_transformed`],
    /// [`HalfSpace::try_transformed`]).
    pub fn try_transformed(&self, m: &Transform) -> Result<Self, GeometryError> {
        Ok(match self {
            Solid::Quadric(q) => Solid::Quadric(q.try_transformed(m)?),
            Solid::HalfSpace(h) => Solid::HalfSpace(h.try_transformed(m)?),
        })
    }

    /// The set of `λ >= 0` where the ray is inside; finite ends carry `solid`.
    #[inline]
    pub fn intervals(&self, ray: &Ray, solid: u32) -> IntervalSet {
        match self {
            Solid::Quadric(q) => q.intervals(ray, solid),
            Solid::HalfSpace(h) => h.intervals(ray, solid),
        }
    }

    /// The defining function `f(x)`; the solid is `f <= 0`.
    pub fn value(&self, x: &Point3<f64>) -> f64 {
        match self {
            Solid::Quadric(q) => q.value(x),
            Solid::HalfSpace(h) => h.value(x),
        }
    }

    /// Whether `x` lies in the closed solid.
    pub fn contains_point(&self, x: &Point3<f64>) -> bool {
        self.value(x) <= 0.0
    }

    /// The outward unit normal at a surface point `x`; `None` where it is
    /// undefined (a cone's apex).
    pub fn normal(&self, x: &Point3<f64>) -> Option<Vector3<f64>> {
        match self {
            Solid::Quadric(q) => q.normal(x),
            Solid::HalfSpace(h) => Some(h.normal()),
        }
    }

    /// The most intervals a ray can meet: 1 for convex solids, 2 otherwise.
    pub fn max_intervals(&self) -> usize {
        match self {
            Solid::Quadric(q) if !q.is_convex() => 2,
            _ => 1,
        }
    }

    /// Whether this is a half-space.
    pub fn is_half_space(&self) -> bool {
        matches!(self, Solid::HalfSpace(_))
    }
}
