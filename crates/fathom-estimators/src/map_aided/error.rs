//! `MapAidedError`: what went wrong in a map-aided filter step or setting, naming the
//! field, the beam and the filter time stamp.

use fathom_core::Time;

use crate::EstimatorError;

/// Errors of the map-aided estimators ([`super`]). Step errors carry the filter time
/// `time` (s) at which the step was attempted; every failing step leaves the filter
/// (state, covariance, time, particles) unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MapAidedError {
    /// A setting is out of its valid range (raised by the `check` of a `Params`).
    #[error("setting {field}: {value} is out of range ({expected})")]
    InvalidParameter {
        /// The field, e.g. `mgpmf.k_sigma`.
        field: String,
        /// The offending value.
        value: f64,
        /// The valid range, e.g. "> 0".
        expected: &'static str,
    },
    /// A measurement or input value is unusable: NaN / infinite, a variance or
    /// standard deviation `<= 0`, a zero beam direction.
    #[error("{what} (index {index}): {value} is not usable ({expected}) at t = {time} s")]
    InvalidInput {
        /// What was checked, e.g. "range beam range_m".
        what: String,
        /// Index of the beam / component.
        index: usize,
        /// The offending value.
        value: f64,
        /// What is required, e.g. "finite and > 0".
        expected: &'static str,
        /// Filter time stamp, s.
        time: Time,
    },
    /// No ray of the predicted pose(s) hits the map: the pose is outside the map (or
    /// the map is empty there), so the ranges carry no usable geometry.
    #[error(
        "no predicted hit for any of the {rays} rays cast from the estimated pose(s) at t = {time} s (pose outside the map?)"
    )]
    PoseOutsideMap {
        /// Number of rays cast.
        rays: usize,
        /// Filter time stamp, s.
        time: Time,
    },
    /// An error of the underlying Kalman filter (already time-stamped).
    #[error(transparent)]
    Filter(#[from] EstimatorError),
}

impl MapAidedError {
    /// The time stamp the error carries (`None` for settings errors and the filter
    /// errors without one).
    pub fn time(&self) -> Option<Time> {
        match self {
            Self::InvalidInput { time, .. } | Self::PoseOutsideMap { time, .. } => Some(*time),
            Self::Filter(e) => e.time(),
            Self::InvalidParameter { .. } => None,
        }
    }
}

/// `value` finite and `> 0`, else [`MapAidedError::InvalidInput`].
pub(crate) fn positive_input(
    what: &str,
    index: usize,
    value: f64,
    time: Time,
) -> Result<f64, MapAidedError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(MapAidedError::InvalidInput {
            what: what.into(),
            index,
            value,
            expected: "finite and > 0",
            time,
        })
    }
}

/// Every component finite, else [`MapAidedError::InvalidInput`] naming the first bad one.
pub(crate) fn finite_input(what: &str, values: &[f64], time: Time) -> Result<(), MapAidedError> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(MapAidedError::InvalidInput {
            what: what.into(),
            index,
            value: values[index],
            expected: "finite",
            time,
        }),
    }
}

impl fathom_core::ParameterError for MapAidedError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            MapAidedError::InvalidParameter { field, .. } => Some(field.as_str().into()),
            MapAidedError::Filter(e) => fathom_core::ParameterError::parameter(e),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_carry_their_time() {
        let e = positive_input("range beam sigma_m", 3, -0.1, 7.0).unwrap_err();
        assert_eq!(e.time(), Some(7.0));
        assert!(e.to_string().contains("index 3"), "{e}");
        assert!(finite_input("x", &[1.0, f64::NAN], 2.0).is_err());
        assert!(finite_input("x", &[1.0, 2.0], 2.0).is_ok());
        let p = MapAidedError::InvalidParameter {
            field: "mgpmf.k_sigma".into(),
            value: 0.0,
            expected: "> 0",
        };
        assert_eq!(p.time(), None);
        assert!(p.to_string().contains("mgpmf.k_sigma"));
        let o = MapAidedError::PoseOutsideMap { rays: 7, time: 1.5 };
        assert_eq!(o.time(), Some(1.5));
    }
}
