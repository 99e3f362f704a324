//! Noise covariances validated once: [`MeasurementNoise`] (`R`: finite, symmetric,
//! positive definite) and [`ProcessNoise`] (`Q`: finite, symmetric, non-negative
//! diagonal), so that filter steps with a constant noise do not re-check it every
//! step ([`crate::KalmanFilter::update_with_noise`],
//! [`crate::KalmanFilter::predict_with_noise`]).

use crate::{EstimatorError, kalman::check_process_noise};
use fathom_core::gaussian::{check_covariance, symmetrize};
use nalgebra::{SMatrix, SVector};

/// A checked measurement noise covariance `R` (`M x M`, finite, symmetric within
/// [`fathom_core::gaussian::SYMMETRY_TOLERANCE`], positive definite), stored exactly
/// symmetric.
///
/// ```
/// use fathom_estimators::MeasurementNoise;
/// use nalgebra::{Matrix2, Vector2};
/// let r = MeasurementNoise::new(Matrix2::new(0.5, 0.1, 0.1, 0.4)).unwrap();
/// assert_eq!(r.matrix()[(0, 1)], 0.1);
/// assert!(MeasurementNoise::new(Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_err());
/// assert!(MeasurementNoise::diagonal(Vector2::new(0.25, 0.0)).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurementNoise<const M: usize> {
    r: SMatrix<f64, M, M>,
}

impl<const M: usize> MeasurementNoise<M> {
    /// Checks `r` once.
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`], [`EstimatorError::NotSymmetric`] or
    /// [`EstimatorError::NotPositiveDefinite`] naming "measurement noise R" (time
    /// stamp 0: the noise is not tied to a filter time).
    pub fn new(r: SMatrix<f64, M, M>) -> Result<Self, EstimatorError> {
        check_covariance("measurement noise R", &r)
            .map_err(|e| EstimatorError::from_core_at(e, 0.0))?;
        Ok(Self { r: symmetrize(&r) })
    }

    /// A diagonal `R = diag(variances)` (each variance finite and > 0).
    ///
    /// # Errors
    /// As [`MeasurementNoise::new`].
    pub fn diagonal(variances: SVector<f64, M>) -> Result<Self, EstimatorError> {
        Self::new(SMatrix::from_diagonal(&variances))
    }

    /// The covariance `R`.
    pub fn matrix(&self) -> &SMatrix<f64, M, M> {
        &self.r
    }
}

/// A checked process noise covariance `Q` (`N x N`): finite, symmetric within
/// [`fathom_core::gaussian::SYMMETRY_TOLERANCE`] relative to its largest diagonal
/// entry, non-negative diagonal: exactly what [`crate::KalmanFilter::predict`]
/// checks every step. Stored as `(Q + Q^T) / 2`, so
/// [`crate::KalmanFilter::predict_with_noise`] gives the same bits as `predict` with
/// the raw `Q`, without the per-step check (on a 6-state step the check is ~15 % of
/// the prediction: it reads `Q` transposed).
///
/// ```
/// use fathom_estimators::ProcessNoise;
/// use nalgebra::Matrix2;
/// let q = ProcessNoise::new(Matrix2::new(0.01, 0.002, 0.002, 0.02)).unwrap();
/// assert_eq!(q.matrix()[(1, 0)], 0.002);
/// assert!(ProcessNoise::new(Matrix2::new(-0.01, 0.0, 0.0, 0.02)).is_err());
/// assert!(ProcessNoise::new(Matrix2::new(0.01, 0.5, 0.0, 0.02)).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProcessNoise<const N: usize> {
    q: SMatrix<f64, N, N>,
}

impl<const N: usize> ProcessNoise<N> {
    /// Checks `q` once (the checks of [`crate::KalmanFilter::predict`]; positive
    /// semi-definiteness is not required of `Q` itself, the predicted covariance
    /// must be positive definite).
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`], [`EstimatorError::NotSymmetric`] or
    /// [`EstimatorError::NotPositiveDefinite`] (negative diagonal entry) naming
    /// "process noise Q" (time stamp 0: the noise is not tied to a filter time).
    pub fn new(q: SMatrix<f64, N, N>) -> Result<Self, EstimatorError> {
        check_process_noise(&q, 0.0)?;
        Ok(Self { q: symmetrize(&q) })
    }

    /// The covariance `(Q + Q^T) / 2`.
    pub fn matrix(&self) -> &SMatrix<f64, N, N> {
        &self.q
    }
}
