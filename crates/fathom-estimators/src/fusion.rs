//! Fusion of two Gaussian estimates of the same state (track-to-track fusion,
//! paper A eq. (10)), computed without explicit inverses.

use crate::EstimatorError;
use fathom_core::{
    CoreError, Gaussian,
    error::ensure_finite,
    gaussian::{check_covariance, symmetrize},
};
use nalgebra::SMatrix;

/// Fuses two estimates of the same state assumed independent (cross-covariance
/// ignored), paper A eq. (10):
///
/// `P = (P1^-1 + P2^-1)^-1`, `x = P (P1^-1 x1 + P2^-1 x2)`.
///
/// Computed in the algebraically identical gain form, which needs only one Cholesky
/// factorization of `P1 + P2` and no inverse of the (possibly ill-conditioned)
/// inputs: `K = P1 (P1 + P2)^-1`, `x = x1 + K (x2 - x1)`, and the Joseph-form
/// `P = (I - K) P1 (I - K)^T + K P2 K^T` (symmetrized), which stays positive definite.
///
/// # Errors
/// [`EstimatorError::Core`]: non-finite means, covariances that are not symmetric
/// positive definite (inputs are re-checked, they may be unchecked Gaussians), or a
/// fused covariance that fails the check.
pub fn fuse_information<const N: usize>(
    a: &Gaussian<N>,
    b: &Gaussian<N>,
) -> Result<Gaussian<N>, EstimatorError> {
    ensure_finite("fusion input a mean", a.mean().iter())?;
    ensure_finite("fusion input b mean", b.mean().iter())?;
    check_covariance("fusion input a covariance", a.cov())?;
    check_covariance("fusion input b covariance", b.cov())?;
    let (p1, p2) = (a.cov(), b.cov());
    let sum = symmetrize(&(p1 + p2));
    let chol = sum
        .cholesky()
        .ok_or_else(|| CoreError::NotPositiveDefinite {
            what: "fusion P1 + P2".into(),
        })?;
    // K^T = (P1 + P2)^-1 P1 (both symmetric).
    let k = chol.solve(p1).transpose();
    let x = a.mean() + k * (b.mean() - a.mean());
    let i_k = SMatrix::<f64, N, N>::identity() - k;
    let p = symmetrize(&(i_k * p1 * i_k.transpose() + k * p2 * k.transpose()));
    Ok(Gaussian::new(x, p).map_err(|e| match e {
        CoreError::NotPositiveDefinite { .. } => CoreError::NotPositiveDefinite {
            what: "fused covariance".into(),
        },
        other => other,
    })?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};

    #[test]
    fn one_dimensional_by_hand() {
        // x1 = 1 (var 1), x2 = 3 (var 3): P = 1/(1 + 1/3) = 0.75, x = 0.75 (1 + 1) = 1.5.
        let a = Gaussian::new(Vector1::new(1.0), Matrix1::new(1.0)).unwrap();
        let b = Gaussian::new(Vector1::new(3.0), Matrix1::new(3.0)).unwrap();
        let f = fuse_information(&a, &b).unwrap();
        assert_relative_eq!(f.mean()[0], 1.5, epsilon = 1e-14);
        assert_relative_eq!(f.cov()[(0, 0)], 0.75, epsilon = 1e-14);
    }

    #[test]
    fn two_dimensional_matches_eq_10() {
        let p1 = Matrix2::new(2.0, 0.5, 0.5, 1.0);
        let p2 = Matrix2::new(1.0, -0.3, -0.3, 4.0);
        let x1 = Vector2::new(1.0, -1.0);
        let x2 = Vector2::new(2.0, 0.5);
        // eq. (10) with explicit inverses
        let i1 = p1.try_inverse().unwrap();
        let i2 = p2.try_inverse().unwrap();
        let p = (i1 + i2).try_inverse().unwrap();
        let x = p * (i1 * x1 + i2 * x2);
        // and a fully hand-computed entry check: P1^-1 = [1 -0.5; -0.5 2] / 1.75
        assert_relative_eq!(
            i1,
            Matrix2::new(1.0, -0.5, -0.5, 2.0) / 1.75,
            epsilon = 1e-14
        );
        let f = fuse_information(
            &Gaussian::new(x1, p1).unwrap(),
            &Gaussian::new(x2, p2).unwrap(),
        )
        .unwrap();
        assert_relative_eq!(*f.mean(), x, epsilon = 1e-12);
        assert_relative_eq!(*f.cov(), p, epsilon = 1e-12);
        assert_eq!(f.cov()[(0, 1)], f.cov()[(1, 0)]);
    }

    #[test]
    fn fusing_with_itself_halves_the_covariance() {
        let g = Gaussian::new(Vector2::new(3.0, -2.0), Matrix2::new(4.0, 1.0, 1.0, 2.0)).unwrap();
        let f = fuse_information(&g, &g).unwrap();
        assert_relative_eq!(*f.mean(), *g.mean(), epsilon = 1e-14);
        assert_relative_eq!(*f.cov(), g.cov() * 0.5, epsilon = 1e-14);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let good = Gaussian::new(Vector1::new(0.0), Matrix1::new(1.0)).unwrap();
        let bad = Gaussian::new_unchecked(Vector1::new(0.0), Matrix1::new(-1.0));
        assert!(matches!(
            fuse_information(&good, &bad),
            Err(EstimatorError::Core(CoreError::NotPositiveDefinite { .. }))
        ));
        let nan = Gaussian::new_unchecked(Vector1::new(f64::NAN), Matrix1::new(1.0));
        assert!(fuse_information(&nan, &good).is_err());
    }
}
