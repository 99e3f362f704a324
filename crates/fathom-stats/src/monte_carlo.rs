//! Monte Carlo aggregation: the mean of a per-run statistic over runs with its
//! Student-t confidence interval, and an insertion-ordered [`Aggregator`] keyed by
//! (method, metric) for experiments.

use crate::error::{StatsError, ensure_finite_non_empty, ensure_level};
use crate::quantile::student_t_quantile;
use crate::run_stats::RunStats;

/// Mean over runs with a two-sided confidence interval at an arbitrary level.
///
/// With run values `x_1..x_n`: `mean = (1/n) sum x_i`,
/// `std = sqrt(sum (x_i - mean)^2 / (n - 1))` (sample std across runs),
/// interval `mean +/- t_{n-1, (1+level)/2} * std / sqrt(n)`.
/// For `n = 1` there is no spread estimate: `std = 0` and `interval = None`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeanInterval {
    /// Mean over runs.
    pub mean: f64,
    /// Sample standard deviation across runs (1/(n-1)); 0 when `n = 1`.
    pub std: f64,
    /// Number of runs.
    pub n: usize,
    /// Confidence level of `interval`, e.g. 0.95.
    pub level: f64,
    /// `[lo, hi]`; `None` when `n = 1`.
    pub interval: Option<[f64; 2]>,
}

/// Mean over runs with its 95 % Student-t confidence interval — the `value` /
/// `ci95` pair of a `summary.json` row.
///
/// `ci95` is `None` (serialized as `null`) only when `n = 1`, i.e. for a single
/// deterministic quantity, as the output contract allows. `std` is the sample std
/// across runs (1/(n-1)), 0 for `n = 1`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeanCi {
    /// Mean over runs.
    pub mean: f64,
    /// 95 % confidence interval `[lo, hi]` of the mean; `None` when `n = 1`.
    pub ci95: Option<[f64; 2]>,
    /// Number of runs.
    pub n: usize,
    /// Sample standard deviation across runs (1/(n-1)); 0 when `n = 1`.
    pub std: f64,
}

impl MeanCi {
    /// The 95 % interval, or `[mean, mean]` for a single run (no spread estimate).
    pub fn bounds(&self) -> [f64; 2] {
        self.ci95.unwrap_or([self.mean, self.mean])
    }
}

