//! Stacked update for a run-time number of measurements with a full (possibly
//! correlated) `R`, using faer for the dynamic-size linear algebra; optional
//! per-component gating (paper B, SC scheme).

use crate::{
    EstimatorError, error::check_finite_entries, gating::GateThreshold, kalman::KalmanFilter,
};
use faer::{Mat, Side, linalg::solvers::Solve};
use fathom_core::gaussian::SYMMETRY_TOLERANCE;
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// Diagnostics of an applied stacked update (dynamic size `m`).
#[derive(Debug, Clone, PartialEq)]
pub struct StackedUpdateInfo {
    /// Innovation `nu` (length `m`).
    pub innovation: DVector<f64>,
    /// Innovation covariance `S = H P H^T + R` (`m x m`, symmetrized).
    pub innovation_cov: DMatrix<f64>,
    /// `nu^T S^-1 nu` (0 when `m = 0`).
    pub nis: f64,
}

/// Report of a per-component gated stacked update.
#[derive(Debug, Clone, PartialEq)]
pub struct StackedGatedReport {
    /// Per-component NIS `nu_i^2 / S_ii` used for gating (paper B eq. 10).
    pub component_nis: Vec<f64>,
    /// Whether each component passed the gate.
    pub accepted: Vec<bool>,
    /// The stacked update of the accepted components (`None` when all were rejected).
    pub update: Option<StackedUpdateInfo>,
}

impl StackedGatedReport {
    /// Indices of the rejected components.
    pub fn rejected(&self) -> impl Iterator<Item = usize> + '_ {
        self.accepted
            .iter()
            .enumerate()
            .filter(|(_, a)| !**a)
            .map(|(i, _)| i)
    }
}

