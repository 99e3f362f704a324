//! The flown trajectory: the state at every control instant with the input held over
//! the following control period, and the exact state at any time in between.
//!
//! `state_at(t)` takes the control sample `k` at or before `t` and integrates the
//! dynamics from it with that sample's input for `t - t_k`, with the flight's own RK4
//! substeps (whole substeps, then one partial step). At a substep instant it is
//! therefore bit-identical to the flight itself, and in between it is the RK4
//! solution; acceleration, specific force and angular acceleration are the dynamics
//! evaluated at that state and input, so the specific force is exactly
//! `C_n^b (a^n - g^n)` of the returned state. During the rest at the start the vehicle
//! is held: zero velocity, acceleration and rates, specific force `C_n^b (-g^n)`.
//! The inputs change at control instants (rotor commands, the held gust), so the
//! state is continuous there but acceleration and specific force may jump (without
//! a motor lag, or with gusts); `state_at(t_k)` uses the input that starts at `t_k`.

use fathom_core::{Time, frames::euler_from_nav_from_body};
use nalgebra::Vector3;

use super::dynamics::{
    RigidBodyState, StepInput, acceleration_in_nav, angular_acceleration, integrate,
    specific_force_in_body,
};
use super::params::Vehicle;
use crate::{TrajError, Trajectory, TrueState};

/// The state at one control instant and the input held until the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightSample {
    /// Control instant, s.
    pub time: Time,
    /// True state at `time`.
    pub state: RigidBodyState,
    /// Rotor commands and wind held from `time` to the next sample (for the last
    /// sample: the last input applied).
    pub input: StepInput,
    /// Whether the vehicle is held at rest from `time` to the next sample.
    pub held: bool,
}

/// The full true state of the quadrotor at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadState {
    /// Time, s.
    pub time: Time,
    /// Position, velocity, attitude, body rate, rotor thrusts.
    pub body: RigidBodyState,
    /// Acceleration in NED, m/s^2.
    pub acc_in_nav: Vector3<f64>,
    /// Specific force in body axes (what an ideal accelerometer senses), m/s^2.
    pub specific_force_in_body: Vector3<f64>,
    /// Angular acceleration in body axes, rad/s^2.
    pub angular_acc_body: Vector3<f64>,
    /// Wind velocity in NED, m/s.
    pub wind_in_nav: Vector3<f64>,
}

impl QuadState {
    /// The subset every fathom trajectory provides.
    pub fn to_true_state(&self) -> TrueState {
        TrueState {
            time: self.time,
            pos_in_nav: self.body.pos_in_nav,
            vel_in_nav: self.body.vel_in_nav,
            acc_in_nav: self.acc_in_nav,
            attitude: euler_from_nav_from_body(&self.body.nav_from_body.to_rotation_matrix()),
            omega_body: self.body.omega_body,
        }
    }
}

/// A flown (or being flown) quadrotor trajectory; implements [`Trajectory`] over
/// `[0, time of the last sample]`.
#[derive(Debug, Clone, PartialEq)]
pub struct FlownTrajectory {
    vehicle: Vehicle,
    control_dt: f64,
    physics_dt: f64,
    samples: Vec<FlightSample>,
}

impl FlownTrajectory {
    /// A trajectory with its first sample.
    pub(crate) fn new(
        vehicle: Vehicle,
        control_dt: f64,
        physics_dt: f64,
        first: FlightSample,
    ) -> Self {
        Self {
            vehicle,
            control_dt,
            physics_dt,
            samples: vec![first],
        }
    }

    /// The last sample (to set its input once the step is decided).
    pub(crate) fn last_mut(&mut self) -> &mut FlightSample {
        let n = self.samples.len();
        &mut self.samples[n - 1]
    }

    /// Appends the next control instant's sample.
    pub(crate) fn push(&mut self, sample: FlightSample) {
        self.samples.push(sample);
    }

    /// The control-instant samples.
    pub fn samples(&self) -> &[FlightSample] {
        &self.samples
    }

    /// The vehicle flown.
    pub fn vehicle(&self) -> &Vehicle {
        &self.vehicle
    }

    /// Control period, s.
    pub fn control_dt(&self) -> f64 {
        self.control_dt
    }

    /// RK4 step, s.
    pub fn physics_dt(&self) -> f64 {
        self.physics_dt
    }

    /// Index of the sample at or before `t` (the trajectory's range already checked).
    fn index_at(&self, t: Time) -> usize {
        let last = self.samples.len() - 1;
        let t0 = self.samples[0].time;
        let mut k = (((t - t0) / self.control_dt).floor().max(0.0) as usize).min(last);
        while k > 0 && self.samples[k].time > t {
            k -= 1;
        }
        while k < last && self.samples[k + 1].time <= t {
            k += 1;
        }
        k
    }

    /// The full true state at `t` (module docs).
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] for a time outside the flight or not finite.
    pub fn quad_state_at(&self, t: Time) -> Result<QuadState, TrajError> {
        let (start, end) = (self.start_time(), self.end_time());
        if !(t.is_finite() && t >= start && t <= end) {
            return Err(TrajError::OutOfRange { t, start, end });
        }
        let sample = &self.samples[self.index_at(t)];
        let v = &self.vehicle;
        let wind = sample.input.wind_in_nav;
        if sample.held {
            let body = sample.state;
            return Ok(QuadState {
                time: t,
                body,
                acc_in_nav: Vector3::zeros(),
                specific_force_in_body: body.nav_from_body.inverse() * -v.gravity_in_nav(),
                angular_acc_body: Vector3::zeros(),
                wind_in_nav: wind,
            });
        }
        let body = integrate(
            v,
            &sample.state,
            &sample.input,
            t - sample.time,
            self.physics_dt,
        );
        Ok(QuadState {
            time: t,
            body,
            acc_in_nav: acceleration_in_nav(v, &body, &wind),
            specific_force_in_body: specific_force_in_body(v, &body, &wind),
            angular_acc_body: angular_acceleration(v, &body),
            wind_in_nav: wind,
        })
    }

    /// Specific force in body axes at `t`, m/s^2.
    ///
    /// # Errors
    /// As [`FlownTrajectory::quad_state_at`].
    pub fn specific_force_at(&self, t: Time) -> Result<Vector3<f64>, TrajError> {
        Ok(self.quad_state_at(t)?.specific_force_in_body)
    }
}

impl Trajectory for FlownTrajectory {
    fn start_time(&self) -> Time {
        self.samples[0].time
    }

    fn end_time(&self) -> Time {
        self.samples[self.samples.len() - 1].time
    }

    fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
        Ok(self.quad_state_at(t)?.to_true_state())
    }
}
