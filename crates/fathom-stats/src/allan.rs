//! Overlapping Allan variance / deviation of a rate record (gyro angular rate,
//! accelerometer specific force), its confidence intervals, and the standard
//! readings of an inertial sensor's noise figures from it (IEEE Std 952-1997,
//! Annex C; seed 004, Table 1 is such an analysis of an ADIS16448).
//!
//! # Estimator
//!
//! `n` rate samples `y_k`, each the average over `tau0`, give the integrated record
//! (angle / velocity) `theta_j = tau0 sum_{k<j} y_k`, `j = 0..=n` (`N = n + 1` "phase"
//! points). For the cluster time `tau = m tau0` the overlapping Allan variance is
//!
//! ```text
//! AVAR(tau) = 1 / (2 tau^2 (N - 2m)) sum_{j=0}^{N-2m-1} (theta_{j+2m} - 2 theta_{j+m} + theta_j)^2
//! ```
//!
//! (NIST SP 1065, eq. 14), computed in `O(n)` per `m` from prefix sums of `y - mean(y)`
//! (a constant offset does not change the second difference; removing it keeps the
//! prefix sums small). `1 <= m <= n / 2`.
//!
//! # Noise terms and their slopes (log-log, deviation)
//!
//! | term | rate PSD | `AVAR(tau)` | slope |
//! | --- | --- | --- | --- |
//! | white rate (ARW `N`, VRW) | `N^2` | `N^2 / tau` | -1/2 |
//! | flicker rate (bias instability `B`) | `B^2 / (2 pi f)` | `(2 ln 2 / pi) B^2` | 0 |
//! | rate random walk `K` | `K^2 / (2 pi f)^2` | `K^2 tau / 3` | +1/2 |
//! | first-order Gauss-Markov (`sigma`, `T`) | Lorentzian | [`avar_gauss_markov`] | +1/2 then -1/2 |
//!
//! The readings: `N` is the -1/2 line at `tau = 1 s` ([`white_noise_coefficient`]),
//! `K` the +1/2 line at `tau = 3 s` ([`random_walk_coefficient`]), and `B` the flat
//! bottom divided by `sqrt(2 ln 2 / pi) = 0.664` ([`bias_instability_at_minimum`], the
//! IEEE-952 reading, or [`bias_instability_plateau`], the plateau with the fitted
//! white part removed, which is less biased by the noisy long-`tau` end).
//!
//! # Confidence
//!
//! The estimate at one `tau` is approximately `AVAR chi^2_edf / edf`; the equivalent
//! degrees of freedom for one dominant noise type are the Howe-Allan-Barnes (1981)
//! approximations ([`equivalent_degrees_of_freedom`], NIST SP 1065, Table 5).

use crate::StatsError;
use crate::error::ensure_finite_non_empty;
use crate::quantile::chi2_quantile;

/// `sqrt(2 ln 2 / pi)`: the Allan deviation of flicker rate noise in units of its
/// bias-instability coefficient `B` (IEEE Std 952, C.1.3).
pub const BIAS_INSTABILITY_FACTOR: f64 = 0.664_282_470_267_960_1;

/// One point of an Allan-variance curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllanPoint {
    /// Cluster size `m` (samples per cluster).
    pub m: usize,
    /// Cluster time `tau = m tau0`, s.
    pub tau: f64,
    /// Overlapping Allan variance, (rate unit)^2.
    pub avar: f64,
    /// Number of second differences averaged, `N - 2m`.
    pub n_terms: usize,
}

impl AllanPoint {
    /// Allan deviation `sqrt(AVAR)`, rate unit.
    pub fn adev(&self) -> f64 {
        self.avar.sqrt()
    }
}

/// Dominant power-law noise type of a rate record, for the degrees of freedom of an
/// Allan-variance estimate (frequency-noise names of time metrology in brackets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RateNoise {
    /// White rate noise: angle / velocity random walk (white FM), slope -1/2.
    White,
    /// Flicker rate noise: bias instability (flicker FM), slope 0.
    Flicker,
    /// Rate random walk (random-walk FM), slope +1/2.
    RandomWalk,
}

impl RateNoise {
    /// Slope of the Allan deviation in log-log axes.
    pub fn adev_slope(self) -> f64 {
        match self {
            Self::White => -0.5,
            Self::Flicker => 0.0,
            Self::RandomWalk => 0.5,
        }
    }
}

