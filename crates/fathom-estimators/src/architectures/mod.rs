//! Multi-sensor fusion architectures built on [`KalmanFilter`](crate::KalmanFilter)
//! (paper A, Lee & Yoon 2011): measurement fusion, track-to-track fusion with a
//! selectable fusion rule, and the equalize-fuse-feedback (EFF) structure.
//!
//! | type | structure |
//! | --- | --- |
//! | [`MeasurementFusion`] | one KF, all sensors' measurements stacked in one update (centralized, "MF") |
//! | [`TrackToTrack`] | one KF per sensor, the two corrected estimates fused each step ("T2T") with a [`FusionRule`]: eq. (10), Bar-Shalom–Campo or covariance intersection |
//! | [`EqualizeFuseFeedback`] | the paper's proposal: (1) equalize the sensors' states with the `R` weights (eq. 9), (2) per-sensor predict/correct from the equalized prior, (3) fuse with eq. (10), (4) feed the fused state back into the main sensor; steps 1 and 4 are switchable ([`EffSwitches`]) |
//!
//! # Feedback without knowing the sensor
//! The estimators never depend on a sensor crate. The EFF feedback goes through the
//! narrow [`FeedbackSink`] trait: the caller implements it for whatever integrates
//! the main sensor (the experiment layer wraps its INS integrator in a small
//! adapter) and the EFF step calls it with the fused estimate. [`NoFeedback`] is the
//! sink for callers that reset their integrator themselves from the returned state.
//!
//! # Failure atomicity
//! Every `step` works on copies of the filters and commits only when every sub-step
//! (and the feedback call) succeeded: a failing step leaves the architecture unchanged.
//!
//! ```
//! use fathom_core::Gaussian;
//! use fathom_estimators::architectures::{FusionRule, TrackModel, TrackToTrack};
//! use nalgebra::{SMatrix, SVector};
//!
//! // Paper-A tuning: INS track (w = 10, v = 9.8) and DVL track (w = 1, v = 0.02).
//! let ins = TrackModel::cv_position_3d(1.0, 10.0, 9.8).unwrap();
//! let dvl = TrackModel::cv_position_3d(1.0, 1.0, 0.02).unwrap();
//! let prior = Gaussian::new(SVector::<f64, 6>::zeros(), SMatrix::<f64, 6, 6>::identity()).unwrap();
//! let mut t2t = TrackToTrack::new(
//!     prior.clone(), prior, SMatrix::zeros(), 0.0, ins, dvl, FusionRule::Independent,
//! ).unwrap();
//! let z_ins = SVector::<f64, 3>::new(3.0, 0.0, 0.0);
//! let z_dvl = SVector::<f64, 3>::new(0.1, 0.0, 0.0);
//! let fused = t2t.step(1.0, &z_ins, &z_dvl).unwrap();
//! // The DVL track dominates: its R is 0.02^2 against 9.8^2.
//! assert!((fused.mean()[0] - 0.1).abs() < 1e-3);
//! ```

mod eff;
mod measurement_fusion;
pub mod rules;
mod track_to_track;

pub use eff::{
    EffOutput, EffSwitches, Equalization, EqualizeFuseFeedback, StateComponent, cv_layout_3d,
};
pub use measurement_fusion::{MeasurementFusion, SensorBlock};
pub use rules::{FusionRule, fuse_bar_shalom_campo, fuse_covariance_intersection};
pub use track_to_track::{TrackSnapshot, TrackToTrack};

use crate::{EstimatorError, models};
use fathom_core::{CoreError, Gaussian, Time, error::ensure_finite, gaussian::check_covariance};
use nalgebra::SMatrix;

