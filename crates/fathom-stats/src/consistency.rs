//! Filter consistency: NEES / NIS and their chi-square acceptance bounds, chi-square
//! quantiles and gate thresholds (e.g. the B-beacons outlier gate, eq. 10).
//!
//! For a consistent filter the NEES `e^T P^-1 e` of an `n`-dimensional error is
//! chi-square with `n` degrees of freedom. Averaged over `M` independent runs,
//! `M * avg ~ chi2(M n)`, so the two-sided acceptance region at level `1 - alpha` is
//! `[chi2inv(alpha/2, M n) / M, chi2inv(1 - alpha/2, M n) / M]`
//! (Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to Tracking and
//! Navigation", sec. 5.4). The same bounds apply to a time average over `K` steps
//! when the per-step values are independent (NIS of an optimal filter; for NEES
//! the steps are correlated, so a time-average test is only indicative).

use crate::error::{StatsError, ensure_finite_non_empty, ensure_level};
use fathom_core::{CoreError, gaussian::check_covariance};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

pub use crate::quantile::{chi2_cdf, chi2_quantile};

fn map_core(what: &str, e: CoreError) -> StatsError {
    match e {
        CoreError::NotPositiveDefinite { .. } => {
            StatsError::NotPositiveDefinite { what: what.into() }
        }
        other => StatsError::Core(other),
    }
}

/// NEES `e^T P^-1 e` of an estimation error `e = est - true` with covariance `P`,
/// via Cholesky (no explicit inverse).
///
/// # Errors
/// [`StatsError::NonFinite`] for a NaN/infinite error component;
/// [`StatsError::NotPositiveDefinite`] if `P` is not positive definite;
/// [`StatsError::Core`] (non-finite or non-symmetric `P`).
pub fn nees<const N: usize>(
    error: &SVector<f64, N>,
    cov: &SMatrix<f64, N, N>,
) -> Result<f64, StatsError> {
    quadratic_form("NEES", error.as_slice(), cov)
}

/// NIS `nu^T S^-1 nu` of an innovation `nu` with innovation covariance `S`.
///
/// # Errors
/// As [`nees`].
pub fn nis<const M: usize>(
    innovation: &SVector<f64, M>,
    innovation_cov: &SMatrix<f64, M, M>,
) -> Result<f64, StatsError> {
    quadratic_form("NIS", innovation.as_slice(), innovation_cov)
}

fn quadratic_form<const N: usize>(
    what: &str,
    v: &[f64],
    cov: &SMatrix<f64, N, N>,
) -> Result<f64, StatsError> {
    if let Some(index) = v.iter().position(|x| !x.is_finite()) {
        return Err(StatsError::NonFinite {
            what: format!("{what} vector"),
            index,
            value: v[index],
        });
    }
    let what_cov = format!("{what} covariance");
    check_covariance(&what_cov, cov).map_err(|e| map_core(&what_cov, e))?;
    let chol = cov
        .cholesky()
        .ok_or(StatsError::NotPositiveDefinite { what: what_cov })?;
    let e = SVector::<f64, N>::from_column_slice(v);
    Ok(e.dot(&chol.solve(&e)))
}

/// NEES / NIS of a dynamically sized vector (e.g. a stacked update whose size
/// changes when gated components are removed).
///
/// # Errors
/// [`StatsError::DimensionMismatch`] if `cov` is not `len x len`;
/// [`StatsError::Empty`] for a zero-length vector; [`StatsError::NonFinite`] /
/// [`StatsError::NonFiniteEntry`]; [`StatsError::NotPositiveDefinite`] if `cov` is
/// not symmetric positive definite (symmetry checked to 1e-9 relative).
pub fn nees_dyn(error: &DVector<f64>, cov: &DMatrix<f64>) -> Result<f64, StatsError> {
    let n = error.len();
    if n == 0 {
        return Err(StatsError::Empty {
            what: "NEES vector".into(),
        });
    }
    if cov.nrows() != n || cov.ncols() != n {
        return Err(StatsError::DimensionMismatch {
            what: format!("NEES covariance ({}x{})", cov.nrows(), cov.ncols()),
            index: 0,
            expected: n,
            found: if cov.nrows() != n {
                cov.nrows()
            } else {
                cov.ncols()
            },
        });
    }
    if let Some(index) = error.iter().position(|x| !x.is_finite()) {
        return Err(StatsError::NonFinite {
            what: "NEES vector".into(),
            index,
            value: error[index],
        });
    }
    let scale = (0..n).map(|i| cov[(i, i)].abs()).fold(0.0_f64, f64::max);
    for r in 0..n {
        for c in 0..n {
            let value = cov[(r, c)];
            if !value.is_finite() {
                return Err(StatsError::NonFiniteEntry {
                    what: "NEES covariance".into(),
                    row: r,
                    col: c,
                    value,
                });
            }
            if (value - cov[(c, r)]).abs() > 1e-9 * scale {
                return Err(StatsError::NotPositiveDefinite {
                    what: format!("NEES covariance (not symmetric at ({r}, {c}))"),
                });
            }
        }
    }
    let chol = cov
        .clone()
        .cholesky()
        .ok_or(StatsError::NotPositiveDefinite {
            what: "NEES covariance".into(),
        })?;
    Ok(error.dot(&chol.solve(error)))
}

