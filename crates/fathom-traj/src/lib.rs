//! True trajectories for simulation: natural cubic splines, the `fusion` UUV
//! mission, the velocity-command kinematic motion of the `beacons` paper, and the
//! flown quadrotor of the `urban` paper ([`quadrotor`]: rigid body, cascaded control,
//! path guidance).
//!
//! Everything here describes what the vehicle *really* did; sensors sample it and
//! estimators never see it. Every trajectory implements [`Trajectory`], which gives
//! the [`TrueState`] (NED position, velocity, acceleration, attitude, body rates) at
//! any time of its range; asking outside the range is a [`TrajError::OutOfRange`].
//!
//! ```
//! use fathom_traj::{
//!     FusionMissionParams, Trajectory, VelocityCommandMotion, VelocityCommandParams,
//!     detect_course_changes, generate_fusion_mission,
//! };
//! use rand::SeedableRng;
//! use rand_chacha::ChaCha8Rng;
//!
//! // The `fusion` mission (spec A): 25 spline knots over 1000 s, search at 100 m.
//! let params = FusionMissionParams::default().check().unwrap();
//! let mut traj_rng = ChaCha8Rng::seed_from_u64(1);
//! let mission = generate_fusion_mission(&params, &mut traj_rng).unwrap();
//! let (s0, s1) = mission.search_interval();
//! let mid = mission.trajectory().state_at(0.5 * (s0 + s1)).unwrap();
//! assert!((mid.pos_in_nav.z - 100.0).abs() < 1.0);
//! let turns = detect_course_changes(mission.trajectory(), 0.0, 1000.0, 1.0, 45f64.to_radians())
//!     .unwrap();
//! assert_eq!(turns.len(), 10);
//!
//! // The velocity-command helix (spec B): 0.01 s steps, 180 s, noisy body velocity.
//! let vc = VelocityCommandParams::default().check().unwrap();
//! let motion = VelocityCommandMotion::generate(&vc, &mut ChaCha8Rng::seed_from_u64(2)).unwrap();
//! assert_eq!(motion.samples().len(), 18_001);
//! // A sensor sampling between motion steps sees the propagated state.
//! let s = motion.state_at(12.345).unwrap();
//! assert!(s.pos_in_nav.z > 0.0);
//! // Out-of-range times are errors, not panics.
//! assert!(motion.state_at(181.0).is_err());
//! ```
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod error;
pub mod fusion_mission;
pub mod quadrotor;
pub mod seabed;
pub mod spline;
pub mod spline_trajectory;
pub mod state;
pub mod velocity_command;

pub use error::TrajError;
pub use fusion_mission::{
    CheckedFusionMissionParams, FusionMission, FusionMissionParams, detect_course_changes,
    generate_fusion_mission,
};
pub use seabed::SeabedProfile;
pub use spline::{CubicSpline, CubicSpline3, SplinePoint, SplinePoint3};
pub use spline_trajectory::{SplineTrajectory, body_rates_from_euler_rates_matrix};
pub use state::{Trajectory, TrueState};
pub use velocity_command::{
    CheckedVelocityCommandParams, MotionSample, VelocityCommandMotion, VelocityCommandParams,
};
