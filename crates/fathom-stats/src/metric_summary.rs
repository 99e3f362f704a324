//! The summary of one metric over Monte Carlo runs, as every `summary.json` row
//! reports it: the mean with an interval that respects the metric, the median with
//! its order-statistic interval, and the count of runs beyond a divergence threshold.
//!
//! The interval of the mean depends on the metric's [`MetricKind`]:
//! - [`MetricKind::NonNegative`] (an RMSE, a maximum error, a NEES, a count): the BCa
//!   bootstrap interval ([`crate::bootstrap`]), whose ends are means of resampled
//!   runs and so never negative, and which follows a skewed distribution where the
//!   Student-t interval cannot;
//! - [`MetricKind::Signed`] (a paired difference of two methods on the same runs, a
//!   bias): the Student-t interval, valid for a mean of well-behaved values of either
//!   sign.
//!
//! Beyond [`BOOTSTRAP_MAX_RUNS`] runs (a cluster campaign) the bootstrap's work
//! (`runs x resamples` draws) is replaced by the Student-t interval, which the central
//! limit makes valid there; a lower end below zero of a non-negative metric is then
//! cut at zero and the method says so ([`IntervalMethod::StudentTCut`]).
//!
//! The bootstrap of each row draws from its own stream, seeded from the run's base
//! seed and the row's key ([`row_seed`]): the same runs give the same interval in one
//! process, in a sharded campaign's merge, and whatever other rows exist.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::bootstrap::{MAX_RESAMPLES, MIN_RESAMPLES, bootstrap_bca_mean};
use crate::error::{StatsError, ensure_finite_non_empty};
use crate::monte_carlo::mean_ci;
use crate::proportion::median_ci;

/// Beyond this many runs the mean's interval is Student-t (module docs).
pub const BOOTSTRAP_MAX_RUNS: usize = 20_000;

/// Whether a metric can be negative; it decides the interval of its mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetricKind {
    /// Never negative (an error norm, an RMSE, a maximum, a NEES, a count): a
    /// negative run value is an error.
    NonNegative,
    /// Either sign (a paired difference, a bias).
    Signed,
}

/// How a row's interval of the mean was computed; its name is the row's `ci_method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalMethod {
    /// `mean +/- t_{n-1} s / sqrt(n)`.
    StudentT,
    /// Student-t with its lower end cut at zero (a non-negative metric over more than
    /// [`BOOTSTRAP_MAX_RUNS`] runs).
    StudentTCut,
    /// The BCa bootstrap interval.
    BootstrapBca,
}

impl serde::Serialize for IntervalMethod {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl IntervalMethod {
    /// The name written in `summary.json` (`ci_method`) and the report's legend.
    pub fn name(self) -> &'static str {
        match self {
            Self::StudentT => "student-t",
            Self::StudentTCut => "student-t-cut-at-0",
            Self::BootstrapBca => "bootstrap-bca",
        }
    }
}

/// Checked settings of the run summaries of one execution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SummarySettings {
    resamples: usize,
    divergence_factor: f64,
    base_seed: u64,
}

impl SummarySettings {
    /// `resamples` bootstrap resamples per interval, runs counted as diverged above
    /// `divergence_factor` times the metric's median, bootstrap streams seeded from
    /// `base_seed`.
    ///
    /// # Errors
    /// [`StatsError::OutOfRange`] for resamples outside `[100, 1000000]` or a factor
    /// that is not finite and above 1.
    pub fn new(
        resamples: usize,
        divergence_factor: f64,
        base_seed: u64,
    ) -> Result<Self, StatsError> {
        if !(MIN_RESAMPLES..=MAX_RESAMPLES).contains(&resamples) {
            return Err(StatsError::OutOfRange {
                what: "bootstrap resamples".into(),
                value: resamples as f64,
                expected: "between 100 and 1000000",
            });
        }
        if !(divergence_factor.is_finite() && divergence_factor > 1.0) {
            return Err(StatsError::OutOfRange {
                what: "divergence factor".into(),
                value: divergence_factor,
                expected: "finite and > 1",
            });
        }
        Ok(Self {
            resamples,
            divergence_factor,
            base_seed,
        })
    }

