//! Navigation sensor models for fathom: jittered sample-time schedules, noise
//! processes, DVL / AHRS / range / depth sensors, the beacons-paper sensor suite
//! and the integrated-position sensors (INS, DVL dead reckoning) of the fusion paper.
//!
//! Every sensor reads the true state of a [`fathom_traj::Trajectory`] at its exact
//! sample time and returns a [`fathom_core::Measurement`] keeping both the noisy
//! and the noise-free value. All randomness comes from an explicit `rng`; same seed
//! and parameters give bit-identical data.
//!
//! ```
//! use fathom_core::{frames::Euler, SensorId, Time};
//! use fathom_sensors::models::{RangeParams, SensorModel};
//! use fathom_traj::{TrajError, Trajectory, TrueState};
//! use nalgebra::Vector3;
//! use rand::SeedableRng;
//!
//! /// A vehicle standing still at 10 m depth.
//! struct Still;
//! impl Trajectory for Still {
//!     fn start_time(&self) -> Time { 0.0 }
//!     fn end_time(&self) -> Time { 100.0 }
//!     fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
//!         Ok(TrueState {
//!             time: t,
//!             pos_in_nav: Vector3::new(0.0, 0.0, 10.0),
//!             vel_in_nav: Vector3::zeros(),
//!             acc_in_nav: Vector3::zeros(),
//!             attitude: Euler::default(),
//!             omega_body: Vector3::zeros(),
//!         })
//!     }
//! }
//!
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//! // Range to a beacon 30 m north at the surface, sigma 0.1 m (the default).
//! let range = RangeParams::new(0, Vector3::new(30.0, 0.0, 0.0)).check().unwrap();
//! let m = range.measure(&Still, 5.0, 5.0, &mut rng).unwrap();
//! assert_eq!(m.sensor, SensorId::Range(0));
//! assert!((m.true_value - 1000.0f64.sqrt()).abs() < 1e-12);
//! assert!((m.value - m.true_value).abs() < 0.5); // 5 sigma
//! // Bad parameters are errors, not panics.
//! assert!(RangeParams { sigma: -1.0, ..RangeParams::new(0, Vector3::zeros()) }.check().is_err());
//! ```
//!
//! Modules: [`schedule`] (Table 2-3 clocks), [`noise`] (white, held common-mode,
//! outliers, bias, scale factor, Gauss-Markov, random walk), [`models`] (DVL, AHRS,
//! range, depth), [`suite`] (the beacons-paper generator and its design
//! covariance), [`integrated`] (INS and DVL dead reckoning), [`inertial`] (IMU error
//! model, with flicker bias instability), [`allan_imu`] (IMU figures from an Allan
//! analysis: the ADIS16448 of seed 004), [`barometer`] (eq. 20 and the linear
//! calibration eq. 11); against a map (through [`fathom_core::RayCaster`], so without
//! depending on the map crate): [`map_range`] (range finders and the lidar), [`gnss`]
//! (constellation, line of sight, pseudoranges, Doppler, single-point positioning,
//! BESTPOS).
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod allan_imu;
pub mod barometer;
pub mod error;
pub mod gnss;
pub mod inertial;
pub mod integrated;
pub mod magnetic;
pub mod map_range;
pub mod models;
pub mod noise;
pub mod schedule;
pub mod suite;
pub mod underwater;

pub use error::SensorError;
pub use suite::{
    BeaconSuiteConfig, BeaconSuiteData, BeaconSuiteParams, NoiseSwitches, OutlierHit, Timing,
    design_covariance, simulate_beacon_suite,
};