/// The overlapping Allan variance of `rate` (samples every `tau0` s) at each cluster
/// size in `cluster_sizes` (module docs).
///
/// # Errors
/// [`StatsError::Empty`] / [`StatsError::NonFinite`] for an empty or non-finite
/// record, [`StatsError::OutOfRange`] for a non-positive `tau0` or a cluster size
/// outside `1..=n/2` (named with its index).
pub fn overlapping_allan_variance(
    rate: &[f64],
    tau0: f64,
    cluster_sizes: &[usize],
) -> Result<Vec<AllanPoint>, StatsError> {
    ensure_finite_non_empty("allan: rate record", rate)?;
    if !(tau0.is_finite() && tau0 > 0.0) {
        return Err(StatsError::OutOfRange {
            what: "allan: tau0".into(),
            value: tau0,
            expected: "> 0",
        });
    }
    let n = rate.len();
    for (i, &m) in cluster_sizes.iter().enumerate() {
        if m == 0 || 2 * m > n {
            return Err(StatsError::OutOfRange {
                what: format!("allan: cluster_sizes[{i}] (record of {n} samples)"),
                value: m as f64,
                expected: "in 1..=n/2",
            });
        }
    }
    let mean = rate.iter().sum::<f64>() / n as f64;
    // s[j] = sum_{k<j} (y_k - mean), j = 0..=n (theta / tau0).
    let mut s = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    s.push(0.0);
    for &y in rate {
        acc += y - mean;
        s.push(acc);
    }
    let n_phase = n + 1;
    Ok(cluster_sizes
        .iter()
        .map(|&m| {
            let n_terms = n_phase - 2 * m;
            let sum: f64 = (0..n_terms)
                .map(|j| {
                    let d = s[j + 2 * m] - 2.0 * s[j + m] + s[j];
                    d * d
                })
                .sum();
            let mf = m as f64;
            AllanPoint {
                m,
                tau: mf * tau0,
                avar: sum / (2.0 * mf * mf * n_terms as f64),
                n_terms,
            }
        })
        .collect())
}

/// Cluster sizes spaced evenly in `log10(m)`, `per_decade` per decade from 1 up to
/// `max_m` (and at most `n / 2`), rounded and without repeats.
///
/// # Errors
/// [`StatsError::OutOfRange`] for `per_decade == 0` or `n_samples < 2`.
pub fn log_spaced_cluster_sizes(
    n_samples: usize,
    per_decade: usize,
    max_m: usize,
) -> Result<Vec<usize>, StatsError> {
    if per_decade == 0 {
        return Err(StatsError::OutOfRange {
            what: "allan: per_decade".into(),
            value: 0.0,
            expected: ">= 1",
        });
    }
    if n_samples < 2 {
        return Err(StatsError::OutOfRange {
            what: "allan: n_samples".into(),
            value: n_samples as f64,
            expected: ">= 2",
        });
    }
    let top = max_m.min(n_samples / 2).max(1);
    let mut out = Vec::new();
    let mut k = 0u32;
    loop {
        let m = 10f64.powf(f64::from(k) / per_decade as f64).round() as usize;
        if m > top {
            break;
        }
        if out.last() != Some(&m) {
            out.push(m);
        }
        k += 1;
    }
    Ok(out)
}

/// Equivalent degrees of freedom of the overlapping Allan variance at cluster size
/// `m` from `n_samples` rate samples (`N = n_samples + 1` phase points), for one
/// dominant noise type (Howe, Allan & Barnes 1981; NIST SP 1065, Table 5):
///
/// ```text
/// white:        (3(N-1)/(2m) - 2(N-2)/N) 4m^2 / (4m^2 + 5)
/// flicker:      m = 1: 2(N-2)^2 / (2.3N - 4.9);   m >= 2: 5N^2 / (4m(N + 3m))
/// random walk:  (N-2)/m ((N-1)^2 - 3m(N-1) + 4m^2) / (N-3)^2
/// ```
pub fn equivalent_degrees_of_freedom(noise: RateNoise, n_samples: usize, m: usize) -> f64 {
    let n = (n_samples + 1) as f64;
    let m = m.max(1) as f64;
    match noise {
        RateNoise::White => {
            (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0)
        }
        RateNoise::Flicker => {
            if m < 1.5 {
                2.0 * (n - 2.0).powi(2) / (2.3 * n - 4.9)
            } else {
                5.0 * n * n / (4.0 * m * (n + 3.0 * m))
            }
        }
        RateNoise::RandomWalk => {
            (n - 2.0) / m * ((n - 1.0).powi(2) - 3.0 * m * (n - 1.0) + 4.0 * m * m)
                / (n - 3.0).powi(2)
        }
    }
}

