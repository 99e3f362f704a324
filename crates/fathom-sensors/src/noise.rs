//! Noise processes: white Gaussian, the held common-mode range noise (paper B,
//! Table 7), outlier injection (Table 8), per-run constants (bias, scale factor),
//! first-order Gauss-Markov and random walk.
//!
//! Every process is a small type with a checking constructor; drawing needs an
//! explicit `rng`. Gaussian draws are `sigma * z` with `z` a standard normal, so a
//! zero sigma is valid (the process is off) and still consumes its draw: switching
//! a noise off does not shift the draws of anything else.

use fathom_core::Time;
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::{
    SensorError,
    error::{check_finite, check_positive, check_sigma},
};

/// `sigma * z` with `z ~ N(0, 1)`; always consumes exactly one standard normal.
pub fn gauss(rng: &mut impl Rng, sigma: f64) -> f64 {
    let z: f64 = rng.sample(StandardNormal);
    sigma * z
}

/// White Gaussian noise `n ~ N(0, sigma^2)`, independent per sample (eqs. 1-3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WhiteGaussian {
    sigma: f64,
}

impl WhiteGaussian {
    /// White noise with standard deviation `sigma` (>= 0; 0 = off).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `sigma` is negative or not finite.
    pub fn new(sigma: f64) -> Result<Self, SensorError> {
        Ok(Self {
            sigma: check_sigma("white noise sigma", sigma)?,
        })
    }

    /// The standard deviation.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// One noise value (one standard-normal draw).
    pub fn sample(&self, rng: &mut impl Rng) -> f64 {
        gauss(rng, self.sigma)
    }
}

/// Common-mode noise held over fixed intervals (Table 7): one value
/// `n_c ~ N(0, sigma_c^2)` per interval `[k t_gap, (k+1) t_gap)`, `k = 0, 1, ...`,
/// shared by every sensor that reads it (the ranges). All values of a run are drawn
/// up front, so the value depends only on the sample time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldCommonMode {
    sigma_c: f64,
    t_gap: f64,
    values: Vec<f64>,
}

impl HeldCommonMode {
    /// Draws the held values covering `[0, t_end]`: `floor(t_end / t_gap) + 1`
    /// standard normals, interval by interval.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative `sigma_c`, a non-positive
    /// `t_gap` or a negative / non-finite `t_end`.
    pub fn generate(
        sigma_c: f64,
        t_gap: f64,
        t_end: Time,
        rng: &mut impl Rng,
    ) -> Result<Self, SensorError> {
        let sigma_c = check_sigma("sigma_c", sigma_c)?;
        let t_gap = check_positive("t_gap", t_gap)?;
        let t_end = check_sigma("t_end", t_end)?;
        let n = (t_end / t_gap).floor() as usize + 1;
        let values = (0..n).map(|_| gauss(rng, sigma_c)).collect();
        Ok(Self {
            sigma_c,
            t_gap,
            values,
        })
    }

    /// The held value at time `t`: `values[floor(t / t_gap)]`.
    ///
    /// # Errors
    /// [`SensorError::TimeNotCovered`] when `t` is negative, not finite or beyond
    /// the generated span.
    pub fn value_at(&self, t: Time) -> Result<f64, SensorError> {
        let end = self.values.len() as f64 * self.t_gap;
        if !(t.is_finite() && t >= 0.0 && t < end) {
            return Err(SensorError::TimeNotCovered {
                what: "held common-mode noise".into(),
                t,
                start: 0.0,
                end,
            });
        }
        let k = ((t / self.t_gap).floor() as usize).min(self.values.len() - 1);
        Ok(self.values[k])
    }

    /// The held values, one per interval.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Standard deviation `sigma_c`.
    pub fn sigma_c(&self) -> f64 {
        self.sigma_c
    }

    /// Hold interval `t_gap`, s.
    pub fn t_gap(&self) -> f64 {
        self.t_gap
    }
}

/// Unchecked outlier-injection parameters (Table 8).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OutlierParams {
    /// Number `N` of measurements to corrupt.
    pub count: usize,
    /// Magnitude `sigma_o` of the added constant (sign random), >= 0.
    pub magnitude: f64,
}

impl Default for OutlierParams {
    /// `N = 276` (paper Table 14), `sigma_o = 1 m`.
    fn default() -> Self {
        Self {
            count: 276,
            magnitude: 1.0,
        }
    }
}

