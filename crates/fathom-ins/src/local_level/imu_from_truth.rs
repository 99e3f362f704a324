//! Error-free IMU increments from sampled truth, by exact inversion of the reduced
//! mechanization ([`super::mechanization`]); the local-level counterpart of
//! [`mod@crate::imu_from_truth`].
//!
//! For each interval `[t_{k-1}, t_k]`, with the previous increment known:
//!
//! - **attitude**: `q_k = q_{k-1} (x) q(phi)` gives `phi = log(q_{k-1}^* (x) q_k)`; the
//!   coning relation `phi = (I + [c x]) dtheta_k`, `c = dtheta_{k-1} / 12`, is solved
//!   exactly with `(I + [a x])^{-1} b = (b - a x b + a (a . b)) / (1 + |a|^2)`;
//! - **velocity**: `u = C_b^n(k-1)^T (v_k - v_{k-1} - g^n dt)` equals
//!   `(I + [a x]) dv_k + (1/12) dv_{k-1} x dtheta_k` with
//!   `a = 0.5 dtheta_k + dtheta_{k-1} / 12`, again solved exactly.
//!
//! Fed to [`super::LocalLevelMechanization`] started at the first sample (same
//! gravity), they reproduce the true attitude and velocity at every sample to
//! rounding and the position to the trapezoidal error (module docs there). They are
//! the integrals of the true body rate and specific force `C_b^n^T (a^n - g^n)` to the
//! algorithm's truncation order (O(dt^3) coning / sculling residuals).

use nalgebra::Vector3;

use crate::error::{InsError, check_finite};
use crate::imu_from_truth::InversionStep;
use crate::rotation::rotation_vector_from_quat;
use crate::state::ImuIncrement;

use super::LocalTruthSample;

/// Streaming inverse of the reduced mechanization: push true samples in time order,
/// get the increment over each interval. No allocation per sample.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalImuFromTruth {
    gravity: f64,
    step: InversionStep<LocalTruthSample>,
}

impl LocalImuFromTruth {
    /// An inverter for gravity `g` (m/s^2, down positive) that has seen no sample.
    ///
    /// # Errors
    /// [`InsError::NonFinite`] for a non-finite gravity.
    pub fn new(gravity: f64) -> Result<Self, InsError> {
        check_finite("gravity", &[gravity])?;
        Ok(Self {
            gravity,
            step: InversionStep::default(),
        })
    }

    /// Pushes the next true sample; `None` for the first, then the increment over
    /// `[t_{k-1}, t_k]`.
    ///
    /// # Errors
    /// [`InsError::NonFinite`] for a non-finite sample, [`InsError::NonIncreasingTime`]
    /// if time does not strictly increase. On error the inverter is unchanged.
    pub fn push(&mut self, sample: &LocalTruthSample) -> Result<Option<ImuIncrement>, InsError> {
        check_finite("truth time", &[sample.time])?;
        sample.to_state().check()?;
        let Some((prev, dt)) = self.step.interval(sample, |s| s.time)? else {
            return Ok(None);
        };
        let phi = rotation_vector_from_quat(&(prev.nav_from_body.inverse() * sample.nav_from_body));
        let dv_sf_nav =
            sample.vel_in_nav - prev.vel_in_nav - Vector3::new(0.0, 0.0, self.gravity * dt);
        let u = prev.nav_from_body.inverse() * dv_sf_nav;
        Ok(Some(self.step.advance(sample, dt, &phi, &u)))
    }
}

