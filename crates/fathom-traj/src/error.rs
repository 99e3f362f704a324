//! Errors of trajectory construction and evaluation.

use fathom_core::CoreError;

/// Errors raised while building or evaluating a trajectory.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajError {
    /// A spline needs at least two knots.
    #[error("spline needs at least 2 knots, got {got}")]
    TooFewKnots {
        /// Number of knots given.
        got: usize,
    },
    /// Knot times and knot values have different lengths.
    #[error("{times} knot times but {values} knot values")]
    LengthMismatch {
        /// Number of knot times.
        times: usize,
        /// Number of knot values.
        values: usize,
    },
    /// The trajectory was asked for a time it does not cover.
    #[error("time {t} s is outside the trajectory [{start}, {end}] s")]
    OutOfRange {
        /// Requested time, s.
        t: f64,
        /// Start of the trajectory, s.
        start: f64,
        /// End of the trajectory, s.
        end: f64,
    },
    /// A check of the shared vocabulary failed (non-finite value, non-increasing time, ...).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// A parameter is invalid.
    #[error("invalid parameter `{field}`: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        field: String,
        /// Why it is invalid.
        reason: String,
    },
}