impl OutlierParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when the magnitude is negative or not finite.
    pub fn check(&self) -> Result<OutlierInjector, SensorError> {
        Ok(OutlierInjector {
            count: self.count,
            magnitude: check_sigma("outlier magnitude", self.magnitude)?,
        })
    }
}

/// One injected outlier: which measurement and the constant added to it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Outlier {
    /// Index of the corrupted measurement in the set it was chosen from.
    pub index: usize,
    /// The added constant, `+sigma_o` or `-sigma_o`.
    pub offset: f64,
}

/// Validated outlier injection: `N` measurements chosen uniformly at random
/// without replacement, each shifted by `+-sigma_o` with a fair random sign.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutlierInjector {
    count: usize,
    magnitude: f64,
}

impl OutlierInjector {
    /// Number of outliers `N`.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Magnitude `sigma_o`.
    pub fn magnitude(&self) -> f64 {
        self.magnitude
    }

    /// Chooses the outliers among `n_measurements` measurements.
    ///
    /// Draw order: `rand::seq::index::sample(rng, n_measurements, N)`, then one
    /// `bool` per chosen index (in the order `sample` returned them) for the sign.
    /// The result is sorted by index.
    ///
    /// # Errors
    /// [`SensorError::TooManyOutliers`] when `N > n_measurements`.
    pub fn choose(
        &self,
        n_measurements: usize,
        rng: &mut impl Rng,
    ) -> Result<Vec<Outlier>, SensorError> {
        if self.count > n_measurements {
            return Err(SensorError::TooManyOutliers {
                requested: self.count,
                available: n_measurements,
            });
        }
        let chosen = rand::seq::index::sample(rng, n_measurements, self.count);
        let mut out: Vec<Outlier> = chosen
            .iter()
            .map(|index| {
                let positive: bool = rng.random();
                Outlier {
                    index,
                    offset: if positive {
                        self.magnitude
                    } else {
                        -self.magnitude
                    },
                }
            })
            .collect();
        out.sort_by_key(|o| o.index);
        Ok(out)
    }

    /// Chooses the outliers among `values` (as [`OutlierInjector::choose`]) and adds
    /// their offsets in place.
    ///
    /// # Errors
    /// [`SensorError::TooManyOutliers`] when `N > values.len()`.
    pub fn inject(
        &self,
        values: &mut [f64],
        rng: &mut impl Rng,
    ) -> Result<Vec<Outlier>, SensorError> {
        let out = self.choose(values.len(), rng)?;
        for o in &out {
            values[o.index] += o.offset;
        }
        Ok(out)
    }
}

/// How a per-run constant (bias, scale factor) is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum RunConstantDist {
    /// A given value (no draw).
    Fixed(f64),
    /// `N(0, sigma^2)` (one standard-normal draw).
    Gaussian {
        /// Standard deviation, >= 0.
        sigma: f64,
    },
    /// `U(-half_width, +half_width)` (one `f64` uniform draw `u`, value
    /// `half_width * (2u - 1)`).
    Uniform {
        /// Half width, >= 0.
        half_width: f64,
    },
}

impl RunConstantDist {
    /// Validates the distribution's parameter.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-finite value or negative width.
    pub fn check(&self) -> Result<Self, SensorError> {
        match *self {
            Self::Fixed(v) => check_finite("fixed run constant", v).map(Self::Fixed),
            Self::Gaussian { sigma } => Ok(Self::Gaussian {
                sigma: check_sigma("run constant sigma", sigma)?,
            }),
            Self::Uniform { half_width } => Ok(Self::Uniform {
                half_width: check_sigma("run constant half_width", half_width)?,
            }),
        }
    }

    /// Draws one value (see the variants for the draws consumed).
    ///
    /// # Errors
    /// As [`RunConstantDist::check`].
    pub fn draw(&self, rng: &mut impl Rng) -> Result<f64, SensorError> {
        Ok(match self.check()? {
            Self::Fixed(v) => v,
            Self::Gaussian { sigma } => gauss(rng, sigma),
            Self::Uniform { half_width } => {
                let u: f64 = rng.random();
                half_width * (2.0 * u - 1.0)
            }
        })
    }

