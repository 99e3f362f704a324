//! The two integrated-position sensors of the fusion paper (A, "Sensor models"):
//! an INS that double-integrates biased, noisy accelerations and a DVL dead
//! reckoning that integrates scale-factor-corrupted, noisy velocities.
//!
//! # Integration scheme (both sensors)
//! Raw samples are taken at the ends of each output interval `[t, t + dt]`, and
//! the interval is integrated exactly for a raw signal varying linearly in between
//! (trapezoid on the integrand):
//! - INS: `p += v dt + dt^2 (a_0 / 3 + a_1 / 6)`, `v += dt (a_0 + a_1) / 2`;
//! - DVL: `p += dt (v_0 + v_1) / 2`.
//!
//! `a_0` / `v_0` is the sample taken at the end of the previous step (or at start),
//! so each raw sample and its noise is drawn once. Noise-free, the integrators
//! reproduce truths with piecewise-linear acceleration (INS) / velocity (DVL) exactly
//! when the knots fall on the output grid, in particular constant acceleration and
//! constant velocity.
//!
//! Both work per NED axis (the spec's "per axis"; no attitude error is modelled).

use fathom_core::{Measurement, SensorId, Time};
use fathom_traj::Trajectory;
use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::{
    SensorError,
    error::{check_finite3, check_positive, check_sigma},
    noise::gauss,
};

fn gauss3(rng: &mut impl Rng, sigma: f64) -> Vector3<f64> {
    let x = gauss(rng, sigma);
    let y = gauss(rng, sigma);
    let z = gauss(rng, sigma);
    Vector3::new(x, y, z)
}

/// Unchecked INS parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InsParams {
    /// Per-axis accelerometer bias sigma `sigma_ba`, m/s^2 (bias drawn once per run).
    /// Default 2e-4.
    pub accel_bias_sigma: f64,
    /// Per-axis white accelerometer noise sigma `sigma_a`, m/s^2 per sample.
    /// Default 1e-3.
    pub accel_noise_sigma: f64,
}

impl Default for InsParams {
    fn default() -> Self {
        Self {
            accel_bias_sigma: 2e-4,
            accel_noise_sigma: 1e-3,
        }
    }
}

impl InsParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for negative or non-finite sigmas.
    pub fn check(&self) -> Result<InsConfig, SensorError> {
        Ok(InsConfig {
            accel_bias_sigma: check_sigma("ins.accel_bias_sigma", self.accel_bias_sigma)?,
            accel_noise_sigma: check_sigma("ins.accel_noise_sigma", self.accel_noise_sigma)?,
        })
    }
}

/// Validated INS parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsConfig {
    accel_bias_sigma: f64,
    accel_noise_sigma: f64,
}

/// INS integrator: `a_m = a + b_a + n_a` per axis, integrated twice (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct InsIntegrator {
    config: InsConfig,
    time: Time,
    pos_in_nav: Vector3<f64>,
    vel_in_nav: Vector3<f64>,
    accel_bias: Vector3<f64>,
    last_acc_meas: Vector3<f64>,
}

impl InsIntegrator {
    /// Starts at `t0` from the true position and velocity.
    ///
    /// Draws: bias x, y, z (3 normals), then the noise of the acceleration sample
    /// at `t0` (3 normals).
    ///
    /// # Errors
    /// [`SensorError::Traj`] when `t0` is outside the trajectory.
    pub fn start(
        config: &InsConfig,
        traj: &impl Trajectory,
        t0: Time,
        rng: &mut impl Rng,
    ) -> Result<Self, SensorError> {
        let st = traj.state_at(t0)?;
        let accel_bias = gauss3(rng, config.accel_bias_sigma);
        let last_acc_meas = st.acc_in_nav + accel_bias + gauss3(rng, config.accel_noise_sigma);
        Ok(Self {
            config: *config,
            time: t0,
            pos_in_nav: st.pos_in_nav,
            vel_in_nav: st.vel_in_nav,
            accel_bias,
            last_acc_meas,
        })
    }

    /// Integrates from the current time to `time + dt` and returns the position
    /// measurement there (`true_value` = true position, stamp = sample time).
    ///
    /// Draws the noise of the new acceleration sample (3 normals).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `dt` is not positive;
    /// [`SensorError::Traj`] when `time + dt` is outside the trajectory.
    pub fn step(
        &mut self,
        traj: &impl Trajectory,
        dt: f64,
        rng: &mut impl Rng,
    ) -> Result<Measurement<Vector3<f64>>, SensorError> {
        let dt = check_positive("ins dt", dt)?;
        let t1 = self.time + dt;
        let st = traj.state_at(t1)?;
        let a0 = self.last_acc_meas;
        let a1 = st.acc_in_nav + self.accel_bias + gauss3(rng, self.config.accel_noise_sigma);
        self.pos_in_nav += self.vel_in_nav * dt + (a0 / 3.0 + a1 / 6.0) * (dt * dt);
        self.vel_in_nav += (a0 + a1) * (0.5 * dt);
        self.last_acc_meas = a1;
        self.time = t1;
        Ok(Measurement {
            sensor: SensorId::Ins,
            sample_time: t1,
            stamp: t1,
            value: self.pos_in_nav,
            true_value: st.pos_in_nav,
        })
    }

