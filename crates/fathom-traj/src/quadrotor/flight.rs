//! A flight: the vehicle, its controller and guidance, the wind, stepped one control
//! period at a time, recording the [`FlownTrajectory`].
//!
//! Per control step `[t_k, t_k + dt]`: the controller's state is the truth, or the
//! estimate the caller hands in (`control = "estimate"`, processor in the loop); the
//! guidance turns it into a setpoint, the controller into rotor commands; the
//! commands and the current wind are held while RK4 advances the truth by the
//! physics substeps; then the gusts advance. During the rest at the start the vehicle
//! is held at the first waypoint (level, at the first waypoint's yaw, rotors at hover
//! thrust so that take-off is continuous) and nothing is controlled.
//!
//! Random draws: the wind's (none in calm air), at the start and once per control
//! step, in step order; the controller and guidance draw nothing. Same seed, same
//! settings and the same estimates => bit-identical flight.

use rand::Rng;

use super::controller::{CascadedController, ControlOutput, ControlState, Setpoint};
use super::dynamics::{RigidBodyState, StepInput, integrate};
use super::guidance::Guidance;
use super::params::{Path, Quadrotor};
use super::trajectory::{FlightSample, FlownTrajectory};
use super::wind::WindState;
use crate::TrajError;

/// A quadrotor flight that the caller advances step by step.
#[derive(Debug, Clone, PartialEq)]
pub struct Flight {
    quad: Quadrotor,
    controller: CascadedController,
    guidance: Guidance,
    wind: WindState,
    state: RigidBodyState,
    steps_done: usize,
    rest_steps: usize,
    trajectory: FlownTrajectory,
}

impl Flight {
    /// A flight of `path` by `quad`, at rest at the first waypoint at `t = 0` (draws
    /// the initial gusts from `rng`).
    pub fn new(quad: &Quadrotor, path: &Path, rng: &mut impl Rng) -> Self {
        let v = &quad.vehicle;
        let first = path.waypoints()[0];
        let yaw = first.yaw_rad.unwrap_or(0.0);
        let state = RigidBodyState::at_rest(first.pos_in_nav, yaw, v.hover_thrust_per_rotor());
        let wind = quad.wind.start(rng);
        let s = &quad.flight;
        let rest_steps = (s.params().rest_duration_s / s.control_dt()).round() as usize;
        let input = StepInput {
            thrust_cmd: [v.hover_thrust_per_rotor(); 4],
            wind_in_nav: quad.wind.velocity(&wind),
        };
        let trajectory = FlownTrajectory::new(
            *v,
            s.control_dt(),
            s.physics_dt(),
            FlightSample {
                time: 0.0,
                state,
                input,
                held: rest_steps > 0,
            },
        );
        Self {
            quad: *quad,
            controller: CascadedController::new(v, &quad.gains),
            guidance: Guidance::new(path, yaw),
            wind,
            state,
            steps_done: 0,
            rest_steps,
            trajectory,
        }
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.steps_done as f64 * self.quad.flight.control_dt()
    }

    /// The true state now.
    pub fn truth(&self) -> &RigidBodyState {
        &self.state
    }

    /// The truth as a controller state (what flying on the truth uses).
    pub fn truth_as_control_state(&self) -> ControlState {
        ControlState::from_truth(&self.state)
    }

    /// Whether the vehicle is still resting (the next step is held).
    pub fn is_resting(&self) -> bool {
        self.steps_done < self.rest_steps
    }

    /// Whether the guidance has finished the path.
    pub fn is_finished(&self) -> bool {
        self.guidance.is_finished()
    }

    /// The guidance (phase, yaw command).
    pub fn guidance(&self) -> &Guidance {
        &self.guidance
    }

    /// The controller (velocity integral).
    pub fn controller(&self) -> &CascadedController {
        &self.controller
    }

    /// The vehicle and settings flown.
    pub fn quadrotor(&self) -> &Quadrotor {
        &self.quad
    }