/// Errors of the fusion architectures: which track or step failed, at what time.
#[derive(Debug, thiserror::Error)]
pub enum ArchitectureError {
    /// A filter step (predict, update, set state) of one track failed.
    #[error("track `{track}`: {source}")]
    Filter {
        /// Which track ("main", "aux", "mf").
        track: &'static str,
        /// The filter's error (carries the time stamp).
        #[source]
        source: EstimatorError,
    },
    /// Fusing the two track estimates failed.
    #[error("{rule} fusion at t = {time} s: {source}")]
    Fusion {
        /// The fusion rule's name.
        rule: &'static str,
        /// Time of the fused estimate, s.
        time: Time,
        /// The underlying error.
        #[source]
        source: EstimatorError,
    },
    /// The feedback sink refused the fused estimate.
    #[error("feedback into the main sensor at t = {time} s failed: {source}")]
    Feedback {
        /// Time of the fused estimate, s.
        time: Time,
        /// The sink's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// A configuration value is invalid (model matrices, measurement block sizes,
    /// equalization layout).
    #[error("{what}: {reason}")]
    InvalidConfig {
        /// What was configured.
        what: String,
        /// Why it is invalid.
        reason: String,
    },
}

impl ArchitectureError {
    fn filter(track: &'static str) -> impl FnOnce(EstimatorError) -> Self {
        move |source| Self::Filter { track, source }
    }

    fn config(what: impl Into<String>, err: CoreError) -> Self {
        Self::InvalidConfig {
            what: what.into(),
            reason: err.to_string(),
        }
    }
}

/// The narrow interface through which the EFF step feeds the fused estimate back
/// into the main sensor (step 4). Implemented by the caller for its integrator, e.g.
/// an INS whose position and velocity are reset to the fused state.
pub trait FeedbackSink<const N: usize> {
    /// Why the sink could not take the estimate.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Takes the fused estimate at `time` (s). Called once per EFF step when
    /// feedback is switched on, after the fusion and before the step commits.
    ///
    /// # Errors
    /// The sink's own error; the EFF step then fails and stays unchanged.
    fn feed_back(&mut self, time: Time, fused: &Gaussian<N>) -> Result<(), Self::Error>;
}

/// A sink that ignores the estimate (feedback switched off, or done by the caller
/// from the returned [`EffOutput`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoFeedback;

impl<const N: usize> FeedbackSink<N> for NoFeedback {
    type Error = std::convert::Infallible;

    fn feed_back(&mut self, _time: Time, _fused: &Gaussian<N>) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The linear model of one track: transition `F`, process noise `Q`, measurement
/// matrix `H` and measurement noise `R` for a fixed step (paper A eqs. (5)-(6)).
#[derive(Debug, Clone, PartialEq)]
pub struct TrackModel<const N: usize, const M: usize> {
    f: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    h: SMatrix<f64, M, N>,
    r: SMatrix<f64, M, M>,
}

impl<const N: usize, const M: usize> TrackModel<N, M> {
    /// Checks and builds a model.
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] for non-finite `F` or `H`, a `Q` that is
    /// not symmetric with a non-negative diagonal, or an `R` that is not symmetric
    /// positive definite.
    pub fn new(
        f: SMatrix<f64, N, N>,
        q: SMatrix<f64, N, N>,
        h: SMatrix<f64, M, N>,
        r: SMatrix<f64, M, M>,
    ) -> Result<Self, ArchitectureError> {
        ensure_finite("transition matrix F", f.iter())
            .map_err(|e| ArchitectureError::config("track model", e))?;
        ensure_finite("measurement matrix H", h.iter())
            .map_err(|e| ArchitectureError::config("track model", e))?;
        ensure_finite("process noise Q", q.iter())
            .map_err(|e| ArchitectureError::config("track model", e))?;
        for i in 0..N {
            if q[(i, i)] < 0.0 {
                return Err(ArchitectureError::InvalidConfig {
                    what: "track model process noise Q".into(),
                    reason: format!("diagonal entry {i} is negative ({})", q[(i, i)]),
                });
            }
            for j in 0..i {
                let tol = fathom_core::gaussian::SYMMETRY_TOLERANCE
                    * (1.0 + q[(i, j)].abs().max(q[(j, i)].abs()));
                if (q[(i, j)] - q[(j, i)]).abs() > tol {
                    return Err(ArchitectureError::InvalidConfig {
                        what: "track model process noise Q".into(),
                        reason: format!("not symmetric at ({i}, {j})"),
                    });
                }
            }
        }
        check_covariance("measurement noise R", &r)
            .map_err(|e| ArchitectureError::config("track model", e))?;
        Ok(Self { f, q, h, r })
    }