/// Two-sided confidence interval `[lo, hi]` of the true Allan **deviation** at one
/// point, from `edf chi^2` quantiles: `AVAR edf / chi^2_{(1 +- level)/2}(edf)`.
///
/// # Errors
/// [`StatsError::OutOfRange`] for a level outside (0, 1) or a non-positive `edf`.
pub fn adev_confidence_interval(
    point: &AllanPoint,
    edf: f64,
    level: f64,
) -> Result<[f64; 2], StatsError> {
    if !(edf.is_finite() && edf > 0.0) {
        return Err(StatsError::OutOfRange {
            what: "allan: edf".into(),
            value: edf,
            expected: "> 0",
        });
    }
    crate::error::ensure_level("allan: confidence level", level)?;
    let hi_q = chi2_quantile(0.5 + 0.5 * level, edf)?;
    let lo_q = chi2_quantile(0.5 - 0.5 * level, edf)?;
    Ok([
        (point.avar * edf / hi_q).sqrt(),
        (point.avar * edf / lo_q).sqrt(),
    ])
}

fn in_range<'a>(
    what: &str,
    points: &'a [AllanPoint],
    tau_min: f64,
    tau_max: f64,
) -> Result<Vec<&'a AllanPoint>, StatsError> {
    let sel: Vec<_> = points
        .iter()
        .filter(|p| p.tau >= tau_min && p.tau <= tau_max && p.avar > 0.0)
        .collect();
    if sel.is_empty() {
        return Err(StatsError::Empty {
            what: format!("{what}: no Allan point with tau in [{tau_min}, {tau_max}] s"),
        });
    }
    Ok(sel)
}

/// White-noise coefficient `N` (ARW in rad/sqrt(s), VRW in m/s/sqrt(s)): the line of
/// slope -1/2 through the points with `tau` in `[tau_min, tau_max]` (least squares in
/// log-log with the slope fixed, i.e. the geometric mean of `adev sqrt(tau)`), read
/// at `tau = 1 s`. Choose a range where white noise dominates.
///
/// # Errors
/// [`StatsError::Empty`] when no point lies in the range.
pub fn white_noise_coefficient(
    points: &[AllanPoint],
    tau_min: f64,
    tau_max: f64,
) -> Result<f64, StatsError> {
    let sel = in_range("white_noise_coefficient", points, tau_min, tau_max)?;
    let mean_log = sel
        .iter()
        .map(|p| (p.adev() * p.tau.sqrt()).ln())
        .sum::<f64>()
        / sel.len() as f64;
    Ok(mean_log.exp())
}

/// Rate-random-walk coefficient `K`: the line of slope +1/2 through the points in the
/// range (`adev = K sqrt(tau / 3)`), i.e. its value at `tau = 3 s`.
///
/// # Errors
/// [`StatsError::Empty`] when no point lies in the range.
pub fn random_walk_coefficient(
    points: &[AllanPoint],
    tau_min: f64,
    tau_max: f64,
) -> Result<f64, StatsError> {
    let sel = in_range("random_walk_coefficient", points, tau_min, tau_max)?;
    let mean_log = sel
        .iter()
        .map(|p| (p.adev() * (3.0 / p.tau).sqrt()).ln())
        .sum::<f64>()
        / sel.len() as f64;
    Ok(mean_log.exp())
}

/// Least-squares slope of `log adev` against `log tau` over the points in the range.
///
/// # Errors
/// [`StatsError::Empty`] when fewer than two points lie in the range.
pub fn adev_slope(points: &[AllanPoint], tau_min: f64, tau_max: f64) -> Result<f64, StatsError> {
    let sel = in_range("adev_slope", points, tau_min, tau_max)?;
    if sel.len() < 2 {
        return Err(StatsError::TooFewSamples {
            what: "adev_slope".into(),
            needed: 2,
            got: sel.len(),
        });
    }
    let k = sel.len() as f64;
    let xs: Vec<f64> = sel.iter().map(|p| p.tau.ln()).collect();
    let ys: Vec<f64> = sel.iter().map(|p| p.adev().ln()).collect();
    let mx = xs.iter().sum::<f64>() / k;
    let my = ys.iter().sum::<f64>() / k;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    Ok(sxy / sxx)
}

