//! Sample statistics of a list of values: RMS, order statistics (quantile of type 7,
//! median, interquartile range) and the paired difference of two per-run lists with
//! its confidence interval. One implementation each, used by every experiment.

use crate::error::{StatsError, ensure_finite_non_empty};
use crate::monte_carlo::{MeanCi, mean_ci};

/// Root mean square `sqrt((1/n) sum x_i^2)`.
///
/// # Errors
/// [`StatsError::Empty`] or [`StatsError::NonFinite`] (index of the value).
pub fn rms(values: &[f64]) -> Result<f64, StatsError> {
    ensure_finite_non_empty("RMS input", values)?;
    Ok((values.iter().map(|x| x * x).sum::<f64>() / values.len() as f64).sqrt())
}

/// The `p`-quantile of `values` by linear interpolation between order statistics
/// (Hyndman-Fan type 7, the default of R and NumPy): with the sorted values
/// `x_(0..n-1)` and `h = (n - 1) p`, `x_(floor h) + (h - floor h) (x_(ceil h) - x_(floor h))`.
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::NonFinite`], or [`StatsError::OutOfRange`]
/// unless `0 <= p <= 1`.
pub fn quantile(values: &[f64], p: f64) -> Result<f64, StatsError> {
    ensure_finite_non_empty("quantile input", values)?;
    ensure_probability(p)?;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Ok(quantile_of_sorted(&sorted, p))
}

/// [`quantile`] of values already sorted ascending (checked by the callers above).
fn quantile_of_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

fn ensure_probability(p: f64) -> Result<(), StatsError> {
    if (0.0..=1.0).contains(&p) {
        Ok(())
    } else {
        Err(StatsError::OutOfRange {
            what: "quantile probability".into(),
            value: p,
            expected: "in [0, 1]",
        })
    }
}

/// The median and the quartiles of a list of values (type-7 quantiles): the summary
/// of a heavy-tailed per-run statistic, where the mean and its t-interval are
/// dominated by a few runs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Quartiles {
    /// 25 % quantile.
    pub q1: f64,
    /// Median.
    pub median: f64,
    /// 75 % quantile.
    pub q3: f64,
}

impl Quartiles {
    /// The quartiles of `values`.
    ///
    /// # Errors
    /// As [`quantile`].
    pub fn of(values: &[f64]) -> Result<Self, StatsError> {
        ensure_finite_non_empty("quartiles input", values)?;
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Ok(Self {
            q1: quantile_of_sorted(&sorted, 0.25),
            median: quantile_of_sorted(&sorted, 0.5),
            q3: quantile_of_sorted(&sorted, 0.75),
        })
    }

    /// Interquartile range `q3 - q1`.
    pub fn iqr(&self) -> f64 {
        self.q3 - self.q1
    }
}

/// The median of `values` (type-7 quantile at 0.5).
///
/// # Errors
/// As [`quantile`].
pub fn median(values: &[f64]) -> Result<f64, StatsError> {
    quantile(values, 0.5)
}

/// The per-run differences `a_i - b_i` and their mean with its 95 % Student-t CI: the
/// paired comparison of two methods run on the same random numbers.
///
/// # Errors
/// [`StatsError::LengthMismatch`], then as [`mean_ci`].
pub fn paired_mean_ci(a: &[f64], b: &[f64]) -> Result<MeanCi, StatsError> {
    if a.len() != b.len() {
        return Err(StatsError::LengthMismatch {
            what: "paired difference".into(),
            left_name: "a",
            left: a.len(),
            right_name: "b",
            right: b.len(),
        });
    }
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    mean_ci(&d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rms_and_order_statistics() {
        assert_eq!(rms(&[3.0, 4.0]).unwrap(), 12.5_f64.sqrt());
        assert!(rms(&[]).is_err());
        assert!(rms(&[1.0, f64::NAN]).is_err());
        let v = [4.0, 1.0, 3.0, 2.0];
        assert_eq!(median(&v).unwrap(), 2.5);
        assert_eq!(quantile(&v, 0.0).unwrap(), 1.0);
        assert_eq!(quantile(&v, 1.0).unwrap(), 4.0);
        // numpy.quantile([1, 2, 3, 4], 0.1) = 1.3
        assert!((quantile(&v, 0.1).unwrap() - 1.3).abs() < 1e-12);
        assert!(quantile(&v, 1.5).is_err());
        let q = Quartiles::of(&v).unwrap();
        assert_eq!((q.q1, q.median, q.q3), (1.75, 2.5, 3.25));
        assert_eq!(q.iqr(), 1.5);
    }

    #[test]
    fn paired_difference() {
        let d = paired_mean_ci(&[2.0, 3.0, 4.0], &[1.0, 1.0, 1.0]).unwrap();
        assert_eq!(d.mean, 2.0);
        let [lo, hi] = d.ci95.unwrap();
        assert!(lo < 2.0 && hi > 2.0);
        assert!(paired_mean_ci(&[1.0], &[1.0, 2.0]).is_err());
    }
}
