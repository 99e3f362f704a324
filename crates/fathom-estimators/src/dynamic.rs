//! [`DynKalmanFilter`]: the linear Kalman filter with a state size chosen at run
//! time (faer for the products and factorizations), for sizes the fixed-size
//! [`crate::KalmanFilter`] is not instantiated for (the Python bindings dispatch
//! small sizes to the fixed-size filter and larger ones here).
//!
//! Same equations, invariants, checks and error messages as the fixed-size filter:
//! predict `x = F x`, `P = F P F^T + (Q + Q^T) / 2`; update `S = H P H^T + R`,
//! `K = P H^T S^-1` (Cholesky of `S`), `x = x + K nu`, Joseph form
//! `P = (I - K H) P (I - K H)^T + K R K^T`, symmetrized; `x` finite and `P`
//! positive definite after every step; a failing step returns the error naming the
//! quantity, index and time, and leaves the filter unchanged.

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use fathom_core::Time;
use fathom_core::gaussian::SYMMETRY_TOLERANCE;
use nalgebra::{DMatrix, DVector};

use crate::error::check_finite_entries;
use crate::kalman::check_time;
use crate::noise::check_process_noise;
use crate::{EstimatorError, StackedUpdateInfo};

/// Largest state size accepted (a 4096 x 4096 covariance is 128 MiB; larger sizes
/// are refused before anything is allocated).
pub const MAX_DYN_DIM: usize = 4096;

/// A Kalman filter with a run-time state size `n` (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DynKalmanFilter {
    x: DVector<f64>,
    p: DMatrix<f64>,
    time: Time,
}

