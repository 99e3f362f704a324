//! The quadrotor truth of seed 004 (spec D, "Vehicle"): a 6-DOF rigid body with four
//! rotors, a cascaded controller and straight-leg path guidance, integrated with RK4;
//! the flown path is a [`crate::Trajectory`] so that every sensor model samples it.
//!
//! - [`params`]: settings (vehicle, gains, wind, clock, path) and their checks;
//! - [`allocation`]: moments from thrusts, eq. (21), and its inverse, eq. (22) (with
//!   the check that the paper's eq. (22) inverts eq. (21));
//! - [`dynamics`]: rigid body, motor lag, drag, wind; RK4;
//! - [`wind`]: mean wind plus Gauss-Markov gusts;
//! - [`controller`]: position/velocity -> thrust vector -> attitude -> rates -> moments;
//! - [`guidance`]: waypoints with hover times and yaw turns, along-leg speed plus
//!   cross-track correction;
//! - [`flight`]: the stepping API (truth or a caller's estimate in the loop) and
//!   [`fly_on_truth`];
//! - [`trajectory`]: the flown trajectory, exact between control instants.
//!
//! ```
//! use fathom_traj::Trajectory;
//! use fathom_traj::quadrotor::{PathParams, QuadrotorParams, Waypoint, fly_on_truth};
//! use nalgebra::Vector3;
//! use rand::SeedableRng;
//!
//! let quad = QuadrotorParams::default().check().unwrap();
//! // rest 10 s on the ground, climb 10 m, fly 20 m north, turn to east, hover 2 s
//! let path = PathParams::new(vec![
//!     Waypoint::new(Vector3::zeros(), 0.0),
//!     Waypoint::new(Vector3::new(0.0, 0.0, -10.0), 1.0),
//!     Waypoint::new(Vector3::new(20.0, 0.0, -10.0), 2.0).with_yaw(90f64.to_radians()),
//! ])
//! .check()
//! .unwrap();
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
//! let traj = fly_on_truth(&quad, &path, &mut rng).unwrap();
//! let end = traj.state_at(traj.end_time()).unwrap();
//! assert!((end.pos_in_nav - Vector3::new(20.0, 0.0, -10.0)).norm() < 0.3);
//! assert!((end.attitude.yaw.to_degrees() - 90.0).abs() < 1.0);
//! // an ideal accelerometer at rest reads -g along body z
//! let f = traj.specific_force_at(1.0).unwrap();
//! assert!((f.z + 9.806_65).abs() < 1e-12);
//! ```

pub mod allocation;
pub mod controller;
pub mod dynamics;
pub mod flight;
pub mod guidance;
pub mod params;
pub mod trajectory;
pub mod wind;

#[cfg(test)]
mod tests;

pub use allocation::{
    EQ21_EQ22_FINDINGS, eq22_discrepancies, moments_from_thrusts, thrusts_from_wrench,
};
pub use controller::{CascadedController, ControlOutput, ControlState, Setpoint};
pub use dynamics::{RigidBodyState, StepInput};
pub use flight::{Flight, fly_on_truth};
pub use guidance::{Guidance, Phase};
pub use params::{
    ControllerGains, ControllerParams, FlightParams, FlightSettings, Path, PathParams, Quadrotor,
    QuadrotorParams, Vehicle, VehicleParams, Waypoint, Wind, WindParams,
};
pub use trajectory::{FlightSample, FlownTrajectory, QuadState};
