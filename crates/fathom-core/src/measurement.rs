//! Stamped measurement records: which sensor, when it was sampled, when it says it
//! was sampled, what it read and what it would have read without noise.

use crate::Time;

/// Identifies the sensor a measurement came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum SensorId {
    /// Doppler velocity log (body velocity).
    Dvl,
    /// Attitude and heading reference system (angular rate and attitude).
    Ahrs,
    /// Range to the beacon with this zero-based index.
    Range(usize),
    /// Depth gauge.
    Depth,
    /// Inertial navigation system output (integrated position).
    Ins,
    /// DVL dead reckoning output (integrated position).
    DvlDeadReckoning,
    /// Barometric altimeter (static pressure).
    Barometer,
}

impl std::fmt::Display for SensorId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Dvl => write!(f, "dvl"),
            Self::Ahrs => write!(f, "ahrs"),
            Self::Range(k) => write!(f, "range{}", k + 1),
            Self::Depth => write!(f, "depth"),
            Self::Ins => write!(f, "ins"),
            Self::DvlDeadReckoning => write!(f, "dvl_dr"),
            Self::Barometer => write!(f, "baro"),
        }
    }
}

/// One measurement as a simulator delivers it.
///
/// `sample_time` is when the sensor actually sampled; `stamp` is the time it
/// reports (differs when a time-stamp error is simulated). `value` is the noisy
/// reading and `true_value` the noise-free one, so the noise can be verified.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Measurement<T> {
    /// The sensor that produced it.
    pub sensor: SensorId,
    /// Actual sample time, s.
    pub sample_time: Time,
    /// Reported time stamp, s.
    pub stamp: Time,
    /// Noisy measured value.
    pub value: T,
    /// Noise-free value at `sample_time`.
    pub true_value: T,
}

impl<T> Measurement<T> {
    /// Applies `f` to both the noisy and the noise-free value.
    pub fn map<U>(self, mut f: impl FnMut(T) -> U) -> Measurement<U> {
        Measurement {
            sensor: self.sensor,
            sample_time: self.sample_time,
            stamp: self.stamp,
            value: f(self.value),
            true_value: f(self.true_value),
        }
    }
}

impl Measurement<f64> {
    /// The measurement noise actually realised, `value - true_value`.
    pub fn noise(&self) -> f64 {
        self.value - self.true_value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_and_display() {
        let m = Measurement {
            sensor: SensorId::Range(0),
            sample_time: 1.0,
            stamp: 1.0,
            value: 10.5,
            true_value: 10.0,
        };
        assert_eq!(m.noise(), 0.5);
        assert_eq!(m.sensor.to_string(), "range1");
        let doubled = m.map(|v| 2.0 * v);
        assert_eq!(doubled.noise(), 1.0);
    }
}
