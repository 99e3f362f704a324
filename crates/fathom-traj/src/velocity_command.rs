//! The velocity-command kinematic motion of the `beacons` experiment (spec B,
//! "Robot motion"; Han et al. 2016, Tables 1 and 9): a body-frame velocity command
//! plus Gaussian motion noise per step, integrated with 6-DOF kinematics.
//!
//! # Model
//!
//! Motion samples at `t_k = k dt`, `k = 0..=N`, `N = round(duration / dt)`. Each
//! sample carries the *actual* body velocity of its step,
//! `nu_k = (u, v, w, p, q, r)_k = command + sigma ∘ n_k`, `n_k ~ N(0, I_6)`, and the
//! state is propagated over the step with that velocity (explicit Euler, as the
//! paper's Table 5 line 6):
//!
//! ```text
//! pos(t_k + tau) = pos_k + tau * C_b^n(att_k) (u, v, w)_k
//! att(t_k + tau) = att_k + tau * E(att_k) (p, q, r)_k        (E: euler_rates_from_body_rates)
//! ```
//!
//! for `0 <= tau <= dt`; sample `k+1` is this with `tau = dt` (yaw wrapped to
//! `(-pi, pi]`). [`Trajectory::state_at`] uses the same formula from the sample at
//! or before `t`, so a sensor sampled between motion steps sees the exact state
//! (`state_at(t_k)` reproduces sample `k`, and the state is continuous in `t`).
//!
//! In the returned [`TrueState`]: `vel_in_nav = C_b^n(att_k) (u, v, w)_k`, the exact
//! time derivative of the position within the step; `omega_body = (p, q, r)_k`;
//! `acc_in_nav = 0` (the velocity is piecewise constant; its true derivative is a
//! train of impulses at the step boundaries). Because the attitude turns within the
//! step, `TrueState::vel_in_body()` differs from `(u, v, w)_k` by a rotation of at most
//! `|omega| dt` (0.005 rad with the paper's values); the step's actual body velocity
//! itself is [`VelocityCommandMotion::body_velocity_at`].
//!
//! Random draws: 6 standard normals per sample, in the order `u, v, w, p, q, r`, for
//! `k = 0..=N` (the last sample's velocity is only reported, never integrated);
//! draws do not depend on the sigma values, so a zero sigma still consumes them.

use fathom_core::{
    Time,
    error::{ensure_finite, ensure_non_negative, ensure_positive},
    frames::{Euler, euler_rates_from_body_rates, nav_from_body},
    units::wrap_pi,
};
use nalgebra::Vector3;
use rand::Rng;
use rand_distr::StandardNormal;

use crate::{TrajError, Trajectory, TrueState};

/// Parameters of the velocity-command motion (SI units; body velocity order
/// `(u, v, w, p, q, r)` in m/s and rad/s). Validate with [`VelocityCommandParams::check`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VelocityCommandParams {
    /// Run duration, s (paper: 180).
    pub duration: f64,
    /// Motion step, s (paper: 0.01).
    pub dt: f64,
    /// Commanded body velocity `(u, v, w, p, q, r)` (paper: `(0.5, 0, 0.2, 0, 0, 0.5)`).
    pub command: [f64; 6],
    /// Standard deviation of the per-step velocity noise, same order (paper:
    /// `(0.10, 0, 0.15, 0, 0, 0.10)`).
    pub motion_sigma: [f64; 6],
    /// Initial position in NED, m (paper: origin).
    pub initial_pos_in_nav: Vector3<f64>,
    /// Initial attitude (paper: all zero, heading 0 = north).
    pub initial_attitude: Euler,
}

impl Default for VelocityCommandParams {
    /// The paper's values (Table 1, Table 9).
    fn default() -> Self {
        Self {
            duration: 180.0,
            dt: 0.01,
            command: [0.5, 0.0, 0.2, 0.0, 0.0, 0.5],
            motion_sigma: [0.10, 0.0, 0.15, 0.0, 0.0, 0.10],
            initial_pos_in_nav: Vector3::zeros(),
            initial_attitude: Euler::default(),
        }
    }
}

/// [`VelocityCommandParams`] that passed [`VelocityCommandParams::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedVelocityCommandParams(VelocityCommandParams);

