//! Affine placements `x = L y + v` that carry their exact inverse.
//!
//! Elementary steps know their inverse exactly (`T(v)⁻¹ = T(-v)`,
//! `S(λ)⁻¹ = S(1/λ)`, `R(φ)⁻¹ = R(φ)ᵀ`), and a composition inverts in
//! reverse order, so no numeric inversion happens except for a general
//! matrix, which is checked.
//!
//! The translation is kept apart from the linear part: a solid placed far
//! from the origin keeps small coefficients around a far *centre* (see
//! [`crate::Quadric`]), which is what keeps hits accurate at any distance.

use nalgebra::{Matrix3, Matrix4, Point3, Vector3, Vector4};

use crate::GeometryError;

/// An invertible affine map `x ↦ L x + v` together with `L⁻¹`.
///
/// Steps compose in the order they are chained: `Transform::scale(2.0).then(&Transform::translate(v))`
/// scales first, then translates.
///
/// ```
/// use nalgebra::{Point3, Vector3};
/// use quadric::Transform;
/// let m = Transform::scale(2.0).unwrap()
///     .then(&Transform::rotate_z_degrees(90.0).unwrap())
///     .then(&Transform::translate(Vector3::new(1.0, 0.0, 0.0)).unwrap());
/// let p = m.apply_point(&Point3::new(1.0, 0.0, 0.0));
/// assert_eq!(p, Point3::new(1.0, 2.0, 0.0));
/// assert_eq!(m.inverse().apply_point(&p), Point3::new(1.0, 0.0, 0.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    linear: Matrix3<f64>,
    inverse: Matrix3<f64>,
    translation: Vector3<f64>,
}

fn finite(x: f64, what: &'static str) -> Result<f64, GeometryError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(GeometryError::NonFinite { what })
    }
}

/// Sine and cosine of an angle in degrees, exact at multiples of 90°.
fn sin_cos_degrees(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r == 0.0 {
        (0.0, 1.0)
    } else if r == 90.0 {
        (1.0, 0.0)
    } else if r == 180.0 {
        (0.0, -1.0)
    } else if r == 270.0 {
        (-1.0, 0.0)
    } else {
        r.to_radians().sin_cos()
    }
}

impl Transform {
    /// The identity.
    pub fn identity() -> Self {
        Transform { linear: Matrix3::identity(), inverse: Matrix3::identity(), translation: Vector3::zeros() }
    }