/// Two-sided chi-square acceptance region for the average of `count` independent
/// NEES/NIS values with `dof_each` degrees of freedom each.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChiSquareBounds {
    /// Lower bound on the average, `chi2inv((1-level)/2, count dof_each) / count`.
    pub lo: f64,
    /// Upper bound on the average, `chi2inv((1+level)/2, count dof_each) / count`.
    pub hi: f64,
    /// Two-sided level, e.g. 0.95.
    pub level: f64,
    /// Degrees of freedom of each value (state or measurement dimension).
    pub dof_each: usize,
    /// Number of values averaged (runs `M`, or time steps `K`).
    pub count: usize,
}

impl ChiSquareBounds {
    /// Bounds for the average of `count` values, each chi-square with `dof_each`
    /// degrees of freedom, at two-sided `level`.
    ///
    /// # Errors
    /// [`StatsError::OutOfRange`] if `dof_each` or `count` is 0 or `level` is not in (0, 1).
    pub fn for_average(dof_each: usize, count: usize, level: f64) -> Result<Self, StatsError> {
        ensure_level("chi-square bounds level", level)?;
        for (what, v) in [
            ("degrees of freedom per value", dof_each),
            ("values averaged", count),
        ] {
            if v == 0 {
                return Err(StatsError::OutOfRange {
                    what: what.into(),
                    value: 0.0,
                    expected: ">= 1",
                });
            }
        }
        let total = (dof_each * count) as f64;
        let m = count as f64;
        let alpha = 1.0 - level;
        Ok(Self {
            lo: chi2_quantile(0.5 * alpha, total)? / m,
            hi: chi2_quantile(1.0 - 0.5 * alpha, total)? / m,
            level,
            dof_each,
            count,
        })
    }

    /// 95 % bounds for the average NEES over `runs` Monte Carlo runs of an
    /// `state_dim`-dimensional error.
    ///
    /// # Errors
    /// As [`ChiSquareBounds::for_average`].
    pub fn average_nees(state_dim: usize, runs: usize) -> Result<Self, StatsError> {
        Self::for_average(state_dim, runs, 0.95)
    }

    /// 95 % bounds for the time average over `steps` steps of a single run's NEES/NIS
    /// (exact for independent steps, e.g. the NIS of an optimal filter).
    ///
    /// # Errors
    /// As [`ChiSquareBounds::for_average`].
    pub fn time_average(dim: usize, steps: usize) -> Result<Self, StatsError> {
        Self::for_average(dim, steps, 0.95)
    }

    /// Whether `avg` lies inside `[lo, hi]`.
    pub fn contains(&self, avg: f64) -> bool {
        self.lo <= avg && avg <= self.hi
    }
}

/// Mean of NEES/NIS values (over runs at one time, or over the steps of one run).
///
/// # Errors
/// [`StatsError::Empty`] or [`StatsError::NonFinite`] naming the index.
pub fn average(values: &[f64]) -> Result<f64, StatsError> {
    ensure_finite_non_empty("NEES/NIS values", values)?;
    Ok(values.iter().sum::<f64>() / values.len() as f64)
}

/// Time-averaged NEES of one run, `(1/K) sum_k NEES_k`; compare with
/// [`ChiSquareBounds::time_average`].
///
/// # Errors
/// As [`average`].
pub fn time_averaged_nees(nees_series: &[f64]) -> Result<f64, StatsError> {
    average(nees_series)
}