/// Bias instability read the IEEE-952 way: the smallest Allan deviation with `tau` in
/// the range, divided by [`BIAS_INSTABILITY_FACTOR`]. Returns `(B, tau at the
/// minimum)`. Biased by the white-noise part at the short end and by the scatter of
/// the few-term estimates at the long end: keep `tau_max` well below the record length
/// (a tenth of it or less).
///
/// # Errors
/// [`StatsError::Empty`] when no point lies in the range.
pub fn bias_instability_at_minimum(
    points: &[AllanPoint],
    tau_min: f64,
    tau_max: f64,
) -> Result<(f64, f64), StatsError> {
    let sel = in_range("bias_instability_at_minimum", points, tau_min, tau_max)?;
    let best = sel
        .iter()
        .min_by(|a, b| a.avar.total_cmp(&b.avar))
        .copied()
        .copied()
        .ok_or_else(|| StatsError::Empty {
            what: "bias_instability_at_minimum".into(),
        })?;
    Ok((best.adev() / BIAS_INSTABILITY_FACTOR, best.tau))
}

/// Bias instability from the plateau: the Allan variance minus the white part
/// `white^2 / tau` (the coefficient from [`white_noise_coefficient`]), averaged over
/// the points in the range, as `sqrt(mean) / BIAS_INSTABILITY_FACTOR`. A negative
/// mean (the plateau drowned in white noise) reads as 0.
///
/// # Errors
/// [`StatsError::Empty`] when no point lies in the range; [`StatsError::OutOfRange`]
/// for a negative or non-finite `white`.
pub fn bias_instability_plateau(
    points: &[AllanPoint],
    white: f64,
    tau_min: f64,
    tau_max: f64,
) -> Result<f64, StatsError> {
    if !(white.is_finite() && white >= 0.0) {
        return Err(StatsError::OutOfRange {
            what: "bias_instability_plateau: white".into(),
            value: white,
            expected: ">= 0",
        });
    }
    let sel = in_range("bias_instability_plateau", points, tau_min, tau_max)?;
    let mean = sel
        .iter()
        .map(|p| p.avar - white * white / p.tau)
        .sum::<f64>()
        / sel.len() as f64;
    Ok(mean.max(0.0).sqrt() / BIAS_INSTABILITY_FACTOR)
}

/// Allan variance of white rate noise with coefficient `n` (per sqrt(s)): `n^2 / tau`.
pub fn avar_white(n: f64, tau: f64) -> f64 {
    n * n / tau
}

/// Allan variance of flicker rate noise with bias-instability coefficient `b`:
/// `(2 ln 2 / pi) b^2`, independent of `tau`.
pub fn avar_flicker(b: f64) -> f64 {
    (BIAS_INSTABILITY_FACTOR * b).powi(2)
}

/// Allan variance of a rate random walk with coefficient `k` (per s^1.5): `k^2 tau / 3`.
pub fn avar_random_walk(k: f64, tau: f64) -> f64 {
    k * k * tau / 3.0
}

