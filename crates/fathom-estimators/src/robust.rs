//! Robust measurement handling that cannot lock the filter out, for the update-scheme
//! policy ([`crate::schemes::SchemeFilter::with_robust`]).
//!
//! Real measurements are sometimes wrong by far more than their nominal noise, and a
//! filter is sometimes wrong by far more than its covariance says. A hard innovation
//! gate alone handles the first and fails badly at the second: once the state is off
//! and `P` small, every measurement fails the gate, `P` grows only slowly with the
//! process noise, and the filter may reject everything for a long time (lock-out).
//! A [`RobustPolicy`] replaces "accept or reject" by three regimes on the normalized
//! innovation `e = |nu| / sqrt(S)`, `S = H P H^T + r` at the prior:
//!
//! - `e <= k`: a normal update;
//! - `k < e` and inside the gate: **Huber down-weighting**: the update uses the variance
//!   `r e / k` instead of `r`. This is the iteratively-reweighted-least-squares weight
//!   `w = k / e` of Huber's M-estimator applied to the measurement noise, so a wrong
//!   measurement moves the state by a bounded amount instead of being swallowed whole
//!   or thrown away;
//! - outside the gate: rejected (gross errors).
//!
//! **Lock-out recovery**: after `after_rejections` consecutive *inconsistent*
//! measurements (rejected or down-weighted), either overall or on any one channel, the
//! state covariance is multiplied by `inflation > 1` and the counts restart. A
//! measurement with `e <= k` ends the run overall and on its channel. The gate thus
//! widens geometrically while the filter keeps rejecting, until measurements pass
//! again: a filter that rejects everything for a while always recovers.
//!
//! - Down-weighted measurements count too, because they are the second half of the
//!   same failure: once a few measurements get through with small weights, each one
//!   still shrinks `P` while the innovations stay large, and the filter would crawl
//!   back at a bounded step per measurement.
//! - Runs are also counted per channel because a lock-out can be partial: with the
//!   state wrong along one direction only, the beacons that do not see that direction
//!   keep agreeing (resetting an overall count), while every range from the beacons
//!   that do is rejected.
//!
//! For a consistent filter a run of `n` values with `e > k` has probability
//! `P(|N(0,1)| > k)^n` (2e-7 for `k = 2`, `n = 5`), so the rule practically never
//! fires when nothing is wrong. A beacon that is consistently wrong (e.g. multipath)
//! triggers an inflation every `n` of its ranges; the other beacons shrink `P` again.
//!
//! Bad input: non-finite measurements never reach the robust step: the scheme filter
//! drops and counts them first ([`crate::schemes`], "Bad data"), so they are neither
//! gated, down-weighted nor counted as rejections by the lock-out monitor. A
//! covariance inflation that overflows is an error with the filter time.

use crate::EstimatorError;

/// Unchecked robust-handling parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustParams {
    /// Huber threshold `k` on the normalized innovation (> 0), or `None` for no
    /// down-weighting.
    pub huber_k: Option<f64>,
    /// Lock-out recovery, or `None` for none.
    pub recovery: Option<RecoveryParams>,
}

/// Lock-out recovery by covariance inflation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecoveryParams {
    /// Consecutive inconsistent (rejected or down-weighted) measurements that trigger
    /// an inflation (>= 1).
    pub after_rejections: usize,
    /// Factor applied to the whole state covariance (> 1).
    pub inflation: f64,
}

/// Checked [`RobustParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustPolicy {
    huber_k: Option<f64>,
    recovery: Option<RecoveryParams>,
}

impl RobustParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] naming the parameter.
    pub fn check(&self) -> Result<RobustPolicy, EstimatorError> {
        if let Some(k) = self.huber_k
            && !(k.is_finite() && k > 0.0)
        {
            return Err(EstimatorError::OutOfRange {
                what: "Huber threshold k".into(),
                value: k,
                expected: "> 0",
            });
        }
        if let Some(r) = self.recovery {
            if r.after_rejections == 0 {
                return Err(EstimatorError::OutOfRange {
                    what: "recovery: consecutive rejections".into(),
                    value: 0.0,
                    expected: ">= 1",
                });
            }
            if !(r.inflation.is_finite() && r.inflation > 1.0) {
                return Err(EstimatorError::OutOfRange {
                    what: "recovery: covariance inflation".into(),
                    value: r.inflation,
                    expected: "> 1",
                });
            }
        }
        Ok(RobustPolicy {
            huber_k: self.huber_k,
            recovery: self.recovery,
        })
    }
}