/// Ensemble average NEES per time step over runs: `runs[i][k]` is the NEES of run
/// `i` at step `k`; returns `ANEES_k = (1/M) sum_i runs[i][k]`, to compare with
/// [`ChiSquareBounds::average_nees`] (`M` = number of runs).
///
/// # Errors
/// [`StatsError::Empty`] for no runs or empty runs, [`StatsError::LengthMismatch`]
/// if a run's length differs from the first run's (naming the run), or
/// [`StatsError::NonFiniteEntry`] naming run and step.
pub fn ensemble_average(runs: &[Vec<f64>]) -> Result<Vec<f64>, StatsError> {
    let first = runs.first().ok_or(StatsError::Empty {
        what: "ensemble NEES runs".into(),
    })?;
    if first.is_empty() {
        return Err(StatsError::Empty {
            what: "ensemble NEES run 0".into(),
        });
    }
    let mut sum = vec![0.0; first.len()];
    for (i, run) in runs.iter().enumerate() {
        if run.len() != first.len() {
            return Err(StatsError::LengthMismatch {
                what: format!("ensemble NEES run {i}"),
                left_name: "run 0",
                left: first.len(),
                right_name: "this run",
                right: run.len(),
            });
        }
        for (k, (s, &v)) in sum.iter_mut().zip(run).enumerate() {
            if !v.is_finite() {
                return Err(StatsError::NonFiniteEntry {
                    what: "ensemble NEES".into(),
                    row: i,
                    col: k,
                    value: v,
                });
            }
            *s += v;
        }
    }
    let m = runs.len() as f64;
    Ok(sum.into_iter().map(|s| s / m).collect())
}

/// Fraction of `values` (e.g. an ANEES series) inside `bounds`; about `bounds.level`
/// for a consistent filter.
///
/// # Errors
/// [`StatsError::Empty`] or [`StatsError::NonFinite`].
pub fn fraction_within(values: &[f64], bounds: &ChiSquareBounds) -> Result<f64, StatsError> {
    ensure_finite_non_empty("values checked against chi-square bounds", values)?;
    let inside = values.iter().filter(|&&v| bounds.contains(v)).count();
    Ok(inside as f64 / values.len() as f64)
}

/// Gate threshold on a normalized innovation squared so that a valid measurement
/// with `dof` components passes with probability `p_gate`: `chi2inv(p_gate, dof)`.
///
/// # Errors
/// [`StatsError::OutOfRange`] unless `0 < p_gate < 1` and `dof > 0`.
pub fn gate_threshold_for_probability(p_gate: f64, dof: usize) -> Result<f64, StatsError> {
    chi2_quantile(p_gate, dof as f64)
}

