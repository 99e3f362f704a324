//! Bootstrap confidence intervals of the mean over Monte Carlo runs: the
//! bias-corrected and accelerated (BCa) interval and the plain percentile interval,
//! both from a caller-seeded random number generator.
//!
//! With the run values `x_1..x_n` and `B` resamples (each `n` values drawn from the
//! runs with replacement), the resample means `m*_1..m*_B` are sorted and read at two
//! probabilities. The percentile interval reads them at `(1 - level)/2` and
//! `(1 + level)/2`. BCa (Efron, 1987) shifts those probabilities by the bias
//! correction `z0 = Phi^-1(#{m*_b < mean} / B)` and the acceleration
//! `a = sum d_i^3 / (6 (sum d_i^2)^(3/2))`, `d_i` the jackknife deviations of the
//! mean, to `alpha_k = Phi(z0 + (z0 + z_k) / (1 - a (z0 + z_k)))`.
//!
//! Every resample mean of non-negative values is non-negative, so neither interval of a
//! non-negative metric (an RMSE, a maximum, a NEES) has a negative end, whatever the
//! tail: the property the Student-t interval lacks.

use rand::Rng;

use crate::error::{StatsError, ensure_finite_non_empty, ensure_level};
use crate::quantile::normal_quantile;

/// The fewest resamples accepted (fewer give unstable tail quantiles).
pub const MIN_RESAMPLES: usize = 100;
/// The most resamples accepted (a bound on the work of one interval).
pub const MAX_RESAMPLES: usize = 1_000_000;

fn check_resamples(resamples: usize) -> Result<(), StatsError> {
    if (MIN_RESAMPLES..=MAX_RESAMPLES).contains(&resamples) {
        Ok(())
    } else {
        Err(StatsError::OutOfRange {
            what: "bootstrap resamples".into(),
            value: resamples as f64,
            expected: "between 100 and 1000000",
        })
    }
}

/// The sorted means of `resamples` bootstrap resamples of `values`.
fn resample_means<R: Rng + ?Sized>(values: &[f64], resamples: usize, rng: &mut R) -> Vec<f64> {
    let n = values.len();
    let mut means: Vec<f64> = (0..resamples)
        .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    means
}

/// The type-7 quantile of sorted values at probability `p` in `[0, 1]`.
fn read_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

fn checked(values: &[f64], level: f64, resamples: usize) -> Result<&[f64], StatsError> {
    ensure_level("confidence level", level)?;
    ensure_finite_non_empty("bootstrap input", values)?;
    check_resamples(resamples)?;
    Ok(values)
}

/// The percentile bootstrap interval of the mean of `values` at `level`.
///
/// # Errors
/// [`StatsError::Empty`], [`StatsError::NonFinite`], a level outside `(0, 1)`, or a
/// resample count outside `[MIN_RESAMPLES, MAX_RESAMPLES]`.
pub fn bootstrap_percentile_mean<R: Rng + ?Sized>(
    values: &[f64],
    level: f64,
    resamples: usize,
    rng: &mut R,
) -> Result<[f64; 2], StatsError> {
    let values = checked(values, level, resamples)?;
    let means = resample_means(values, resamples, rng);
    Ok([
        read_sorted(&means, 0.5 * (1.0 - level)),
        read_sorted(&means, 0.5 * (1.0 + level)),
    ])
}