    /// Variance of the distribution.
    pub fn variance(&self) -> f64 {
        match *self {
            Self::Fixed(_) => 0.0,
            Self::Gaussian { sigma } => sigma * sigma,
            Self::Uniform { half_width } => half_width * half_width / 3.0,
        }
    }
}

/// A constant additive bias `b`, drawn once per run: `y = x + b`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConstantBias {
    value: f64,
}

impl ConstantBias {
    /// Draws the bias from `dist`.
    ///
    /// # Errors
    /// As [`RunConstantDist::check`].
    pub fn draw(dist: &RunConstantDist, rng: &mut impl Rng) -> Result<Self, SensorError> {
        Ok(Self {
            value: dist.draw(rng)?,
        })
    }

    /// The bias value.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// `x + b`.
    pub fn apply(&self, x: f64) -> f64 {
        x + self.value
    }
}

/// A scale-factor error `s`, drawn once per run: `y = (1 + s) x`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScaleFactor {
    value: f64,
}

impl ScaleFactor {
    /// Draws the scale-factor error from `dist`.
    ///
    /// # Errors
    /// As [`RunConstantDist::check`].
    pub fn draw(dist: &RunConstantDist, rng: &mut impl Rng) -> Result<Self, SensorError> {
        Ok(Self {
            value: dist.draw(rng)?,
        })
    }

    /// The scale-factor error `s`.
    pub fn value(&self) -> f64 {
        self.value
    }

    /// `(1 + s) x`.
    pub fn apply(&self, x: f64) -> f64 {
        (1.0 + self.value) * x
    }
}

/// First-order Gauss-Markov process with stationary standard deviation `sigma` and
/// correlation time `tau`, discretized exactly:
/// `x_k = e^{-dt/tau} x_{k-1} + w_k`, `Var(w_k) = sigma^2 (1 - e^{-2 dt/tau})`,
/// started from the stationary distribution `x_0 ~ N(0, sigma^2)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaussMarkov {
    sigma: f64,
    tau: f64,
    state: f64,
}

impl GaussMarkov {
    /// A stationary process (draws `x_0`, one standard normal).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative `sigma` or non-positive `tau`.
    pub fn new(sigma: f64, tau: f64, rng: &mut impl Rng) -> Result<Self, SensorError> {
        let sigma = check_sigma("gauss-markov sigma", sigma)?;
        let tau = check_positive("gauss-markov tau", tau)?;
        Ok(Self {
            sigma,
            tau,
            state: gauss(rng, sigma),
        })
    }

    /// Advances by `dt` (one standard normal) and returns the new value.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `dt` is not positive and finite.
    pub fn step(&mut self, dt: f64, rng: &mut impl Rng) -> Result<f64, SensorError> {
        let dt = check_positive("gauss-markov dt", dt)?;
        let phi = (-dt / self.tau).exp();
        let w_sigma = self.sigma * (-(-2.0 * dt / self.tau).exp_m1()).sqrt();
        self.state = phi * self.state + gauss(rng, w_sigma);
        Ok(self.state)
    }

    /// Current value.
    pub fn value(&self) -> f64 {
        self.state
    }
}

/// Random walk `x_k = x_{k-1} + w_k`, `w_k ~ N(0, q dt)` (`q` in units^2/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RandomWalk {
    q: f64,
    state: f64,
}

impl RandomWalk {
    /// A walk with intensity `q` (>= 0) starting at `x0`.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative `q` or non-finite `x0`.
    pub fn new(q: f64, x0: f64) -> Result<Self, SensorError> {
        Ok(Self {
            q: check_sigma("random walk q", q)?,
            state: check_finite("random walk x0", x0)?,
        })
    }

    /// Advances by `dt` (one standard normal) and returns the new value.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `dt` is not positive and finite.
    pub fn step(&mut self, dt: f64, rng: &mut impl Rng) -> Result<f64, SensorError> {
        let dt = check_positive("random walk dt", dt)?;
        self.state += gauss(rng, (self.q * dt).sqrt());
        Ok(self.state)
    }