    /// Translation by `v`.
    pub fn translate(v: Vector3<f64>) -> Result<Self, GeometryError> {
        if !v.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the translation" });
        }
        Ok(Transform { translation: v, ..Self::identity() })
    }

    /// Uniform scaling by `s`.
    pub fn scale(s: f64) -> Result<Self, GeometryError> {
        Self::scale_xyz(Vector3::new(s, s, s))
    }

    /// Per-axis scaling by `(sx, sy, sz)`; every factor must be finite and non-zero.
    pub fn scale_xyz(s: Vector3<f64>) -> Result<Self, GeometryError> {
        for c in s.iter() {
            finite(*c, "a scale factor")?;
            if *c == 0.0 {
                return Err(GeometryError::Singular { reason: "a scale factor is zero" });
            }
        }
        let inv = s.map(|c| 1.0 / c);
        if !inv.iter().all(|c| c.is_finite() && *c != 0.0) {
            return Err(GeometryError::Singular { reason: "a scale factor's inverse overflows" });
        }
        Ok(Transform {
            linear: Matrix3::from_diagonal(&s),
            inverse: Matrix3::from_diagonal(&inv),
            translation: Vector3::zeros(),
        })
    }

    fn rotation(axis: usize, degrees: f64) -> Result<Self, GeometryError> {
        finite(degrees, "a rotation angle")?;
        let (s, c) = sin_cos_degrees(degrees);
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut r = Matrix3::identity();
        r[(i, i)] = c;
        r[(j, j)] = c;
        r[(i, j)] = -s;
        r[(j, i)] = s;
        Ok(Transform { linear: r, inverse: r.transpose(), translation: Vector3::zeros() })
    }

    /// Rotation about the x axis by `degrees` (right-handed: y towards z).
    pub fn rotate_x_degrees(degrees: f64) -> Result<Self, GeometryError> {
        Self::rotation(0, degrees)
    }

    /// Rotation about the y axis by `degrees` (right-handed: z towards x).
    pub fn rotate_y_degrees(degrees: f64) -> Result<Self, GeometryError> {
        Self::rotation(1, degrees)
    }

    /// Rotation about the z axis by `degrees` (right-handed: x towards y).
    pub fn rotate_z_degrees(degrees: f64) -> Result<Self, GeometryError> {
        Self::rotation(2, degrees)
    }

    /// A general affine 4x4 matrix (last row `[0, 0, 0, 1]`), inverted
    /// numerically and checked: a singular or badly conditioned matrix
    /// (the inverse reproducing the identity to worse than `1e-9`) is an error.
    pub fn from_matrix(m: &Matrix4<f64>) -> Result<Self, GeometryError> {
        if !m.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the transform matrix" });
        }
        if m.row(3) != Vector4::new(0.0, 0.0, 0.0, 1.0).transpose() {
            return Err(GeometryError::NotAffine);
        }
        let linear: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
        let translation: Vector3<f64> = m.fixed_view::<3, 1>(0, 3).into_owned();
        let inverse = linear.try_inverse().ok_or(GeometryError::Singular { reason: "the matrix has no inverse" })?;
        if !inverse.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::Singular { reason: "the matrix inverse overflows" });
        }
        // `amax` and `f64::max` skip NaN, so test every entry: NaN fails `<=`.
        let close = |m: Matrix3<f64>| (m - Matrix3::identity()).iter().all(|x| x.abs() <= 1e-9);
        if !(close(linear * inverse) && close(inverse * linear)) {
            return Err(GeometryError::Singular { reason: "the matrix is too close to singular" });
        }
        Ok(Transform { linear, inverse, translation })
    }

    /// `other ∘ self`: first `self`, then `other`. The inverse composes in
    /// reverse order from the exact inverses of the parts.
    pub fn then(&self, other: &Transform) -> Transform {
        Transform {
            linear: other.linear * self.linear,
            inverse: self.inverse * other.inverse,
            translation: other.linear * self.translation + other.translation,
        }
    }

    /// [`then`](Self::then), checked: an error if the composition is not a
    /// usable invertible transform, i.e. if the linear part or the translation
    /// overflows ([`GeometryError::NonFinite`]), or if the inverse overflows or
    /// the product of the part and its inverse is no longer the identity to
    /// within `1e-3` (underflow to a singular matrix, or a condition number
    /// beyond about `10¹²`: [`GeometryError::Singular`]).
    ///
    /// ```
    /// use quadric::{GeometryError, Transform};
    /// let big = Transform::scale(1e200).unwrap();
    /// assert!(big.checked_then(&Transform::scale(1e-100).unwrap()).is_ok());
    /// assert!(matches!(big.checked_then(&big), Err(GeometryError::NonFinite { .. })));
    /// ```
    pub fn checked_then(&self, other: &Transform) -> Result<Transform, GeometryError> {
        let m = self.then(other);
        if !m.linear.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the composed transform's linear part" });
        }
        if !m.inverse.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::Singular { reason: "the composed transform's inverse overflows" });
        }
        if !m.translation.iter().all(|c| c.is_finite()) {
            return Err(GeometryError::NonFinite { what: "the composed transform's translation" });
        }
        // Both parts are exact compositions of exact inverses, so the residual
        // is about κ·ε unless an entry underflowed.
        let residual = (m.linear * m.inverse - Matrix3::identity()).amax();
        if residual.is_nan() || residual > 1e-3 {
            return Err(GeometryError::Singular { reason: "the composed transform is numerically singular" });
        }
        Ok(m)
    }

    /// The inverse map.
    pub fn inverse(&self) -> Transform {
        Transform { linear: self.inverse, inverse: self.linear, translation: -(self.inverse * self.translation) }
    }

    /// The linear part `L`.
    pub fn linear(&self) -> &Matrix3<f64> {
        &self.linear
    }

    /// The inverse of the linear part, `L⁻¹`.
    pub fn linear_inverse(&self) -> &Matrix3<f64> {
        &self.inverse
    }

    /// The translation `v`.
    pub fn translation(&self) -> &Vector3<f64> {
        &self.translation
    }

    /// The homogeneous 4x4 matrix `M`.
    pub fn matrix(&self) -> Matrix4<f64> {
        let mut m = self.linear.to_homogeneous();
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.translation);
        m
    }

    /// `M x`.
    pub fn apply_point(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.linear * p.coords + self.translation)
    }

    /// `L x` (a direction).
    pub fn apply_vector(&self, v: &Vector3<f64>) -> Vector3<f64> {
        self.linear * v
    }

    /// Whether every entry is finite (always true for transforms built here,
    /// unless a long chain overflowed).
    pub fn is_finite(&self) -> bool {
        self.linear.iter().chain(self.inverse.iter()).chain(self.translation.iter()).all(|c| c.is_finite())
    }
}

impl Default for Transform {
    fn default() -> Self {
        Self::identity()
    }
}
