//! Sample covariance of multivariate samples with per-entry confidence intervals
//! (iid normal theory, or batch means for autocorrelated samples), and the largest
//! relative deviation of an estimate from a design covariance (B-beacons,
//! "Generator verification", eqs. 5-9).
//!
//! Samples are given as a slice of rows, one sample per row: `&[R]` with
//! `R: AsRef<[f64]>` (so `&[Vec<f64>]`, `&[[f64; 5]]` and `&[&[f64]]` all work); every
//! row must have the same length `d >= 1`. Results are `d x d` nalgebra
//! [`DMatrix`]es (small, so no faer needed).

use crate::error::{StatsError, ensure_level};
use crate::quantile::{normal_quantile, student_t_quantile};
use nalgebra::{DMatrix, DVector};

/// How the mean of the samples is handled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MeanMode {
    /// The mean is estimated from the samples and subtracted; normalization
    /// `1/(n-1)` (unbiased). Needs `n >= 2`.
    Estimated,
    /// The mean is known to be zero (e.g. simulated noise): no subtraction,
    /// normalization `1/n`. Needs `n >= 1`.
    KnownZero,
}

/// Which confidence interval a [`CovarianceCi`] carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum CiMethod {
    /// iid normal theory: `Var(s_ij) ~ (s_ii s_jj + s_ij^2) / dof`, normal quantile.
    NormalTheory,
    /// Batch means over `batches` contiguous batches of `batch_len` samples each,
    /// Student-t quantile with `batches - 1` degrees of freedom.
    BatchMeans {
        /// Number of batches `B`.
        batches: usize,
        /// Samples per batch `m = floor(n / B)`.
        batch_len: usize,
    },
}

/// A covariance estimate with a per-entry two-sided confidence interval.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CovarianceCi {
    /// The point estimate (from all samples).
    pub cov: DMatrix<f64>,
    /// Lower interval bounds, entry by entry.
    pub lo: DMatrix<f64>,
    /// Upper interval bounds, entry by entry.
    pub hi: DMatrix<f64>,
    /// Number of samples.
    pub n: usize,
    /// Confidence level of each entry's interval, e.g. 0.95 (per entry, not joint).
    pub level: f64,
    /// How the intervals were computed.
    pub method: CiMethod,
}

impl CovarianceCi {
    /// Dimension `d` of the samples.
    pub fn dim(&self) -> usize {
        self.cov.nrows()
    }

    /// `[lo, hi]` of entry (`row`, `col`), `None` if out of range.
    pub fn interval(&self, row: usize, col: usize) -> Option<[f64; 2]> {
        (row < self.dim() && col < self.dim()).then(|| [self.lo[(row, col)], self.hi[(row, col)]])
    }

    /// Whether `value` lies in the interval of entry (`row`, `col`) (false if out of range).
    pub fn covers(&self, row: usize, col: usize, value: f64) -> bool {
        self.interval(row, col)
            .is_some_and(|[lo, hi]| lo <= value && value <= hi)
    }

    /// Upper-triangle entries `(row, col)`, `row <= col`, whose interval does not
    /// contain the `design` value, in row-major order.
    ///
    /// # Errors
    /// [`StatsError::DimensionMismatch`] if `design` is not `d x d`;
    /// [`StatsError::NonFiniteEntry`] for a NaN/infinite design entry.
    pub fn uncovered_entries(
        &self,
        design: &DMatrix<f64>,
    ) -> Result<Vec<(usize, usize)>, StatsError> {
        check_matrix("design covariance", design, self.dim())?;
        let d = self.dim();
        let mut out = Vec::new();
        for r in 0..d {
            for c in r..d {
                if !self.covers(r, c, design[(r, c)]) {
                    out.push((r, c));
                }
            }
        }
        Ok(out)
    }
}

/// Largest deviation of an estimate from a design covariance, see
/// [`max_relative_deviation`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MaxDeviation {
    /// The largest deviation (dimensionless; 0.05 = 5 %).
    pub value: f64,
    /// Row of the worst entry.
    pub row: usize,
    /// Column of the worst entry (`col >= row`).
    pub col: usize,
    /// Whether the worst entry's design value is zero (deviation scaled by the
    /// largest design variance instead of the entry itself).
    pub design_zero: bool,
}

