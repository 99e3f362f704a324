//! [`MeasurementNoise`]: a measurement noise covariance `R` validated once (finite,
//! symmetric, positive definite), so that filter updates with a constant `R` do not
//! re-check it every step ([`crate::KalmanFilter::update_with_noise`]).

use crate::EstimatorError;
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
