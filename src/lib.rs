//! fathom: simulate navigation sensors and run, compare and evaluate navigation
//! estimators for underwater vehicles.
//!
//! This umbrella crate re-exports the layered fathom crates under short names, so
//! one dependency gives the whole toolkit; each crate can also be used on its own.
//!
//! ```
//! use fathom::core::{Gaussian, units};
//! use fathom::estimators::KalmanFilter;
//! use nalgebra::{Matrix1, Vector1};
//!
//! // A 1-D Kalman filter: prior N(0, 1), one measurement z = 1 with R = 1.
//! let prior = Gaussian::new(Vector1::new(0.0), Matrix1::new(1.0)).unwrap();
//! let mut kf = KalmanFilter::new(prior, 0.0).unwrap();
//! kf.update(&Vector1::new(1.0), &Matrix1::new(1.0), &Matrix1::new(1.0)).unwrap();
//! assert!((kf.state()[0] - 0.5).abs() < 1e-12);
//! assert!((units::knots_to_mps(1.0) - 0.514_444).abs() < 1e-6);
//! ```

pub use fathom_core as core;
pub use fathom_data as data;
pub use fathom_estimators as estimators;
pub use fathom_experiments as experiments;
pub use fathom_ins as ins;
pub use fathom_map as map;
pub use fathom_replay as replay;
pub use fathom_report as report;
pub use fathom_sensors as sensors;
pub use fathom_sim as sim;
pub use fathom_stats as stats;
pub use fathom_traj as traj;