    /// Current value.
    pub fn value(&self) -> f64 {
        self.state
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Chi-square (normal approximation) check of a zero-mean variance: for
    /// `n` iid `N(0, v)` samples, `sum x^2 / (n v) ~ chi2_n / n`, std `sqrt(2/n)`.
    /// `rel_sd_factor` inflates the std for correlated samples. Bound: 4 sigma.
    pub(crate) fn zero_mean_var_ok(xs: &[f64], design_var: f64, rel_sd_factor: f64) -> bool {
        let n = xs.len() as f64;
        let var = xs.iter().map(|x| x * x).sum::<f64>() / n;
        (var / design_var - 1.0).abs() < 4.0 * rel_sd_factor * (2.0 / n).sqrt()
    }

    #[test]
    fn white_gaussian_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let w = WhiteGaussian::new(0.3).unwrap();
        let xs: Vec<f64> = (0..100_000).map(|_| w.sample(&mut rng)).collect();
        assert!(zero_mean_var_ok(&xs, 0.09, 1.0));
        // Negative control: 5 % larger sigma must be rejected.
        assert!(!zero_mean_var_ok(&xs, (0.3f64 * 1.05).powi(2), 1.0));
        // Zero sigma is valid and gives zero noise.
        assert_eq!(WhiteGaussian::new(0.0).unwrap().sample(&mut rng), 0.0);
        assert!(WhiteGaussian::new(-0.1).is_err());
        assert!(WhiteGaussian::new(f64::NAN).is_err());
    }