/// Allan variance of a first-order Gauss-Markov rate with standard deviation `sigma`
/// and correlation time `t_c` (continuous time; IEEE Std 952, C.1.5):
///
/// ```text
/// AVAR(tau) = (2 sigma^2 t_c / tau) [1 - (t_c / (2 tau)) (3 - 4 e^{-x} + e^{-2x})],  x = tau / t_c
/// ```
///
/// `2 sigma^2 tau / (3 t_c)` for `tau << t_c` (a random walk), `2 sigma^2 t_c / tau`
/// for `tau >> t_c` (white); the maximum, `0.62 sigma`, is at `tau = 1.89 t_c`. For
/// `x < 1e-3` the series `2 sigma^2 x (1/3 - x/4)` avoids cancellation.
pub fn avar_gauss_markov(sigma: f64, t_c: f64, tau: f64) -> f64 {
    let x = tau / t_c;
    if x < 1e-3 {
        return 2.0 * sigma * sigma * x * (1.0 / 3.0 - x / 4.0);
    }
    let bracket = 1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x);
    2.0 * sigma * sigma / x * bracket
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    fn normals(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
    }

    /// Every point of a white-rate record lies inside its chi-square interval around
    /// the true `N / sqrt(tau)` (level `1 - 0.01 / points`: Bonferroni, at most 1 %
    /// chance that any point falls outside); the fitted coefficient is within 4
    /// standard errors; the slope is -1/2. Negative control: a 5 % wrong `N` falls
    /// outside the intervals at several short-`tau` points.
    #[test]
    fn white_rate_noise_has_slope_minus_half() {
        let (tau0, n): (f64, usize) = (0.01, 200_000);
        let sigma = 0.3; // per-sample std of the rate -> N = sigma sqrt(tau0)
        let y: Vec<f64> = normals(n, 11).iter().map(|z| 0.7 + sigma * z).collect();
        let coef = sigma * tau0.sqrt();
        let ms = log_spaced_cluster_sizes(n, 5, n / 10).unwrap();
        let pts = overlapping_allan_variance(&y, tau0, &ms).unwrap();
        let level = 1.0 - 0.01 / pts.len() as f64;
        let mut outside_wrong = 0;
        for p in &pts {
            let edf = equivalent_degrees_of_freedom(RateNoise::White, n, p.m);
            let [lo, hi] = adev_confidence_interval(p, edf, level).unwrap();
            let truth = avar_white(coef, p.tau).sqrt();
            assert!(lo <= truth && truth <= hi, "m {} [{lo}, {hi}] {truth}", p.m);
            let wrong = 1.05 * truth;
            if !(lo <= wrong && wrong <= hi) {
                outside_wrong += 1;
            }
        }
        assert!(outside_wrong >= 3, "negative control: {outside_wrong}");
        let fit = white_noise_coefficient(&pts, tau0, 100.0 * tau0).unwrap();
        let edf_min = equivalent_degrees_of_freedom(RateNoise::White, n, 100);
        let se = 1.0 / (2.0 * edf_min).sqrt();
        assert!((fit / coef - 1.0).abs() < 4.0 * se, "fit {fit} vs {coef}");
        let slope = adev_slope(&pts, tau0, 1000.0 * tau0).unwrap();
        assert!((slope + 0.5).abs() < 0.03, "slope {slope}");
    }

    /// A discrete random walk of the rate (step variance q) has the exact Allan
    /// variance `q (2 m^2 + 1) / (6 m)` (continuous limit `K^2 tau / 3`); points inside
    /// their intervals (Bonferroni level as above), slope +1/2, and `K` recovered.
    /// Negative control: the white-noise expectation (slope -1/2) is rejected.
    #[test]
    fn rate_random_walk_has_slope_plus_half() {
        let (tau0, n): (f64, usize) = (0.1, 100_000);
        let k: f64 = 2e-3; // per s^1.5
        let q = k * k * tau0;
        let mut acc = 0.0;
        let y: Vec<f64> = normals(n, 12)
            .iter()
            .map(|z| {
                acc += q.sqrt() * z;
                acc
            })
            .collect();
        let ms = log_spaced_cluster_sizes(n, 4, n / 20).unwrap();
        let pts = overlapping_allan_variance(&y, tau0, &ms).unwrap();
        let level = 1.0 - 0.01 / pts.len() as f64;
        for p in &pts {
            let mf = p.m as f64;
            let truth = (q * (2.0 * mf * mf + 1.0) / (6.0 * mf)).sqrt();
            let edf = equivalent_degrees_of_freedom(RateNoise::RandomWalk, n, p.m);
            let [lo, hi] = adev_confidence_interval(p, edf, level).unwrap();
            assert!(lo <= truth && truth <= hi, "m {} [{lo}, {hi}] {truth}", p.m);
        }
        let slope = adev_slope(&pts, 10.0 * tau0, 5000.0 * tau0).unwrap();
        assert!((slope - 0.5).abs() < 0.1, "slope {slope}");
        assert!((slope + 0.5).abs() > 0.5, "negative control");
        let fit = random_walk_coefficient(&pts, 10.0 * tau0, 1000.0 * tau0).unwrap();
        assert!((fit / k - 1.0).abs() < 0.25, "K {fit} vs {k}");
        // the continuous-time formula is the large-m limit of the exact one
        assert!((avar_random_walk(k, 1000.0 * tau0) / (q * 2000.0 / 6.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn gauss_markov_formula_limits_and_peak() {
        let (s, t) = (2.0, 10.0);
        // small tau: random walk with q = 2 s^2 / t
        let tau = 1e-3;
        assert!(
            (avar_gauss_markov(s, t, tau) / (2.0 * s * s * tau / (3.0 * t)) - 1.0).abs() < 1e-3
        );
        // series and closed form agree at the switch
        let x = 1e-3 * t;
        let a = avar_gauss_markov(s, t, x * 0.999_999);
        let b = avar_gauss_markov(s, t, x * 1.000_001);
        assert!((a / b - 1.0).abs() < 1e-5);
        // large tau: white with 2 s^2 t / tau
        let tau = 1e5;
        assert!((avar_gauss_markov(s, t, tau) / (2.0 * s * s * t / tau) - 1.0).abs() < 1e-3);
        // peak 0.618 sigma near 1.89 t
        let (mut best, mut at) = (0.0, 0.0);
        for i in 1..4000 {
            let tau = 0.01 * i as f64;
            let v = avar_gauss_markov(s, t, tau).sqrt();
            if v > best {
                (best, at) = (v, tau);
            }
        }
        assert!((best / s - 0.618).abs() < 2e-3, "{best}");
        assert!((at / t - 1.89).abs() < 0.02, "{at}");
    }

    #[test]
    fn readings_of_a_constructed_curve() {
        // white N = 0.01 plus a flicker plateau B = 0.002 (exact variances)
        let (nw, b) = (0.01, 0.002);
        let pts: Vec<AllanPoint> = (0..40)
            .map(|i| {
                let tau = 0.01 * 10f64.powf(i as f64 / 8.0);
                AllanPoint {
                    m: i + 1,
                    tau,
                    avar: avar_white(nw, tau) + avar_flicker(b),
                    n_terms: 1000,
                }
            })
            .collect();
        let n_fit = white_noise_coefficient(&pts, 0.0, 0.1).unwrap();
        assert!((n_fit / nw - 1.0).abs() < 0.01, "{n_fit}");
        let plateau = bias_instability_plateau(&pts, nw, 10.0, 1e4).unwrap();
        assert!((plateau / b - 1.0).abs() < 1e-12, "{plateau}");
        let (b_min, tau_min) = bias_instability_at_minimum(&pts, 0.0, 1e4).unwrap();
        // the minimum is at the long end, still lifted by the white part
        let last = pts.last().unwrap();
        assert_eq!(tau_min, last.tau);
        assert!((b_min - last.adev() / BIAS_INSTABILITY_FACTOR).abs() < 1e-15);
        assert!(b_min > b, "{b_min} at {tau_min}");
        assert!(bias_instability_plateau(&pts, f64::NAN, 1.0, 2.0).is_err());
        assert!(white_noise_coefficient(&pts, 1e9, 2e9).is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            overlapping_allan_variance(&[], 0.01, &[1]),
            Err(StatsError::Empty { .. })
        ));
        assert!(matches!(
            overlapping_allan_variance(&[1.0, f64::NAN], 0.01, &[1]),
            Err(StatsError::NonFinite { index: 1, .. })
        ));
        assert!(overlapping_allan_variance(&[1.0, 2.0], 0.0, &[1]).is_err());
        let e = overlapping_allan_variance(&[1.0; 10], 0.1, &[1, 6]).unwrap_err();
        assert!(e.to_string().contains("cluster_sizes[1]"), "{e}");
        assert!(overlapping_allan_variance(&[1.0; 10], 0.1, &[0]).is_err());
        assert!(log_spaced_cluster_sizes(100, 0, 10).is_err());
        assert_eq!(
            log_spaced_cluster_sizes(1000, 3, 100).unwrap(),
            vec![1, 2, 5, 10, 22, 46, 100]
        );
        let p = AllanPoint {
            m: 1,
            tau: 1.0,
            avar: 1.0,
            n_terms: 10,
        };
        assert!(adev_confidence_interval(&p, 0.0, 0.95).is_err());
        assert!(adev_confidence_interval(&p, 5.0, 1.0).is_err());
        // constant record: zero variance, no panic
        let pts = overlapping_allan_variance(&[3.0; 8], 0.5, &[1, 2, 4]).unwrap();
        assert!(
            pts.iter()
                .all(|p| p.avar == 0.0 && p.n_terms == 9 - 2 * p.m)
        );
    }
}