impl CheckedVelocityCommandParams {
    /// The validated parameters.
    pub fn params(&self) -> &VelocityCommandParams {
        &self.0
    }

    /// Number of motion steps `N = round(duration / dt)` (samples: `N + 1`).
    pub fn n_steps(&self) -> usize {
        (self.0.duration / self.0.dt).round() as usize
    }
}

const SIGMA_NAMES: [&str; 6] = [
    "motion_sigma.u",
    "motion_sigma.v",
    "motion_sigma.w",
    "motion_sigma.p",
    "motion_sigma.q",
    "motion_sigma.r",
];

impl VelocityCommandParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`TrajError::Core`] for a non-positive or non-finite `dt` or `duration`, a
    /// negative or non-finite sigma (named by component), or a non-finite command,
    /// initial position or attitude; [`TrajError::InvalidParameter`] when `duration <
    /// dt` (no step) or the initial pitch is not within (-90, 90) deg.
    pub fn check(&self) -> Result<CheckedVelocityCommandParams, TrajError> {
        ensure_positive("dt", self.dt)?;
        ensure_positive("duration", self.duration)?;
        for (name, &s) in SIGMA_NAMES.iter().zip(&self.motion_sigma) {
            ensure_non_negative(name, s)?;
        }
        ensure_finite("command", self.command.iter())?;
        ensure_finite("initial_pos_in_nav", self.initial_pos_in_nav.iter())?;
        ensure_finite("initial_attitude", self.initial_attitude.to_vector().iter())?;
        if (self.duration / self.dt).round() < 1.0 {
            return Err(TrajError::InvalidParameter {
                field: "duration".into(),
                reason: format!(
                    "{} s is shorter than one step dt = {} s",
                    self.duration, self.dt
                ),
            });
        }
        if self.initial_attitude.pitch.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(TrajError::InvalidParameter {
                field: "initial_attitude".into(),
                reason: format!(
                    "pitch {} rad is at or beyond +/- 90 deg (Euler rates singular)",
                    self.initial_attitude.pitch
                ),
            });
        }
        Ok(CheckedVelocityCommandParams(self.clone()))
    }
}

/// One motion sample: the state at `time` and the actual body velocity applied over
/// the following step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSample {
    /// Sample time `k dt`, s.
    pub time: Time,
    /// Position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Attitude (yaw wrapped to `(-pi, pi]`).
    pub attitude: Euler,
    /// Actual linear body velocity `(u, v, w)` of the step, m/s.
    pub vel_in_body: Vector3<f64>,
    /// Actual body angular rate `(p, q, r)` of the step, rad/s.
    pub omega_body: Vector3<f64>,
}

impl MotionSample {
    /// The state `tau` seconds after this sample, propagated with this sample's
    /// velocity (module docs).
    fn propagate(&self, tau: f64) -> (Vector3<f64>, Euler) {
        let pos = self.pos_in_nav + tau * (nav_from_body(&self.attitude) * self.vel_in_body);
        let rates = euler_rates_from_body_rates(&self.attitude, &self.omega_body);
        let a = self.attitude.to_vector() + tau * rates;
        (pos, Euler::new(a.x, a.y, wrap_pi(a.z)))
    }
}

/// The generated velocity-command motion: its samples and a [`Trajectory`] over them.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityCommandMotion {
    dt: f64,
    samples: Vec<MotionSample>,
}

impl VelocityCommandMotion {
    /// Generates the motion with velocity noise drawn from `rng` (module docs).
    ///
    /// # Errors
    /// [`TrajError::Core`] (`NonFinite`) when the propagated state stops being
    /// finite (e.g. the pitch driven to +/- 90 deg by the commanded/noisy `q`).
    pub fn generate(
        params: &CheckedVelocityCommandParams,
        rng: &mut impl Rng,
    ) -> Result<Self, TrajError> {
        let sigma = params.params().motion_sigma;
        Self::simulate(params, |nu| {
            for (x, s) in nu.iter_mut().zip(sigma) {
                let n: f64 = rng.sample(StandardNormal);
                *x += s * n;
            }
        })
    }