    #[test]
    fn held_noise_constant_inside_and_changes_across_intervals() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let h = HeldCommonMode::generate(0.2, 1.0, 10.0, &mut rng).unwrap();
        assert_eq!(h.values().len(), 11);
        for k in 0..10 {
            let t = k as f64;
            let v = h.value_at(t + 0.01).unwrap();
            assert_eq!(h.value_at(t + 0.5).unwrap(), v);
            assert_eq!(h.value_at(t + 0.99).unwrap(), v);
            assert_ne!(h.value_at(t + 1.01).unwrap(), v);
        }
        assert!(h.value_at(10.0).is_ok());
        assert!(h.value_at(-0.1).is_err());
        assert!(h.value_at(11.0).is_err());
        assert!(h.value_at(f64::NAN).is_err());
        assert!(HeldCommonMode::generate(0.2, 0.0, 10.0, &mut rng).is_err());
        assert!(HeldCommonMode::generate(-0.2, 1.0, 10.0, &mut rng).is_err());
    }

    #[test]
    fn held_noise_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let h = HeldCommonMode::generate(0.05, 1.0, 50_000.0, &mut rng).unwrap();
        assert!(zero_mean_var_ok(h.values(), 0.0025, 1.0));
        assert!(!zero_mean_var_ok(h.values(), 0.0025 * 1.1, 1.0));
    }

    #[test]
    fn outliers_hit_exactly_n_distinct_samples_with_exact_magnitude() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let inj = OutlierParams {
            count: 276,
            magnitude: 1.0,
        }
        .check()
        .unwrap();
        let mut values = vec![0.0; 7200];
        let hits = inj.inject(&mut values, &mut rng).unwrap();
        assert_eq!(hits.len(), 276);
        assert!(hits.windows(2).all(|w| w[1].index > w[0].index));
        assert_eq!(values.iter().filter(|v| **v != 0.0).count(), 276);
        for o in &hits {
            assert_eq!(values[o.index].abs(), 1.0);
            assert_eq!(values[o.index], o.offset);
        }
        let positive = hits.iter().filter(|o| o.offset > 0.0).count();
        // Binomial(276, 0.5): 4-sigma bound on the number of positive signs.
        assert!((positive as f64 - 138.0).abs() < 4.0 * (276.0f64 * 0.25).sqrt());
        assert!(matches!(
            inj.choose(100, &mut rng),
            Err(SensorError::TooManyOutliers {
                requested: 276,
                available: 100
            })
        ));
        assert!(
            OutlierParams {
                count: 1,
                magnitude: -1.0
            }
            .check()
            .is_err()
        );
    }

    #[test]
    fn outlier_choice_is_uniform() {
        // Each index is hit with probability N/n; binomial 5-sigma bound per index.
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let inj = OutlierParams {
            count: 10,
            magnitude: 1.0,
        }
        .check()
        .unwrap();
        let trials = 20_000;
        let mut counts = [0usize; 50];
        for _ in 0..trials {
            for o in inj.choose(50, &mut rng).unwrap() {
                counts[o.index] += 1;
            }
        }
        let (mean, sd) = (trials as f64 * 0.2, (trials as f64 * 0.2 * 0.8).sqrt());
        assert!(counts.iter().all(|&c| (c as f64 - mean).abs() < 5.0 * sd));
    }

    #[test]
    fn run_constants_have_design_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(15);
        let g = RunConstantDist::Gaussian { sigma: 2e-4 };
        let xs: Vec<f64> = (0..50_000)
            .map(|_| ConstantBias::draw(&g, &mut rng).unwrap().value())
            .collect();
        assert!(zero_mean_var_ok(&xs, g.variance(), 1.0));
        assert!(!zero_mean_var_ok(&xs, 1.1 * g.variance(), 1.0));
        // Uniform: Var(x^2)/E[x^2]^2 = (1/5 - 1/9) / (1/9) = 0.8, i.e. 0.4 x chi-square's 2.
        let u = RunConstantDist::Uniform { half_width: 0.002 };
        let xs: Vec<f64> = (0..50_000)
            .map(|_| ScaleFactor::draw(&u, &mut rng).unwrap().value())
            .collect();
        assert!(xs.iter().all(|x| x.abs() <= 0.002));
        assert!(zero_mean_var_ok(&xs, u.variance(), 0.4f64.sqrt()));
        assert!(!zero_mean_var_ok(&xs, 1.05 * u.variance(), 0.4f64.sqrt()));
        let s = ScaleFactor::draw(&RunConstantDist::Fixed(0.01), &mut rng).unwrap();
        assert_abs_diff_eq!(s.apply(2.0), 2.02, epsilon = 1e-15);
        let b = ConstantBias::draw(&RunConstantDist::Fixed(0.5), &mut rng).unwrap();
        assert_eq!(b.apply(1.0), 1.5);
        assert!(
            RunConstantDist::Uniform { half_width: -1.0 }
                .check()
                .is_err()
        );
        assert!(
            RunConstantDist::Fixed(f64::INFINITY)
                .draw(&mut rng)
                .is_err()
        );
    }

    #[test]
    fn gauss_markov_variance_and_lag1_autocorrelation() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        let (sigma, tau, dt) = (0.5, 1.0, 0.1);
        let mut gm = GaussMarkov::new(sigma, tau, &mut rng).unwrap();
        let n = 200_000;
        let mut xs = Vec::with_capacity(n);
        xs.push(gm.value());
        for _ in 1..n {
            xs.push(gm.step(dt, &mut rng).unwrap());
        }
        let rho = (-dt / tau).exp();
        // Sample variance of AR(1): rel. std sqrt(2/n (1+rho^2)/(1-rho^2)).
        let inflate = ((1.0 + rho * rho) / (1.0 - rho * rho)).sqrt();
        assert!(zero_mean_var_ok(&xs, sigma * sigma, inflate));
        assert!(!zero_mean_var_ok(&xs, 1.2 * sigma * sigma, inflate));
        // Lag-1 autocorrelation estimate: std ~ sqrt((1 - rho^2)/n); 4-sigma bound.
        let num: f64 = xs.windows(2).map(|w| w[0] * w[1]).sum();
        let den: f64 = xs.iter().map(|x| x * x).sum();
        let r = num / den;
        let bound = 4.0 * ((1.0 - rho * rho) / n as f64).sqrt();
        assert!((r - rho).abs() < bound, "r = {r}, rho = {rho}");
        // Negative control: a 10 % longer tau is rejected.
        assert!((r - (-dt / (1.1 * tau)).exp()).abs() > bound);
        assert!(GaussMarkov::new(0.5, 0.0, &mut rng).is_err());
        assert!(gm.step(-1.0, &mut rng).is_err());
    }

    #[test]
    fn random_walk_variance_grows_linearly() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let (q, dt, steps) = (0.5, 0.2, 10);
        let finals: Vec<f64> = (0..20_000)
            .map(|_| {
                let mut w = RandomWalk::new(q, 0.0).unwrap();
                for _ in 0..steps {
                    w.step(dt, &mut rng).unwrap();
                }
                w.value()
            })
            .collect();
        let design = q * dt * steps as f64;
        assert!(zero_mean_var_ok(&finals, design, 1.0));
        assert!(!zero_mean_var_ok(&finals, 1.1 * design, 1.0));
        assert!(RandomWalk::new(-1.0, 0.0).is_err());
        assert!(RandomWalk::new(1.0, f64::NAN).is_err());
    }
}