    /// Bootstrap resamples per interval.
    pub fn resamples(&self) -> usize {
        self.resamples
    }

    /// A run diverged when its value exceeds this factor times the median.
    pub fn divergence_factor(&self) -> f64 {
        self.divergence_factor
    }

    /// The base seed the bootstrap streams derive from.
    pub fn base_seed(&self) -> u64 {
        self.base_seed
    }
}

/// The runs of a metric beyond its divergence threshold.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Divergence {
    /// The threshold: the divergence factor times the median.
    pub threshold: f64,
    /// Runs whose value exceeds it.
    pub runs: usize,
    /// `runs / n`.
    pub fraction: f64,
}

/// One metric summarized over runs (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MetricSummary {
    /// Number of runs.
    pub n: usize,
    /// Mean over runs.
    pub mean: f64,
    /// Sample standard deviation over runs (1/(n-1)); 0 for one run.
    pub std: f64,
    /// 95 % interval of the mean; `None` for one run.
    pub ci95: Option<[f64; 2]>,
    /// How `ci95` was computed.
    pub ci_method: IntervalMethod,
    /// Median over runs (type-7 quantile).
    pub median: f64,
    /// Order-statistic interval of the median at (at least) 95 %; `None` below six runs.
    pub median_ci95: Option<[f64; 2]>,
    /// Runs beyond the divergence threshold: for a non-negative metric with a
    /// positive median, `None` otherwise (a signed metric, or a median of zero).
    pub divergence: Option<Divergence>,
}

/// The seed of the bootstrap stream of the row `method` / `metric` (FNV-1a over the
/// base seed and the key): stable across processes, platforms and releases.
pub fn row_seed(base_seed: u64, method: &str, metric: &str) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let bytes = base_seed
        .to_le_bytes()
        .into_iter()
        .chain(method.bytes())
        .chain([0xff])
        .chain(metric.bytes());
    for b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(PRIME);
    }
    h
}

