//! Intervals for counts: the Clopper-Pearson interval of a binomial proportion (e.g.
//! outlier recall pooled over Monte Carlo runs) and the distribution-free interval of
//! a median from order statistics (for heavy-tailed per-run statistics, where the
//! Student-t interval of the mean means little).

use statrs::distribution::{Binomial, ContinuousCDF, DiscreteCDF};

use crate::error::{StatsError, ensure_finite_non_empty, ensure_level};

/// A proportion `k / n` with its two-sided interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Proportion {
    /// Successes.
    pub k: u64,
    /// Trials.
    pub n: u64,
    /// `k / n`.
    pub value: f64,
    /// The interval `[lo, hi]`.
    pub interval: [f64; 2],
}

/// The exact (Clopper-Pearson) interval of a binomial proportion at `level`:
/// `lo = B^-1((1-level)/2; k, n-k+1)`, `hi = B^-1((1+level)/2; k+1, n-k)` with the beta
/// quantile `B^-1`, `lo = 0` for `k = 0` and `hi = 1` for `k = n`. Conservative: the
/// coverage is at least `level` for every true proportion.
///
/// # Errors
/// [`StatsError::Empty`] for `n = 0`, [`StatsError::OutOfRange`] for `k > n` or a
/// level outside `(0, 1)`.
pub fn clopper_pearson(k: u64, n: u64, level: f64) -> Result<Proportion, StatsError> {
    ensure_level("confidence level", level)?;
    if n == 0 {
        return Err(StatsError::Empty {
            what: "binomial trials".into(),
        });
    }
    if k > n {
        return Err(StatsError::OutOfRange {
            what: "binomial successes".into(),
            value: k as f64,
            expected: "at most the number of trials",
        });
    }
    let alpha = 1.0 - level;
    let beta_quantile = |p: f64, a: f64, b: f64| -> Result<f64, StatsError> {
        statrs::distribution::Beta::new(a, b)
            .map(|d| d.inverse_cdf(p))
            .map_err(|e| StatsError::OutOfRange {
                what: format!("beta distribution ({e})"),
                value: a,
                expected: "positive shape parameters",
            })
    };
    let (kf, nf) = (k as f64, n as f64);
    let lo = if k == 0 {
        0.0
    } else {
        beta_quantile(alpha / 2.0, kf, nf - kf + 1.0)?
    };
    let hi = if k == n {
        1.0
    } else {
        beta_quantile(1.0 - alpha / 2.0, kf + 1.0, nf - kf)?
    };
    Ok(Proportion {
        k,
        n,
        value: kf / nf,
        interval: [lo, hi],
    })
}

/// The median of `values` with its distribution-free interval at (at least) `level`
/// from order statistics: with the sorted values `x_(1..n)` and `B ~ Binomial(n, 1/2)`,
/// `[x_(j), x_(n+1-j)]` for the largest `j` with `P(j <= B <= n - j) >= level`.
/// `None` as interval when `n` is too small for `level`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MedianCi {
    /// Sample median (type-7 quantile at 0.5).
    pub median: f64,
    /// `[x_(j), x_(n+1-j)]`, or `None` when no `j >= 1` reaches the level.
    pub interval: Option<[f64; 2]>,
}

/// [`MedianCi`] of `values` at `level`.
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::NonFinite`], or a level outside `(0, 1)`.
pub fn median_ci(values: &[f64], level: f64) -> Result<MedianCi, StatsError> {
    ensure_level("confidence level", level)?;
    ensure_finite_non_empty("median input", values)?;
    let median = crate::sample::median(values)?;
    let n = values.len() as u64;
    let b = Binomial::new(0.5, n).map_err(|e| StatsError::OutOfRange {
        what: format!("binomial distribution ({e})"),
        value: n as f64,
        expected: "a valid number of trials",
    })?;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    // Coverage of [x_(j), x_(n+1-j)] = P(j <= B <= n - j) = 1 - 2 P(B <= j - 1).
    let mut best = None;
    for j in 1..=n / 2 {
        let coverage = 1.0 - 2.0 * b.cdf(j - 1);
        if coverage >= level {
            best = Some(j);
        } else {
            break;
        }
    }
    let interval = best.map(|j| [sorted[(j - 1) as usize], sorted[(n - j) as usize]]);
    Ok(MedianCi { median, interval })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clopper_pearson_matches_reference_values() {
        // R: binom.test(7, 20)$conf.int = 0.1539092 0.5921885
        let p = clopper_pearson(7, 20, 0.95).unwrap();
        assert!((p.interval[0] - 0.1539092).abs() < 1e-6, "{p:?}");
        assert!((p.interval[1] - 0.5921885).abs() < 1e-6, "{p:?}");
        // All successes: upper bound 1, lower (alpha/2)^(1/n).
        let all = clopper_pearson(276, 276, 0.95).unwrap();
        assert_eq!(all.interval[1], 1.0);
        assert!((all.interval[0] - 0.025_f64.powf(1.0 / 276.0)).abs() < 1e-9);
        let none = clopper_pearson(0, 10, 0.95).unwrap();
        assert_eq!(none.interval[0], 0.0);
        assert!(clopper_pearson(3, 2, 0.95).is_err());
        assert!(clopper_pearson(0, 0, 0.95).is_err());
    }

    #[test]
    fn clopper_pearson_covers_at_least_the_level() {
        // Exact coverage for p = 0.3, n = 30, summed over all outcomes.
        let (n, p) = (30u64, 0.3);
        let b = Binomial::new(p, n).unwrap();
        let coverage: f64 = (0..=n)
            .filter(|&k| {
                let iv = clopper_pearson(k, n, 0.95).unwrap().interval;
                iv[0] <= p && p <= iv[1]
            })
            .map(|k| statrs::distribution::Discrete::pmf(&b, k))
            .sum();
        assert!(coverage >= 0.95, "{coverage}");
        // Negative control: a 50 % interval does not reach 95 % coverage.
        let narrow: f64 = (0..=n)
            .filter(|&k| {
                let iv = clopper_pearson(k, n, 0.5).unwrap().interval;
                iv[0] <= p && p <= iv[1]
            })
            .map(|k| statrs::distribution::Discrete::pmf(&b, k))
            .sum();
        assert!(narrow < 0.95, "{narrow}");
    }

    #[test]
    fn median_interval_from_order_statistics() {
        // n = 10: P(2 <= B <= 8) = 0.9785 >= 0.95, P(3 <= B <= 7) = 0.8906 < 0.95.
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        let m = median_ci(&v, 0.95).unwrap();
        assert_eq!(m.median, 5.5);
        assert_eq!(m.interval, Some([2.0, 9.0]));
        // n = 5 cannot reach 95 %: P(1 <= B <= 4) = 0.9375.
        assert_eq!(
            median_ci(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.95)
                .unwrap()
                .interval,
            None
        );
        assert!(median_ci(&[], 0.95).is_err());
    }
}