/// The BCa bootstrap interval of the mean of `values` at `level` (module docs).
/// A single value or identical values give the degenerate interval `[x, x]`.
///
/// # Errors
/// As [`bootstrap_percentile_mean`].
pub fn bootstrap_bca_mean<R: Rng + ?Sized>(
    values: &[f64],
    level: f64,
    resamples: usize,
    rng: &mut R,
) -> Result<[f64; 2], StatsError> {
    let values = checked(values, level, resamples)?;
    let n = values.len();
    let nf = n as f64;
    let mean = values.iter().sum::<f64>() / nf;
    if values.iter().all(|&v| v == values[0]) {
        return Ok([mean, mean]);
    }
    let means = resample_means(values, resamples, rng);
    // Bias correction: ties with the mean count half, and the proportion is kept
    // inside (0, 1) so that z0 stays finite.
    let below = means.iter().filter(|&&m| m < mean).count() as f64;
    let equal = means.iter().filter(|&&m| m == mean).count() as f64;
    let b = resamples as f64;
    let p0 = ((below + 0.5 * equal) / b).clamp(0.5 / b, 1.0 - 0.5 / b);
    let z0 = normal_quantile(p0)?;
    // Acceleration from the jackknife means (sum - x_i) / (n - 1).
    let sum: f64 = values.iter().sum();
    let jack: Vec<f64> = values.iter().map(|x| (sum - x) / (nf - 1.0)).collect();
    let jack_mean = jack.iter().sum::<f64>() / nf;
    let (s2, s3) = jack.iter().fold((0.0, 0.0), |(s2, s3), j| {
        let d = jack_mean - j;
        (s2 + d * d, s3 + d * d * d)
    });
    let a = if s2 > 0.0 {
        s3 / (6.0 * s2.powf(1.5))
    } else {
        0.0
    };
    let z_lo = normal_quantile(0.5 * (1.0 - level))?;
    let z_hi = normal_quantile(0.5 * (1.0 + level))?;
    let adjusted = |z: f64| -> Result<f64, StatsError> {
        let w = z0 + z;
        let denom = 1.0 - a * w;
        // A denominator at or below zero (an extreme acceleration) reads the tail.
        if denom <= 0.0 {
            return Ok(if z < 0.0 { 0.0 } else { 1.0 });
        }
        Ok(crate::quantile::normal_cdf(z0 + w / denom))
    };
    Ok([
        read_sorted(&means, adjusted(z_lo)?),
        read_sorted(&means, adjusted(z_hi)?),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn intervals_bracket_the_mean_and_repeat_with_the_seed() {
        let v: Vec<f64> = (1..=30).map(|i| f64::from(i).sqrt()).collect();
        let mean = v.iter().sum::<f64>() / 30.0;
        for f in [bootstrap_bca_mean::<ChaCha8Rng>, bootstrap_percentile_mean] {
            let a = f(&v, 0.95, 2000, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
            let b = f(&v, 0.95, 2000, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
            assert_eq!(a, b);
            assert!(a[0] < mean && mean < a[1], "{a:?} {mean}");
        }
    }

    #[test]
    fn degenerate_and_bad_input() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert_eq!(
            bootstrap_bca_mean(&[2.0, 2.0, 2.0], 0.95, 500, &mut rng).unwrap(),
            [2.0, 2.0]
        );
        assert_eq!(
            bootstrap_bca_mean(&[4.0], 0.95, 500, &mut rng).unwrap(),
            [4.0, 4.0]
        );
        assert!(bootstrap_bca_mean(&[], 0.95, 500, &mut rng).is_err());
        assert!(bootstrap_bca_mean(&[1.0, f64::NAN], 0.95, 500, &mut rng).is_err());
        assert!(bootstrap_bca_mean(&[1.0, 2.0], 0.95, 10, &mut rng).is_err());
        assert!(bootstrap_percentile_mean(&[1.0, 2.0], 1.5, 500, &mut rng).is_err());
    }

    #[test]
    fn non_negative_values_give_non_negative_ends() {
        // One huge value among small ones: the t-interval's lower end is negative here.
        let mut v = vec![0.1; 19];
        v.push(100.0);
        let t = crate::monte_carlo::mean_ci(&v).unwrap().ci95.unwrap();
        assert!(t[0] < 0.0, "{t:?}");
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let bca = bootstrap_bca_mean(&v, 0.95, 2000, &mut rng).unwrap();
        let pct = bootstrap_percentile_mean(&v, 0.95, 2000, &mut rng).unwrap();
        assert!(bca[0] >= 0.0 && pct[0] >= 0.0, "{bca:?} {pct:?}");
    }
}