/// Summarizes the run `values` of the row `method` / `metric`.
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::NonFinite`] (index of the run), or
/// [`StatsError::OutOfRange`] naming the run of a [`MetricKind::NonNegative`] metric
/// whose value is negative.
pub fn summarize_metric(
    values: &[f64],
    kind: MetricKind,
    settings: &SummarySettings,
    method: &str,
    metric: &str,
) -> Result<MetricSummary, StatsError> {
    ensure_finite_non_empty(&format!("runs of {method}/{metric}"), values)?;
    if kind == MetricKind::NonNegative
        && let Some((i, &v)) = values.iter().enumerate().find(|(_, v)| **v < 0.0)
    {
        return Err(StatsError::OutOfRange {
            what: format!("run {i} of the non-negative metric {method}/{metric}"),
            value: v,
            expected: ">= 0 (a metric that can be negative is declared signed)",
        });
    }
    let t = mean_ci(values)?;
    let (ci95, ci_method) = match (kind, t.ci95) {
        (_, None) => (None, IntervalMethod::StudentT),
        (MetricKind::Signed, Some(ci)) => (Some(ci), IntervalMethod::StudentT),
        (MetricKind::NonNegative, Some(_)) if values.len() <= BOOTSTRAP_MAX_RUNS => {
            let mut rng = ChaCha8Rng::seed_from_u64(row_seed(settings.base_seed, method, metric));
            let ci = bootstrap_bca_mean(values, 0.95, settings.resamples, &mut rng)?;
            (Some(ci), IntervalMethod::BootstrapBca)
        }
        (MetricKind::NonNegative, Some([lo, hi])) => {
            if lo < 0.0 {
                (Some([0.0, hi]), IntervalMethod::StudentTCut)
            } else {
                (Some([lo, hi]), IntervalMethod::StudentT)
            }
        }
    };
    let med = median_ci(values, 0.95)?;
    let divergence = (kind == MetricKind::NonNegative && med.median > 0.0).then(|| {
        let threshold = settings.divergence_factor * med.median;
        let runs = values.iter().filter(|&&v| v > threshold).count();
        Divergence {
            threshold,
            runs,
            fraction: runs as f64 / values.len() as f64,
        }
    });
    Ok(MetricSummary {
        n: values.len(),
        mean: t.mean,
        std: t.std,
        ci95,
        ci_method,
        median: med.median,
        median_ci95: med.interval,
        divergence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> SummarySettings {
        SummarySettings::new(2000, 10.0, 42).unwrap()
    }

    #[test]
    fn heavy_tail_gives_a_positive_interval_a_median_and_a_divergence_count() {
        // 48 runs near 0.1 m and 2 diverged runs at 40 m: the t-interval of this
        // mean reaches below zero, the bootstrap's does not.
        let mut v: Vec<f64> = (0..48).map(|i| 0.09 + 0.001 * f64::from(i)).collect();
        v.extend([40.0, 45.0]);
        assert!(mean_ci(&v).unwrap().ci95.unwrap()[0] < 0.0);
        let s =
            summarize_metric(&v, MetricKind::NonNegative, &settings(), "GREKF", "rmse_3d").unwrap();
        assert_eq!(s.ci_method, IntervalMethod::BootstrapBca);
        let [lo, hi] = s.ci95.unwrap();
        assert!(lo >= 0.0 && lo <= s.mean && s.mean <= hi, "{s:?}");
        assert!(s.median < 0.2);
        let d = s.divergence.unwrap();
        assert_eq!((d.runs, d.fraction), (2, 0.04));
        // Same key, same seed: the same interval; another key draws another stream.
        let again =
            summarize_metric(&v, MetricKind::NonNegative, &settings(), "GREKF", "rmse_3d").unwrap();
        assert_eq!(again, s);
        assert_ne!(
            row_seed(42, "GREKF", "rmse_3d"),
            row_seed(42, "GREKF", "rmse_h")
        );
        assert_ne!(row_seed(42, "AB", "C"), row_seed(42, "A", "BC"));
    }

    #[test]
    fn signed_metrics_use_student_t_and_no_divergence() {
        let v = [-0.2, 0.1, 0.3, -0.1, 0.05, 0.2];
        let s = summarize_metric(&v, MetricKind::Signed, &settings(), "A-B", "diff").unwrap();
        assert_eq!(s.ci_method, IntervalMethod::StudentT);
        assert_eq!(s.ci95, mean_ci(&v).unwrap().ci95);
        assert!(s.divergence.is_none());
        assert!(s.median_ci95.is_some());
    }

    #[test]
    fn bad_input_is_refused_with_the_run() {
        let e = summarize_metric(
            &[0.1, -0.2],
            MetricKind::NonNegative,
            &settings(),
            "MF",
            "rmse",
        )
        .unwrap_err();
        assert!(e.to_string().contains("run 1"), "{e}");
        assert!(summarize_metric(&[], MetricKind::Signed, &settings(), "MF", "rmse").is_err());
        assert!(SummarySettings::new(5, 10.0, 0).is_err());
        assert!(SummarySettings::new(1000, 1.0, 0).is_err());
        assert!(SummarySettings::new(1000, f64::NAN, 0).is_err());
        let one =
            summarize_metric(&[3.0], MetricKind::NonNegative, &settings(), "MF", "rmse").unwrap();
        assert_eq!((one.ci95, one.median, one.median_ci95), (None, 3.0, None));
    }

    #[test]
    fn beyond_the_bootstrap_limit_student_t_is_cut_at_zero() {
        let mut v = vec![0.0; BOOTSTRAP_MAX_RUNS + 1];
        v[0] = 1e9;
        let s = summarize_metric(&v, MetricKind::NonNegative, &settings(), "M", "nees").unwrap();
        assert_eq!(s.ci_method, IntervalMethod::StudentTCut);
        assert_eq!(s.ci95.unwrap()[0], 0.0);
        assert!(s.divergence.is_none(), "median 0: no threshold");
    }
}
