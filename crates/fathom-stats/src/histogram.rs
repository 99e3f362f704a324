//! Fixed-width histograms of error samples (for the error-histogram figures).

use crate::error::{StatsError, ensure_finite_non_empty};

/// A histogram with `n_bins` equal-width bins.
///
/// Bin `k` holds values in `[edges[k], edges[k+1])`, except the last bin, which also
/// holds values equal to its upper edge (so the maximum of the data is counted).
/// Values outside `[edges[0], edges[n_bins]]` (possible only with
/// [`Histogram::with_range`]) are counted in `underflow` / `overflow`, so
/// `sum(counts) + underflow + overflow = n`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Histogram {
    /// `n_bins + 1` increasing bin edges.
    pub edges: Vec<f64>,
    /// Count per bin (`n_bins` entries).
    pub counts: Vec<usize>,
    /// Values below `edges[0]`.
    pub underflow: usize,
    /// Values above `edges[n_bins]`.
    pub overflow: usize,
}

impl Histogram {
    /// Histogram over the data's own range `[min, max]` (all values counted in
    /// bins). If all values are equal to `v`, the range is `[v - 0.5, v + 0.5]`.
    ///
    /// # Errors
    /// [`StatsError::Empty`], [`StatsError::NonFinite`] (naming the index), or
    /// [`StatsError::OutOfRange`] for `n_bins = 0`.
    pub fn new(data: &[f64], n_bins: usize) -> Result<Self, StatsError> {
        ensure_finite_non_empty("histogram data", data)?;
        let lo = data.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = data.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, hi + 0.5)
        };
        Self::with_range(data, n_bins, lo, hi)
    }

    /// Histogram over an explicit range `[lo, hi]`; values outside it go to
    /// `underflow` / `overflow`.
    ///
    /// # Errors
    /// As [`Histogram::new`], plus [`StatsError::OutOfRange`] unless `lo < hi`, both finite.
    pub fn with_range(data: &[f64], n_bins: usize, lo: f64, hi: f64) -> Result<Self, StatsError> {
        ensure_finite_non_empty("histogram data", data)?;
        if n_bins == 0 {
            return Err(StatsError::OutOfRange {
                what: "histogram bin count".into(),
                value: 0.0,
                expected: ">= 1",
            });
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(StatsError::OutOfRange {
                what: format!("histogram range upper bound (lower bound {lo})"),
                value: hi,
                expected: "finite, above a finite lower bound",
            });
        }
        let width = (hi - lo) / n_bins as f64;
        let mut edges: Vec<f64> = (0..=n_bins).map(|k| lo + width * k as f64).collect();
        edges[n_bins] = hi;
        let mut counts = vec![0; n_bins];
        let (mut underflow, mut overflow) = (0, 0);
        for &x in data {
            if x < lo {
                underflow += 1;
            } else if x > hi {
                overflow += 1;
            } else {
                // Estimate, then correct against the stored edges so rounding can
                // never put a value in a bin whose edges do not contain it.
                let mut k = (((x - lo) / width).floor() as usize).min(n_bins - 1);
                while k > 0 && x < edges[k] {
                    k -= 1;
                }
                while k + 1 < n_bins && x >= edges[k + 1] {
                    k += 1;
                }
                counts[k] += 1;
            }
        }
        Ok(Self {
            edges,
            counts,
            underflow,
            overflow,
        })
    }

    /// Number of bins.
    pub fn n_bins(&self) -> usize {
        self.counts.len()
    }

    /// Total number of values, including under/overflow.
    pub fn total(&self) -> usize {
        self.counts.iter().sum::<usize>() + self.underflow + self.overflow
    }

    /// Bin centres.
    pub fn centers(&self) -> Vec<f64> {
        self.edges.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect()
    }

    /// Probability density per bin, `count / (total * width)`, comparable with a pdf.
    pub fn density(&self) -> Vec<f64> {
        let total = self.total() as f64;
        self.counts
            .iter()
            .zip(self.edges.windows(2))
            .map(|(&c, w)| c as f64 / (total * (w[1] - w[0])))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn counts_and_edges() {
        let h = Histogram::new(&[0.0, 0.1, 0.5, 0.99, 1.0, 1.0], 2).unwrap();
        assert_eq!(h.edges, vec![0.0, 0.5, 1.0]);
        // 0.5 opens the upper bin; the max (1.0) is counted in the last bin.
        assert_eq!(h.counts, vec![2, 4]);
        assert_eq!(h.total(), 6);
        assert_eq!(h.centers(), vec![0.25, 0.75]);
        let dens = h.density();
        assert_relative_eq!(dens.iter().sum::<f64>() * 0.5, 1.0, epsilon = 1e-12);
    }

    #[test]
    fn awkward_widths_keep_every_value() {
        let data: Vec<f64> = (0..1000).map(|k| 0.1 * f64::from(k)).collect();
        let h = Histogram::new(&data, 7).unwrap();
        assert_eq!(h.counts.iter().sum::<usize>(), 1000);
        assert_eq!((h.underflow, h.overflow), (0, 0));
        for (k, w) in h.edges.windows(2).enumerate() {
            let inside = data
                .iter()
                .filter(|&&x| x >= w[0] && (x < w[1] || (k == 6 && x <= w[1])))
                .count();
            assert_eq!(inside, h.counts[k], "bin {k}");
        }
    }

    #[test]
    fn explicit_range_and_constant_data() {
        let h = Histogram::with_range(&[-1.0, 0.2, 0.7, 2.0, 1.0], 2, 0.0, 1.0).unwrap();
        assert_eq!(h.counts, vec![1, 2]);
        assert_eq!((h.underflow, h.overflow), (1, 1));
        assert_eq!(h.total(), 5);
        let c = Histogram::new(&[3.0, 3.0], 4).unwrap();
        assert_eq!(c.edges.first(), Some(&2.5));
        assert_eq!(c.counts.iter().sum::<usize>(), 2);
    }

    #[test]
    fn bad_input() {
        assert!(matches!(
            Histogram::new(&[], 3),
            Err(StatsError::Empty { .. })
        ));
        assert!(matches!(
            Histogram::new(&[1.0, f64::NAN], 3),
            Err(StatsError::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            Histogram::new(&[1.0], 0),
            Err(StatsError::OutOfRange { .. })
        ));
        assert!(Histogram::with_range(&[1.0], 2, 1.0, 1.0).is_err());
        assert!(Histogram::with_range(&[1.0], 2, 0.0, f64::NAN).is_err());
    }
}