/// Mean over runs with a Student-t confidence interval at `level` (e.g. 0.95).
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::NonFinite`] (index of the run), or
/// [`StatsError::OutOfRange`] unless `0 < level < 1`.
pub fn mean_interval(values: &[f64], level: f64) -> Result<MeanInterval, StatsError> {
    ensure_level("confidence level", level)?;
    ensure_finite_non_empty("Monte Carlo values", values)?;
    let n = values.len();
    let nf = n as f64;
    let mean = values.iter().sum::<f64>() / nf;
    if n == 1 {
        return Ok(MeanInterval {
            mean,
            std: 0.0,
            n,
            level,
            interval: None,
        });
    }
    let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0)).sqrt();
    let t = student_t_quantile(0.5 * (1.0 + level), nf - 1.0)?;
    let half = t * std / nf.sqrt();
    Ok(MeanInterval {
        mean,
        std,
        n,
        level,
        interval: Some([mean - half, mean + half]),
    })
}

/// Mean over runs with its 95 % Student-t confidence interval.
///
/// # Errors
/// As [`mean_interval`].
pub fn mean_ci(values: &[f64]) -> Result<MeanCi, StatsError> {
    let m = mean_interval(values, 0.95)?;
    Ok(MeanCi {
        mean: m.mean,
        ci95: m.interval,
        n: m.n,
        std: m.std,
    })
}

/// [`mean_ci`] as `(mean, [lo, hi])`, the interval being `[mean, mean]` for a single
/// run: the `value` and `ci95` of a summary row.
///
/// # Errors
/// As [`mean_interval`].
pub fn mean_and_ci95(values: &[f64]) -> Result<(f64, [f64; 2]), StatsError> {
    let m = mean_ci(values)?;
    Ok((m.mean, m.bounds()))
}

/// One aggregated row: a (method, metric) key and its [`MeanCi`] over runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AggregateRow {
    /// Method name, e.g. `"EFF"` or `"SC/high"`.
    pub method: String,
    /// Metric name, e.g. `"mean_3d"`.
    pub metric: String,
    /// Mean over runs and its 95 % CI.
    pub stats: MeanCi,
}

/// Accumulates per-run values under (method, metric) keys.
///
/// Keys are kept in first-insertion order in a `Vec` (no hash-map iteration order),
/// so the summary rows come out in the same order on every run. Values under a key
/// keep their push order; push runs in seed order (e.g. collect parallel results
/// first, then push, or [`Aggregator::extend`] per-run aggregators in seed order)
/// to get bit-identical results.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Aggregator {
    entries: Vec<(String, String, Vec<f64>)>,
}

impl Aggregator {
    /// An empty aggregator.
    pub fn new() -> Self {
        Self::default()
    }

    fn slot(&mut self, method: &str, metric: &str) -> &mut Vec<f64> {
        let pos = self
            .entries
            .iter()
            .position(|(m, k, _)| m == method && k == metric);
        let i = match pos {
            Some(i) => i,
            None => {
                self.entries
                    .push((method.to_owned(), metric.to_owned(), Vec::new()));
                self.entries.len() - 1
            }
        };
        &mut self.entries[i].2
    }

    /// Adds one run's `value` under (`method`, `metric`).
    ///
    /// # Errors
    /// [`StatsError::NonFinite`] naming the key and the index the value would have
    /// had; nothing is stored in that case.
    pub fn push(&mut self, method: &str, metric: &str, value: f64) -> Result<(), StatsError> {
        let slot = self.slot(method, metric);
        if !value.is_finite() {
            return Err(StatsError::NonFinite {
                what: format!("aggregator value for {method}/{metric}"),
                index: slot.len(),
                value,
            });
        }
        slot.push(value);
        Ok(())
    }

    /// Adds the four statistics of one run under `method`, with metric names
    /// `mean{suffix}`, `std{suffix}`, `max{suffix}`, `rmse{suffix}` (e.g. suffix
    /// `"_3d"` gives `mean_3d`; suffix `""` gives `mean`).
    ///
    /// # Errors
    /// As [`Aggregator::push`].
    pub fn push_run_stats(
        &mut self,
        method: &str,
        stats: &RunStats,
        suffix: &str,
    ) -> Result<(), StatsError> {
        self.push(method, &format!("mean{suffix}"), stats.mean)?;
        self.push(method, &format!("std{suffix}"), stats.std)?;
        self.push(method, &format!("max{suffix}"), stats.max)?;
        self.push(method, &format!("rmse{suffix}"), stats.rmse)
    }

    /// Appends all values of `other` (keys new to `self` are added in `other`'s order).
    pub fn extend(&mut self, other: &Aggregator) {
        for (method, metric, values) in &other.entries {
            self.slot(method, metric).extend_from_slice(values);
        }
    }

    /// The values stored under a key, in push order.
    pub fn values(&self, method: &str, metric: &str) -> Option<&[f64]> {
        self.entries
            .iter()
            .find(|(m, k, _)| m == method && k == metric)
            .map(|(_, _, v)| v.as_slice())
    }

    /// The keys `(method, metric)` in first-insertion order.
    pub fn keys(&self) -> impl Iterator<Item = (&str, &str)> {
        self.entries
            .iter()
            .map(|(m, k, _)| (m.as_str(), k.as_str()))
    }

    /// Number of keys.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no key has been added.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// [`MeanCi`] of one key.
    ///
    /// # Errors
    /// [`StatsError::Empty`] if the key is unknown or has no values.
    pub fn mean_ci(&self, method: &str, metric: &str) -> Result<MeanCi, StatsError> {
        let values = self.values(method, metric).unwrap_or(&[]);
        mean_ci(values).map_err(|e| match e {
            StatsError::Empty { .. } => StatsError::Empty {
                what: format!("aggregator key {method}/{metric}"),
            },
            other => other,
        })
    }

    /// One row per key, in first-insertion order.
    ///
    /// # Errors
    /// [`StatsError::Empty`] naming a key that has no values (possible only if every
    /// push to it was rejected).
    pub fn summarize(&self) -> Result<Vec<AggregateRow>, StatsError> {
        self.entries
            .iter()
            .map(|(method, metric, _)| {
                Ok(AggregateRow {
                    method: method.clone(),
                    metric: metric.clone(),
                    stats: self.mean_ci(method, metric)?,
                })
            })
            .collect()
    }
}

/// A confidence band: `(x, lo, hi)` per point.
pub type CiBand = Vec<(f64, f64, f64)>;

/// The per-x mean over runs and its 95 % CI band `(x, lo, hi)` (Student t over the
/// runs at each x), for a mean curve drawn with its interval. Every run has one value
/// per x; with fewer than two runs the band is empty. Where every run's value is
/// non-negative (an error norm) the band's lower edge is cut at 0.
///
/// # Errors
/// [`StatsError::LengthMismatch`] if a run's length differs from `xs`.
pub fn mean_curve_ci95(xs: &[f64], runs: &[&[f64]]) -> Result<(Vec<f64>, CiBand), StatsError> {
    if let Some(r) = runs.iter().find(|r| r.len() != xs.len()) {
        return Err(StatsError::LengthMismatch {
            what: "mean curve".to_string(),
            left_name: "x values",
            left: xs.len(),
            right_name: "a run",
            right: r.len(),
        });
    }
    let mut mean = Vec::with_capacity(xs.len());
    let mut band = Vec::new();
    let mut column = Vec::with_capacity(runs.len());
    for (j, &x) in xs.iter().enumerate() {
        column.clear();
        column.extend(runs.iter().map(|r| r[j]));
        let m = column.iter().sum::<f64>() / column.len().max(1) as f64;
        mean.push(m);
        if runs.len() >= 2 {
            let (_, [lo, hi]) = mean_and_ci95(&column)?;
            // A non-negative quantity (an error norm): the band stops at 0.
            let lo = if column.iter().all(|&v| v >= 0.0) {
                lo.max(0.0)
            } else {
                lo
            };
            band.push((x, lo, hi));
        }
    }
    Ok((mean, band))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn known_interval() {
        // mean 2.5, sample std sqrt(5/3), t_{3,0.975} = 3.182446.
        let m = mean_ci(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        let half = 3.182_446 * (5.0_f64 / 3.0).sqrt() / 2.0;
        assert_relative_eq!(m.mean, 2.5);
        assert_relative_eq!(m.std, (5.0_f64 / 3.0).sqrt(), epsilon = 1e-14);
        let [lo, hi] = m.ci95.unwrap();
        assert_relative_eq!(lo, 2.5 - half, epsilon = 1e-5);
        assert_relative_eq!(hi, 2.5 + half, epsilon = 1e-5);
        assert_eq!(m.n, 4);
        let wider = mean_interval(&[1.0, 2.0, 3.0, 4.0], 0.99).unwrap();
        let [wlo, _] = wider.interval.unwrap();
        assert!(wlo < lo);
    }

    #[test]
    fn single_run_has_no_interval() {
        let m = mean_ci(&[3.0]).unwrap();
        assert_eq!((m.mean, m.std, m.n, m.ci95), (3.0, 0.0, 1, None));
    }

    #[test]
    fn bad_input() {
        assert!(matches!(mean_ci(&[]), Err(StatsError::Empty { .. })));
        assert!(matches!(
            mean_ci(&[1.0, f64::NAN]),
            Err(StatsError::NonFinite { index: 1, .. })
        ));
        assert!(mean_interval(&[1.0, 2.0], 0.0).is_err());
    }

    /// Coverage of the 95 % t-interval over 2000 seeded experiments of n = 10 normal
    /// samples: the count of covering intervals is Binomial(2000, 0.95), sd =
    /// sqrt(2000 * 0.95 * 0.05) = 9.75, so a 3-sd band is 1900 +/- 29.
    /// Negative control: a truth shifted by one population sd is covered far less
    /// often (its expected coverage is P(|T_9 + sqrt(10)| < 2.262) ~ 0.19).
    #[test]
    fn t_interval_coverage() {
        let normal = Normal::new(5.0, 2.0).unwrap();
        let trials = 2000;
        let (mut covered, mut covered_shifted) = (0, 0);
        for seed in 0..trials {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let v: Vec<f64> = (0..10).map(|_| normal.sample(&mut rng)).collect();
            let [lo, hi] = mean_ci(&v).unwrap().ci95.unwrap();
            covered += usize::from(lo <= 5.0 && 5.0 <= hi);
            covered_shifted += usize::from(lo <= 7.0 && 7.0 <= hi);
        }
        assert!((1871..=1929).contains(&covered), "covered {covered}");
        assert!(covered_shifted < 1000, "shifted covered {covered_shifted}");
    }

    #[test]
    fn aggregator_keeps_insertion_order() {
        let mut agg = Aggregator::new();
        for run in 0..3 {
            let x = f64::from(run);
            agg.push("MF", "mean_3d", 2.0 + x).unwrap();
            agg.push("EFF", "mean_3d", 1.0 + x).unwrap();
            agg.push("MF", "std_3d", 0.5).unwrap();
        }
        let keys: Vec<_> = agg.keys().collect();
        assert_eq!(
            keys,
            vec![("MF", "mean_3d"), ("EFF", "mean_3d"), ("MF", "std_3d")]
        );
        assert_eq!(agg.values("EFF", "mean_3d").unwrap(), &[1.0, 2.0, 3.0]);
        let rows = agg.summarize().unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[1].method, "EFF");
        assert_relative_eq!(rows[1].stats.mean, 2.0);
        assert_eq!(rows[2].stats.ci95, Some([0.5, 0.5]));
        assert!(matches!(
            agg.push("MF", "mean_3d", f64::NAN),
            Err(StatsError::NonFinite { index: 3, .. })
        ));
        assert_eq!(agg.values("MF", "mean_3d").unwrap().len(), 3);
        assert!(agg.mean_ci("T2T", "mean_3d").is_err());

        let mut other = Aggregator::new();
        other
            .push_run_stats("T2T", &RunStats::of(&[1.0, 3.0]).unwrap(), "_3d")
            .unwrap();
        other.push("MF", "mean_3d", 5.0).unwrap();
        agg.extend(&other);
        assert_eq!(agg.values("MF", "mean_3d").unwrap(), &[2.0, 3.0, 4.0, 5.0]);
        assert_eq!(agg.values("T2T", "rmse_3d").unwrap(), &[5.0_f64.sqrt()]);
        assert_eq!(agg.len(), 7);
    }

    #[test]
    fn mean_curve_band_brackets_the_mean() {
        let (mean, band) =
            mean_curve_ci95(&[0.0, 1.0, 2.0], &[&[1.0, 2.0, 3.0], &[3.0, 4.0, 5.0]]).unwrap();
        assert_eq!(mean, [2.0, 3.0, 4.0]);
        assert_eq!(band.len(), 3);
        for ((x, lo, hi), m) in band.iter().zip(&mean) {
            assert!(lo < m && m < hi, "{x}: {lo} {m} {hi}");
        }
        let (_, one) = mean_curve_ci95(&[0.0], &[&[1.0]]).unwrap();
        assert!(one.is_empty());
        assert!(mean_curve_ci95(&[0.0, 1.0], &[&[1.0]]).is_err());
    }
}
