//! `Gaussian`: a mean with a checked (finite, symmetric, positive-definite) covariance.

use crate::{CoreError, error::ensure_finite};
use nalgebra::{SMatrix, SVector};

/// Relative tolerance used by [`check_covariance`] for symmetry.
pub const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// A Gaussian estimate `N(mean, cov)` with an `N`-dimensional state.
///
/// The constructor checks the covariance; [`Gaussian::new_unchecked`] is for
/// filter internals that maintain the invariant themselves.
#[derive(Debug, Clone, PartialEq)]
pub struct Gaussian<const N: usize> {
    mean: SVector<f64, N>,
    cov: SMatrix<f64, N, N>,
}

impl<const N: usize> Gaussian<N> {
    /// Creates a Gaussian after checking the mean is finite and the covariance is
    /// finite, symmetric and positive definite.
    ///
    /// # Errors
    /// [`CoreError::NonFinite`], [`CoreError::NotSymmetric`] or
    /// [`CoreError::NotPositiveDefinite`].
    pub fn new(mean: SVector<f64, N>, cov: SMatrix<f64, N, N>) -> Result<Self, CoreError> {
        ensure_finite("gaussian mean", mean.iter())?;
        check_covariance("gaussian covariance", &cov)?;
        Ok(Self { mean, cov })
    }

    /// Creates a Gaussian without checks (the caller guarantees the invariants).
    pub fn new_unchecked(mean: SVector<f64, N>, cov: SMatrix<f64, N, N>) -> Self {
        Self { mean, cov }
    }

    /// The mean.
    pub fn mean(&self) -> &SVector<f64, N> {
        &self.mean
    }

    /// The covariance.
    pub fn cov(&self) -> &SMatrix<f64, N, N> {
        &self.cov
    }

    /// Splits into `(mean, covariance)`.
    pub fn into_parts(self) -> (SVector<f64, N>, SMatrix<f64, N, N>) {
        (self.mean, self.cov)
    }

    /// Squared Mahalanobis distance of `x` from the mean, `(x-m)^T P^-1 (x-m)`
    /// (the NEES when `x` is the true state).
    ///
    /// # Errors
    /// [`CoreError::NotPositiveDefinite`] if the covariance cannot be factored.
    pub fn mahalanobis_sq(&self, x: &SVector<f64, N>) -> Result<f64, CoreError> {
        let chol = self
            .cov
            .cholesky()
            .ok_or_else(|| CoreError::NotPositiveDefinite {
                what: "gaussian covariance".into(),
            })?;
        let d = x - self.mean;
        Ok(d.dot(&chol.solve(&d)))
    }
}

/// Checks a covariance matrix: finite, symmetric within a relative tolerance of
/// [`SYMMETRY_TOLERANCE`] (relative to the largest diagonal entry), and positive
/// definite (a Cholesky factorization exists).
///
/// # Errors
/// [`CoreError::NonFinite`], [`CoreError::NotSymmetric`] or
/// [`CoreError::NotPositiveDefinite`], naming `what`.
pub fn check_covariance<const N: usize>(
    what: &str,
    cov: &SMatrix<f64, N, N>,
) -> Result<(), CoreError> {
    // nalgebra iterates column-major; report a row-major index for humans.
    for r in 0..N {
        for c in 0..N {
            let v = cov[(r, c)];
            if !v.is_finite() {
                return Err(CoreError::NonFinite {
                    what: what.to_owned(),
                    index: r * N + c,
                    value: v,
                });
            }
        }
    }
    let scale = (0..N)
        .map(|i| cov[(i, i)].abs())
        .fold(0.0_f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut worst = (0, 0, 0.0_f64);
    for r in 0..N {
        for c in (r + 1)..N {
            let diff = (cov[(r, c)] - cov[(c, r)]).abs();
            if diff > worst.2 {
                worst = (r, c, diff);
            }
        }
    }
    if worst.2 > SYMMETRY_TOLERANCE * scale {
        return Err(CoreError::NotSymmetric {
            what: what.to_owned(),
            row: worst.0,
            col: worst.1,
            diff: worst.2,
        });
    }
    if cov.cholesky().is_none() {
        return Err(CoreError::NotPositiveDefinite {
            what: what.to_owned(),
        });
    }
    Ok(())
}

/// Returns `(A + A^T) / 2`.
pub fn symmetrize<const N: usize>(a: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (a + a.transpose()) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix2, Vector2};

    #[test]
    fn rejects_bad_covariances() {
        let m = Vector2::zeros();
        assert!(matches!(
            Gaussian::new(m, Matrix2::new(1.0, 0.0, 0.0, -1.0)),
            Err(CoreError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            Gaussian::new(m, Matrix2::new(1.0, 0.1, 0.0, 1.0)),
            Err(CoreError::NotSymmetric { row: 0, col: 1, .. })
        ));
        assert!(matches!(
            Gaussian::new(m, Matrix2::new(1.0, 0.0, 0.0, f64::NAN)),
            Err(CoreError::NonFinite { index: 3, .. })
        ));
        assert!(Gaussian::new(Vector2::new(f64::INFINITY, 0.0), Matrix2::identity()).is_err());
    }

    #[test]
    fn mahalanobis() {
        let g = Gaussian::new(Vector2::new(1.0, 1.0), Matrix2::new(4.0, 0.0, 0.0, 1.0)).unwrap();
        assert_relative_eq!(
            g.mahalanobis_sq(&Vector2::new(3.0, 2.0)).unwrap(),
            2.0,
            epsilon = 1e-12
        );
    }
}
