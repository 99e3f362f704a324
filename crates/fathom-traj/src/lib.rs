//! True trajectories for simulation: natural cubic splines, the `fusion` UUV
//! mission, and the velocity-command kinematic motion of the `beacons` paper.
//!
//! Everything here describes what the vehicle *really* did; sensors sample it and
//! estimators never see it.

pub mod error;
pub mod state;

pub use error::TrajError;
pub use state::{Trajectory, TrueState};