    /// Resets the integrator's position and velocity (the EFF feedback). The bias
    /// and the latest acceleration sample are kept.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when a component is not finite.
    pub fn reset(
        &mut self,
        pos_in_nav: Vector3<f64>,
        vel_in_nav: Vector3<f64>,
    ) -> Result<(), SensorError> {
        self.pos_in_nav = check_finite3("ins reset position", &pos_in_nav)?;
        self.vel_in_nav = check_finite3("ins reset velocity", &vel_in_nav)?;
        Ok(())
    }

    /// Integrated position, NED, m.
    pub fn pos_in_nav(&self) -> Vector3<f64> {
        self.pos_in_nav
    }

    /// Integrated velocity, NED, m/s.
    pub fn vel_in_nav(&self) -> Vector3<f64> {
        self.vel_in_nav
    }

    /// Time of the integrator state, s.
    pub fn time(&self) -> Time {
        self.time
    }

    /// The accelerometer bias drawn for this run, m/s^2.
    pub fn accel_bias(&self) -> Vector3<f64> {
        self.accel_bias
    }
}

/// Unchecked DVL dead-reckoning parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DvlDrParams {
    /// Half width `h` of the per-axis scale-factor error `s ~ U(-h, h)` drawn once per
    /// run. Default 0.002 (0.2 %).
    pub scale_half_width: f64,
    /// Per-axis white velocity noise sigma, m/s per sample. Default 0.02.
    pub vel_noise_sigma: f64,
}

impl Default for DvlDrParams {
    fn default() -> Self {
        Self {
            scale_half_width: 0.002,
            vel_noise_sigma: 0.02,
        }
    }
}

impl DvlDrParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for negative or non-finite values.
    pub fn check(&self) -> Result<DvlDrConfig, SensorError> {
        Ok(DvlDrConfig {
            scale_half_width: check_sigma("dvl_dr.scale_half_width", self.scale_half_width)?,
            vel_noise_sigma: check_sigma("dvl_dr.vel_noise_sigma", self.vel_noise_sigma)?,
        })
    }
}

/// Validated DVL dead-reckoning parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlDrConfig {
    scale_half_width: f64,
    vel_noise_sigma: f64,
}

/// DVL dead reckoning: `v_m = (1 + s) v + n_v` per axis, integrated once.
#[derive(Debug, Clone, PartialEq)]
pub struct DvlDeadReckoning {
    config: DvlDrConfig,
    time: Time,
    pos_in_nav: Vector3<f64>,
    scale_factor: Vector3<f64>,
    last_vel_meas: Vector3<f64>,
}

impl DvlDeadReckoning {
    /// Starts at `t0` from the true position.
    ///
    /// Draws: scale factors x, y, z (3 uniform `f64`, `s = h (2u - 1)`), then the
    /// noise of the velocity sample at `t0` (3 normals).
    ///
    /// # Errors
    /// [`SensorError::Traj`] when `t0` is outside the trajectory.
    pub fn start(
        config: &DvlDrConfig,
        traj: &impl Trajectory,
        t0: Time,
        rng: &mut impl Rng,
    ) -> Result<Self, SensorError> {
        let st = traj.state_at(t0)?;
        let h = config.scale_half_width;
        let mut scale_factor = Vector3::zeros();
        for i in 0..3 {
            let u: f64 = rng.random();
            scale_factor[i] = h * (2.0 * u - 1.0);
        }
        let mut dr = Self {
            config: *config,
            time: t0,
            pos_in_nav: st.pos_in_nav,
            scale_factor,
            last_vel_meas: Vector3::zeros(),
        };
        dr.last_vel_meas = dr.measure_vel(&st.vel_in_nav, rng);
        Ok(dr)
    }

    fn measure_vel(&self, vel: &Vector3<f64>, rng: &mut impl Rng) -> Vector3<f64> {
        vel + self.scale_factor.component_mul(vel) + gauss3(rng, self.config.vel_noise_sigma)
    }