impl RobustPolicy {
    /// The Huber threshold, if any.
    pub fn huber_k(&self) -> Option<f64> {
        self.huber_k
    }

    /// The recovery rule, if any.
    pub fn recovery(&self) -> Option<RecoveryParams> {
        self.recovery
    }

    /// The factor on the measurement variance for a normalized innovation
    /// `e = |nu| / sqrt(S)`: 1 for `e <= k` (or without Huber), `e / k` beyond.
    pub fn variance_factor(&self, e: f64) -> f64 {
        match self.huber_k {
            Some(k) if e > k => e / k,
            _ => 1.0,
        }
    }
}

/// Counts consecutive inconsistent measurements and says when the covariance must be
/// inflated.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LockoutMonitor {
    consecutive: usize,
    per_channel: Vec<usize>,
    recoveries: usize,
}

impl LockoutMonitor {
    /// Records one measurement of `channel`: `consistent` = applied with its nominal
    /// variance (`e <= k`); otherwise (rejected or down-weighted) it extends the runs.
    /// Returns the inflation factor to apply now, if this measurement completes a run
    /// of `after_rejections` overall or on its channel (module docs).
    pub fn record(
        &mut self,
        channel: usize,
        consistent: bool,
        policy: &RobustPolicy,
    ) -> Option<f64> {
        if self.per_channel.len() <= channel {
            self.per_channel.resize(channel + 1, 0);
        }
        if consistent {
            self.consecutive = 0;
            self.per_channel[channel] = 0;
            return None;
        }
        self.consecutive += 1;
        self.per_channel[channel] += 1;
        let r = policy.recovery?;
        if self.consecutive >= r.after_rejections || self.per_channel[channel] >= r.after_rejections
        {
            self.consecutive = 0;
            self.per_channel.iter_mut().for_each(|c| *c = 0);
            self.recoveries += 1;
            Some(r.inflation)
        } else {
            None
        }
    }

    /// Inflations triggered so far.
    pub fn recoveries(&self) -> usize {
        self.recoveries
    }

