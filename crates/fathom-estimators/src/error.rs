//! `EstimatorError`: what went wrong in a filter step, naming the quantity, the index
//! and the filter time stamp.

use fathom_core::{CoreError, Time};

/// Errors of the estimators. Filter-step variants carry the filter time `time` (s)
/// at which the step was attempted (for a prediction: the target time).
///
/// Stand-alone math helpers that have no notion of time (fusion, [`crate::gating::nis`],
/// model builders) report [`EstimatorError::Core`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// A value that must be finite is NaN or infinite.
    #[error("{what}: value at index {index} is not finite ({value}) at t = {time} s")]
    NonFinite {
        /// What was checked (e.g. "measurement z", "measurement matrix H").
        what: String,
        /// Index of the offending element (row-major for matrices).
        index: usize,
        /// The offending value.
        value: f64,
        /// Filter time stamp, s.
        time: Time,
    },
    /// A matrix that must be symmetric is not (beyond a relative tolerance).
    #[error(
        "{what}: matrix is not symmetric (entry ({row}, {col}) differs from its transpose by {diff:e}) at t = {time} s"
    )]
    NotSymmetric {
        /// What matrix was checked.
        what: String,
        /// Row of the worst entry.
        row: usize,
        /// Column of the worst entry.
        col: usize,
        /// Absolute difference to the transposed entry.
        diff: f64,
        /// Filter time stamp, s.
        time: Time,
    },
    /// A matrix that must be positive definite is not (Cholesky failed), or a
    /// variance that must be positive is not.
    #[error("{what} is not positive definite at t = {time} s")]
    NotPositiveDefinite {
        /// What matrix was checked (e.g. "measurement noise R",
        /// "innovation covariance S", "updated covariance P").
        what: String,
        /// Filter time stamp, s.
        time: Time,
    },
    /// Inputs of inconsistent sizes.
    #[error("{what}: expected dimension {expected}, got {got}")]
    DimensionMismatch {
        /// Which input has the wrong size.
        what: String,
        /// The expected size.
        expected: usize,
        /// The size given.
        got: usize,
    },
    /// A prediction to a time before the filter's current time.
    #[error("{what}: target time {next} s is before the filter time {prev} s")]
    TimeBackwards {
        /// What step was attempted.
        what: String,
        /// The filter's current time, s.
        prev: Time,
        /// The requested time, s.
        next: Time,
    },
    /// A parameter is out of its valid range.
    #[error("{what}: {value} is out of range ({expected})")]
    OutOfRange {
        /// The parameter's name.
        what: String,
        /// The offending value.
        value: f64,
        /// Human-readable valid range, e.g. "> 0".
        expected: &'static str,
    },
    /// A smoother cannot use a recorded forward pass: recording was not turned on, or
    /// the record is inconsistent (an update recorded without its prediction step).
    #[error("{what} (t = {time} s)")]
    Smoother {
        /// What is wrong.
        what: String,
        /// Time stamp of the offending record, s.
        time: Time,
    },
    /// An error from the shared vocabulary (checks without a time stamp).
    #[error(transparent)]
    Core(#[from] CoreError),
}

impl EstimatorError {
    /// The filter time stamp the error carries (`None` for the variants without
    /// one: dimension, range and time-free [`EstimatorError::Core`] errors; for
    /// [`EstimatorError::TimeBackwards`] the requested time).
    pub fn time(&self) -> Option<Time> {
        match self {
            Self::NonFinite { time, .. }
            | Self::NotSymmetric { time, .. }
            | Self::NotPositiveDefinite { time, .. }
            | Self::Smoother { time, .. } => Some(*time),
            Self::TimeBackwards { next, .. } => Some(*next),
            _ => None,
        }
    }

    /// The same error stamped with the filter time `time` (variants that carry a
    /// time stamp; others unchanged). Used for errors raised by models that do not
    /// know the filter time (e.g. [`crate::ekf::MotionModel::propagate`]).
    pub fn at_time(self, time: Time) -> Self {
        match self {
            Self::NonFinite {
                what, index, value, ..
            } => Self::NonFinite {
                what,
                index,
                value,
                time,
            },
            Self::NotSymmetric {
                what,
                row,
                col,
                diff,
                ..
            } => Self::NotSymmetric {
                what,
                row,
                col,
                diff,
                time,
            },
            Self::NotPositiveDefinite { what, .. } => Self::NotPositiveDefinite { what, time },
            Self::Core(core) => Self::from_core_at(core, time),
            other => other,
        }
    }

