//! Noise covariances validated once: [`MeasurementNoise`] (`R`: finite, symmetric,
//! positive definite) and [`ProcessNoise`] (`Q`: finite, symmetric, non-negative
//! diagonal), so that filter steps with a constant noise do not re-check it every
//! step ([`crate::KalmanFilter::update_with_noise`],
//! [`crate::KalmanFilter::predict_with_noise`]); and the one `Q` check that
//! [`ProcessNoise`], the fixed-size [`crate::KalmanFilter`] and the run-time-size
//! [`crate::DynKalmanFilter`] all run (`check_process_noise`).

use crate::{EstimatorError, error::check_finite};
use fathom_core::Time;
use fathom_core::gaussian::{SYMMETRY_TOLERANCE, check_covariance, symmetrize};
use nalgebra::{Dim, IsContiguous, Matrix, RawStorage, SMatrix, SVector};

/// `Q` of any size, fixed or run-time (`q` square, checked by the caller): finite
/// (the row-major index of the first bad entry), non-negative diagonal, symmetric
/// within [`SYMMETRY_TOLERANCE`] relative to the largest diagonal entry; errors name
/// "process noise Q" and carry `time`.
pub(crate) fn check_process_noise<R: Dim, C: Dim, S>(
    q: &Matrix<f64, R, C, S>,
    time: Time,
) -> Result<(), EstimatorError>
where
    S: RawStorage<f64, R, C> + IsContiguous,
{
    const WHAT: &str = "process noise Q";
    let n = q.nrows();
    check_finite(WHAT, q.as_slice(), n, n, time)?;
    let mut scale = f64::MIN_POSITIVE;
    for i in 0..n {
        let d = q[(i, i)];
        if d < 0.0 {
            return Err(EstimatorError::NotPositiveDefinite {
                what: format!("{WHAT} (diagonal entry {i} = {d})"),
                time,
            });
        }
        scale = scale.max(d);
    }
    for r in 0..n {
        for c in (r + 1)..n {
            let diff = (q[(r, c)] - q[(c, r)]).abs();
            if diff > SYMMETRY_TOLERANCE * scale {
                return Err(EstimatorError::NotSymmetric {
                    what: WHAT.into(),
                    row: r,
                    col: c,
                    diff,
                    time,
                });
            }
        }
    }
    Ok(())
}

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
