//! Sample-time schedules: jittered sensor clocks (paper B, Table 2) and the
//! time stamps they report.
//!
//! A clock with nominal period `dt` produces sample times
//! `t_{s,i} = t_{s,i-1} + dt + n_t`, `n_t ~ N(0, sigma_t^2)` (Table 2), starting from
//! `t_{s,-1} = t0` (so the first sample is one jittered period after `t0`) and
//! stopping at the last sample `<= t_end`.
//!
//! **Monotonicity.** A step `dt + n_t` must be positive. The check requires
//! `sigma_t < dt / 4`, so a non-positive step is a `> 4 sigma` event
//! (probability `< 3.2e-5` per step); when it happens anyway the jitter is redrawn
//! (the step distribution is thus the Gaussian truncated at `-dt`, a negligible
//! change). Sample times are therefore always strictly increasing.
//!
//! **Time stamps.** The reported stamp is
//! `stamp_i = t_{s,i} + stamp_offset + e_i`, `e_i ~ N(0, stamp_jitter_sigma^2)`
//! independent per sample (both default 0, so `stamp == sample_time`). Stamps are
//! *not* guaranteed to be monotonic when stamp jitter is on; consumers that
//! process by stamp must sort.
//!
//! **RNG draw order of [`Clock::generate`].** First the sample times: one standard
//! normal per step attempt, including the final attempt whose time passes `t_end`
//! (and any redraws); then one standard normal per sample for the stamp jitter,
//! in sample order. Draws happen even when a sigma is zero, so switching a jitter
//! on or off does not shift the other draws of the same clock.

use fathom_core::Time;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::{
    SensorError,
    error::{check_finite, check_positive, check_sigma},
    noise::gauss,
};

/// Maximum number of redraws of a non-positive jittered step before giving up.
const MAX_STEP_ATTEMPTS: usize = 1000;

/// Default sample-time jitter sigma_t, s (the paper gives none; 1 ms decided).
pub const DEFAULT_JITTER_SIGMA: f64 = 1e-3;

/// Unchecked parameters of one sensor clock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClockParams {
    /// Nominal period `dt`, s (> 0).
    pub period: f64,
    /// Standard deviation `sigma_t` of the per-step jitter, s (>= 0, < period/4).
    pub jitter_sigma: f64,
    /// Constant time-stamp error (reported minus actual), s. Default 0.
    pub stamp_offset: f64,
    /// Standard deviation of the white time-stamp error, s (>= 0). Default 0.
    pub stamp_jitter_sigma: f64,
}

impl ClockParams {
    /// A clock with the given period, the default jitter (1 ms) and exact stamps.
    pub fn with_period(period: f64) -> Self {
        Self {
            period,
            jitter_sigma: DEFAULT_JITTER_SIGMA,
            stamp_offset: 0.0,
            stamp_jitter_sigma: 0.0,
        }
    }

    /// Validates the parameters; `name` identifies the clock in errors.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-positive period, negative or
    /// non-finite sigmas or a non-finite offset; [`SensorError::JitterTooLarge`]
    /// when `jitter_sigma >= period / 4`.
    pub fn check(&self, name: &str) -> Result<Clock, SensorError> {
        let period = check_positive(&format!("{name}.period"), self.period)?;
        let jitter_sigma = check_sigma(&format!("{name}.jitter_sigma"), self.jitter_sigma)?;
        if jitter_sigma >= period / 4.0 {
            return Err(SensorError::JitterTooLarge {
                what: name.to_owned(),
                sigma_t: jitter_sigma,
                period,
            });
        }
        let stamp_offset = check_finite(&format!("{name}.stamp_offset"), self.stamp_offset)?;
        let stamp_jitter_sigma = check_sigma(
            &format!("{name}.stamp_jitter_sigma"),
            self.stamp_jitter_sigma,
        )?;
        Ok(Clock {
            name: name.to_owned(),
            params: Self {
                period,
                jitter_sigma,
                stamp_offset,
                stamp_jitter_sigma,
            },
        })
    }
}

