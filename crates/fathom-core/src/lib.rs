//! Shared vocabulary of fathom: time stamps, NED/body frame conventions, Gaussians,
//! stamped measurement records and the errors they raise, and the ray-casting
//! interface through which sensors and estimators see a map ([`raycast`]).
//!
//! Every other fathom crate speaks in these types. Conventions (project wide):
//!
//! - SI units inside the code; conversions from knots, degrees, ... are named
//!   functions in [`units`] and happen once, at the configuration boundary.
//! - Navigation frame NED (x north, y east, z down, so `z` is depth); body frame
//!   x forward, y starboard, z down; Euler angles roll/pitch/yaw in ZYX order.
//! - Time is `f64` seconds from the start of the run ([`Time`]).
//!
//! ```
//! use fathom_core::{frames::{nav_from_body, Euler}, Gaussian, units};
//! use nalgebra::{Matrix2, Vector2, Vector3};
//!
//! // A vehicle heading east (yaw 90 deg) moving forward at 2 knots.
//! let att = Euler::new(0.0, 0.0, units::deg_to_rad(90.0));
//! let vel_in_nav = nav_from_body(&att) * Vector3::new(units::knots_to_mps(2.0), 0.0, 0.0);
//! assert!((vel_in_nav.y - 1.028_888).abs() < 1e-6);
//!
//! // A checked Gaussian: bad covariances are errors, not panics.
//! let g = Gaussian::new(Vector2::new(1.0, 2.0), Matrix2::new(2.0, 0.5, 0.5, 1.0)).unwrap();
//! assert_eq!(g.mean()[1], 2.0);
//! assert!(Gaussian::new(Vector2::zeros(), Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_err());
//! ```
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod echo;
pub mod error;
pub mod frames;
pub mod gaussian;
pub mod measurement;
pub mod raycast;
pub mod time;
pub mod units;

pub use error::{CoreError, ParameterError};
pub use gaussian::Gaussian;
pub use measurement::{Measurement, SensorId};
pub use raycast::{Material, Ray, RayCaster, RayHit};
pub use time::Time;