    /// The trajectory flown so far (a [`crate::Trajectory`] up to [`Flight::time`]).
    pub fn trajectory(&self) -> &FlownTrajectory {
        &self.trajectory
    }

    /// The finished (or interrupted) trajectory.
    pub fn into_trajectory(self) -> FlownTrajectory {
        self.trajectory
    }

    /// Advances one control period, following the path. `estimate` is the state the
    /// controller and guidance act on (`None`: the truth). Returns the controller's
    /// decision (`None` while resting).
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] for a non-finite estimate (nothing changes),
    /// [`TrajError::FlightDiverged`] if the truth stops being finite.
    pub fn step(
        &mut self,
        estimate: Option<&ControlState>,
        rng: &mut impl Rng,
    ) -> Result<Option<ControlOutput>, TrajError> {
        self.advance(None, estimate, rng)
    }

    /// Advances one control period toward `setpoint` instead of the path's (the
    /// guidance is not updated): for step responses and manual flight.
    ///
    /// # Errors
    /// As [`Flight::step`].
    pub fn step_with_setpoint(
        &mut self,
        setpoint: &Setpoint,
        estimate: Option<&ControlState>,
        rng: &mut impl Rng,
    ) -> Result<Option<ControlOutput>, TrajError> {
        self.advance(Some(setpoint), estimate, rng)
    }

    fn advance(
        &mut self,
        setpoint: Option<&Setpoint>,
        estimate: Option<&ControlState>,
        rng: &mut impl Rng,
    ) -> Result<Option<ControlOutput>, TrajError> {
        if let Some(e) = estimate {
            e.check()?;
        }
        let t = self.time();
        let dt = self.quad.flight.control_dt();
        let v = self.quad.vehicle;
        let wind_now = self.quad.wind.velocity(&self.wind);
        let resting = self.is_resting();
        let (input, output, next) = if resting {
            let input = StepInput {
                thrust_cmd: [v.hover_thrust_per_rotor(); 4],
                wind_in_nav: wind_now,
            };
            (input, None, self.state)
        } else {
            let cs = estimate
                .copied()
                .unwrap_or_else(|| self.truth_as_control_state());
            let sp = match setpoint {
                Some(sp) => *sp,
                None => self.guidance.update(t, &cs, dt),
            };
            let out = self.controller.update(&cs, &sp, dt);
            let input = StepInput {
                thrust_cmd: out.thrust_cmd,
                wind_in_nav: wind_now,
            };
            let next = integrate(&v, &self.state, &input, dt, self.quad.flight.physics_dt());
            (input, Some(out), next)
        };
        if !next.is_finite() {
            return Err(TrajError::FlightDiverged {
                t: t + dt,
                what: "true state".into(),
            });
        }
        let last = self.trajectory.last_mut();
        last.input = input;
        last.held = resting;
        self.quad.wind.step(&mut self.wind, dt, rng);
        self.steps_done += 1;
        self.state = next;
        self.trajectory.push(FlightSample {
            time: self.time(),
            state: next,
            input,
            held: self.is_resting(),
        });
        Ok(output)
    }
}

/// Flies `path` on the truth from rest to the end of the last waypoint's hover and
/// returns the flown trajectory.
///
/// # Errors
/// [`TrajError::PathNotCompleted`] if the path is not done within the flight's
/// `max_duration_s`; [`TrajError::FlightDiverged`] as [`Flight::step`].
pub fn fly_on_truth(
    quad: &Quadrotor,
    path: &Path,
    rng: &mut impl Rng,
) -> Result<FlownTrajectory, TrajError> {
    let mut flight = Flight::new(quad, path, rng);
    let max = quad.flight.params().max_duration_s;
    while !flight.is_finished() {
        if flight.time() >= max {
            return Err(TrajError::PathNotCompleted {
                max_duration: max,
                phase: format!("{:?}", flight.guidance().phase()),
            });
        }
        flight.step(None, rng)?;
    }
    Ok(flight.into_trajectory())
}
