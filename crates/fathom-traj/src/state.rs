//! The true kinematic state of a vehicle and the `Trajectory` trait that yields it
//! at any time.

use fathom_core::{
    Time,
    frames::{Euler, body_from_nav},
};
use nalgebra::Vector3;

use crate::TrajError;

/// The true state of the vehicle at one instant (NED navigation frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueState {
    /// Time, s.
    pub time: Time,
    /// Position in NED, m (z is depth, positive down).
    pub pos_in_nav: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Acceleration in NED, m/s^2.
    pub acc_in_nav: Vector3<f64>,
    /// Attitude, roll/pitch/yaw of the body-to-NED rotation.
    pub attitude: Euler,
    /// Body angular rate `(p, q, r)` relative to NED, expressed in the body frame, rad/s.
    pub omega_body: Vector3<f64>,
}

impl TrueState {
    /// Velocity in the body frame, `C_n^b v_n`, m/s.
    pub fn vel_in_body(&self) -> Vector3<f64> {
        body_from_nav(&self.attitude) * self.vel_in_nav
    }
}

/// A true trajectory: gives the vehicle's true state at any time in
/// `[start_time, end_time]`.
pub trait Trajectory {
    /// First instant the trajectory is defined, s.
    fn start_time(&self) -> Time;
    /// Last instant the trajectory is defined, s.
    fn end_time(&self) -> Time;
    /// The true state at `t`.
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] when `t` is outside `[start_time, end_time]` or
    /// not finite.
    fn state_at(&self, t: Time) -> Result<TrueState, TrajError>;
}
