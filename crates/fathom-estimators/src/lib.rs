//! Kalman filter core of fathom: a fixed-size linear/extended Kalman filter with
//! Joseph-form updates, innovation gating, sequential scalar and stacked (faer)
//! updates, track-to-track fusion (paper A eq. (10)) and constant-velocity models.
//!
//! ```
//! use fathom_core::Gaussian;
//! use fathom_estimators::{GateThreshold, KalmanFilter, models};
//! use nalgebra::{Matrix1, Matrix2, RowVector2, SMatrix, Vector1, Vector2};
//!
//! // 1-axis constant velocity [p, v], starting at t = 0.
//! let prior = Gaussian::new(Vector2::new(0.0, 1.0), Matrix2::identity()).unwrap();
//! let mut kf = KalmanFilter::new(prior, 0.0).unwrap();
//! let f = models::cv_transition_1d(1.0).unwrap();
//! let q = models::cv_white_accel_q_1d(1.0, 0.01).unwrap();
//! kf.predict(&f, &q, 1.0).unwrap();
//!
//! // Position measurement z = p + v, v ~ N(0, 0.5^2), gated at 2.5 sigma.
//! let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
//! let r = Matrix1::new(0.25);
//! let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
//! let outcome = kf.update_gated(&Vector1::new(1.2), &h, &r, gate).unwrap();
//! assert!(outcome.is_accepted());
//! assert!(kf.covariance()[(0, 0)] < 0.25);
//! assert_eq!(kf.time(), 1.0);
//!
//! // Bad input is an error naming what failed, and the filter is left unchanged.
//! let before = kf.clone();
//! assert!(kf.update(&Vector1::new(f64::NAN), &h, &r).is_err());
//! assert_eq!(kf, before);
//!
//! // Sequential scalar updates (diagonal R), e.g. two position fixes.
//! let rep = kf
//!     .update_sequential_scalar(&[1.1, 1.3], &[RowVector2::new(1.0, 0.0); 2], &[0.25, 0.25], None)
//!     .unwrap();
//! assert_eq!(rep.num_accepted(), 2);
//!
//! // Track-to-track fusion of two independent estimates (eq. (10)).
//! let a = Gaussian::new(Vector1::new(1.0), Matrix1::new(1.0)).unwrap();
//! let b = Gaussian::new(Vector1::new(3.0), Matrix1::new(3.0)).unwrap();
//! let fused = fathom_estimators::fusion::fuse_information(&a, &b).unwrap();
//! assert!((fused.mean()[0] - 1.5).abs() < 1e-12 && (fused.cov()[(0, 0)] - 0.75).abs() < 1e-12);
//! ```
//!
//! Map-aided navigation (seed 004) lives in [`map_aided`]: the 12-state error-state
//! INS with GPS/INS, GREKF, MGPMF and particle-filter updates and the mode switching;
//! it sees the map only through [`fathom_core::RayCaster`].
//!
//! Post-processing lives in [`smoother`]: the filters record their forward pass on
//! request, and the Rauch-Tung-Striebel backward pass (fixed interval, or fixed lag)
//! gives every step's estimate given all the data.
//!
//! Error convention: filter steps return [`EstimatorError`] variants carrying the
//! filter time stamp; time-free helpers (fusion, [`gating::nis`], [`models`]) wrap a
//! [`fathom_core::CoreError`]. Every failing step leaves the filter unchanged.
//!
//! # Bad input
//!
//! One policy for every filter: bad data never reach the state or the covariance.
//! A non-finite (NaN, +-inf) measurement, input or time is either **refused with an
//! error** naming the quantity, the index and the filter time (the default), or,
//! in the filter built to skip bad data (the scheme policy, which already logs
//! every measurement's fate), **dropped and counted**: logged, counted in the
//! report and never applied. A covariance that stops being positive definite
//! (an absurd input that overflows, an indefinite `Q`, a variance `<= 0`) is always
//! an error carrying the filter time of the failing step (usually
//! [`EstimatorError::NotPositiveDefinite`], or [`EstimatorError::NonFinite`] for
//! "predicted covariance P" when it overflowed). Every failing step leaves the
//! filter unchanged, so no NaN is ever propagated.
//!
//! | filter | entry points | non-finite measurement / input / time | covariance loses positive definiteness |
//! | --- | --- | --- | --- |
//! | [`KalmanFilter`] ([`kalman`], [`stacked`]) | `predict*`, `update*`, `update_sequential_scalar*`, `update_stacked*` | error: quantity, index, time | error with the time ("innovation covariance S", "predicted / updated covariance P") |
//! | [`ekf::Ekf`] (beacon and wheel-odometry models) | `predict_to`, `update_sequential`, `update_stacked`, `try_apply_input` | error: quantity, item index, time (a model's input error is stamped with the prediction's target time; an unchecked `apply_input` sample fails the next prediction) | error with the time |
//! | [`schemes::SchemeFilter`] (+ [`robust`]) | `process`, `advance_to` | **dropped + counted**: [`schemes::Disposition::NonFinite`], [`schemes::ChannelCounts::non_finite`], [`schemes::SchemeFilter::non_finite_inputs`] | error with the time of the failing epoch / prediction; the group stays pending |
//! | [`velocity_filter::VelocityFilter`] | `predict`, `update`, `step` (all or nothing) | error: quantity, time | error with the time |
//! | [`integrated_nav::IntegratedNavFilter`] | `propagate` (also refuses an overflowing state), `propagate_covariance`, `update_velocity`, `update_depth` | error: quantity, index, time | error with the time |
//! | [`error_state::ErrorStateFilter`] | `predict`, `update_velocity`, `update_depth` | error: quantity (INS / aid / depth, `Phi`, `Q_d`), index, time | error with the time |
//! | [`architectures::MeasurementFusion`] | `step`, `step_stacked` | error: sensor, index in its block, time | error with the time |
//! | [`architectures::TrackToTrack`] | `step` | error: track, index, time | filter or fusion error with the time |
//! | [`architectures::EqualizeFuseFeedback`] | `step` | error: track, sensor state / measurement, index, time | filter or fusion error with the time |
//! | [`map_aided`] ([`map_aided::Ins12Filter`], [`map_aided::Grekf`], [`map_aided::Mgpmf`], [`map_aided::ParticleFilter`], [`map_aided::SwitchingFilter`]) | `predict`, `update_gps`, `update`, `update_map`, `observe_los` | error [`map_aided::MapAidedError`]: quantity, beam index, time; a pose from which no ray hits the map is [`map_aided::MapAidedError::PoseOutsideMap`] with the time (filter and particles unchanged) | error with the time |
//! | [`smoother`] ([`smoother::ForwardPass`], [`smoother::FixedLagSmoother`]) | `push_*` / `record_*` (never fail; a misuse is kept), `smooth*`, `lagged` | error at `smooth*`: quantity, step index, time | [`EstimatorError::NotPositiveDefinite`] naming the step, with its time |
//! | [`fusion`], [`architectures::rules`], [`gating::nis`] (no notion of time) | `fuse_*`, `nis` | [`EstimatorError::Core`] (the architectures add the time) | [`EstimatorError::Core`] |
//!
//! A NaN NIS never passes a gate ([`GateThreshold::accepts`]). The INS crate
//! (`fathom-ins`) follows the same rule: `Strapdown::step` refuses a non-finite
//! increment or a step whose new state would not be finite (the strapdown has no
//! clock: the caller adds the time), and the error-model functions are pure (a NaN
//! in gives a NaN `Phi` / `Q_d`, which [`error_state::ErrorStateFilter::predict`]
//! refuses with the time).
//!
//! Allocation: the fixed-size path (`predict*`, `update*` with `const M`) does not
//! allocate except to build an error. The sequential update allocates its report; the
//! stacked update allocates faer/nalgebra dynamic matrices.
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod architectures;
pub mod beacon_ekf;
pub mod dynamic;
pub mod ekf;
pub mod error;
pub mod error_state;
pub mod fusion;
pub mod gating;
pub mod integrated_nav;
pub mod kalman;
pub(crate) mod lanes;
pub(crate) mod linalg;
pub mod map_aided;
pub mod models;
pub mod noise;
pub mod robust;
pub mod schemes;
pub mod simd;
pub mod smoother;
pub mod stacked;
pub mod velocity_filter;
pub mod wheel_odometry;

#[cfg(test)]
mod consistency_tests;

pub use dynamic::DynKalmanFilter;
pub use error::EstimatorError;
pub use fusion::fuse_information;
pub use gating::{Gate, GateThreshold, UpdateInfo};
pub use kalman::{KalmanFilter, ScalarMeasurement, ScalarOutcome, SequentialReport};
pub use noise::{MeasurementNoise, ProcessNoise};
pub use stacked::{StackedGatedReport, StackedUpdateInfo};
