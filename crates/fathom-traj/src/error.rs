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
    /// A generated mission leaves the allowed speed band during its search phase.
    #[error("mission speed {speed} m/s at t = {t} s is outside [{min}, {max}] m/s")]
    SpeedOutOfBounds {
        /// Time of the violation, s.
        t: f64,
        /// Speed found, m/s.
        speed: f64,
        /// Lower bound, m/s.
        min: f64,
        /// Upper bound, m/s.
        max: f64,
    },
    /// A generated mission leaves the allowed depth band during its search phase.
    #[error(
        "mission depth {depth} m at t = {t} s deviates from {nominal} m by more than {tolerance} m"
    )]
    DepthOutOfTolerance {
        /// Time of the violation, s.
        t: f64,
        /// Depth found, m.
        depth: f64,
        /// Nominal search depth, m.
        nominal: f64,
        /// Allowed deviation, m.
        tolerance: f64,
    },
    /// A generated mission does not show the required number of course changes.
    #[error("mission has {detected} course changes during the search, expected {expected}")]
    CourseChangeCount {
        /// Required number.
        expected: usize,
        /// Number detected.
        detected: usize,
    },
    /// A simulated flight left the finite numbers (unstable gains, absurd input).
    #[error("flight diverged at t = {t} s: {what} is not finite")]
    FlightDiverged {
        /// Time of the step that diverged, s.
        t: f64,
        /// What became non-finite.
        what: String,
    },
    /// A flight did not finish its path within the allowed time.
    #[error("path not completed within {max_duration} s (still at {phase})")]
    PathNotCompleted {
        /// The time limit, s.
        max_duration: f64,
        /// Where the guidance was.
        phase: String,
    },
}

impl fathom_core::ParameterError for TrajError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            TrajError::InvalidParameter { field, .. } => Some(field.as_str().into()),
            TrajError::Core(e) => fathom_core::ParameterError::parameter(e),
            _ => None,
        }
    }
}