    /// Transition matrix `F`.
    pub fn f(&self) -> &SMatrix<f64, N, N> {
        &self.f
    }

    /// Process noise `Q`.
    pub fn q(&self) -> &SMatrix<f64, N, N> {
        &self.q
    }

    /// Measurement matrix `H`.
    pub fn h(&self) -> &SMatrix<f64, M, N> {
        &self.h
    }

    /// Measurement noise `R`.
    pub fn r(&self) -> &SMatrix<f64, M, M> {
        &self.r
    }
}

impl TrackModel<6, 3> {
    /// The paper-A track model for the state `[x, vx, y, vy, z, vz]`: constant
    /// velocity `A` with step `dt`, `Q = w^2 I6`, `H` selecting the position,
    /// `R = v^2 I3`.
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] for a negative or non-finite `dt` or `w`,
    /// or a `v` that is not positive and finite.
    pub fn cv_position_3d(dt: f64, w: f64, v: f64) -> Result<Self, ArchitectureError> {
        let f = models::cv_transition_3d(dt).map_err(|e| ArchitectureError::InvalidConfig {
            what: "track model dt".into(),
            reason: e.to_string(),
        })?;
        let q =
            models::cv_scaled_identity_q_3d(w).map_err(|e| ArchitectureError::InvalidConfig {
                what: "track model w".into(),
                reason: e.to_string(),
            })?;
        if !(v.is_finite() && v > 0.0) {
            return Err(ArchitectureError::InvalidConfig {
                what: "track model v".into(),
                reason: format!("measurement noise std must be positive and finite, got {v}"),
            });
        }
        Self::new(
            f,
            q,
            models::cv_position_h_3d(),
            SMatrix::<f64, 3, 3>::identity() * (v * v),
        )
    }

    /// Constant-velocity track in the paper-A layout with the discrete
    /// white-noise-acceleration `Q` of standard deviation `accel_sigma` (m/s^2,
    /// [`models::cv_discrete_white_accel_q_3d`]) and a position measurement of
    /// standard deviation `pos_sigma` (m): the reading of paper A's tuning in the
    /// notation of its references (Bar-Shalom; Li and Jilkov).
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] for a bad `dt` or `accel_sigma`, or a
    /// `pos_sigma` that is not positive and finite.
    pub fn cv_position_3d_dwna(
        dt: f64,
        accel_sigma: f64,
        pos_sigma: f64,
    ) -> Result<Self, ArchitectureError> {
        let invalid = |what: &str, e: EstimatorError| ArchitectureError::InvalidConfig {
            what: what.into(),
            reason: e.to_string(),
        };
        let f = models::cv_transition_3d(dt).map_err(|e| invalid("track model dt", e))?;
        let q = models::cv_discrete_white_accel_q_3d(dt, accel_sigma)
            .map_err(|e| invalid("track model acceleration std", e))?;
        if !(pos_sigma.is_finite() && pos_sigma > 0.0) {
            return Err(ArchitectureError::InvalidConfig {
                what: "track model position std".into(),
                reason: format!("must be positive and finite, got {pos_sigma}"),
            });
        }
        Self::new(
            f,
            q,
            models::cv_position_h_3d(),
            SMatrix::<f64, 3, 3>::identity() * (pos_sigma * pos_sigma),
        )
    }
}
