//! Typed errors for bad input to the kernel.

/// Why a solid, transform or ray could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// A coefficient, matrix entry, vector component or angle is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// What was not finite.
        what: &'static str,
    },
    /// A quadric's matrix is not symmetric.
    #[error("the quadric matrix is not symmetric (entry ({row},{col}) differs from ({col},{row}))")]
    NotSymmetric {
        /// Row of the first differing entry.
        row: usize,
        /// Column of the first differing entry.
        col: usize,
    },
    /// A half-space with a zero normal `(a, b, c)`.
    #[error("the half-space normal (a, b, c) is zero")]
    ZeroNormal,
    /// A ray direction of zero length.
    #[error("the ray direction is zero")]
    ZeroDirection,
    /// A transform that cannot be inverted.
    #[error("the transform is singular: {reason}")]
    Singular {
        /// Which part made it singular.
        reason: &'static str,
    },
    /// A general matrix whose last row is not `[0, 0, 0, 1]`.
    #[error("the matrix is not affine: its last row must be [0, 0, 0, 1]")]
    NotAffine,
    /// A quadric with no quadratic or linear part whose constant makes it
    /// all of space by accident or empty: all ten coefficients zero
    /// (`0 <= 0`), or only a positive constant (`k <= 0` nowhere).
    #[error("the quadric is degenerate: {reason}")]
    Degenerate {
        /// Which case it is.
        reason: &'static str,
    },
    /// A transform under which a part of the solid that is non-zero in exact
    /// arithmetic would be stored below the normal range (zero or
    /// subnormal), so that the placed solid is not the one described (a unit
    /// ball scaled by `1e170` would become all of space); see
    /// [`Quadric::try_transformed`](crate::Quadric::try_transformed).
    #[error("the placed solid's {part} underflows: it would be stored below the smallest normal number (2.2e-308), so the solid would not be the one described")]
    Underflow {
        /// Which part underflowed.
        part: &'static str,
    },
}