    /// The commanded, noise-free motion (no random draws): with the paper's command
    /// a helix of radius `u / r = 1 m` descending at `w = 0.2 m/s`.
    ///
    /// # Errors
    /// As [`VelocityCommandMotion::generate`].
    pub fn commanded(params: &CheckedVelocityCommandParams) -> Result<Self, TrajError> {
        Self::simulate(params, |_| {})
    }

    fn simulate(
        params: &CheckedVelocityCommandParams,
        mut add_noise: impl FnMut(&mut [f64; 6]),
    ) -> Result<Self, TrajError> {
        let p = params.params();
        let n = params.n_steps();
        let mut samples = Vec::with_capacity(n + 1);
        let mut pos = p.initial_pos_in_nav;
        let mut att = Euler::new(
            p.initial_attitude.roll,
            p.initial_attitude.pitch,
            wrap_pi(p.initial_attitude.yaw),
        );
        for k in 0..=n {
            let mut nu = p.command;
            add_noise(&mut nu);
            let sample = MotionSample {
                time: k as f64 * p.dt,
                pos_in_nav: pos,
                attitude: att,
                vel_in_body: Vector3::new(nu[0], nu[1], nu[2]),
                omega_body: Vector3::new(nu[3], nu[4], nu[5]),
            };
            let (next_pos, next_att) = sample.propagate(p.dt);
            samples.push(sample);
            let check = [
                next_pos.x,
                next_pos.y,
                next_pos.z,
                next_att.roll,
                next_att.pitch,
                next_att.yaw,
            ];
            ensure_finite(&format!("motion state at step {}", k + 1), check.iter())?;
            pos = next_pos;
            att = next_att;
        }
        Ok(Self { dt: p.dt, samples })
    }

    /// The motion samples `k = 0..=N` (e.g. to plot the path).
    pub fn samples(&self) -> &[MotionSample] {
        &self.samples
    }

    /// Motion step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Index of the sample at or before `t` (the last sample for `t = end_time`).
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] when `t` is not finite or outside the run.
    pub fn sample_index_at(&self, t: Time) -> Result<usize, TrajError> {
        let (start, end) = (self.start_time(), self.end_time());
        if !(t >= start && t <= end) {
            return Err(TrajError::OutOfRange { t, start, end });
        }
        let last = self.samples.len() - 1;
        let mut k = (((t - start) / self.dt).floor() as usize).min(last);
        // Guard against rounding of t / dt near a sample time.
        while k > 0 && self.samples[k].time > t {
            k -= 1;
        }
        while k < last && self.samples[k + 1].time <= t {
            k += 1;
        }
        Ok(k)
    }

    /// The actual body velocity `(u, v, w)` and rate `(p, q, r)` applied at `t` (those
    /// of the sample at or before `t`).
    ///
    /// # Errors
    /// As [`VelocityCommandMotion::sample_index_at`].
    pub fn body_velocity_at(&self, t: Time) -> Result<(Vector3<f64>, Vector3<f64>), TrajError> {
        let s = &self.samples[self.sample_index_at(t)?];
        Ok((s.vel_in_body, s.omega_body))
    }
}

impl Trajectory for VelocityCommandMotion {
    fn start_time(&self) -> Time {
        self.samples[0].time
    }

    fn end_time(&self) -> Time {
        self.samples[self.samples.len() - 1].time
    }

    fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
        let s = &self.samples[self.sample_index_at(t)?];
        let (pos_in_nav, attitude) = s.propagate(t - s.time);
        Ok(TrueState {
            time: t,
            pos_in_nav,
            vel_in_nav: nav_from_body(&s.attitude) * s.vel_in_body,
            acc_in_nav: Vector3::zeros(),
            attitude,
            omega_body: s.omega_body,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::{assert_abs_diff_eq, assert_relative_eq};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    fn paper() -> CheckedVelocityCommandParams {
        VelocityCommandParams::default().check().unwrap()
    }

    #[test]
    fn zero_noise_is_the_helix() {
        let m = VelocityCommandMotion::commanded(&paper()).unwrap();
        assert_eq!(m.samples().len(), 18_001);
        assert_eq!(m.end_time(), 180.0);
        let (u, w, r, dt) = (0.5, 0.2, 0.5, 0.01);
        let alpha = r * dt;
        for k in [0_usize, 1, 314, 6283, 9000, 18_000] {
            let s = &m.samples()[k];
            let t = k as f64 * dt;
            // Exact closed form of the Euler-integrated sums sum_{j<k} dt u (cos, sin)(j alpha).
            let (x_d, y_d) = if k == 0 {
                (0.0, 0.0)
            } else {
                let g = (k as f64 * alpha / 2.0).sin() / (alpha / 2.0).sin();
                let ph = (k as f64 - 1.0) * alpha / 2.0;
                (dt * u * g * ph.cos(), dt * u * g * ph.sin())
            };
            assert_abs_diff_eq!(s.pos_in_nav.x, x_d, epsilon = 1e-9);
            assert_abs_diff_eq!(s.pos_in_nav.y, y_d, epsilon = 1e-9);
            // Continuous helix: radius u/r = 1 m about (0, 1), depth w t; Euler
            // integration is first order, error below u dt.
            let rad = u / r;
            assert_abs_diff_eq!(s.pos_in_nav.x, rad * (r * t).sin(), epsilon = u * dt);
            assert_abs_diff_eq!(
                s.pos_in_nav.y,
                rad * (1.0 - (r * t).cos()),
                epsilon = u * dt
            );
            assert_abs_diff_eq!(s.pos_in_nav.z, w * t, epsilon = 1e-9);
            assert_abs_diff_eq!(s.attitude.yaw, wrap_pi(r * t), epsilon = 1e-9);
            let centre = Vector3::new(0.0, rad, s.pos_in_nav.z);
            assert_abs_diff_eq!((s.pos_in_nav - centre).norm(), 1.0, epsilon = u * dt);
        }
        assert_abs_diff_eq!(m.samples()[18_000].pos_in_nav.z, 36.0, epsilon = 1e-9);
    }

    #[test]
    fn noisy_run_is_deterministic_per_seed() {
        let p = paper();
        let a = VelocityCommandMotion::generate(&p, &mut ChaCha8Rng::seed_from_u64(11)).unwrap();
        let b = VelocityCommandMotion::generate(&p, &mut ChaCha8Rng::seed_from_u64(11)).unwrap();
        let c = VelocityCommandMotion::generate(&p, &mut ChaCha8Rng::seed_from_u64(12)).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.samples()[100].vel_in_body, c.samples()[100].vel_in_body);
        assert_ne!(
            a.samples()[18_000].pos_in_nav,
            c.samples()[18_000].pos_in_nav
        );
        // The noisy path stays near the commanded helix depth scale.
        let z = a.samples()[18_000].pos_in_nav.z;
        assert!((z - 36.0).abs() < 2.0, "{z}");
    }

    #[test]
    fn state_between_samples_is_linear_propagation() {
        let m =
            VelocityCommandMotion::generate(&paper(), &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
        for k in [0_usize, 5, 777, 17_999] {
            let s = m.samples()[k];
            let t = s.time + 0.37 * m.dt();
            let st = m.state_at(t).unwrap();
            let c = nav_from_body(&s.attitude);
            let expect = s.pos_in_nav + (t - s.time) * (c * s.vel_in_body);
            assert_relative_eq!(st.pos_in_nav, expect, epsilon = 1e-12);
            assert_abs_diff_eq!(
                st.attitude.yaw,
                wrap_pi(s.attitude.yaw + (t - s.time) * s.omega_body.z),
                epsilon = 1e-12
            );
            assert_relative_eq!(st.vel_in_nav, c * s.vel_in_body, epsilon = 1e-12);
            assert_eq!(st.omega_body, s.omega_body);
            assert_eq!(st.acc_in_nav, Vector3::zeros());
            assert_eq!(
                m.body_velocity_at(t).unwrap(),
                (s.vel_in_body, s.omega_body)
            );
            // At the next sample time the state is that sample (continuity).
            let next = m.samples()[k + 1];
            let sn = m.state_at(next.time).unwrap();
            assert_relative_eq!(sn.pos_in_nav, next.pos_in_nav, epsilon = 1e-12);
            // Just before it, the propagation from sample k lands on the same point.
            let before = m.state_at(next.time - 1e-9).unwrap();
            assert_relative_eq!(before.pos_in_nav, next.pos_in_nav, epsilon = 1e-8);
        }
        assert!(matches!(
            m.state_at(180.001),
            Err(TrajError::OutOfRange { .. })
        ));
        assert!(m.state_at(-1e-6).is_err());
        assert!(m.state_at(f64::NAN).is_err());
        assert!(m.state_at(180.0).is_ok());
    }

    /// Two-sided 99.9 % chi-square check that `noise` (known zero mean) has standard
    /// deviation `sigma`: `sum(n^2) / sigma^2 ~ chi2(N)`.
    fn variance_matches(noise: &[f64], sigma: f64) -> bool {
        let n = noise.len() as f64;
        let stat = noise.iter().map(|x| x * x).sum::<f64>() / (sigma * sigma);
        let chi2 = ChiSquared::new(n).unwrap();
        let (lo, hi) = (chi2.inverse_cdf(0.0005), chi2.inverse_cdf(0.9995));
        stat >= lo && stat <= hi
    }

    #[test]
    fn applied_noise_has_the_designed_sigma() {
        let p = paper();
        let m = VelocityCommandMotion::generate(&p, &mut ChaCha8Rng::seed_from_u64(2016)).unwrap();
        let cmd = p.params().command;
        let sigma = p.params().motion_sigma;
        for i in 0..6 {
            let noise: Vec<f64> = m
                .samples()
                .iter()
                .map(|s| {
                    let nu = if i < 3 {
                        s.vel_in_body[i]
                    } else {
                        s.omega_body[i - 3]
                    };
                    nu - cmd[i]
                })
                .collect();
            if sigma[i] == 0.0 {
                assert!(noise.iter().all(|&x| x == 0.0), "component {i}");
            } else {
                assert!(variance_matches(&noise, sigma[i]), "component {i}");
                // Negative control: a 10 % wrong sigma fails the same check.
                assert!(!variance_matches(&noise, 1.1 * sigma[i]), "component {i}");
                assert!(!variance_matches(&noise, 0.9 * sigma[i]), "component {i}");
            }
        }
    }

    #[test]
    fn params_check() {
        assert!(VelocityCommandParams::default().check().is_ok());
        let bad = |f: fn(&mut VelocityCommandParams)| {
            let mut p = VelocityCommandParams::default();
            f(&mut p);
            p.check().unwrap_err()
        };
        assert!(matches!(bad(|p| p.dt = 0.0), TrajError::Core(_)));
        assert!(matches!(bad(|p| p.dt = f64::NAN), TrajError::Core(_)));
        assert!(matches!(bad(|p| p.duration = -1.0), TrajError::Core(_)));
        let e = bad(|p| p.motion_sigma[2] = -0.1);
        assert!(e.to_string().contains("motion_sigma.w"), "{e}");
        assert!(matches!(
            bad(|p| p.command[5] = f64::INFINITY),
            TrajError::Core(_)
        ));
        assert!(matches!(
            bad(|p| p.initial_pos_in_nav.x = f64::NAN),
            TrajError::Core(_)
        ));
        assert!(matches!(
            bad(|p| p.duration = 0.001),
            TrajError::InvalidParameter { field, .. } if field == "duration"
        ));
        assert!(matches!(
            bad(|p| p.initial_attitude.pitch = 2.0),
            TrajError::InvalidParameter { field, .. } if field == "initial_attitude"
        ));
    }

    #[test]
    fn overflowing_state_is_an_error_not_a_panic() {
        let p = VelocityCommandParams {
            command: [1.5e308, 0.0, 0.0, 0.0, 0.0, 0.0],
            motion_sigma: [0.0; 6],
            duration: 3.0,
            dt: 1.0,
            ..Default::default()
        };
        let err = VelocityCommandMotion::commanded(&p.check().unwrap()).unwrap_err();
        assert!(
            matches!(&err, TrajError::Core(fathom_core::CoreError::NonFinite { what, .. }) if what.contains("step 2")),
            "{err}"
        );
    }
}