    /// Integrates from the current time to `time + dt` and returns the position
    /// measurement there. Draws the noise of the new velocity sample (3 normals).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when `dt` is not positive;
    /// [`SensorError::Traj`] when `time + dt` is outside the trajectory.
    pub fn step(
        &mut self,
        traj: &impl Trajectory,
        dt: f64,
        rng: &mut impl Rng,
    ) -> Result<Measurement<Vector3<f64>>, SensorError> {
        let dt = check_positive("dvl dead reckoning dt", dt)?;
        let t1 = self.time + dt;
        let st = traj.state_at(t1)?;
        let v1 = self.measure_vel(&st.vel_in_nav, rng);
        self.pos_in_nav += (self.last_vel_meas + v1) * (0.5 * dt);
        self.last_vel_meas = v1;
        self.time = t1;
        Ok(Measurement {
            sensor: SensorId::DvlDeadReckoning,
            sample_time: t1,
            stamp: t1,
            value: self.pos_in_nav,
            true_value: st.pos_in_nav,
        })
    }

    /// Resets the integrated position.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when a component is not finite.
    pub fn reset(&mut self, pos_in_nav: Vector3<f64>) -> Result<(), SensorError> {
        self.pos_in_nav = check_finite3("dvl dead reckoning reset position", &pos_in_nav)?;
        Ok(())
    }

    /// Integrated position, NED, m.
    pub fn pos_in_nav(&self) -> Vector3<f64> {
        self.pos_in_nav
    }

    /// Latest measured velocity, NED, m/s.
    pub fn vel_meas_in_nav(&self) -> Vector3<f64> {
        self.last_vel_meas
    }

    /// Time of the integrator state, s.
    pub fn time(&self) -> Time {
        self.time
    }

    /// The per-axis scale-factor errors `s` drawn for this run.
    pub fn scale_factor(&self) -> Vector3<f64> {
        self.scale_factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use fathom_core::frames::Euler;
    use fathom_traj::{TrajError, TrueState};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Constant-acceleration truth `p = p0 + v0 t + a t^2 / 2`.
    struct ConstAcc {
        p0: Vector3<f64>,
        v0: Vector3<f64>,
        a: Vector3<f64>,
    }

    impl Trajectory for ConstAcc {
        fn start_time(&self) -> Time {
            0.0
        }
        fn end_time(&self) -> Time {
            2000.0
        }
        fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
            if !(0.0..=2000.0).contains(&t) {
                return Err(TrajError::OutOfRange {
                    t,
                    start: 0.0,
                    end: 2000.0,
                });
            }
            Ok(TrueState {
                time: t,
                pos_in_nav: self.p0 + self.v0 * t + self.a * (0.5 * t * t),
                vel_in_nav: self.v0 + self.a * t,
                acc_in_nav: self.a,
                attitude: Euler::default(),
                omega_body: Vector3::zeros(),
            })
        }
    }

    fn truth(a: Vector3<f64>) -> ConstAcc {
        ConstAcc {
            p0: Vector3::new(10.0, -5.0, 20.0),
            v0: Vector3::new(1.0, 0.5, -0.1),
            a,
        }
    }

