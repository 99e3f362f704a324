//! Errors raised by the checks of the shared vocabulary (finite values, monotonic
//! time, positive-definite covariances).

/// Errors of the shared vocabulary; each variant names what failed and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoreError {
    /// A value that must be finite is NaN or infinite.
    #[error("{what}: value at index {index} is not finite ({value})")]
    NonFinite {
        /// What was being checked (e.g. "covariance", "knot times").
        what: String,
        /// Index of the offending element (row-major for matrices).
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Time stamps that must strictly increase do not.
    #[error("{what}: time at index {index} ({next} s) does not follow the previous one ({prev} s)")]
    NonIncreasingTime {
        /// What sequence was being checked.
        what: String,
        /// Index of the element that breaks the order.
        index: usize,
        /// The previous time, s.
        prev: f64,
        /// The offending time, s.
        next: f64,
    },
    /// A matrix that must be symmetric is not (beyond a relative tolerance).
    #[error(
        "{what}: matrix is not symmetric (entry ({row}, {col}) differs from its transpose by {diff:e})"
    )]
    NotSymmetric {
        /// What matrix was being checked.
        what: String,
        /// Row of the worst entry.
        row: usize,
        /// Column of the worst entry.
        col: usize,
        /// Absolute difference to the transposed entry.
        diff: f64,
    },
    /// A covariance that must be positive definite is not (Cholesky failed).
    #[error("{what}: covariance is not positive definite")]
    NotPositiveDefinite {
        /// What matrix was being checked.
        what: String,
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
}

/// Checks that every element of `values` is finite.
///
/// # Errors
/// [`CoreError::NonFinite`] naming `what` and the first offending index.
pub fn ensure_finite<'a>(
    what: &str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), CoreError> {
    for (index, &value) in values.into_iter().enumerate() {
        if !value.is_finite() {
            return Err(CoreError::NonFinite {
                what: what.to_owned(),
                index,
                value,
            });
        }
    }
    Ok(())
}

/// Checks that `value` is finite and strictly positive.
///
/// # Errors
/// [`CoreError::OutOfRange`] (or [`CoreError::NonFinite`]) naming `what`.
pub fn ensure_positive(what: &str, value: f64) -> Result<(), CoreError> {
    ensure_finite(what, [value].iter())?;
    if value <= 0.0 {
        return Err(CoreError::OutOfRange {
            what: what.to_owned(),
            value,
            expected: "> 0",
        });
    }
    Ok(())
}

/// Checks that `value` is finite and not negative.
///
/// # Errors
/// [`CoreError::OutOfRange`] (or [`CoreError::NonFinite`]) naming `what`.
pub fn ensure_non_negative(what: &str, value: f64) -> Result<(), CoreError> {
    ensure_finite(what, [value].iter())?;
    if value < 0.0 {
        return Err(CoreError::OutOfRange {
            what: what.to_owned(),
            value,
            expected: ">= 0",
        });
    }
    Ok(())
}

/// An error about one named parameter, so that a front end can name the
/// configuration key behind it (`fathom-sim` maps the name onto the keys of the
/// scenario table the parameters came from).
pub trait ParameterError: std::error::Error {
    /// The parameter the error is about, as the error names it (`rate_hz`,
    /// `imu.accel_bias_corr_time_s`, `mgpmf.grid_points[0]`), or `None` if it is not
    /// about one parameter.
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>>;
}

/// The name of element `index` of a value named `what`: when `what` ends in a
/// comma-separated list of names (`vkf speed0, sf0, b0`), the `index`-th of them;
/// else `what` with the index (`sigma0[2]`).
pub fn element_name(what: &str, index: usize) -> std::borrow::Cow<'_, str> {
    let names: Vec<&str> = what.split(", ").collect();
    if names.len() > 1
        && let Some(name) = names.get(index)
    {
        let last = name.rsplit(' ').next().unwrap_or(name);
        return std::borrow::Cow::Borrowed(last);
    }
    std::borrow::Cow::Owned(format!("{what}[{index}]"))
}

impl ParameterError for CoreError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            CoreError::NonFinite { what, index, .. } => Some(element_name(what, *index)),
            CoreError::OutOfRange { what, .. } => Some(what.as_str().into()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::element_name;

    #[test]
    fn element_names_pick_a_listed_name_or_index_the_value() {
        assert_eq!(element_name("vkf speed0, sf0, b0", 2), "b0");
        assert_eq!(element_name("vkf speed0, sf0, b0", 0), "speed0");
        assert_eq!(element_name("nav sigma0", 1), "nav sigma0[1]");
        assert_eq!(element_name("a, b", 5), "a, b[5]");
    }

    use super::*;

    #[test]
    fn finite_check_names_index() {
        let err = ensure_finite("x", [1.0, f64::NAN].iter()).unwrap_err();
        assert!(matches!(err, CoreError::NonFinite { index: 1, .. }));
        assert!(err.to_string().contains("x: value at index 1"));
        assert!(ensure_finite("x", [1.0, 2.0].iter()).is_ok());
    }

    #[test]
    fn positivity_checks() {
        assert!(ensure_positive("sigma", 0.0).is_err());
        assert!(ensure_positive("sigma", -1.0).is_err());
        assert!(ensure_positive("sigma", f64::INFINITY).is_err());
        assert!(ensure_positive("sigma", 1e-9).is_ok());
        assert!(ensure_non_negative("sigma", 0.0).is_ok());
        assert!(ensure_non_negative("sigma", -1e-9).is_err());
    }
}