/// Probability that a valid measurement with `dof` components passes the gate
/// `nu^T S^-1 nu <= threshold`: `chi2cdf(threshold, dof)` (e.g. B-beacons eq. 10,
/// `d^2 = 2.5^2`, one component: 0.98758).
///
/// # Errors
/// [`StatsError::OutOfRange`] if `dof = 0`; [`StatsError::NonFinite`] for a NaN threshold.
pub fn gate_probability(threshold: f64, dof: usize) -> Result<f64, StatsError> {
    chi2_cdf(threshold, dof as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    #[test]
    fn nees_known_values_and_errors() {
        let p = Matrix2::new(4.0, 0.0, 0.0, 1.0);
        assert_relative_eq!(
            nees(&Vector2::new(2.0, 1.0), &p).unwrap(),
            2.0,
            epsilon = 1e-14
        );
        assert_relative_eq!(
            nis(&Vector2::new(2.0, 0.0), &p).unwrap(),
            1.0,
            epsilon = 1e-14
        );
        assert_relative_eq!(
            nees_dyn(
                &DVector::from_vec(vec![2.0, 1.0]),
                &DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 1.0])
            )
            .unwrap(),
            2.0,
            epsilon = 1e-14
        );
        let bad = Matrix2::new(1.0, 2.0, 2.0, 1.0);
        assert!(matches!(
            nees(&Vector2::new(1.0, 0.0), &bad),
            Err(StatsError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            nees(&Vector2::new(f64::NAN, 0.0), &p),
            Err(StatsError::NonFinite { index: 0, .. })
        ));
        assert!(
            nees(
                &Vector2::new(1.0, 0.0),
                &Matrix2::new(1.0, f64::NAN, f64::NAN, 1.0)
            )
            .is_err()
        );
        let dbad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(matches!(
            nees_dyn(&DVector::from_vec(vec![1.0, 0.0]), &dbad),
            Err(StatsError::NotPositiveDefinite { .. })
        ));
        assert!(nees_dyn(&DVector::from_vec(vec![1.0]), &dbad).is_err());
        assert!(nees_dyn(&DVector::zeros(0), &DMatrix::zeros(0, 0)).is_err());
    }

    #[test]
    fn bounds_match_tables() {
        // One run, dof 2: [chi2inv(0.025, 2), chi2inv(0.975, 2)] = [0.0506, 7.3778].
        let b = ChiSquareBounds::average_nees(2, 1).unwrap();
        assert_relative_eq!(b.lo, 0.050_636, epsilon = 1e-6);
        assert_relative_eq!(b.hi, 7.377_759, epsilon = 1e-6);
        // M n = 100: chi2inv(0.025, 100) = 74.2219, chi2inv(0.975, 100) = 129.561.
        let b = ChiSquareBounds::average_nees(2, 50).unwrap();
        assert_relative_eq!(b.lo, 74.221_93 / 50.0, epsilon = 1e-6);
        assert_relative_eq!(b.hi, 129.561_2 / 50.0, epsilon = 1e-6);
        assert!(b.contains(2.0) && !b.contains(3.0));
        let b99 = ChiSquareBounds::for_average(2, 50, 0.99).unwrap();
        assert!(b99.lo < b.lo && b99.hi > b.hi);
        assert!(ChiSquareBounds::for_average(0, 50, 0.95).is_err());
        assert!(ChiSquareBounds::for_average(2, 0, 0.95).is_err());
        assert!(ChiSquareBounds::for_average(2, 5, 1.0).is_err());
        assert_eq!(
            ChiSquareBounds::time_average(3, 10).unwrap(),
            ChiSquareBounds::for_average(3, 10, 0.95).unwrap()
        );
    }

    #[test]
    fn gate() {
        assert_relative_eq!(
            gate_probability(6.25, 1).unwrap(),
            0.987_580,
            epsilon = 1e-6
        );
        assert_relative_eq!(
            gate_threshold_for_probability(0.987_580_67, 1).unwrap(),
            6.25,
            epsilon = 1e-5
        );
        assert_relative_eq!(
            gate_threshold_for_probability(0.99, 2).unwrap(),
            9.210_340,
            epsilon = 1e-6
        );
        assert!(gate_threshold_for_probability(0.99, 0).is_err());
    }

    /// Average NEES over M = 50 draws of a consistent 3D Gaussian error, repeated
    /// for 1000 seeds: inside the 95 % bounds in Binomial(1000, 0.95) cases, so
    /// 950 +/- 3 sd (sd 6.9) = [929, 971]. Negative control: the same errors judged
    /// with a covariance 100x too small fall above the bounds in every trial.
    #[test]
    fn average_nees_of_consistent_gaussian() {
        let p = Matrix3::new(2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5);
        let l = p.cholesky().unwrap().l();
        let runs = 50;
        let bounds = ChiSquareBounds::average_nees(3, runs).unwrap();
        let (mut inside, mut inside_bad) = (0, 0);
        let mut per_run = Vec::new();
        for seed in 0..1000 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut ok = Vec::with_capacity(runs);
            let mut bad = Vec::with_capacity(runs);
            for _ in 0..runs {
                let w = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
                let e = l * w;
                ok.push(nees(&e, &p).unwrap());
                bad.push(nees(&e, &(p / 100.0)).unwrap());
            }
            let avg = average(&ok).unwrap();
            inside += usize::from(bounds.contains(avg));
            let avg_bad = average(&bad).unwrap();
            inside_bad += usize::from(bounds.contains(avg_bad));
            assert!(avg_bad > bounds.hi);
            per_run.push(ok);
        }
        assert!((929..=971).contains(&inside), "inside {inside}");
        assert_eq!(inside_bad, 0);

        // Read the same numbers as 50 "time steps" x 1000 "runs": the ensemble
        // average per step over 1000 runs stays within its own 95 % bounds for
        // about 95 % of the 50 steps (Binomial(50, 0.95): at least 43 = mean - 3 sd).
        let anees = ensemble_average(&per_run).unwrap();
        assert_eq!(anees.len(), runs);
        let b1000 = ChiSquareBounds::average_nees(3, 1000).unwrap();
        let frac = fraction_within(&anees, &b1000).unwrap();
        assert!(frac >= 43.0 / 50.0, "fraction {frac}");
        assert!(time_averaged_nees(&anees).unwrap() > 2.8);
    }

    #[test]
    fn ensemble_errors() {
        assert!(ensemble_average(&[]).is_err());
        assert!(matches!(
            ensemble_average(&[vec![1.0, 2.0], vec![1.0]]),
            Err(StatsError::LengthMismatch {
                left: 2,
                right: 1,
                ..
            })
        ));
        assert!(matches!(
            ensemble_average(&[vec![1.0, 2.0], vec![1.0, f64::NAN]]),
            Err(StatsError::NonFiniteEntry { row: 1, col: 1, .. })
        ));
        assert_eq!(
            ensemble_average(&[vec![1.0, 2.0], vec![3.0, 4.0]]).unwrap(),
            vec![2.0, 3.0]
        );
        assert!(average(&[]).is_err());
    }
}
