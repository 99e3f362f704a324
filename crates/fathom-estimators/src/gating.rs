//! Innovation gating: the normalized innovation squared (NIS) and checked gate
//! thresholds (squared sigma distance or chi-square probability).

use crate::EstimatorError;
use fathom_core::{CoreError, error::ensure_finite};
use nalgebra::{SMatrix, SVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Diagnostics of an applied update: innovation `nu`, its covariance
/// `S = H P H^T + R` and the NIS `nu^T S^-1 nu`.
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateInfo<const M: usize> {
    /// Innovation `nu = z - H x` (or the one given to the `*_with_innovation` updates).
    pub innovation: SVector<f64, M>,
    /// Innovation covariance `S = H P^- H^T + R` (symmetrized).
    pub innovation_cov: SMatrix<f64, M, M>,
    /// Normalized innovation squared `nu^T S^-1 nu` (chi-square with `M` dof when
    /// the filter is consistent).
    pub nis: f64,
}

/// A checked gate threshold on the NIS `nu^T S^-1 nu`: a measurement is accepted
/// when `NIS <= nis_max` and rejected otherwise (NaN NIS is rejected).
///
/// For a scalar measurement the paper B gate (eq. 10) is `nu^2 / S > d^2` with
/// `d = 2.5` (two-sided 98.76 %): [`GateThreshold::from_sigma_distance`]`(2.5)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GateThreshold {
    nis_max: f64,
}

impl GateThreshold {
    /// A gate with the squared (Mahalanobis) distance `d2` as NIS threshold.
    ///
    /// # Errors
    /// [`EstimatorError::Core`] if `d2` is not finite or not `> 0`.
    pub fn from_squared_distance(d2: f64) -> Result<Self, EstimatorError> {
        fathom_core::error::ensure_positive("gate squared distance", d2)?;
        Ok(Self { nis_max: d2 })
    }

    /// A gate at `d` standard deviations: threshold `d^2` (e.g. `d = 2.5` gives 6.25).
    ///
    /// # Errors
    /// [`EstimatorError::Core`] if `d` is not finite or not `> 0`.
    pub fn from_sigma_distance(d: f64) -> Result<Self, EstimatorError> {
        fathom_core::error::ensure_positive("gate sigma distance", d)?;
        Self::from_squared_distance(d * d)
    }

    /// A gate accepting a consistent measurement of dimension `dof` with probability
    /// `probability`: the threshold is the chi-square quantile
    /// `chi2_inv(probability; dof)` (e.g. `0.95`, dof 1 gives 3.841).
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] unless `0 < probability < 1` and `dof >= 1`.
    pub fn from_chi_square_probability(
        probability: f64,
        dof: usize,
    ) -> Result<Self, EstimatorError> {
        if !(probability > 0.0 && probability < 1.0) {
            return Err(EstimatorError::OutOfRange {
                what: "gate probability".into(),
                value: probability,
                expected: "0 < p < 1",
            });
        }
        let bad_dof = || EstimatorError::OutOfRange {
            what: "gate degrees of freedom".into(),
            value: dof as f64,
            expected: ">= 1",
        };
        if dof == 0 {
            return Err(bad_dof());
        }
        let chi2 = ChiSquared::new(dof as f64).map_err(|_| bad_dof())?;
        Self::from_squared_distance(chi2.inverse_cdf(probability))
    }

    /// The NIS threshold.
    pub fn nis_max(&self) -> f64 {
        self.nis_max
    }

    /// Whether a measurement with this NIS passes the gate (`nis <= nis_max`; NaN fails).
    pub fn accepts(&self, nis: f64) -> bool {
        nis <= self.nis_max
    }
}

/// Outcome of a gated update.
#[derive(Debug, Clone, PartialEq)]
pub enum Gate<const M: usize> {
    /// The measurement passed the gate and was applied.
    Accepted(UpdateInfo<M>),
    /// The measurement failed the gate; the filter state is unchanged.
    Rejected {
        /// The NIS that exceeded the threshold.
        nis: f64,
    },
}

impl<const M: usize> Gate<M> {
    /// Whether the measurement was applied.
    pub fn is_accepted(&self) -> bool {
        matches!(self, Gate::Accepted(_))
    }

    /// The NIS of the measurement, accepted or not.
    pub fn nis(&self) -> f64 {
        match self {
            Gate::Accepted(info) => info.nis,
            Gate::Rejected { nis } => *nis,
        }
    }
}

/// Normalized innovation squared `nu^T S^-1 nu`, solved with a Cholesky factor of
/// `S` (no explicit inverse).
///
/// # Errors
/// [`EstimatorError::Core`] if `nu` or `S` is not finite or `S` is not positive definite.
pub fn nis<const M: usize>(
    nu: &SVector<f64, M>,
    s: &SMatrix<f64, M, M>,
) -> Result<f64, EstimatorError> {
    ensure_finite("innovation", nu.iter())?;
    ensure_finite("innovation covariance S", s.iter())?;
    let chol = s.cholesky().ok_or_else(|| CoreError::NotPositiveDefinite {
        what: "innovation covariance S".into(),
    })?;
    Ok(nu.dot(&chol.solve(nu)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix2, Vector1, Vector2};

    #[test]
    fn thresholds() {
        assert_relative_eq!(
            GateThreshold::from_sigma_distance(2.5).unwrap().nis_max(),
            6.25
        );
        assert_relative_eq!(
            GateThreshold::from_chi_square_probability(0.95, 1)
                .unwrap()
                .nis_max(),
            3.841_458_820_694_124,
            epsilon = 1e-6
        );
        assert_relative_eq!(
            GateThreshold::from_chi_square_probability(0.99, 3)
                .unwrap()
                .nis_max(),
            11.344_866_730_144_373,
            epsilon = 1e-6
        );
        // two-sided 98.76 % for a scalar is d = 2.5
        assert_relative_eq!(
            GateThreshold::from_chi_square_probability(0.987_580_669_348_447_7, 1)
                .unwrap()
                .nis_max(),
            6.25,
            epsilon = 1e-6
        );
    }

    #[test]
    fn bad_thresholds_are_errors() {
        assert!(GateThreshold::from_squared_distance(0.0).is_err());
        assert!(GateThreshold::from_squared_distance(f64::NAN).is_err());
        assert!(GateThreshold::from_sigma_distance(-1.0).is_err());
        assert!(GateThreshold::from_chi_square_probability(1.0, 2).is_err());
        assert!(GateThreshold::from_chi_square_probability(0.0, 2).is_err());
        assert!(GateThreshold::from_chi_square_probability(f64::NAN, 2).is_err());
        assert!(GateThreshold::from_chi_square_probability(0.9, 0).is_err());
    }

    #[test]
    fn accepts_is_inclusive_and_rejects_nan() {
        let g = GateThreshold::from_squared_distance(4.0).unwrap();
        assert!(g.accepts(4.0));
        assert!(!g.accepts(4.000_001));
        assert!(!g.accepts(f64::NAN));
    }

    #[test]
    fn nis_matches_explicit_formula() {
        let s = Matrix2::new(2.0, 0.5, 0.5, 1.0);
        let nu = Vector2::new(1.0, -2.0);
        let expected = (nu.transpose() * s.try_inverse().unwrap() * nu)[0];
        assert_relative_eq!(nis(&nu, &s).unwrap(), expected, epsilon = 1e-12);
        assert_relative_eq!(
            nis(&Vector1::new(3.0), &nalgebra::Matrix1::new(4.0)).unwrap(),
            2.25
        );
        assert!(nis(&nu, &Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_err());
    }
}
