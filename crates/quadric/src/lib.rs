//! # quadric — exact ray–quadric interval sets
//!
//! The kernel of Komplex: for a ray `p + λr` and a quadric solid
//! `{x : [x;1]ᵀ Q [x;1] <= 0}` or a half-space `{x : a x + b y + c z + d <= 0}`,
//! the exact set of `λ >= 0` where the ray is inside, as an [`IntervalSet`],
//! accurate to near float64's rounding floor at any distance from the origin.
//!
//! ```
//! use nalgebra::{Point3, Vector3};
//! use quadric::{HalfSpace, Quadric, Ray, Transform};
//!
//! // A capped cylinder: the tube x² + z² <= 1 between y = 0 and y = 2.
//! let tube = Quadric::tube_y();
//! let top = HalfSpace::new(0.0, 1.0, 0.0, -2.0).unwrap();
//! let bottom = HalfSpace::new(0.0, -1.0, 0.0, 0.0).unwrap();
//! let ray = Ray::new(Point3::new(-5.0, 1.0, 0.0), Vector3::x()).unwrap();
//! let inside = tube.intervals(&ray, 0)
//!     .intersect(&top.intervals(&ray, 1)).unwrap()
//!     .intersect(&bottom.intervals(&ray, 2)).unwrap();
//! assert_eq!(format!("{inside}"), "[4, 6]");
//! ```
#![deny(missing_docs)]

mod error;
mod exact;
mod halfspace;
mod interval;
pub mod lanes;
pub mod normal;
mod quadric;
mod ray;
pub mod roots;
mod solid;
#[cfg(feature = "proptest")]
pub mod strategies;
mod transform;

pub use error::GeometryError;
pub use halfspace::{HalfSpace, Rebased};
pub use interval::{Bound, CapacityError, Interval, IntervalSet, Pieces, NO_SOLID};
pub use nalgebra;
pub use quadric::precision::{CertifiedIntervals, CertifiedRoot, Precision};
pub use quadric::Quadric;
pub use ray::Ray;
pub use solid::Solid;
pub use transform::Transform;