    /// The current run of consecutive inconsistent measurements.
    pub fn consecutive(&self) -> usize {
        self.consecutive
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy() -> RobustPolicy {
        RobustParams {
            huber_k: Some(2.0),
            recovery: Some(RecoveryParams {
                after_rejections: 3,
                inflation: 4.0,
            }),
        }
        .check()
        .unwrap()
    }

    #[test]
    fn huber_factor() {
        let p = policy();
        assert_eq!(p.variance_factor(0.5), 1.0);
        assert_eq!(p.variance_factor(2.0), 1.0);
        assert_eq!(p.variance_factor(5.0), 2.5);
        let none = RobustParams {
            huber_k: None,
            recovery: None,
        }
        .check()
        .unwrap();
        assert_eq!(none.variance_factor(100.0), 1.0);
    }

    #[test]
    fn monitor_inflates_after_a_run_of_rejections_only() {
        let p = policy();
        let mut m = LockoutMonitor::default();
        assert_eq!(m.record(0, false, &p), None);
        assert_eq!(m.record(1, false, &p), None);
        assert_eq!(m.record(0, true, &p), None); // resets the overall run and channel 0
        assert_eq!(m.record(0, false, &p), None);
        assert_eq!(m.record(2, false, &p), None);
        assert_eq!(m.record(3, false, &p), Some(4.0));
        assert_eq!(m.consecutive(), 0);
        assert_eq!(m.recoveries(), 1);
        // A partial lock-out: channel 1 always inconsistent, channel 0 always fine.
        let mut m = LockoutMonitor::default();
        let fired: Vec<Option<f64>> = (0..6).map(|k| m.record(k % 2, k % 2 == 0, &p)).collect();
        assert_eq!(fired, [None, None, None, None, None, Some(4.0)]);
    }

    /// A standing robot at the origin, four beacons at 20 m, and a filter that starts
    /// 8 m off with a tiny covariance. Odometry says "standing", so the process noise
    /// is zero and nothing but the measurements can fix the state.
    fn locked_start(
        scheme: crate::schemes::UpdateScheme,
        robust: Option<RobustPolicy>,
    ) -> (f64, usize, usize) {
        use crate::ekf::Ekf;
        use crate::schemes::{Event, Observation, SchemeFilter, SchemeParams};
        use crate::wheel_odometry::{CalibratedRange, OdometryRate, WheelOdometryParams};
        use crate::{GateThreshold, schemes::Disposition};
        use fathom_core::Gaussian;
        use nalgebra::{DMatrix, Matrix3, Vector2, Vector3};

        let motion = WheelOdometryParams {
            distance_sigma_per_sqrt_m: 0.05,
            heading_sigma_per_sqrt_m: 0.01,
            heading_sigma_per_sqrt_rad: 0.05,
            calibration_random_walk: vec![],
        }
        .check()
        .unwrap();
        let prior = Gaussian::new(Vector3::new(8.0, 0.0, 0.0), Matrix3::identity() * 0.01).unwrap();
        let ekf = Ekf::<3, _>::new(prior, 0.0, motion, OdometryRate::default()).unwrap();
        let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
        let config = SchemeParams {
            scheme,
            epoch_period: 0.1,
            stale_tolerance: 0.0,
            channel_cov: DMatrix::identity(4, 4) * 0.09,
            gates: vec![Some(gate); 4],
        }
        .check()
        .unwrap();
        let mut f = SchemeFilter::new(ekf, config);
        if let Some(p) = robust {
            f = f.with_robust(p);
        }
        let beacons = [(20.0, 0.0), (0.0, 20.0), (-20.0, 0.0), (0.0, -20.0)];
        for k in 0..200 {
            let c = k % 4;
            let b = Vector2::new(beacons[c].0, beacons[c].1);
            f.process(Event::Measurement(Observation {
                channel: c,
                stamp: 0.25 * (k + 1) as f64,
                value: b.norm(),
                model: CalibratedRange {
                    beacon: b,
                    offset_state: None,
                    scale_state: None,
                },
                tag: k,
            }))
            .unwrap();
        }
        f.advance_to(60.0).unwrap();
        let x = f.ekf().state();
        let rejected = f
            .decisions()
            .iter()
            .filter(|d| d.disposition == Disposition::Rejected)
            .count();
        (x[0].hypot(x[1]), rejected, f.recoveries())
    }

    #[test]
    fn hard_gating_locks_out_and_recovery_does_not() {
        use crate::schemes::UpdateScheme;
        for scheme in UpdateScheme::ALL {
            // Negative control: the hard gate alone rejects every range and stays 8 m off.
            let (err, rejected, _) = locked_start(scheme, None);
            assert!(err > 7.9, "{scheme:?}: {err}");
            assert_eq!(rejected, 200, "{scheme:?}");
            // Huber + recovery: a few inflations open the gate, then the fix converges.
            let (err, rejected, recoveries) = locked_start(scheme, Some(policy()));
            assert!(err < 0.1, "{scheme:?}: {err}");
            assert!(
                recoveries >= 1 && rejected < 50,
                "{scheme:?}: {recoveries} {rejected}"
            );
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        let bad_k = RobustParams {
            huber_k: Some(0.0),
            recovery: None,
        };
        assert!(bad_k.check().is_err());
        for (after, inflation) in [(0, 2.0), (2, 1.0), (2, f64::NAN)] {
            let p = RobustParams {
                huber_k: None,
                recovery: Some(RecoveryParams {
                    after_rejections: after,
                    inflation,
                }),
            };
            assert!(p.check().is_err());
        }
    }
}