/// A validated sensor clock (see the module docs for the model).
#[derive(Debug, Clone, PartialEq)]
pub struct Clock {
    name: String,
    params: ClockParams,
}

impl Clock {
    /// The validated parameters.
    pub fn params(&self) -> &ClockParams {
        &self.params
    }

    /// The clock's name as used in errors.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Draws the jittered sample times in `(t0, t_end]` and their stamps
    /// (Table 2). See the module docs for the RNG draw order.
    ///
    /// # Errors
    /// [`SensorError::BadInterval`] when the bounds are not finite or
    /// `t_end < t0`; [`SensorError::StepRedrawExhausted`] in the practically
    /// impossible case that no positive step was drawn in 1000 attempts.
    pub fn generate(
        &self,
        t0: Time,
        t_end: Time,
        rng: &mut impl Rng,
    ) -> Result<SampleTimes, SensorError> {
        if !(t0.is_finite() && t_end.is_finite()) || t_end < t0 {
            return Err(SensorError::BadInterval {
                what: self.name.clone(),
                start: t0,
                end: t_end,
            });
        }
        let p = &self.params;
        let mut sample_times = Vec::with_capacity(((t_end - t0) / p.period) as usize + 1);
        let mut t = t0;
        loop {
            let mut step = 0.0;
            let mut ok = false;
            for _ in 0..MAX_STEP_ATTEMPTS {
                step = p.period + gauss(rng, p.jitter_sigma);
                if step > 0.0 {
                    ok = true;
                    break;
                }
            }
            if !ok {
                return Err(SensorError::StepRedrawExhausted {
                    what: self.name.clone(),
                    t,
                    attempts: MAX_STEP_ATTEMPTS,
                });
            }
            let next = t + step;
            if next > t_end {
                break;
            }
            sample_times.push(next);
            t = next;
        }
        let stamps = sample_times
            .iter()
            .map(|&s| s + p.stamp_offset + gauss(rng, p.stamp_jitter_sigma))
            .collect();
        Ok(SampleTimes {
            sample_times,
            stamps,
        })
    }
}

/// The sample instants of one sensor and the stamps it reports for them.
///
/// Invariants: both lists have the same length, all values are finite and the
/// sample times strictly increase.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SampleTimes {
    sample_times: Vec<Time>,
    stamps: Vec<Time>,
}

impl SampleTimes {
    /// Builds a schedule from explicit times (e.g. an exact uniform grid).
    ///
    /// # Errors
    /// [`SensorError::NotSynchronous`] when the lengths differ;
    /// [`SensorError::Core`] when a time is not finite or the sample times do not
    /// strictly increase.
    pub fn new(sample_times: Vec<Time>, stamps: Vec<Time>) -> Result<Self, SensorError> {
        if sample_times.len() != stamps.len() {
            return Err(SensorError::NotSynchronous {
                what: "sample times vs stamps".into(),
                index: sample_times.len().min(stamps.len()),
                detail: format!(
                    "{} sample times, {} stamps",
                    sample_times.len(),
                    stamps.len()
                ),
            });
        }
        fathom_core::time::ensure_strictly_increasing("sample times", &sample_times)?;
        fathom_core::error::ensure_finite("stamps", stamps.iter())?;
        Ok(Self {
            sample_times,
            stamps,
        })
    }

    /// Exact (jitter-free) schedule whose stamps equal the sample times.
    ///
    /// # Errors
    /// As [`SampleTimes::new`].
    pub fn exact(sample_times: Vec<Time>) -> Result<Self, SensorError> {
        let stamps = sample_times.clone();
        Self::new(sample_times, stamps)
    }

    /// Actual sample times, s (strictly increasing).
    pub fn sample_times(&self) -> &[Time] {
        &self.sample_times
    }

    /// Reported stamps, s (same length; not necessarily monotonic).
    pub fn stamps(&self) -> &[Time] {
        &self.stamps
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.sample_times.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.sample_times.is_empty()
    }