fn to_faer(a: &DMatrix<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

fn from_faer(a: &Mat<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

/// `(A + A^T) / 2`.
fn symmetrized(a: &DMatrix<f64>) -> DMatrix<f64> {
    (a + a.transpose()) * 0.5
}

fn dims(what: &str, expected: usize, got: usize) -> Result<(), EstimatorError> {
    if expected == got {
        Ok(())
    } else {
        Err(EstimatorError::DimensionMismatch {
            what: what.into(),
            expected,
            got,
        })
    }
}

/// Whether the (exactly symmetric) `a` has a Cholesky factor.
fn is_positive_definite(a: &DMatrix<f64>) -> bool {
    a.iter().all(|v| v.is_finite()) && to_faer(a).llt(Side::Lower).is_ok()
}

/// A covariance check with the rules (and messages) of
/// [`fathom_core::gaussian::check_covariance`]: finite (row-major index of the first
/// bad entry), symmetric within [`SYMMETRY_TOLERANCE`] relative to the largest
/// diagonal entry (the worst entry is named), positive definite.
///
/// # Errors
/// [`EstimatorError::DimensionMismatch`] for a non-square matrix,
/// [`EstimatorError::NonFinite`], [`EstimatorError::NotSymmetric`] or
/// [`EstimatorError::NotPositiveDefinite`] naming `what`, stamped with `time`.
pub fn check_covariance(what: &str, cov: &DMatrix<f64>, time: Time) -> Result<(), EstimatorError> {
    let n = cov.nrows();
    dims(&format!("{what} cols"), n, cov.ncols())?;
    check_finite_entries(what, n, n, |r, c| cov[(r, c)], time)?;
    let scale = (0..n)
        .map(|i| cov[(i, i)].abs())
        .fold(0.0_f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut worst = (0, 0, 0.0_f64);
    for r in 0..n {
        for c in (r + 1)..n {
            let diff = (cov[(r, c)] - cov[(c, r)]).abs();
            if diff > worst.2 {
                worst = (r, c, diff);
            }
        }
    }
    if worst.2 > SYMMETRY_TOLERANCE * scale {
        return Err(EstimatorError::NotSymmetric {
            what: what.to_owned(),
            row: worst.0,
            col: worst.1,
            diff: worst.2,
            time,
        });
    }
    if !is_positive_definite(&symmetrized(cov)) {
        return Err(EstimatorError::NotPositiveDefinite {
            what: what.to_owned(),
            time,
        });
    }
    Ok(())
}

impl DynKalmanFilter {
    /// A filter starting from `x0`, `P0` at time `time`.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for a size of 0 or above [`MAX_DYN_DIM`],
    /// [`EstimatorError::DimensionMismatch`] ("initial covariance P0 rows/cols"),
    /// non-finite time or "initial state x0", or a covariance error naming "initial
    /// covariance P0".
    pub fn new(x0: DVector<f64>, p0: DMatrix<f64>, time: Time) -> Result<Self, EstimatorError> {
        let n = x0.len();
        if n == 0 || n > MAX_DYN_DIM {
            return Err(EstimatorError::OutOfRange {
                what: "state size n".into(),
                value: n as f64,
                expected: "1 ..= 4096",
            });
        }
        check_time("initial time", time, time)?;
        dims("initial covariance P0 rows", n, p0.nrows())?;
        dims("initial covariance P0 cols", n, p0.ncols())?;
        check_finite_entries("initial state x0", n, 1, |i, _| x0[i], time)?;
        check_covariance("initial covariance P0", &p0, time)?;
        Ok(Self {
            x: x0,
            p: symmetrized(&p0),
            time,
        })
    }

    /// The state size `n`.
    pub fn dim(&self) -> usize {
        self.x.len()
    }

    /// The state estimate `x`.
    pub fn state(&self) -> &DVector<f64> {
        &self.x
    }

    /// The covariance `P`.
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.p
    }

    /// The time stamp (s) of the estimate.
    pub fn time(&self) -> Time {
        self.time
    }

    /// Replaces state and covariance, keeping the time.
    ///
    /// # Errors
    /// As [`DynKalmanFilter::new`], naming "state x" / "covariance P"; the filter is
    /// unchanged.
    pub fn set_estimate(&mut self, x: DVector<f64>, p: DMatrix<f64>) -> Result<(), EstimatorError> {
        let n = self.dim();
        dims("state x", n, x.len())?;
        dims("covariance P rows", n, p.nrows())?;
        dims("covariance P cols", n, p.ncols())?;
        check_finite_entries("state x", n, 1, |i, _| x[i], self.time)?;
        check_covariance("covariance P", &p, self.time)?;
        self.x = x;
        self.p = symmetrized(&p);
        Ok(())
    }

    /// Predicts to `new_time`: `x = F x`, `P = F P F^T + Q` (symmetrized); `Q`
    /// symmetric with a non-negative diagonal, the result positive definite.
    ///
    /// # Errors
    /// As [`crate::KalmanFilter::predict`] (plus dimension errors); the filter is
    /// unchanged.
    pub fn predict(
        &mut self,
        f: &DMatrix<f64>,
        q: &DMatrix<f64>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        self.check_model("transition matrix F", f, q, new_time)?;
        let x_pred = f * &self.x;
        self.predict_core(x_pred, f, q, new_time)
    }

    /// EKF / control prediction: the caller gives the predicted state `x_pred` (e.g.
    /// `f(x, u)` or `F x + B u`) and the Jacobian `F`; `P = F P F^T + Q`.
    ///
    /// # Errors
    /// As [`DynKalmanFilter::predict`], plus non-finite "predicted state x".
    pub fn predict_nonlinear(
        &mut self,
        x_pred: &DVector<f64>,
        f: &DMatrix<f64>,
        q: &DMatrix<f64>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        self.check_model("transition Jacobian F", f, q, new_time)?;
        dims("predicted state x", self.dim(), x_pred.len())?;
        self.predict_core(x_pred.clone(), f, q, new_time)
    }

    fn check_model(
        &self,
        f_name: &str,
        f: &DMatrix<f64>,
        q: &DMatrix<f64>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        let n = self.dim();
        check_time("predict", new_time, self.time)?;
        dims(&format!("{f_name} rows"), n, f.nrows())?;
        dims(&format!("{f_name} cols"), n, f.ncols())?;
        dims("process noise Q rows", n, q.nrows())?;
        dims("process noise Q cols", n, q.ncols())?;
        check_finite_entries(f_name, n, n, |r, c| f[(r, c)], new_time)
    }

    fn predict_core(
        &mut self,
        x_pred: DVector<f64>,
        f: &DMatrix<f64>,
        q: &DMatrix<f64>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        let n = self.dim();
        check_finite_entries("predicted state x", n, 1, |i, _| x_pred[i], new_time)?;
        check_process_noise(q, new_time)?;
        let f_f = to_faer(f);
        let fpf = &f_f * to_faer(&self.p) * f_f.transpose();
        let p_pred = symmetrized(&(from_faer(&fpf) + symmetrized(q)));
        if !is_positive_definite(&p_pred) {
            return Err(EstimatorError::NotPositiveDefinite {
                what: "predicted covariance P".into(),
                time: new_time,
            });
        }
        self.x = x_pred;
        self.p = p_pred;
        self.time = new_time;
        Ok(())
    }

    /// Linear update with `m = z.len()` measurements `z = H x + v`, `v ~ N(0, R)`
    /// (Joseph form, see the module docs).
    ///
    /// # Errors
    /// Dimension errors ("measurement matrix H rows/cols", "measurement noise R
    /// rows/cols"); non-finite "measurement z" or "measurement matrix H"; a covariance
    /// error naming "measurement noise R"; "innovation covariance S" or "updated
    /// covariance P" not positive definite. Errors carry `time()` and leave the filter
    /// unchanged.
    pub fn update(
        &mut self,
        z: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<StackedUpdateInfo, EstimatorError> {
        let (n, m, t) = (self.dim(), z.len(), self.time);
        dims("measurement matrix H rows", m, h.nrows())?;
        dims("measurement matrix H cols", n, h.ncols())?;
        dims("measurement noise R rows", m, r.nrows())?;
        dims("measurement noise R cols", m, r.ncols())?;
        check_finite_entries("measurement z", m, 1, |i, _| z[i], t)?;
        check_finite_entries("measurement matrix H", m, n, |i, j| h[(i, j)], t)?;
        check_covariance("measurement noise R", r, t)?;
        if m == 0 {
            return Ok(StackedUpdateInfo {
                innovation: DVector::zeros(0),
                innovation_cov: DMatrix::zeros(0, 0),
                nis: 0.0,
            });
        }
        let nu = z - h * &self.x;
        let h_f = to_faer(h);
        let r_f = to_faer(&symmetrized(r));
        let p_f = to_faer(&self.p);
        let pht = &p_f * h_f.transpose();
        let s = symmetrized(&from_faer(&(&h_f * &pht + &r_f)));
        let llt =
            to_faer(&s)
                .llt(Side::Lower)
                .map_err(|_| EstimatorError::NotPositiveDefinite {
                    what: "innovation covariance S".into(),
                    time: t,
                })?;
        let nu_f = Mat::<f64>::from_fn(m, 1, |i, _| nu[i]);
        let s_inv_nu = llt.solve(&nu_f);
        let nis = (0..m).map(|i| nu[i] * s_inv_nu[(i, 0)]).sum::<f64>();
        // K^T = S^-1 (P H^T)^T (S symmetric)
        let k = llt.solve(pht.transpose().to_owned()).transpose().to_owned();
        let dx = &k * &nu_f;
        let ikh = Mat::<f64>::identity(n, n) - &k * &h_f;
        let p_new = symmetrized(&from_faer(
            &(&ikh * &p_f * ikh.transpose() + &k * &r_f * k.transpose()),
        ));
        let x_new = &self.x + DVector::from_fn(n, |i, _| dx[(i, 0)]);
        check_finite_entries("updated state x", n, 1, |i, _| x_new[i], t)?;
        if !is_positive_definite(&p_new) {
            return Err(EstimatorError::NotPositiveDefinite {
                what: "updated covariance P".into(),
                time: t,
            });
        }
        self.x = x_new;
        self.p = p_new;
        Ok(StackedUpdateInfo {
            innovation: nu,
            innovation_cov: s,
            nis,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::KalmanFilter;
    use fathom_core::Gaussian;
    use nalgebra::{SMatrix, SVector};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// 3-D constant velocity, 6 states, 3 position measurements, dt = 0.1 s.
    fn cv_model() -> (
        SMatrix<f64, 6, 6>,
        SMatrix<f64, 6, 6>,
        SMatrix<f64, 3, 6>,
        SMatrix<f64, 3, 3>,
    ) {
        let dt = 0.1;
        let mut f = SMatrix::<f64, 6, 6>::identity();
        let mut q = SMatrix::<f64, 6, 6>::zeros();
        let qa = 0.5;
        for i in 0..3 {
            f[(i, i + 3)] = dt;
            q[(i, i)] = qa * dt.powi(4) / 4.0;
            q[(i, i + 3)] = qa * dt.powi(3) / 2.0;
            q[(i + 3, i)] = qa * dt.powi(3) / 2.0;
            q[(i + 3, i + 3)] = qa * dt * dt;
        }
        let mut h = SMatrix::<f64, 3, 6>::zeros();
        for i in 0..3 {
            h[(i, i)] = 1.0;
        }
        let r = SMatrix::<f64, 3, 3>::new(0.25, 0.05, 0.0, 0.05, 0.3, 0.02, 0.0, 0.02, 0.2);
        (f, q, h, r)
    }

    fn d<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>) -> DMatrix<f64> {
        DMatrix::from_fn(R, C, |i, j| a[(i, j)])
    }

    /// The dynamic filter follows the fixed-size one on a 6/3 constant-velocity
    /// problem over 1000 steps (relative 1e-12: same equations, different kernels).
    #[test]
    fn matches_the_fixed_size_filter() {
        let (f, q, h, r) = cv_model();
        let x0 = SVector::<f64, 6>::new(1.0, -2.0, 3.0, 0.5, 0.1, -0.2);
        let p0 = SMatrix::<f64, 6, 6>::identity() * 4.0;
        let mut fixed = KalmanFilter::new(Gaussian::new(x0, p0).unwrap(), 0.0).unwrap();
        let mut dynamic =
            DynKalmanFilter::new(DVector::from_column_slice(x0.as_slice()), d(&p0), 0.0).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst = 0.0_f64;
        for k in 1..=1000 {
            let t = f64::from(k) * 0.1;
            fixed.predict(&f, &q, t).unwrap();
            dynamic.predict(&d(&f), &d(&q), t).unwrap();
            let z = SVector::<f64, 3>::from_fn(|i, _| {
                0.05 * t * (i as f64 + 1.0) + rng.random_range(-0.5..0.5)
            });
            let a = fixed.update(&z, &h, &r).unwrap();
            let b = dynamic
                .update(&DVector::from_column_slice(z.as_slice()), &d(&h), &d(&r))
                .unwrap();
            let rel = |x: f64, y: f64| (x - y).abs() / x.abs().max(1.0);
            worst = worst.max(rel(a.nis, b.nis));
            for i in 0..6 {
                worst = worst.max(rel(fixed.state()[i], dynamic.state()[i]));
                for j in 0..6 {
                    worst = worst.max(rel(
                        fixed.covariance()[(i, j)],
                        dynamic.covariance()[(i, j)],
                    ));
                }
            }
        }
        assert!(worst < 1e-12, "largest relative difference {worst:e}");
        // negative control: a different R moves the estimate far beyond the bound
        let mut other = dynamic.clone();
        let z = DVector::from_column_slice(&[1.0, 2.0, 3.0]);
        other.update(&z, &d(&h), &(d(&r) * 2.0)).unwrap();
        dynamic.update(&z, &d(&h), &d(&r)).unwrap();
        assert!((other.state() - dynamic.state()).amax() > 1e-6);
    }

    /// Bad input: the fixed-size filter's errors and messages, the filter unchanged.
    #[test]
    fn bad_input_is_refused_with_the_fixed_size_messages() {
        let (f, q, h, r) = cv_model();
        let x0 = SVector::<f64, 6>::zeros();
        let p0 = SMatrix::<f64, 6, 6>::identity();
        let mut fixed = KalmanFilter::new(Gaussian::new(x0, p0).unwrap(), 2.0).unwrap();
        let mut dynamic = DynKalmanFilter::new(DVector::zeros(6), d(&p0), 2.0).unwrap();
        let before = dynamic.clone();
        let z = SVector::<f64, 3>::new(1.0, 2.0, 3.0);
        let zd = DVector::from_column_slice(z.as_slice());

        let mut r_nan = r;
        r_nan[(1, 2)] = f64::NAN;
        let mut r_npd = r;
        r_npd[(2, 2)] = -1.0;
        for bad in [r_nan, r_npd] {
            let a = fixed.update(&z, &h, &bad).unwrap_err();
            let b = dynamic.update(&zd, &d(&h), &d(&bad)).unwrap_err();
            assert_eq!(a.to_string(), b.to_string());
            assert_eq!(dynamic, before);
        }
        let mut z_nan = zd.clone();
        z_nan[1] = f64::NAN;
        let e = dynamic.update(&z_nan, &d(&h), &d(&r)).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 2.0),
            "{e}"
        );

        let mut q_neg = q;
        q_neg[(4, 4)] = -1.0;
        let a = fixed.predict(&f, &q_neg, 3.0).unwrap_err();
        let b = dynamic.predict(&d(&f), &d(&q_neg), 3.0).unwrap_err();
        assert_eq!(a.to_string(), b.to_string());
        let a = fixed.predict(&f, &q, 1.0).unwrap_err();
        let b = dynamic.predict(&d(&f), &d(&q), 1.0).unwrap_err();
        assert_eq!(a.to_string(), b.to_string());

        let mut p_npd = d(&p0);
        p_npd[(0, 1)] = 2.0;
        p_npd[(1, 0)] = 2.0;
        let a = fixed
            .set_estimate(Gaussian::new_unchecked(
                x0,
                SMatrix::from_fn(|i, j| p_npd[(i, j)]),
            ))
            .unwrap_err();
        let b = dynamic.set_estimate(DVector::zeros(6), p_npd).unwrap_err();
        assert_eq!(a.to_string(), b.to_string());
        assert!(
            b.to_string()
                .contains("covariance P is not positive definite"),
            "{b}"
        );

        let e = dynamic
            .update(&zd, &DMatrix::zeros(3, 5), &d(&r))
            .unwrap_err();
        assert!(
            matches!(
                e,
                EstimatorError::DimensionMismatch {
                    expected: 6,
                    got: 5,
                    ..
                }
            ),
            "{e}"
        );
        assert_eq!(dynamic, before);
        assert!(DynKalmanFilter::new(DVector::zeros(0), DMatrix::zeros(0, 0), 0.0).is_err());
        assert!(
            DynKalmanFilter::new(DVector::zeros(MAX_DYN_DIM + 1), DMatrix::zeros(1, 1), 0.0)
                .is_err()
        );
    }
}
