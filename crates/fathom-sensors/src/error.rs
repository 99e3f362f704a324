//! Errors raised by sensor parameter checks, schedules, noise processes and the
//! measurement generators.

use fathom_core::{CoreError, Time};
use fathom_traj::TrajError;

/// Errors of the sensor crate; every variant names what failed and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// A parameter is out of its valid range (NaN, negative sigma, ...).
    #[error("invalid parameter `{field}` = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name (e.g. `"dvl.sigma[1]"`).
        field: String,
        /// The offending value.
        value: f64,
        /// What was expected.
        reason: &'static str,
    },
    /// The timing jitter is too large for the period: steps could become non-positive.
    #[error(
        "{what}: jitter sigma {sigma_t} s must be < period/4 = {} s so that sample times increase",
        period / 4.0
    )]
    JitterTooLarge {
        /// Which clock.
        what: String,
        /// Jitter standard deviation, s.
        sigma_t: f64,
        /// Nominal period, s.
        period: f64,
    },
    /// A time interval is empty or reversed.
    #[error("{what}: time interval [{start}, {end}] s is empty or not finite")]
    BadInterval {
        /// What interval.
        what: String,
        /// Start, s.
        start: Time,
        /// End, s.
        end: Time,
    },
    /// A time lies outside the span a pre-drawn noise sequence covers.
    #[error("{what}: time {t} s is outside the covered span [{start}, {end}) s")]
    TimeNotCovered {
        /// Which noise sequence.
        what: String,
        /// Requested time, s.
        t: Time,
        /// Start of the covered span, s.
        start: Time,
        /// End of the covered span, s.
        end: Time,
    },
    /// More outliers were requested than there are measurements to hit.
    #[error("cannot inject {requested} outliers into {available} measurements")]
    TooManyOutliers {
        /// Number of outliers requested.
        requested: usize,
        /// Number of measurements available.
        available: usize,
    },
    /// A list that must not be empty is empty.
    #[error("{what} must not be empty")]
    Empty {
        /// What list.
        what: String,
    },
    /// Data that should be synchronous are not (different lengths or sample times).
    #[error("{what}: not synchronous at sample {index} ({detail})")]
    NotSynchronous {
        /// Which data.
        what: String,
        /// First sample index where the streams disagree.
        index: usize,
        /// What disagrees.
        detail: String,
    },
    /// A jittered step stayed non-positive after many redraws (practically impossible
    /// when the jitter check passed).
    #[error("{what}: could not draw a positive step after {attempts} attempts at t = {t} s")]
    StepRedrawExhausted {
        /// Which clock.
        what: String,
        /// Time of the previous sample, s.
        t: Time,
        /// Number of attempts made.
        attempts: usize,
    },
    /// A check of the shared vocabulary failed.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// The trajectory could not be evaluated.
    #[error(transparent)]
    Traj(#[from] TrajError),
}

/// Checks that `value` is finite and `>= 0` (a standard deviation; zero means "off").
pub(crate) fn check_sigma(field: &str, value: f64) -> Result<f64, SensorError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SensorError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite and >= 0",
        })
    }
}

/// Checks that `value` is finite and `> 0`.
pub(crate) fn check_positive(field: &str, value: f64) -> Result<f64, SensorError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SensorError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Checks that `value` is finite.
pub(crate) fn check_finite(field: &str, value: f64) -> Result<f64, SensorError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SensorError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite",
        })
    }
}

/// Checks every component of a 3-vector of standard deviations.
pub(crate) fn check_sigma3(
    field: &str,
    v: &nalgebra::Vector3<f64>,
) -> Result<nalgebra::Vector3<f64>, SensorError> {
    for i in 0..3 {
        check_sigma(&format!("{field}[{i}]"), v[i])?;
    }
    Ok(*v)
}

/// Checks every component of a 3-vector is finite.
pub(crate) fn check_finite3(
    field: &str,
    v: &nalgebra::Vector3<f64>,
) -> Result<nalgebra::Vector3<f64>, SensorError> {
    for i in 0..3 {
        check_finite(&format!("{field}[{i}]"), v[i])?;
    }
    Ok(*v)
}

impl fathom_core::ParameterError for SensorError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            SensorError::InvalidParameter { field, .. } => Some(field.as_str().into()),
            SensorError::Core(e) => fathom_core::ParameterError::parameter(e),
            SensorError::Traj(e) => fathom_core::ParameterError::parameter(e),
            _ => None,
        }
    }
}
