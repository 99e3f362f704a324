//! `StatsError`: the errors of the evaluation statistics (empty or non-finite input,
//! mismatched lengths, invalid levels, non-positive-definite covariances).

use fathom_core::CoreError;

/// Errors of `fathom-stats`; each variant names what failed and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StatsError {
    /// A statistic was asked of an empty input.
    #[error("{what}: input is empty")]
    Empty {
        /// What input was empty.
        what: String,
    },
    /// Fewer samples than the statistic needs (e.g. a sample covariance with one sample).
    #[error("{what}: needs at least {needed} samples, got {got}")]
    TooFewSamples {
        /// What statistic was being computed.
        what: String,
        /// Minimum number of samples.
        needed: usize,
        /// Number of samples given.
        got: usize,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("{what}: value at index {index} is not finite ({value})")]
    NonFinite {
        /// What input was being checked.
        what: String,
        /// Index of the first offending element.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// An entry of a sample row or matrix that must be finite is NaN or infinite.
    #[error("{what}: entry ({row}, {col}) is not finite ({value})")]
    NonFiniteEntry {
        /// What input was being checked.
        what: String,
        /// Row (sample index for sample sets).
        row: usize,
        /// Column (component index for sample sets).
        col: usize,
        /// The offending value.
        value: f64,
    },
    /// Two inputs that must have the same length do not.
    #[error("{what}: lengths differ ({left_name} has {left}, {right_name} has {right})")]
    LengthMismatch {
        /// What operation was being performed.
        what: String,
        /// Name of the first input.
        left_name: &'static str,
        /// Length of the first input.
        left: usize,
        /// Name of the second input.
        right_name: &'static str,
        /// Length of the second input.
        right: usize,
    },
    /// A sample row or matrix has the wrong dimension.
    #[error("{what}: item {index} has dimension {found}, expected {expected}")]
    DimensionMismatch {
        /// What input was being checked.
        what: String,
        /// Index of the offending row/item (0 for a single matrix).
        index: usize,
        /// Expected dimension.
        expected: usize,
        /// Found dimension.
        found: usize,
    },
    /// A parameter is out of its valid range.
    #[error("{what}: {value} is out of range ({expected})")]
    OutOfRange {
        /// The parameter's name.
        what: String,
        /// The offending value.
        value: f64,
        /// Human-readable valid range, e.g. "in (0, 1)".
        expected: &'static str,
    },
    /// A covariance that must be positive definite is not (Cholesky failed).
    #[error("{what}: covariance is not positive definite")]
    NotPositiveDefinite {
        /// What matrix was being factored.
        what: String,
    },
    /// The input is degenerate for the requested statistic (e.g. an all-zero design).
    #[error("{what}: {reason}")]
    Degenerate {
        /// What input was being used.
        what: String,
        /// Why it cannot be used.
        reason: &'static str,
    },
    /// A distribution from `statrs` could not be built (should not happen after the
    /// parameter checks; reported instead of panicking).
    #[error("{what}: distribution error: {detail}")]
    Distribution {
        /// Which distribution.
        what: String,
        /// The underlying error message.
        detail: String,
    },
    /// An error from the shared vocabulary.
    #[error(transparent)]
    Core(#[from] CoreError),
}

/// Checks that `values` is non-empty and every element is finite.
///
/// # Errors
/// [`StatsError::Empty`] or [`StatsError::NonFinite`] naming `what` and the index.
pub(crate) fn ensure_finite_non_empty(what: &str, values: &[f64]) -> Result<(), StatsError> {
    if values.is_empty() {
        return Err(StatsError::Empty { what: what.into() });
    }
    for (index, &value) in values.iter().enumerate() {
        if !value.is_finite() {
            return Err(StatsError::NonFinite {
                what: what.into(),
                index,
                value,
            });
        }
    }
    Ok(())
}

/// Checks that a confidence / probability level lies strictly inside (0, 1).
///
/// # Errors
/// [`StatsError::OutOfRange`] naming `what`.
pub(crate) fn ensure_level(what: &str, level: f64) -> Result<(), StatsError> {
    if !(level.is_finite() && level > 0.0 && level < 1.0) {
        return Err(StatsError::OutOfRange {
            what: what.into(),
            value: level,
            expected: "in (0, 1)",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_data() {
        let e = StatsError::LengthMismatch {
            what: "distance series".into(),
            left_name: "est",
            left: 3,
            right_name: "truth",
            right: 4,
        };
        assert_eq!(
            e.to_string(),
            "distance series: lengths differ (est has 3, truth has 4)"
        );
        let e = ensure_finite_non_empty("x", &[1.0, f64::NAN]).unwrap_err();
        assert!(matches!(e, StatsError::NonFinite { index: 1, .. }));
        assert!(matches!(
            ensure_finite_non_empty("x", &[]),
            Err(StatsError::Empty { .. })
        ));
        assert!(ensure_level("level", 1.0).is_err());
        assert!(ensure_level("level", f64::NAN).is_err());
        assert!(ensure_level("level", 0.95).is_ok());
    }
}