    /// Iterates over `(sample_time, stamp)` pairs.
    pub fn iter(&self) -> impl Iterator<Item = (Time, Time)> + '_ {
        self.sample_times
            .iter()
            .copied()
            .zip(self.stamps.iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn times_strictly_increase_and_stay_in_range() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        // Jitter just below the limit: non-positive steps are redrawn, never emitted.
        let clock = ClockParams {
            period: 0.01,
            jitter_sigma: 0.0024,
            stamp_offset: 0.0,
            stamp_jitter_sigma: 0.0,
        }
        .check("ahrs")
        .unwrap();
        let s = clock.generate(0.0, 200.0, &mut rng).unwrap();
        assert!(s.len() > 19_000);
        assert!(s.sample_times()[0] > 0.0);
        assert!(*s.sample_times().last().unwrap() <= 200.0);
        assert!(s.sample_times().windows(2).all(|w| w[1] > w[0]));
        assert_eq!(s.stamps(), s.sample_times());
    }

    #[test]
    fn jitter_statistics_match_design() {
        // Step = dt + n_t: mean dt, variance sigma_t^2 (chi-square bound, 4 sigma).
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let sigma_t: f64 = 1e-3;
        let clock = ClockParams::with_period(0.1).check("c").unwrap();
        let s = clock.generate(0.0, 10_000.0, &mut rng).unwrap();
        let steps: Vec<f64> = s.sample_times().windows(2).map(|w| w[1] - w[0]).collect();
        let n = steps.len() as f64;
        let var = steps.iter().map(|d| (d - 0.1).powi(2)).sum::<f64>() / n;
        let bound = 4.0 * (2.0 / n).sqrt();
        assert!((var / sigma_t.powi(2) - 1.0).abs() < bound);
        // Negative control: a 10 % larger design sigma is rejected by the same bound.
        assert!((var / (1.1 * sigma_t).powi(2) - 1.0).abs() > bound);
    }

    #[test]
    fn zero_jitter_gives_uniform_grid() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let clock = ClockParams {
            jitter_sigma: 0.0,
            stamp_offset: 0.5,
            ..ClockParams::with_period(0.25)
        }
        .check("c")
        .unwrap();
        let s = clock.generate(1.0, 2.0, &mut rng).unwrap();
        assert_eq!(s.len(), 4);
        for (k, (t, stamp)) in s.iter().enumerate() {
            assert_abs_diff_eq!(t, 1.0 + 0.25 * (k + 1) as f64, epsilon = 1e-12);
            assert_abs_diff_eq!(stamp, t + 0.5, epsilon = 1e-12);
        }
    }

    #[test]
    fn same_seed_same_times() {
        let clock = ClockParams {
            stamp_jitter_sigma: 1e-3,
            ..ClockParams::with_period(0.1)
        }
        .check("c")
        .unwrap();
        let a = clock
            .generate(0.0, 50.0, &mut ChaCha8Rng::seed_from_u64(9))
            .unwrap();
        let b = clock
            .generate(0.0, 50.0, &mut ChaCha8Rng::seed_from_u64(9))
            .unwrap();
        assert_eq!(a, b);
        assert_ne!(a.stamps(), a.sample_times());
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(matches!(
            ClockParams::with_period(0.01).check("x").map(|_| ()),
            Ok(())
        ));
        assert!(matches!(
            ClockParams {
                jitter_sigma: 0.0025,
                ..ClockParams::with_period(0.01)
            }
            .check("ahrs"),
            Err(SensorError::JitterTooLarge { .. })
        ));
        assert!(ClockParams::with_period(0.0).check("x").is_err());
        assert!(ClockParams::with_period(f64::NAN).check("x").is_err());
        assert!(
            ClockParams {
                stamp_jitter_sigma: -1.0,
                ..ClockParams::with_period(0.1)
            }
            .check("x")
            .is_err()
        );
        let clock = ClockParams::with_period(0.1).check("x").unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert!(matches!(
            clock.generate(1.0, 0.0, &mut rng),
            Err(SensorError::BadInterval { .. })
        ));
        assert!(SampleTimes::exact(vec![0.0, 1.0, 1.0]).is_err());
        assert!(SampleTimes::new(vec![0.0], vec![]).is_err());
    }
}
