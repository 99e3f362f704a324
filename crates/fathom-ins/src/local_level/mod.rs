//! The reduced strapdown of the 12-state INS of seed 004 (eq. 1-5): local NED frame,
//! constant gravity, no Earth rate, no transport rate. A MEMS IMU cannot sense Earth
//! rate (15 deg/h against a 17 deg/h bias instability), so the paper drops it; over
//! a few hundred metres the NED frame is then an inertial frame with uniform gravity.
//!
//! - [`mechanization`]: the nominal-state propagation with IMU increments
//!   (`delta_theta`, `delta_v`), the same two-sample coning / sculling algorithm as
//!   the WGS-84 [`crate::strapdown`] with the frame-rate terms removed;
//! - [`imu_from_truth`]: the exact inversion of that step: error-free increments from
//!   sampled truth that the mechanization reproduces;
//! - [`stationary_gyro_bias`]: the gyro-bias calibration at rest by averaging (the
//!   paper's 12-state filter does not estimate the gyro bias).
//!
//! The 12-state error dynamics `F`, `G` (eq. 3-4) belong next to these.
//!
//! The truth is taken as plain samples ([`LocalTruthSample`]: time, NED position,
//! velocity, attitude quaternion), so this crate needs no trajectory type.

pub mod imu_from_truth;
pub mod mechanization;

pub use imu_from_truth::{LocalImuFromTruth, local_imu_from_truth};
pub use mechanization::LocalLevelMechanization;

use fathom_core::frames::{Euler, euler_from_nav_from_body};
use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{InsError, check_finite};
use crate::state::ImuIncrement;

/// Nominal navigation state of the reduced mechanization (local NED, metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalLevelState {
    /// Position in the local NED frame, m (z down).
    pub pos_in_nav: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude `C_b^n` (rotates body vectors into NED).
    pub nav_from_body: UnitQuaternion<f64>,
}

impl LocalLevelState {
    /// Roll/pitch/yaw (ZYX) of `nav_from_body`.
    pub fn euler(&self) -> Euler {
        euler_from_nav_from_body(&self.nav_from_body.to_rotation_matrix())
    }

    /// Checks that every field is finite.
    ///
    /// # Errors
    /// [`InsError::NonFinite`] naming the field.
    pub fn check(&self) -> Result<(), InsError> {
        check_finite("pos_in_nav", self.pos_in_nav.as_slice())?;
        check_finite("vel_in_nav", self.vel_in_nav.as_slice())?;
        check_finite(
            "nav_from_body",
            self.nav_from_body.as_ref().coords.as_slice(),
        )
    }
}

/// One sample of the true trajectory in the local NED frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalTruthSample {
    /// Time, s.
    pub time: f64,
    /// True position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// True velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// True attitude `C_b^n`.
    pub nav_from_body: UnitQuaternion<f64>,
}

impl LocalTruthSample {
    /// The sample as a nominal state (e.g. to start the mechanization at the truth).
    pub fn to_state(&self) -> LocalLevelState {
        LocalLevelState {
            pos_in_nav: self.pos_in_nav,
            vel_in_nav: self.vel_in_nav,
            nav_from_body: self.nav_from_body,
        }
    }
}

/// Gyro bias estimated by averaging the increments of a stationary IMU:
/// `sum delta_theta / sum dt`, rad/s. In the reduced model the true angular rate at
/// rest is zero (no Earth rate), so the mean rate is the bias (plus the averaged
/// noise: ARW / sqrt(T) per axis for a rest of T seconds).
///
/// # Errors
/// [`InsError::TruthTooShort`] for no increment, or the increment's own check
/// (non-finite values, non-positive `dt`).
pub fn stationary_gyro_bias(increments: &[ImuIncrement]) -> Result<Vector3<f64>, InsError> {
    if increments.is_empty() {
        return Err(InsError::TruthTooShort { len: 0, min: 1 });
    }
    let mut sum = Vector3::zeros();
    let mut time = 0.0;
    for inc in increments {
        inc.check()?;
        sum += inc.delta_theta;
        time += inc.dt;
    }
    Ok(sum / time)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gyro_bias_is_the_mean_rate() {
        let b = Vector3::new(1e-4, -2e-4, 3e-5);
        let incs: Vec<_> = (0..100)
            .map(|k| {
                let dt = if k % 2 == 0 { 0.01 } else { 0.02 };
                let wobble =
                    Vector3::new(1.0, -1.0, 0.5) * 1e-6 * if k % 2 == 0 { 1.0 } else { -1.0 };
                ImuIncrement::new(dt, b * dt + wobble, Vector3::zeros())
            })
            .collect();
        let est = stationary_gyro_bias(&incs).unwrap();
        assert!((est - b).amax() < 1e-15, "{est}");
        assert!(stationary_gyro_bias(&[]).is_err());
        let mut bad = incs.clone();
        bad[3].delta_theta.y = f64::NAN;
        assert!(matches!(
            stationary_gyro_bias(&bad),
            Err(InsError::NonFinite {
                what: "delta_theta",
                ..
            })
        ));
    }
}