/// Batch form of [`LocalImuFromTruth`]: the `n - 1` increments between `n` samples.
///
/// # Errors
/// [`InsError::TruthTooShort`] for fewer than 2 samples, otherwise as
/// [`LocalImuFromTruth::push`].
pub fn local_imu_from_truth(
    truth: &[LocalTruthSample],
    gravity: f64,
) -> Result<Vec<ImuIncrement>, InsError> {
    if truth.len() < 2 {
        return Err(InsError::TruthTooShort {
            len: truth.len(),
            min: 2,
        });
    }
    let mut inv = LocalImuFromTruth::new(gravity)?;
    let mut out = Vec::with_capacity(truth.len() - 1);
    for s in truth {
        if let Some(inc) = inv.push(s)? {
            out.push(inc);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local_level::LocalLevelMechanization;
    use fathom_core::frames::{Euler, euler_rates_from_body_rates_matrix};
    use nalgebra::UnitQuaternion;

    const G: f64 = 9.806_65;

    /// An analytic manoeuvre: sinusoidal position, rolling / pitching / turning body.
    fn analytic(t: f64) -> (LocalTruthSample, Vector3<f64>, Vector3<f64>) {
        let pos = Vector3::new(
            20.0 * (0.3 * t).sin(),
            15.0 * (1.0 - (0.2 * t).cos()),
            -20.0 + 2.0 * (0.5 * t).sin(),
        );
        let vel = Vector3::new(
            6.0 * (0.3 * t).cos(),
            3.0 * (0.2 * t).sin(),
            (0.5 * t).cos(),
        );
        let acc = Vector3::new(
            -1.8 * (0.3 * t).sin(),
            0.6 * (0.2 * t).cos(),
            -0.5 * (0.5 * t).sin(),
        );
        let att = Euler::new(0.2 * (0.9 * t).sin(), 0.15 * (0.7 * t).cos(), 0.4 * t);
        let euler_rates = Vector3::new(0.18 * (0.9 * t).cos(), -0.105 * (0.7 * t).sin(), 0.4);
        let omega_body = euler_rates_from_body_rates_matrix(&att)
            .try_inverse()
            .unwrap()
            * euler_rates;
        let q = UnitQuaternion::from_euler_angles(att.roll, att.pitch, att.yaw);
        let f_body = q.inverse() * (acc - Vector3::new(0.0, 0.0, G));
        (
            LocalTruthSample {
                time: t,
                pos_in_nav: pos,
                vel_in_nav: vel,
                nav_from_body: q,
            },
            omega_body,
            f_body,
        )
    }

    /// The increments reproduce a 300 s manoeuvre: attitude and velocity to rounding,
    /// position to the telescoped trapezoidal error; and they are the physical body rate
    /// and specific force (mid-interval means agree to O(dt^2)). Negative control: a
    /// gravity 1e-4 off in the mechanization drifts metres.
    #[test]
    fn error_free_increments_reproduce_a_manoeuvre() {
        let dt = 0.01;
        let truth: Vec<_> = (0..=30_000).map(|k| analytic(k as f64 * dt).0).collect();
        let incs = local_imu_from_truth(&truth, G).unwrap();
        let mut mech = LocalLevelMechanization::new(truth[0].to_state(), G).unwrap();
        let (mut max_p, mut max_v, mut max_att): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let (mut max_w, mut max_f): (f64, f64) = (0.0, 0.0);
        for (k, inc) in incs.iter().enumerate() {
            mech.step(inc).unwrap();
            let t = &truth[k + 1];
            let s = mech.state();
            max_p = max_p.max((s.pos_in_nav - t.pos_in_nav).norm());
            max_v = max_v.max((s.vel_in_nav - t.vel_in_nav).norm());
            max_att = max_att.max(s.nav_from_body.angle_to(&t.nav_from_body));
            let (_, w_mid, f_mid) = analytic((k as f64 + 0.5) * dt);
            max_w = max_w.max((inc.mean_angular_rate() - w_mid).norm());
            max_f = max_f.max((inc.mean_specific_force() - f_mid).norm());
        }
        eprintln!(
            "300 s manoeuvre: max position error {max_p:.2e} m, velocity {max_v:.2e} m/s, \
             attitude {max_att:.2e} rad; increments vs physical mid-interval rate {max_w:.2e} rad/s, \
             specific force {max_f:.2e} m/s^2"
        );
        assert!(max_p < 1e-4);
        assert!(max_v < 1e-9);
        assert!(max_att < 1e-9);
        assert!(max_w < 1e-4 && max_f < 1e-3);

        let mut wrong = LocalLevelMechanization::new(truth[0].to_state(), G + 1e-4).unwrap();
        for inc in &incs {
            wrong.step(inc).unwrap();
        }
        let drift = (wrong.state().pos_in_nav - truth.last().unwrap().pos_in_nav).norm();
        assert!(drift > 1.0, "negative control drift {drift}");
    }

    #[test]
    fn stationary_level_imu_reads_minus_g() {
        let s = analytic(0.0).0;
        let rest = LocalTruthSample {
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::identity(),
            ..s
        };
        let truth: Vec<_> = (0..5)
            .map(|k| LocalTruthSample {
                time: k as f64 * 0.01,
                ..rest
            })
            .collect();
        for inc in local_imu_from_truth(&truth, G).unwrap() {
            assert_eq!(inc.delta_theta, Vector3::zeros());
            assert!((inc.delta_v - Vector3::new(0.0, 0.0, -G * 0.01)).amax() < 1e-15);
        }
    }

    #[test]
    fn streaming_matches_batch_and_bad_input_is_reported() {
        let truth: Vec<_> = (0..50).map(|k| analytic(k as f64 * 0.01).0).collect();
        let batch = local_imu_from_truth(&truth, G).unwrap();
        let mut inv = LocalImuFromTruth::new(G).unwrap();
        let streamed: Vec<_> = truth.iter().filter_map(|s| inv.push(s).unwrap()).collect();
        assert_eq!(batch, streamed);
        assert!(matches!(
            local_imu_from_truth(&truth[..1], G),
            Err(InsError::TruthTooShort { len: 1, min: 2 })
        ));
        let mut bad = truth[..5].to_vec();
        bad[3].time = bad[2].time;
        assert!(matches!(
            local_imu_from_truth(&bad, G),
            Err(InsError::NonIncreasingTime { index: 3, .. })
        ));
        let mut bad = truth[..5].to_vec();
        bad[2].pos_in_nav.z = f64::NAN;
        assert!(matches!(
            local_imu_from_truth(&bad, G),
            Err(InsError::NonFinite {
                what: "pos_in_nav",
                ..
            })
        ));
        assert!(LocalImuFromTruth::new(f64::NAN).is_err());
    }
}