fn check_matrix(what: &str, m: &DMatrix<f64>, dim: usize) -> Result<(), StatsError> {
    if m.nrows() != dim || m.ncols() != dim {
        return Err(StatsError::DimensionMismatch {
            what: format!("{what} ({}x{})", m.nrows(), m.ncols()),
            index: 0,
            expected: dim,
            found: if m.nrows() != dim {
                m.nrows()
            } else {
                m.ncols()
            },
        });
    }
    for r in 0..dim {
        for c in 0..dim {
            let value = m[(r, c)];
            if !value.is_finite() {
                return Err(StatsError::NonFiniteEntry {
                    what: what.into(),
                    row: r,
                    col: c,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Checks the sample rows (count, equal length >= 1, finite) and returns `d`.
fn check_samples<R: AsRef<[f64]>>(
    what: &str,
    samples: &[R],
    min_n: usize,
) -> Result<usize, StatsError> {
    if samples.is_empty() {
        return Err(StatsError::Empty { what: what.into() });
    }
    if samples.len() < min_n {
        return Err(StatsError::TooFewSamples {
            what: what.into(),
            needed: min_n,
            got: samples.len(),
        });
    }
    let d = samples[0].as_ref().len();
    if d == 0 {
        return Err(StatsError::Degenerate {
            what: what.into(),
            reason: "samples have dimension 0",
        });
    }
    for (row, s) in samples.iter().enumerate() {
        let s = s.as_ref();
        if s.len() != d {
            return Err(StatsError::DimensionMismatch {
                what: what.into(),
                index: row,
                expected: d,
                found: s.len(),
            });
        }
        if let Some(col) = s.iter().position(|v| !v.is_finite()) {
            return Err(StatsError::NonFiniteEntry {
                what: what.into(),
                row,
                col,
                value: s[col],
            });
        }
    }
    Ok(d)
}

fn min_samples(mode: MeanMode) -> usize {
    match mode {
        MeanMode::Estimated => 2,
        MeanMode::KnownZero => 1,
    }
}

/// The mean to subtract: the sample mean, or zero.
fn center<R: AsRef<[f64]>>(samples: &[R], d: usize, mode: MeanMode) -> DVector<f64> {
    let mut mean = DVector::zeros(d);
    if mode == MeanMode::Estimated {
        for s in samples {
            for (m, v) in mean.iter_mut().zip(s.as_ref()) {
                *m += v;
            }
        }
        mean /= samples.len() as f64;
    }
    mean
}

/// Sum of outer products `sum (x - mu)(x - mu)^T` over `samples`.
fn scatter<R: AsRef<[f64]>>(samples: &[R], mu: &DVector<f64>) -> DMatrix<f64> {
    let d = mu.len();
    let mut acc = DMatrix::zeros(d, d);
    let mut dev = vec![0.0; d];
    for s in samples {
        for ((e, v), m) in dev.iter_mut().zip(s.as_ref()).zip(mu.iter()) {
            *e = v - m;
        }
        for r in 0..d {
            for c in r..d {
                acc[(r, c)] += dev[r] * dev[c];
            }
        }
    }
    for r in 0..d {
        for c in 0..r {
            acc[(r, c)] = acc[(c, r)];
        }
    }
    acc
}

/// Covariance of `samples` (one sample per row) with the given [`MeanMode`]:
/// `Estimated`: `S = 1/(n-1) sum (x_k - xbar)(x_k - xbar)^T`;
/// `KnownZero`: `S = 1/n sum x_k x_k^T`.
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::TooFewSamples`] (`n < 2` with `Estimated`),
/// [`StatsError::DimensionMismatch`] (ragged rows, naming the row),
/// [`StatsError::NonFiniteEntry`] (naming sample and component), or
/// [`StatsError::Degenerate`] for zero-length rows.
pub fn covariance<R: AsRef<[f64]>>(
    samples: &[R],
    mode: MeanMode,
) -> Result<DMatrix<f64>, StatsError> {
    let d = check_samples("covariance samples", samples, min_samples(mode))?;
    Ok(covariance_unchecked(samples, d, mode))
}

fn covariance_unchecked<R: AsRef<[f64]>>(samples: &[R], d: usize, mode: MeanMode) -> DMatrix<f64> {
    let mu = center(samples, d, mode);
    let n = samples.len() as f64;
    let denom = match mode {
        MeanMode::Estimated => n - 1.0,
        MeanMode::KnownZero => n,
    };
    scatter(samples, &mu) / denom
}

/// Unbiased sample covariance (mean subtracted, `1/(n-1)`).
///
/// # Errors
/// As [`covariance`].
pub fn sample_covariance<R: AsRef<[f64]>>(samples: &[R]) -> Result<DMatrix<f64>, StatsError> {
    covariance(samples, MeanMode::Estimated)
}

/// Covariance of samples whose mean is known to be zero (no subtraction, `1/n`).
///
/// # Errors
/// As [`covariance`].
pub fn zero_mean_covariance<R: AsRef<[f64]>>(samples: &[R]) -> Result<DMatrix<f64>, StatsError> {
    covariance(samples, MeanMode::KnownZero)
}

/// Covariance with iid normal-theory per-entry intervals.
///
/// For iid Gaussian samples, `Var(s_ij) = (sigma_ii sigma_jj + sigma_ij^2) / dof`
/// with `dof = n - 1` (`Estimated`) or `n` (`KnownZero`); the interval is
/// `s_ij +/- z_{(1+level)/2} sqrt((s_ii s_jj + s_ij^2) / dof)` with the estimates
/// plugged in. Valid only for independent samples; use
/// [`covariance_ci_batch_means`] for autocorrelated ones.
///
/// # Errors
/// As [`covariance`], plus [`StatsError::OutOfRange`] unless `0 < level < 1`.
pub fn covariance_ci_normal<R: AsRef<[f64]>>(
    samples: &[R],
    mode: MeanMode,
    level: f64,
) -> Result<CovarianceCi, StatsError> {
    ensure_level("covariance confidence level", level)?;
    let d = check_samples("covariance samples", samples, min_samples(mode))?;
    let cov = covariance_unchecked(samples, d, mode);
    let n = samples.len();
    let dof = match mode {
        MeanMode::Estimated => n as f64 - 1.0,
        MeanMode::KnownZero => n as f64,
    };
    let z = normal_quantile(0.5 * (1.0 + level))?;
    let half = DMatrix::from_fn(d, d, |r, c| {
        let var = (cov[(r, r)] * cov[(c, c)] + cov[(r, c)].powi(2)) / dof;
        z * var.max(0.0).sqrt()
    });
    Ok(CovarianceCi {
        lo: &cov - &half,
        hi: &cov + &half,
        cov,
        n,
        level,
        method: CiMethod::NormalTheory,
    })
}

/// Covariance with batch-means per-entry intervals, for autocorrelated samples
/// (e.g. a noise generator with a correlated component drawn every `t_gap`).
///
/// The first `B * m` samples (`m = floor(n / B)`; the `n mod B` trailing samples are
/// left out of the batches) are split into `B` contiguous batches. With the mean `mu`
/// of all samples (or zero for `KnownZero`), batch `k` gives
/// `b_k = c / m * sum_{t in k} (x_t - mu)(x_t - mu)^T` with `c = n/(n-1)`
/// (`Estimated`) or `1` (`KnownZero`). The interval is centred on the all-sample
/// estimate [`covariance`]: `s_ij +/- t_{B-1, (1+level)/2} sd_k(b_k,ij) / sqrt(B)`.
/// Batches must be much longer than the correlation time for the batch estimates
/// to be nearly independent.
///
/// # Errors
/// As [`covariance_ci_normal`], plus [`StatsError::OutOfRange`] if `batches < 2`
/// and [`StatsError::TooFewSamples`] if a batch would hold fewer than 2 samples.
pub fn covariance_ci_batch_means<R: AsRef<[f64]>>(
    samples: &[R],
    mode: MeanMode,
    batches: usize,
    level: f64,
) -> Result<CovarianceCi, StatsError> {
    ensure_level("covariance confidence level", level)?;
    if batches < 2 {
        return Err(StatsError::OutOfRange {
            what: "number of batches".into(),
            value: batches as f64,
            expected: ">= 2",
        });
    }
    let needed = (2 * batches).max(min_samples(mode));
    let d = check_samples("batch-means covariance samples", samples, needed)?;
    let n = samples.len();
    let m = n / batches;
    let mu = center(samples, d, mode);
    let c = match mode {
        MeanMode::Estimated => n as f64 / (n as f64 - 1.0),
        MeanMode::KnownZero => 1.0,
    };
    let batch_estimates: Vec<DMatrix<f64>> = samples[..batches * m]
        .chunks(m)
        .map(|chunk| scatter(chunk, &mu) * (c / m as f64))
        .collect();
    let bf = batches as f64;
    let mean_b = batch_estimates
        .iter()
        .fold(DMatrix::zeros(d, d), |acc, b| acc + b)
        / bf;
    let var_b = batch_estimates
        .iter()
        .fold(DMatrix::zeros(d, d), |acc: DMatrix<f64>, b| {
            acc + (b - &mean_b).map(|v| v * v)
        })
        / (bf - 1.0);
    let t = student_t_quantile(0.5 * (1.0 + level), bf - 1.0)?;
    let half = var_b.map(|v| t * (v / bf).max(0.0).sqrt());
    let cov = covariance_unchecked(samples, d, mode);
    Ok(CovarianceCi {
        lo: &cov - &half,
        hi: &cov + &half,
        cov,
        n,
        level,
        method: CiMethod::BatchMeans {
            batches,
            batch_len: m,
        },
    })
}

/// Largest relative deviation of `estimate` from `design` over the upper triangle
/// (`row <= col`; both matrices are taken as symmetric).
///
/// With `scale = max_k |design_kk|` and `tiny = 1e-12 * scale`:
/// - an entry with `|design_ij| > tiny` contributes `|est_ij - design_ij| / |design_ij|`;
/// - an entry whose design is zero (`|design_ij| <= tiny`, e.g. range/depth
///   cross-covariance, or the depth variance in a "correlation only" case) has no
///   relative deviation; it contributes the absolute deviation scaled by the
///   largest design variance, `|est_ij - design_ij| / scale`, and is flagged
///   [`MaxDeviation::design_zero`]. This keeps a generator that leaks noise into a
///   supposedly noise-free component detectable instead of skipping it.
///
/// # Errors
/// [`StatsError::DimensionMismatch`] if the matrices are not square of equal size,
/// [`StatsError::NonFiniteEntry`], or [`StatsError::Degenerate`] if every design
/// variance is zero (or the matrices are 0 x 0).
pub fn max_relative_deviation(
    estimate: &DMatrix<f64>,
    design: &DMatrix<f64>,
) -> Result<MaxDeviation, StatsError> {
    let d = design.nrows();
    check_matrix("design covariance", design, d)?;
    check_matrix("estimated covariance", estimate, d)?;
    let scale = (0..d).map(|k| design[(k, k)].abs()).fold(0.0_f64, f64::max);
    if scale == 0.0 {
        return Err(StatsError::Degenerate {
            what: "design covariance".into(),
            reason: "no positive design variance to scale deviations by",
        });
    }
    let tiny = 1e-12 * scale;
    let mut worst = MaxDeviation {
        value: -1.0,
        row: 0,
        col: 0,
        design_zero: false,
    };
    for r in 0..d {
        for c in r..d {
            let des = design[(r, c)];
            let diff = (estimate[(r, c)] - des).abs();
            let (value, design_zero) = if des.abs() > tiny {
                (diff / des.abs(), false)
            } else {
                (diff / scale, true)
            };
            if value > worst.value {
                worst = MaxDeviation {
                    value,
                    row: r,
                    col: c,
                    design_zero,
                };
            }
        }
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// Draws `n` zero-mean samples `x = L w` with `L L^T = design`.
    fn gaussian_samples(design: &DMatrix<f64>, n: usize, rng: &mut impl Rng) -> Vec<Vec<f64>> {
        let l = design.clone().cholesky().unwrap().l();
        let d = design.nrows();
        (0..n)
            .map(|_| {
                let w = DVector::from_fn(d, |_, _| rng.sample::<f64, _>(StandardNormal));
                (&l * w).iter().copied().collect()
            })
            .collect()
    }

    /// Stationary vector AR(1): `x_t = phi x_{t-1} + sqrt(1 - phi^2) L w_t`, cov = design.
    fn ar1_samples(design: &DMatrix<f64>, phi: f64, n: usize, rng: &mut impl Rng) -> Vec<Vec<f64>> {
        let l = design.clone().cholesky().unwrap().l();
        let d = design.nrows();
        let draw = |rng: &mut dyn rand::RngCore| {
            &l * DVector::from_fn(d, |_, _| rng.sample::<f64, _>(StandardNormal))
        };
        let mut x = draw(rng);
        let k = (1.0 - phi * phi).sqrt();
        (0..n)
            .map(|_| {
                let row = x.iter().copied().collect();
                x = &x * phi + draw(rng) * k;
                row
            })
            .collect()
    }

    /// The B-beacons "both, high" design: ranges diag 0.05, off 0.04, depth 0.04.
    fn beacons_design() -> DMatrix<f64> {
        DMatrix::from_fn(5, 5, |r, c| match (r, c) {
            (4, 4) => 0.04,
            (4, _) | (_, 4) => 0.0,
            (r, c) if r == c => 0.05,
            _ => 0.04,
        })
    }

    #[test]
    fn hand_computed() {
        let s = [[1.0, 2.0], [3.0, 6.0], [5.0, 7.0]];
        let c = sample_covariance(&s).unwrap();
        assert_relative_eq!(
            c,
            DMatrix::from_row_slice(2, 2, &[4.0, 5.0, 5.0, 7.0]),
            epsilon = 1e-14
        );
        let z = zero_mean_covariance(&s).unwrap();
        let expect = DMatrix::from_row_slice(2, 2, &[35.0, 55.0, 55.0, 89.0]) / 3.0;
        assert_relative_eq!(z, expect, epsilon = 1e-13);
        let rows: Vec<Vec<f64>> = s.iter().map(|r| r.to_vec()).collect();
        assert_eq!(sample_covariance(&rows).unwrap(), c);
    }

    #[test]
    fn bad_input() {
        let empty: [[f64; 2]; 0] = [];
        assert!(matches!(
            sample_covariance(&empty),
            Err(StatsError::Empty { .. })
        ));
        assert!(matches!(
            sample_covariance(&[[1.0, 2.0]]),
            Err(StatsError::TooFewSamples {
                needed: 2,
                got: 1,
                ..
            })
        ));
        assert!(zero_mean_covariance(&[[1.0, 2.0]]).is_ok());
        let ragged = vec![vec![1.0, 2.0], vec![1.0]];
        assert!(matches!(
            sample_covariance(&ragged),
            Err(StatsError::DimensionMismatch {
                index: 1,
                expected: 2,
                found: 1,
                ..
            })
        ));
        assert!(matches!(
            sample_covariance(&[[1.0, 2.0], [f64::NAN, 1.0]]),
            Err(StatsError::NonFiniteEntry { row: 1, col: 0, .. })
        ));
        let zero_dim: Vec<Vec<f64>> = vec![vec![], vec![]];
        assert!(sample_covariance(&zero_dim).is_err());
        let s = [[1.0], [2.0], [3.0], [4.0]];
        assert!(covariance_ci_normal(&s, MeanMode::Estimated, 1.0).is_err());
        assert!(covariance_ci_batch_means(&s, MeanMode::Estimated, 1, 0.95).is_err());
        assert!(matches!(
            covariance_ci_batch_means(&s, MeanMode::Estimated, 3, 0.95),
            Err(StatsError::TooFewSamples {
                needed: 6,
                got: 4,
                ..
            })
        ));
        let a = DMatrix::identity(2, 2);
        assert!(max_relative_deviation(&a, &DMatrix::identity(3, 3)).is_err());
        assert!(max_relative_deviation(&a, &DMatrix::zeros(2, 2)).is_err());
    }

    #[test]
    fn relative_deviation_rules() {
        let design = DMatrix::from_row_slice(2, 2, &[0.05, 0.0, 0.0, 0.04]);
        let est = DMatrix::from_row_slice(2, 2, &[0.051, 0.002, 0.002, 0.04]);
        let dev = max_relative_deviation(&est, &design).unwrap();
        // zero design entry: 0.002 / 0.05 = 0.04 > 0.001/0.05 = 0.02.
        assert_relative_eq!(dev.value, 0.04, epsilon = 1e-12);
        assert_eq!((dev.row, dev.col, dev.design_zero), (0, 1, true));
        let est = DMatrix::from_row_slice(2, 2, &[0.05, 0.0, 0.0, 0.036]);
        let dev = max_relative_deviation(&est, &design).unwrap();
        assert_relative_eq!(dev.value, 0.1, epsilon = 1e-12);
        assert_eq!((dev.row, dev.col, dev.design_zero), (1, 1, false));
    }

    /// One long seeded run of the B-beacons "both, high" design: at level 99.9 % per
    /// entry, all 15 entries are covered (family-wise false alarm <= 15 * 0.001) and
    /// the estimate is within 5 % of the design. Negative control: a wrong design
    /// (off-diagonal 0.033, the paper's short-run value, ~35 sd away) is not covered.
    #[test]
    fn long_run_converges_to_design() {
        let design = beacons_design();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let samples = gaussian_samples(&design, 100_000, &mut rng);
        let ci = covariance_ci_normal(&samples, MeanMode::KnownZero, 0.999).unwrap();
        assert_eq!(ci.uncovered_entries(&design).unwrap(), vec![]);
        let dev = max_relative_deviation(&ci.cov, &design).unwrap();
        assert!(dev.value < 0.05, "{dev:?}");

        let mut wrong = design.clone();
        wrong[(0, 1)] = 0.033;
        wrong[(1, 0)] = 0.033;
        assert_eq!(ci.uncovered_entries(&wrong).unwrap(), vec![(0, 1)]);
        assert!(max_relative_deviation(&ci.cov, &wrong).unwrap().value > 0.15);
    }

    /// Coverage of the normal-theory 95 % intervals over 1000 seeds of n = 1000 iid
    /// Gaussian samples: per entry the covering count is Binomial(1000, 0.95),
    /// sd = 6.9, so it must lie in 950 +/- 3 sd = [929, 971] (checked for each of the
    /// 6 upper-triangle entries). Negative control: with the design scaled by 1.15,
    /// entry (0, 0) (3.4 sd of its estimate away) is covered far less (~8 %).
    #[test]
    fn normal_theory_coverage() {
        let design =
            DMatrix::from_row_slice(3, 3, &[1.0, 0.6, -0.3, 0.6, 2.0, 0.0, -0.3, 0.0, 0.5]);
        let scaled = &design * 1.15;
        let mut covered = DMatrix::<u32>::zeros(3, 3);
        let mut covered_scaled_diag = 0;
        for seed in 0..1000 {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
            let s = gaussian_samples(&design, 1000, &mut rng);
            let ci = covariance_ci_normal(&s, MeanMode::Estimated, 0.95).unwrap();
            for r in 0..3 {
                for c in r..3 {
                    covered[(r, c)] += u32::from(ci.covers(r, c, design[(r, c)]));
                }
            }
            covered_scaled_diag += u32::from(ci.covers(0, 0, scaled[(0, 0)]));
        }
        for r in 0..3 {
            for c in r..3 {
                let k = covered[(r, c)];
                assert!((929..=971).contains(&k), "entry ({r},{c}) covered {k}");
            }
        }
        assert!(covered_scaled_diag < 800, "{covered_scaled_diag}");
    }

    /// Autocorrelated AR(1) samples (phi = 0.8): batch-means intervals (B = 20
    /// batches of 200) keep ~95 % coverage over 500 seeds (Binomial(500, 0.95),
    /// sd 4.87: [461, 489]); the iid normal-theory interval on the same data (the
    /// negative control) under-covers badly (expected ~65 %; asserted < 85 %).
    #[test]
    fn batch_means_coverage_on_autocorrelated_samples() {
        let design = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.5, 2.0]);
        let mut bm = [0_u32; 3];
        let mut iid = [0_u32; 3];
        let entries = [(0, 0), (0, 1), (1, 1)];
        for seed in 0..500 {
            let mut rng = ChaCha8Rng::seed_from_u64(5000 + seed);
            let s = ar1_samples(&design, 0.8, 4000, &mut rng);
            let ci_bm = covariance_ci_batch_means(&s, MeanMode::Estimated, 20, 0.95).unwrap();
            assert_eq!(
                ci_bm.method,
                CiMethod::BatchMeans {
                    batches: 20,
                    batch_len: 200
                }
            );
            let ci_iid = covariance_ci_normal(&s, MeanMode::Estimated, 0.95).unwrap();
            assert_relative_eq!(ci_bm.cov, ci_iid.cov);
            for (k, &(r, c)) in entries.iter().enumerate() {
                bm[k] += u32::from(ci_bm.covers(r, c, design[(r, c)]));
                iid[k] += u32::from(ci_iid.covers(r, c, design[(r, c)]));
            }
        }
        for k in 0..3 {
            assert!(
                (461..=489).contains(&bm[k]),
                "batch means entry {k}: {}",
                bm[k]
            );
            assert!(iid[k] < 425, "iid entry {k}: {}", iid[k]);
        }
    }
}