    #[test]
    fn noise_free_ins_reproduces_constant_acceleration() {
        let traj = truth(Vector3::new(0.01, -0.02, 0.003));
        let cfg = InsParams {
            accel_bias_sigma: 0.0,
            accel_noise_sigma: 0.0,
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(40);
        let mut ins = InsIntegrator::start(&cfg, &traj, 0.0, &mut rng).unwrap();
        for _ in 0..100 {
            let m = ins.step(&traj, 1.0, &mut rng).unwrap();
            assert_eq!(m.sensor, SensorId::Ins);
            assert_abs_diff_eq!(m.value, m.true_value, epsilon = 1e-9);
        }
        let st = traj.state_at(100.0).unwrap();
        assert_abs_diff_eq!(ins.vel_in_nav(), st.vel_in_nav, epsilon = 1e-9);
        assert_eq!(ins.time(), 100.0);
    }

    #[test]
    fn noise_free_dvl_reproduces_constant_velocity() {
        let traj = truth(Vector3::zeros());
        let cfg = DvlDrParams {
            scale_half_width: 0.0,
            vel_noise_sigma: 0.0,
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        let mut dr = DvlDeadReckoning::start(&cfg, &traj, 0.0, &mut rng).unwrap();
        for _ in 0..1000 {
            let m = dr.step(&traj, 1.0, &mut rng).unwrap();
            assert_eq!(m.sensor, SensorId::DvlDeadReckoning);
            assert_abs_diff_eq!(m.value, m.true_value, epsilon = 1e-9);
        }
    }

    #[test]
    fn ins_bias_only_error_grows_quadratically() {
        let traj = truth(Vector3::new(0.01, 0.0, -0.002));
        let cfg = InsParams {
            accel_bias_sigma: 2e-4,
            accel_noise_sigma: 0.0,
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        let mut ins = InsIntegrator::start(&cfg, &traj, 0.0, &mut rng).unwrap();
        let b = ins.accel_bias();
        assert!(b.iter().all(|x| *x != 0.0));
        for k in 1..=1000 {
            let m = ins.step(&traj, 1.0, &mut rng).unwrap();
            let t = k as f64;
            assert_abs_diff_eq!(m.value - m.true_value, b * (0.5 * t * t), epsilon = 1e-6);
        }
        // Negative control: a linear-in-time error model does not fit.
        let err = ins.pos_in_nav() - traj.state_at(1000.0).unwrap().pos_in_nav;
        assert!((err - b * 1000.0).norm() > 1.0);
    }

    #[test]
    fn dvl_scale_factor_error_grows_linearly() {
        let traj = truth(Vector3::zeros());
        let cfg = DvlDrParams {
            scale_half_width: 0.002,
            vel_noise_sigma: 0.0,
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(43);
        let mut dr = DvlDeadReckoning::start(&cfg, &traj, 0.0, &mut rng).unwrap();
        let s = dr.scale_factor();
        assert!(s.iter().all(|x| x.abs() <= 0.002 && *x != 0.0));
        let m = (0..500)
            .map(|_| dr.step(&traj, 1.0, &mut rng).unwrap())
            .last();
        let m = m.unwrap();
        assert_abs_diff_eq!(
            m.value - m.true_value,
            s.component_mul(&traj.v0) * 500.0,
            epsilon = 1e-9
        );
    }

    #[test]
    fn reset_sets_state_exactly() {
        let traj = truth(Vector3::new(0.01, 0.0, 0.0));
        let cfg = InsParams::default().check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(44);
        let mut ins = InsIntegrator::start(&cfg, &traj, 0.0, &mut rng).unwrap();
        ins.step(&traj, 1.0, &mut rng).unwrap();
        let (p, v) = (Vector3::new(1.0, 2.0, 3.0), Vector3::new(-0.5, 0.25, 0.125));
        ins.reset(p, v).unwrap();
        assert_eq!(ins.pos_in_nav(), p);
        assert_eq!(ins.vel_in_nav(), v);
        assert!(ins.reset(Vector3::new(f64::NAN, 0.0, 0.0), v).is_err());
        let mut dr = DvlDeadReckoning::start(
            &DvlDrParams::default().check().unwrap(),
            &traj,
            0.0,
            &mut rng,
        )
        .unwrap();
        dr.reset(p).unwrap();
        assert_eq!(dr.pos_in_nav(), p);
    }

    #[test]
    fn errors_and_noise_level() {
        let traj = truth(Vector3::zeros());
        let mut rng = ChaCha8Rng::seed_from_u64(45);
        assert!(
            InsParams {
                accel_bias_sigma: -1.0,
                accel_noise_sigma: 0.0
            }
            .check()
            .is_err()
        );
        assert!(
            DvlDrParams {
                scale_half_width: f64::NAN,
                vel_noise_sigma: 0.0
            }
            .check()
            .is_err()
        );
        let cfg = InsParams::default().check().unwrap();
        let mut ins = InsIntegrator::start(&cfg, &traj, 1999.5, &mut rng).unwrap();
        assert!(ins.step(&traj, 0.0, &mut rng).is_err());
        assert!(matches!(
            ins.step(&traj, 1.0, &mut rng),
            Err(SensorError::Traj(_))
        ));
        assert!(InsIntegrator::start(&cfg, &traj, -1.0, &mut rng).is_err());
        // Velocity noise only: the DVL position error after K unit steps is
        // sum dt (n_k + n_{k+1}) / 2, variance sigma^2 (K - 1/2) per axis.
        let cfg = DvlDrParams {
            scale_half_width: 0.0,
            vel_noise_sigma: 0.02,
        }
        .check()
        .unwrap();
        let k = 20;
        let errs: Vec<f64> = (0..5000)
            .map(|_| {
                let mut dr = DvlDeadReckoning::start(&cfg, &traj, 0.0, &mut rng).unwrap();
                let mut m = None;
                for _ in 0..k {
                    m = Some(dr.step(&traj, 1.0, &mut rng).unwrap());
                }
                let m = m.unwrap();
                m.value.x - m.true_value.x
            })
            .collect();
        let design = 0.02f64.powi(2) * (k as f64 - 0.5);
        assert!(crate::noise::tests::zero_mean_var_ok(&errs, design, 1.0));
        assert!(!crate::noise::tests::zero_mean_var_ok(
            &errs,
            1.2 * design,
            1.0
        ));
    }
}