impl<const N: usize> KalmanFilter<N> {
    /// Stacked update with `m = z.len()` measurements `z = H x + v`, `v ~ N(0, R)`,
    /// `R` a full `m x m` covariance (correlations allowed). `S = H P H^T + R` is
    /// factored with faer's Cholesky (`Llt`), `K = P H^T S^-1`, Joseph-form `P`.
    /// Inputs are nalgebra types; conversion to faer happens here.
    ///
    /// # Errors
    /// [`EstimatorError::DimensionMismatch`] ("measurement matrix H rows/cols",
    /// "measurement noise R rows/cols"); non-finite "measurement z", "measurement
    /// matrix H", "measurement noise R"; R not symmetric; "measurement noise R",
    /// "innovation covariance S" or "updated covariance P" not positive definite.
    /// The filter is unchanged on error.
    pub fn update_stacked(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<StackedUpdateInfo, EstimatorError> {
        self.check_stacked_inputs("measurement z", z, h, r)?;
        let nu = z - h * self.state();
        self.stacked_core(&nu, h, r)
    }

    /// Stacked update with a given innovation `nu = z - h(x)` (EKF flavour of
    /// [`KalmanFilter::update_stacked`]).
    ///
    /// # Errors
    /// As [`KalmanFilter::update_stacked`], naming "innovation nu".
    pub fn update_stacked_with_innovation(
        &mut self,
        nu: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<StackedUpdateInfo, EstimatorError> {
        self.check_stacked_inputs("innovation nu", nu, h, r)?;
        self.stacked_core(nu, h, r)
    }

    /// Per-component gated stacked update (paper B, SC): component `i` is rejected when
    /// `nu_i^2 / S_ii > gate` with `S = H P H^T + R`; the rejected rows of `nu`, `H`
    /// and rows/columns of `R` are removed, then one stacked update uses the rest.
    /// `nu` is the innovation (`z - H x` for a linear model, `z - h(x)` for an EKF).
    ///
    /// # Errors
    /// As [`KalmanFilter::update_stacked_with_innovation`].
    pub fn update_stacked_gated(
        &mut self,
        nu: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
        gate: GateThreshold,
    ) -> Result<StackedGatedReport, EstimatorError> {
        self.check_stacked_inputs("innovation nu", nu, h, r)?;
        let t = self.time();
        let p = self.covariance();
        let m = nu.len();
        let mut component_nis = Vec::with_capacity(m);
        let mut accepted = Vec::with_capacity(m);
        for i in 0..m {
            let hi: SVector<f64, N> = SVector::from_fn(|c, _| h[(i, c)]);
            let s_ii = hi.dot(&(p * hi)) + r[(i, i)];
            if !(s_ii.is_finite() && s_ii > 0.0) {
                return Err(EstimatorError::NotPositiveDefinite {
                    what: format!("innovation covariance S (diagonal entry {i})"),
                    time: t,
                });
            }
            let nis = nu[i] * nu[i] / s_ii;
            component_nis.push(nis);
            accepted.push(gate.accepts(nis));
        }
        let keep: Vec<usize> = (0..m).filter(|&i| accepted[i]).collect();
        let update = if keep.is_empty() {
            None
        } else {
            let nu_k = DVector::from_fn(keep.len(), |i, _| nu[keep[i]]);
            let h_k = DMatrix::from_fn(keep.len(), N, |i, c| h[(keep[i], c)]);
            let r_k = DMatrix::from_fn(keep.len(), keep.len(), |i, j| r[(keep[i], keep[j])]);
            Some(self.stacked_core(&nu_k, &h_k, &r_k)?)
        };
        Ok(StackedGatedReport {
            component_nis,
            accepted,
            update,
        })
    }

    fn check_stacked_inputs(
        &self,
        nu_name: &str,
        nu: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<(), EstimatorError> {
        let m = nu.len();
        let t = self.time();
        for (what, expected, got) in [
            ("measurement matrix H rows", m, h.nrows()),
            ("measurement matrix H cols", N, h.ncols()),
            ("measurement noise R rows", m, r.nrows()),
            ("measurement noise R cols", m, r.ncols()),
        ] {
            if expected != got {
                return Err(EstimatorError::DimensionMismatch {
                    what: what.into(),
                    expected,
                    got,
                });
            }
        }
        check_finite_entries(nu_name, m, 1, |i, _| nu[i], t)?;
        check_finite_entries("measurement matrix H", m, N, |i, j| h[(i, j)], t)?;
        check_finite_entries("measurement noise R", m, m, |i, j| r[(i, j)], t)?;
        let scale = (0..m)
            .map(|i| r[(i, i)].abs())
            .fold(f64::MIN_POSITIVE, f64::max);
        for i in 0..m {
            for j in (i + 1)..m {
                let diff = (r[(i, j)] - r[(j, i)]).abs();
                if diff > SYMMETRY_TOLERANCE * scale {
                    return Err(EstimatorError::NotSymmetric {
                        what: "measurement noise R".into(),
                        row: i,
                        col: j,
                        diff,
                        time: t,
                    });
                }
            }
        }
        Ok(())
    }

    /// Inputs checked (sizes, finite, R symmetric).
    fn stacked_core(
        &mut self,
        nu: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<StackedUpdateInfo, EstimatorError> {
        let t = self.time();
        let m = nu.len();
        if m == 0 {
            return Ok(StackedUpdateInfo {
                innovation: DVector::zeros(0),
                innovation_cov: DMatrix::zeros(0, 0),
                nis: 0.0,
            });
        }
        let h_f = Mat::<f64>::from_fn(m, N, |i, j| h[(i, j)]);
        let r_f = Mat::<f64>::from_fn(m, m, |i, j| 0.5 * (r[(i, j)] + r[(j, i)]));
        if r_f.llt(Side::Lower).is_err() {
            return Err(EstimatorError::NotPositiveDefinite {
                what: "measurement noise R".into(),
                time: t,
            });
        }
        let p = self.covariance();
        let p_f = Mat::<f64>::from_fn(N, N, |i, j| p[(i, j)]);
        let nu_f = Mat::<f64>::from_fn(m, 1, |i, _| nu[i]);

        let pht = &p_f * h_f.transpose(); // N x m
        let s_raw = &h_f * &pht + &r_f;
        let s = Mat::<f64>::from_fn(m, m, |i, j| 0.5 * (s_raw[(i, j)] + s_raw[(j, i)]));
        let llt = s
            .llt(Side::Lower)
            .map_err(|_| EstimatorError::NotPositiveDefinite {
                what: "innovation covariance S".into(),
                time: t,
            })?;
        let s_inv_nu = llt.solve(&nu_f);
        let nis = (0..m).map(|i| nu_f[(i, 0)] * s_inv_nu[(i, 0)]).sum::<f64>();
        // K^T = S^-1 (P H^T)^T  (m x N), S symmetric.
        let k_t = llt.solve(pht.transpose().to_owned());
        let k = k_t.transpose();
        let dx = k * &nu_f;
        let ikh = Mat::<f64>::identity(N, N) - k * &h_f;
        let p_new_f = &ikh * &p_f * ikh.transpose() + k * &r_f * k.transpose();

        let x_new: SVector<f64, N> = self.state() + SVector::<f64, N>::from_fn(|i, _| dx[(i, 0)]);
        let p_new = SMatrix::<f64, N, N>::from_fn(|i, j| p_new_f[(i, j)]);
        self.commit_checked(x_new, p_new)?;
        Ok(StackedUpdateInfo {
            innovation: nu.clone(),
            innovation_cov: DMatrix::from_fn(m, m, |i, j| s[(i, j)]),
            nis,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Gaussian;
    use nalgebra::{Matrix2, Vector2};

    /// Bad input (crate docs): the stacked update follows the core's policy: a
    /// non-finite measurement is an error naming the index and the time, a variance
    /// `<= 0` a positive-definiteness error with the time; the filter is unchanged.
    #[test]
    fn bad_input_is_an_error_with_index_and_time() {
        let prior = Gaussian::new(Vector2::new(1.0, 2.0), Matrix2::identity()).unwrap();
        let mut kf = KalmanFilter::new(prior, 4.0).unwrap();
        let before = kf.clone();
        let h = DMatrix::identity(2, 2);
        let r = DMatrix::identity(2, 2) * 0.1;
        for bad in [f64::NAN, f64::INFINITY] {
            let z = DVector::from_vec(vec![1.0, bad]);
            let e = kf.update_stacked(&z, &h, &r).unwrap_err();
            assert!(
                matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 4.0),
                "{e}"
            );
            let gate = GateThreshold::from_sigma_distance(3.0).unwrap();
            assert!(kf.update_stacked_gated(&z, &h, &r, gate).is_err());
            assert_eq!(kf, before);
        }
        let mut r_bad = r.clone();
        r_bad[(1, 1)] = -0.1;
        let z = DVector::from_vec(vec![1.0, 2.0]);
        let e = kf.update_stacked(&z, &h, &r_bad).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { time, .. } if *time == 4.0),
            "{e}"
        );
        assert_eq!(kf, before);
    }
}
