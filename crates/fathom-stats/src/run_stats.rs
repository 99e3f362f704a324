//! Statistics of one run's error series over time: mean, population std, max, RMSE.

use crate::error::{StatsError, ensure_finite_non_empty};

/// Summary of a series over the time samples of one run (spec README: "mean, std
/// (population, over time samples), max, RMSE").
///
/// With `e_k`, `k = 1..n`:
/// `mean = (1/n) sum e_k`, `std = sqrt((1/n) sum (e_k - mean)^2)` (population, 1/n),
/// `max = max e_k`, `rmse = sqrt((1/n) sum e_k^2)`, so `rmse^2 = mean^2 + std^2`
/// exactly (hence `rmse >= mean` always).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunStats {
    /// Mean over time samples.
    pub mean: f64,
    /// Population standard deviation over time samples (1/n).
    pub std: f64,
    /// Largest sample.
    pub max: f64,
    /// Root mean square of the samples.
    pub rmse: f64,
    /// Number of time samples.
    pub n: usize,
}

impl RunStats {
    /// Computes the statistics of `values` (two-pass for the std, for accuracy).
    ///
    /// # Errors
    /// [`StatsError::Empty`] for an empty series, [`StatsError::NonFinite`] naming
    /// the first NaN/infinite index.
    pub fn of(values: &[f64]) -> Result<Self, StatsError> {
        ensure_finite_non_empty("run statistics series", values)?;
        let n = values.len();
        let nf = n as f64;
        let mean = values.iter().sum::<f64>() / nf;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / nf;
        let ms = values.iter().map(|v| v * v).sum::<f64>() / nf;
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Ok(Self {
            mean,
            std: var.sqrt(),
            max,
            rmse: ms.sqrt(),
            n,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn known_values() {
        let s = RunStats::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_relative_eq!(s.mean, 2.5, epsilon = 1e-15);
        assert_relative_eq!(s.std, 1.25_f64.sqrt(), epsilon = 1e-15);
        assert_relative_eq!(s.max, 4.0);
        assert_relative_eq!(s.rmse, 7.5_f64.sqrt(), epsilon = 1e-15);
        assert_eq!(s.n, 4);
        let one = RunStats::of(&[2.0]).unwrap();
        assert_eq!((one.mean, one.std, one.max, one.rmse), (2.0, 0.0, 2.0, 2.0));
    }

    #[test]
    fn rmse_identity_holds() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..20 {
            let v: Vec<f64> = (0..1000).map(|_| rng.random_range(0.0..3.0)).collect();
            let s = RunStats::of(&v).unwrap();
            assert_relative_eq!(
                s.rmse * s.rmse,
                s.mean * s.mean + s.std * s.std,
                max_relative = 1e-12
            );
            assert!(s.rmse >= s.mean);
        }
    }

    #[test]
    fn bad_input() {
        assert!(matches!(RunStats::of(&[]), Err(StatsError::Empty { .. })));
        assert!(matches!(
            RunStats::of(&[1.0, 2.0, f64::INFINITY]),
            Err(StatsError::NonFinite { index: 2, .. })
        ));
    }
}