    /// Converts a [`CoreError`] from a check done inside a filter step into the
    /// corresponding variant carrying the filter time `time`.
    pub fn from_core_at(err: CoreError, time: Time) -> Self {
        match err {
            CoreError::NonFinite { what, index, value } => Self::NonFinite {
                what,
                index,
                value,
                time,
            },
            CoreError::NotSymmetric {
                what,
                row,
                col,
                diff,
            } => Self::NotSymmetric {
                what,
                row,
                col,
                diff,
                time,
            },
            CoreError::NotPositiveDefinite { what } => Self::NotPositiveDefinite { what, time },
            CoreError::OutOfRange {
                what,
                value,
                expected,
            } => Self::OutOfRange {
                what,
                value,
                expected,
            },
            other => Self::Core(other),
        }
    }
}

/// Finite entries of a matrix stored column-major in `data` (`rows x cols`): a
/// vectorizable fast path, and the row-major index of the first non-finite entry (as
/// [`check_finite_entries`]) only when there is one.
#[inline]
pub(crate) fn check_finite(
    what: &str,
    data: &[f64],
    rows: usize,
    cols: usize,
    time: Time,
) -> Result<(), EstimatorError> {
    if crate::linalg::all_finite(data) {
        return Ok(());
    }
    check_finite_entries(what, rows, cols, |r, c| data[c * rows + r], time)
}

/// Checks every entry of a (row x col) matrix given by `get` is finite; reports the
/// first offending entry with a row-major index.
pub(crate) fn check_finite_entries(
    what: &str,
    rows: usize,
    cols: usize,
    get: impl Fn(usize, usize) -> f64,
    time: Time,
) -> Result<(), EstimatorError> {
    for r in 0..rows {
        for c in 0..cols {
            let value = get(r, c);
            if !value.is_finite() {
                return Err(EstimatorError::NonFinite {
                    what: what.to_owned(),
                    index: r * cols + c,
                    value,
                    time,
                });
            }
        }
    }
    Ok(())
}

impl fathom_core::ParameterError for EstimatorError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            EstimatorError::NonFinite { what, index, .. } => {
                Some(fathom_core::error::element_name(what, *index))
            }
            EstimatorError::OutOfRange { what, .. } => Some(what.as_str().into()),
            EstimatorError::Core(e) => fathom_core::ParameterError::parameter(e),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_errors_gain_the_time_stamp() {
        let e = EstimatorError::from_core_at(
            CoreError::NotPositiveDefinite {
                what: "measurement noise R".into(),
            },
            12.5,
        );
        assert_eq!(
            e,
            EstimatorError::NotPositiveDefinite {
                what: "measurement noise R".into(),
                time: 12.5
            }
        );
        assert!(e.to_string().contains("t = 12.5 s"));
    }

    #[test]
    fn model_errors_are_stamped_with_the_filter_time() {
        let e = EstimatorError::NonFinite {
            what: "input".into(),
            index: 2,
            value: f64::NAN,
            time: 0.1,
        }
        .at_time(7.5);
        assert_eq!(e.time(), Some(7.5));
        assert!(matches!(e, EstimatorError::NonFinite { index: 2, .. }));
        let core = EstimatorError::Core(CoreError::NotPositiveDefinite { what: "Q".into() });
        assert_eq!(core.time(), None);
        assert_eq!(core.at_time(3.0).time(), Some(3.0));
        let range = EstimatorError::OutOfRange {
            what: "k".into(),
            value: -1.0,
            expected: "> 0",
        };
        assert_eq!(range.clone().at_time(1.0), range);
    }

    #[test]
    fn finite_check_reports_row_major_index() {
        let m = [[1.0, 2.0, 3.0], [4.0, f64::NAN, 6.0]];
        let e = check_finite_entries("H", 2, 3, |r, c| m[r][c], 1.0).unwrap_err();
        assert!(matches!(e, EstimatorError::NonFinite { index: 4, .. }));
    }
}
