//! What crosses the link, in SI units and `f64`, before encoding and after decoding:
//! one IMU step with the sensor events at its end ([`Epoch`]), the initial estimate
//! ([`InitialEstimate`]) and the navigation solution ([`Solution`]). The codec
//! (`codec`) maps these to MAVLink messages and back; the offline run with MAVLink
//! quantization passes them through the same encode and decode functions.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// One GNSS receiver output: a position fix (when at least four satellites give one)
/// and the number of satellites in line of sight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsReading {
    /// Receiver instance (`HIL_GPS.id`): 0 the fix from the line-of-sight satellites,
    /// 1 the fix from every received satellite.
    pub id: u8,
    /// The fix, if any.
    pub fix: Option<GpsFixReading>,
    /// Satellites in line of sight.
    pub los_count: u8,
}

/// A position fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsFixReading {
    /// Position, NED of the scenario's origin, m.
    pub pos_in_nav: Vector3<f64>,
    /// Horizontal dilution of precision.
    pub hdop: f64,
    /// Vertical dilution of precision.
    pub vdop: f64,
}

/// One satellite above the elevation mask as a raw-measurement receiver reports it:
/// where it is and, when its signal was received (in line of sight, or reflected),
/// the pseudorange. The navigation tests its line of sight against its own map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatReading {
    /// Satellite position, ECEF, m.
    pub pos_ecef: Vector3<f64>,
    /// Pseudorange, m, when a signal was received.
    pub pseudorange_m: Option<f64>,
}

/// The sensor data of one IMU step: the increment over the step and the events at
/// its end time.
#[derive(Debug, Clone, PartialEq)]
pub struct Epoch {
    /// Step index (the end of the step is `step * dt`).
    pub step: u64,
    /// Time of the end of the step, s.
    pub time: f64,
    /// Step length, s.
    pub dt: f64,
    /// Angle increment, body, rad.
    pub delta_theta: Vector3<f64>,
    /// Velocity increment (specific force integrated), body, m/s.
    pub delta_v: Vector3<f64>,
    /// Static pressure, Pa, when the barometer was read at this instant.
    pub pressure_pa: Option<f64>,
    /// Magnetic field in the body frame, gauss (noise free, from a field model; for
    /// a ground station or an autopilot: fathom's methods do not use it).
    pub mag_body_gauss: Option<Vector3<f64>>,
    /// GNSS outputs at this instant.
    pub gps: Vec<GpsReading>,
    /// Raw GNSS measurements at this instant (every satellite above the mask), for a
    /// navigation that chooses its satellites itself.
    pub raw_gnss: Option<Vec<SatReading>>,
    /// Range-sensor / lidar scan at this instant: per beam in beam order, the
    /// measured range (m) or `None` (no return).
    pub ranges: Option<Vec<Option<f64>>>,
}

/// The initial estimate handed to the navigation at the end of the rest (surveyed
/// start point and alignment, with the initial error of the run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialEstimate {
    /// Step at which navigation starts.
    pub step: u64,
    /// Time, s.
    pub time: f64,
    /// Position, NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity, NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude.
    pub nav_from_body: UnitQuaternion<f64>,
}

/// The navigation solution of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// Step index.
    pub step: u64,
    /// Time, s.
    pub time: f64,
    /// Position, NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity, NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Body rate (bias-corrected gyro), rad/s.
    pub omega_body: Vector3<f64>,
    /// Position error covariance, m².
    pub pos_cov: Matrix3<f64>,
    /// Attitude error covariance (small rotation about N, E, D), rad².
    pub att_cov: Matrix3<f64>,
    /// Position-attitude cross covariance, m rad.
    pub pos_att_cov: Matrix3<f64>,
    /// Velocity error covariance, (m/s)².
    pub vel_cov: Matrix3<f64>,
    /// Whether the map-aided mode was active.
    pub map_aided: bool,
}
