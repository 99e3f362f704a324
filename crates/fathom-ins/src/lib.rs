//! Strapdown inertial navigation for fathom: WGS-84 Earth model, local-level NED
//! mechanization, error-free IMU increments from a true trajectory, and the 15-state
//! INS error dynamics; and the reduced mechanization of seed 004 (local NED,
//! constant gravity, no Earth rate) with its exact IMU inversion ([`local_level`]).
//!
//! ```
//! use fathom_ins::{earth::Geodetic, imu_from_truth::{imu_from_truth, stationary_truth},
//!     strapdown::Strapdown};
//! use nalgebra::UnitQuaternion;
//!
//! // A vehicle resting at 35 N 129 E, 50 m deep, heading 045, for 60 s at 100 Hz.
//! let pos = Geodetic::new(35f64.to_radians(), 129f64.to_radians(), -50.0);
//! let att = UnitQuaternion::from_euler_angles(0.01, -0.02, 45f64.to_radians());
//! let truth = stationary_truth(pos, att, 0.01, 6001).unwrap();
//! let increments = imu_from_truth(&truth).unwrap();
//!
//! // The gyros read Earth rate (15.041 deg/hr) ...
//! let rate_deg_hr = increments[0].mean_angular_rate().norm().to_degrees() * 3600.0;
//! assert!((rate_deg_hr - 15.041).abs() < 1e-3);
//!
//! // ... and the INS fed with them stays put.
//! let mut ins = Strapdown::new(truth[0].to_ins_state()).unwrap();
//! for inc in &increments {
//!     ins.step(inc).unwrap();
//! }
//! let err = fathom_ins::earth::curvilinear_offset(&pos, &ins.state().position());
//! assert!(err.norm() < 1e-6, "position error {err} m");
//! ```
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod earth;
pub mod error;
pub mod error_model;
pub mod imu_from_truth;
pub mod local_level;
pub mod rotation;
pub mod route;
pub mod state;
pub mod strapdown;

pub use error::InsError;
pub use imu_from_truth::{ImuFromTruth, TruthSample, imu_from_truth};
pub use state::{ImuIncrement, InsState};
pub use strapdown::{Strapdown, VerticalChannel};
