//! Errors raised by the INS: bad IMU increments, bad states, bad truth sequences and
//! bad error-model parameters, each naming the offending field, index or time.

use fathom_core::CoreError;

/// Errors of the inertial navigation crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InsError {
    /// A shared-vocabulary check failed (non-finite value, out-of-range parameter, ...).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// An IMU increment has a non-positive time step.
    #[error("IMU increment: dt = {dt} s must be > 0")]
    NonPositiveDt {
        /// The offending time step, s.
        dt: f64,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("{what}: component {index} is not finite ({value})")]
    NonFinite {
        /// Which field (e.g. "delta_theta", "vel_in_nav").
        what: &'static str,
        /// Component index inside the field.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The latitude is at or beyond a pole, where the NED mechanization is singular.
    #[error("latitude {lat} rad is outside (-pi/2, pi/2): NED mechanization is singular")]
    LatitudeOutOfRange {
        /// The offending latitude, rad.
        lat: f64,
    },
    /// A truth sequence is too short to produce increments.
    #[error("truth sequence has {len} samples, at least {min} are needed")]
    TruthTooShort {
        /// Number of samples given.
        len: usize,
        /// Minimum number of samples.
        min: usize,
    },
    /// Truth time stamps do not strictly increase.
    #[error("truth sample {index}: time {time} s does not follow the previous one ({prev} s)")]
    NonIncreasingTime {
        /// Index of the offending sample.
        index: usize,
        /// Previous time, s.
        prev: f64,
        /// Offending time, s.
        time: f64,
    },
    /// A route definition is invalid.
    #[error("route: {what}")]
    InvalidRoute {
        /// Human-readable description of the problem.
        what: String,
    },
}

/// Checks that every component of `values` is finite.
pub(crate) fn check_finite(what: &'static str, values: &[f64]) -> Result<(), InsError> {
    for (index, &value) in values.iter().enumerate() {
        if !value.is_finite() {
            return Err(InsError::NonFinite { what, index, value });
        }
    }
    Ok(())
}

impl fathom_core::ParameterError for InsError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            InsError::Core(e) => fathom_core::ParameterError::parameter(e),
            _ => None,
        }
    }
}
