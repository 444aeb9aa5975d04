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
}
