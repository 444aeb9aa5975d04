//! Typed errors for building blocks and complexes.

/// Why a block or complex could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ComplexError {
    /// A block without solids.
    #[error("block \"{name}\" has no solids")]
    EmptyBlock {
        /// The block's name.
        name: String,
    },
    /// A solid with a non-finite coefficient.
    #[error("block \"{name}\", solid {solid}: a coefficient is not finite")]
    NonFinite {
        /// The block's name.
        name: String,
        /// Index of the solid in the block (0-based).
        solid: usize,
    },
    /// An ε that is negative or not finite.
    #[error("epsilon must be finite and >= 0, got {0}")]
    BadEpsilon(f64),
    /// More blocks than a block id can number.
    #[error("a complex holds at most {max} blocks")]
    TooManyBlocks {
        /// The limit.
        max: usize,
    },
    /// A placement that cannot be assembled ([`crate::Complex::assemble`]).
    #[error("member {index}: {what}")]
    BadPlacement {
        /// Its place in the member list (0-based).
        index: usize,
        /// What is wrong.
        what: String,
    },
    /// A batch query given an output slice of another length than its input.
    #[error("a batch of {queries} queries needs {queries} answer slots, got {answers}")]
    LengthMismatch {
        /// How many points or rays were given.
        queries: usize,
        /// How long the output slice is.
        answers: usize,
    },
    /// A volume option out of range ([`crate::VolumeOptions`]).
    #[error("volume option {option} must be {expected}, got {value}")]
    BadVolumeOption {
        /// The option's name.
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// What it was.
        value: f64,
    },
    /// A clipping box for volumes that is not finite or has `min > max`.
    #[error("the box to measure volumes in must be finite with min <= max on every axis")]
    BadVolumeBounds,
}
