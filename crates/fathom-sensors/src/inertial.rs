//! IMU error model for strapdown simulation (spec C, `vkf`): per-axis turn-on bias,
//! bias instability as a first-order Gauss-Markov process, angle / velocity random
//! walk and scale factor, applied to error-free IMU increments
//! `(delta_theta, delta_v)` over `dt`.
//!
//! Parameters are given in the units of a data sheet ([`ImuSpecParams`]: deg/hr,
//! deg/sqrt(hr), mg, m/s/sqrt(s), ppm) and converted to SI **once**, in
//! [`ImuSpecParams::check`], with the named conversions of [`fathom_core::units`].
//!
//! # Model (per axis `i`, one interval of length `dt`)
//!
//! ```text
//! delta_theta_meas_i = (1 + s_g,i) delta_theta_i + (b_g,i + m_g,i) dt + sigma_arw sqrt(dt) z
//! delta_v_meas_i     = (1 + s_a,i) delta_v_i     + (b_a,i + m_a,i) dt + sigma_vrw sqrt(dt) z
//! m_k = exp(-dt/tau) m_{k-1} + sigma_bi sqrt(1 - exp(-2 dt/tau)) z      (Gauss-Markov)
//! ```
//!
//! `b` (turn-on bias) and `s` (scale-factor error) are drawn once per run from
//! `N(0, sigma^2)`; the Gauss-Markov part `m` starts from its stationary
//! distribution. The crate does not depend on `fathom-ins`: increments are passed as
//! plain vectors.

use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::{check_positive, check_sigma};
use crate::noise::gauss;

/// IMU error figures in data-sheet units (1 sigma, same on the three axes).
/// Validate and convert with [`ImuSpecParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImuSpecParams {
    /// Gyro turn-on bias, deg/hr.
    pub gyro_bias_deg_per_hr: f64,
    /// Gyro bias instability (Gauss-Markov sigma), deg/hr.
    pub gyro_bias_instability_deg_per_hr: f64,
    /// Correlation time of the gyro bias instability, s.
    pub gyro_bias_corr_time_s: f64,
    /// Gyro angle random walk, deg/sqrt(hr).
    pub gyro_arw_deg_per_sqrt_hr: f64,
    /// Gyro scale-factor error, ppm.
    pub gyro_scale_factor_ppm: f64,
    /// Accelerometer turn-on bias, mg.
    pub accel_bias_mg: f64,
    /// Accelerometer bias instability (Gauss-Markov sigma), mg.
    pub accel_bias_instability_mg: f64,
    /// Correlation time of the accelerometer bias instability, s.
    pub accel_bias_corr_time_s: f64,
    /// Accelerometer velocity random walk, m/s/sqrt(s).
    pub accel_vrw_mps_per_sqrt_s: f64,
    /// Accelerometer scale-factor error, ppm.
    pub accel_scale_factor_ppm: f64,
}

impl ImuSpecParams {
    /// Honeywell HG1700 class figures as quoted by the paper (spec C): gyro bias
    /// 1 deg/hr, ARW 0.125 deg/sqrt(hr), accel bias 1 mg, VRW 3.3e-4 m/s/sqrt(s)
    /// (0.065 ft/s/sqrt(hr)), scale factors 150 / 300 ppm. Bias instability (not
    /// quoted): 10 % of the turn-on bias with a 600 s correlation time (a setting).
    pub fn hg1700() -> Self {
        Self {
            gyro_bias_deg_per_hr: 1.0,
            gyro_bias_instability_deg_per_hr: 0.1,
            gyro_bias_corr_time_s: 600.0,
            gyro_arw_deg_per_sqrt_hr: 0.125,
            gyro_scale_factor_ppm: 150.0,
            accel_bias_mg: 1.0,
            accel_bias_instability_mg: 0.1,
            accel_bias_corr_time_s: 600.0,
            accel_vrw_mps_per_sqrt_s: 3.3e-4,
            accel_scale_factor_ppm: 300.0,
        }
    }

    /// Every figure (not the correlation times) multiplied by `factor`; the paper's
    /// "0.1 deg/hr class" IMU is `hg1700().scaled(0.1)`.
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            gyro_bias_deg_per_hr: self.gyro_bias_deg_per_hr * factor,
            gyro_bias_instability_deg_per_hr: self.gyro_bias_instability_deg_per_hr * factor,
            gyro_arw_deg_per_sqrt_hr: self.gyro_arw_deg_per_sqrt_hr * factor,
            gyro_scale_factor_ppm: self.gyro_scale_factor_ppm * factor,
            accel_bias_mg: self.accel_bias_mg * factor,
            accel_bias_instability_mg: self.accel_bias_instability_mg * factor,
            accel_vrw_mps_per_sqrt_s: self.accel_vrw_mps_per_sqrt_s * factor,
            accel_scale_factor_ppm: self.accel_scale_factor_ppm * factor,
            ..*self
        }
    }

    /// Validates the figures and converts them to SI (the only place where
    /// data-sheet units appear).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the field for a negative or non-finite
    /// figure or a non-positive correlation time.
    pub fn check(&self) -> Result<ImuErrorSpec, SensorError> {
        use fathom_core::units::{
            deg_per_hour_to_rad_per_s, deg_per_sqrt_hour_to_rad_per_sqrt_s, milli_g_to_mps2,
        };
        let p = self;
        Ok(ImuErrorSpec {
            gyro_bias: deg_per_hour_to_rad_per_s(check_sigma(
                "imu.gyro_bias_deg_per_hr",
                p.gyro_bias_deg_per_hr,
            )?),
            gyro_bias_instability: deg_per_hour_to_rad_per_s(check_sigma(
                "imu.gyro_bias_instability_deg_per_hr",
                p.gyro_bias_instability_deg_per_hr,
            )?),
            gyro_bias_tau: check_positive("imu.gyro_bias_corr_time_s", p.gyro_bias_corr_time_s)?,
            gyro_arw: deg_per_sqrt_hour_to_rad_per_sqrt_s(check_sigma(
                "imu.gyro_arw_deg_per_sqrt_hr",
                p.gyro_arw_deg_per_sqrt_hr,
            )?),
            gyro_scale_factor: 1e-6
                * check_sigma("imu.gyro_scale_factor_ppm", p.gyro_scale_factor_ppm)?,
            accel_bias: milli_g_to_mps2(check_sigma("imu.accel_bias_mg", p.accel_bias_mg)?),
            accel_bias_instability: milli_g_to_mps2(check_sigma(
                "imu.accel_bias_instability_mg",
                p.accel_bias_instability_mg,
            )?),
            accel_bias_tau: check_positive("imu.accel_bias_corr_time_s", p.accel_bias_corr_time_s)?,
            accel_vrw: check_sigma("imu.accel_vrw_mps_per_sqrt_s", p.accel_vrw_mps_per_sqrt_s)?,
            accel_scale_factor: 1e-6
                * check_sigma("imu.accel_scale_factor_ppm", p.accel_scale_factor_ppm)?,
        })
    }
}

/// Validated IMU error figures in SI units (from [`ImuSpecParams::check`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImuErrorSpec {
    /// Gyro turn-on bias sigma, rad/s.
    pub gyro_bias: f64,
    /// Gyro bias-instability sigma, rad/s.
    pub gyro_bias_instability: f64,
    /// Gyro bias-instability correlation time, s.
    pub gyro_bias_tau: f64,
    /// Gyro angle random walk, rad/sqrt(s).
    pub gyro_arw: f64,
    /// Gyro scale-factor sigma (dimensionless).
    pub gyro_scale_factor: f64,
    /// Accelerometer turn-on bias sigma, m/s^2.
    pub accel_bias: f64,
    /// Accelerometer bias-instability sigma, m/s^2.
    pub accel_bias_instability: f64,
    /// Accelerometer bias-instability correlation time, s.
    pub accel_bias_tau: f64,
    /// Accelerometer velocity random walk, m/s/sqrt(s).
    pub accel_vrw: f64,
    /// Accelerometer scale-factor sigma (dimensionless).
    pub accel_scale_factor: f64,
}

impl ImuErrorSpec {
    /// Draws one run's errors: turn-on biases, scale factors (3 + 3 + 3 + 3 standard
    /// normals) and the stationary initial Gauss-Markov states (3 + 3).
    pub fn draw(&self, rng: &mut impl Rng) -> ImuErrors {
        let mut v3 = |sigma: f64| {
            let x = gauss(rng, sigma);
            let y = gauss(rng, sigma);
            let z = gauss(rng, sigma);
            Vector3::new(x, y, z)
        };
        let gyro_turn_on = v3(self.gyro_bias);
        let accel_turn_on = v3(self.accel_bias);
        let gyro_sf = v3(self.gyro_scale_factor);
        let accel_sf = v3(self.accel_scale_factor);
        let gyro_gm = v3(self.gyro_bias_instability);
        let accel_gm = v3(self.accel_bias_instability);
        ImuErrors {
            spec: *self,
            gyro_turn_on,
            accel_turn_on,
            gyro_sf,
            accel_sf,
            gyro_gm,
            accel_gm,
            cached_dt: f64::NAN,
            coeffs: [0.0; 4],
        }
    }
}

/// One run's IMU errors (from [`ImuErrorSpec::draw`]), evolving in time.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuErrors {
    spec: ImuErrorSpec,
    gyro_turn_on: Vector3<f64>,
    accel_turn_on: Vector3<f64>,
    gyro_sf: Vector3<f64>,
    accel_sf: Vector3<f64>,
    gyro_gm: Vector3<f64>,
    accel_gm: Vector3<f64>,
    cached_dt: f64,
    /// `[phi_g, sigma_w_g, phi_a, sigma_w_a]` of the Gauss-Markov steps for `cached_dt`.
    coeffs: [f64; 4],
}

impl ImuErrors {
    /// Current total gyro bias `b_g + m_g`, rad/s.
    pub fn gyro_bias(&self) -> Vector3<f64> {
        self.gyro_turn_on + self.gyro_gm
    }

    /// Current total accelerometer bias `b_a + m_a`, m/s^2.
    pub fn accel_bias(&self) -> Vector3<f64> {
        self.accel_turn_on + self.accel_gm
    }

    /// Gyro scale-factor errors per axis.
    pub fn gyro_scale_factor(&self) -> Vector3<f64> {
        self.gyro_sf
    }

    /// Accelerometer scale-factor errors per axis.
    pub fn accel_scale_factor(&self) -> Vector3<f64> {
        self.accel_sf
    }

    /// The SI figures these errors were drawn from.
    pub fn spec(&self) -> &ImuErrorSpec {
        &self.spec
    }

    /// Corrupts one error-free increment over `dt` (see the module docs); advances
    /// the Gauss-Markov states first (6 standard normals), then draws the white noise
    /// (6 standard normals). Returns `(delta_theta_meas, delta_v_meas)`.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-positive or non-finite `dt`.
    pub fn corrupt(
        &mut self,
        dt: f64,
        delta_theta: &Vector3<f64>,
        delta_v: &Vector3<f64>,
        rng: &mut impl Rng,
    ) -> Result<(Vector3<f64>, Vector3<f64>), SensorError> {
        let dt = check_positive("imu increment dt", dt)?;
        if dt != self.cached_dt {
            let s = &self.spec;
            let phi_g = (-dt / s.gyro_bias_tau).exp();
            let phi_a = (-dt / s.accel_bias_tau).exp();
            self.coeffs = [
                phi_g,
                s.gyro_bias_instability * (-(-2.0 * dt / s.gyro_bias_tau).exp_m1()).sqrt(),
                phi_a,
                s.accel_bias_instability * (-(-2.0 * dt / s.accel_bias_tau).exp_m1()).sqrt(),
            ];
            self.cached_dt = dt;
        }
        let [phi_g, w_g, phi_a, w_a] = self.coeffs;
        for i in 0..3 {
            self.gyro_gm[i] = phi_g * self.gyro_gm[i] + gauss(rng, w_g);
        }
        for i in 0..3 {
            self.accel_gm[i] = phi_a * self.accel_gm[i] + gauss(rng, w_a);
        }
        let sq = dt.sqrt();
        let (arw, vrw) = (self.spec.gyro_arw * sq, self.spec.accel_vrw * sq);
        let bg = self.gyro_bias();
        let ba = self.accel_bias();
        let mut dth = Vector3::zeros();
        let mut dv = Vector3::zeros();
        for i in 0..3 {
            dth[i] = (1.0 + self.gyro_sf[i]) * delta_theta[i] + bg[i] * dt + gauss(rng, arw);
        }
        for i in 0..3 {
            dv[i] = (1.0 + self.accel_sf[i]) * delta_v[i] + ba[i] * dt + gauss(rng, vrw);
        }
        Ok((dth, dv))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn data_sheet_units_are_converted_once() {
        let s = ImuSpecParams::hg1700().scaled(0.1).check().unwrap();
        assert_relative_eq!(
            s.gyro_bias,
            0.1f64.to_radians() / 3600.0,
            max_relative = 1e-12
        );
        assert_relative_eq!(
            s.gyro_arw,
            0.0125f64.to_radians() / 60.0,
            max_relative = 1e-12
        );
        assert_relative_eq!(s.accel_bias, 1e-4 * 9.806_65, max_relative = 1e-12);
        assert_relative_eq!(s.accel_vrw, 3.3e-5, max_relative = 1e-12);
        assert_relative_eq!(s.gyro_scale_factor, 15e-6, max_relative = 1e-12);
        assert_relative_eq!(s.accel_scale_factor, 30e-6, max_relative = 1e-12);
        let bad = ImuSpecParams {
            accel_bias_mg: -1.0,
            ..ImuSpecParams::hg1700()
        };
        let e = bad.check().unwrap_err().to_string();
        assert!(e.contains("imu.accel_bias_mg"), "{e}");
        let bad = ImuSpecParams {
            gyro_bias_corr_time_s: 0.0,
            ..ImuSpecParams::hg1700()
        };
        assert!(bad.check().is_err());
    }

    /// Stationary statistics: the mean of the white part over many steps and the
    /// random-walk growth match the figures (bounds from the normal distribution).
    #[test]
    fn noise_statistics_match_the_figures() {
        let spec = ImuSpecParams {
            gyro_bias_instability_deg_per_hr: 0.0,
            accel_bias_instability_mg: 0.0,
            gyro_scale_factor_ppm: 0.0,
            accel_scale_factor_ppm: 0.0,
            ..ImuSpecParams::hg1700()
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut e = spec.draw(&mut rng);
        let dt = 0.01;
        let n = 20_000;
        let zero = Vector3::zeros();
        let mut sum_dv = Vector3::zeros();
        let mut sum_sq_dth = 0.0;
        for _ in 0..n {
            let (dth, dv) = e.corrupt(dt, &zero, &zero, &mut rng).unwrap();
            sum_dv += dv;
            let w = dth - e.gyro_bias() * dt;
            sum_sq_dth += w.norm_squared();
        }
        // Mean specific force = turn-on bias + white noise average:
        // sd of the mean = vrw / sqrt(n dt); 5 sigma bound.
        let mean_f = sum_dv / (n as f64 * dt);
        let sd = spec.accel_vrw / (n as f64 * dt).sqrt();
        assert!((mean_f - e.accel_bias()).amax() < 5.0 * sd);
        // White gyro variance per step = arw^2 dt; chi-square with 3n dof, 5 sigma.
        let var = sum_sq_dth / (3.0 * n as f64);
        let expected = spec.gyro_arw.powi(2) * dt;
        assert!((var / expected - 1.0).abs() < 5.0 * (2.0 / (3.0 * n as f64)).sqrt());
        // Negative control: a 10 % wrong expectation fails the same bound.
        assert!((var / (1.1 * expected) - 1.0).abs() > 5.0 * (2.0 / (3.0 * n as f64)).sqrt());
        assert!(e.corrupt(0.0, &zero, &zero, &mut rng).is_err());
    }

    #[test]
    fn scale_factor_and_bias_enter_as_specified() {
        let spec = ImuSpecParams {
            gyro_arw_deg_per_sqrt_hr: 0.0,
            accel_vrw_mps_per_sqrt_s: 0.0,
            gyro_bias_instability_deg_per_hr: 0.0,
            accel_bias_instability_mg: 0.0,
            ..ImuSpecParams::hg1700()
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut e = spec.draw(&mut rng);
        let dth = Vector3::new(0.001, -0.002, 0.0005);
        let dv = Vector3::new(0.05, 0.0, -0.098);
        let (m_th, m_v) = e.corrupt(0.01, &dth, &dv, &mut rng).unwrap();
        for i in 0..3 {
            assert_relative_eq!(
                m_th[i],
                (1.0 + e.gyro_scale_factor()[i]) * dth[i] + e.gyro_bias()[i] * 0.01,
                max_relative = 1e-12
            );
            assert_relative_eq!(
                m_v[i],
                (1.0 + e.accel_scale_factor()[i]) * dv[i] + e.accel_bias()[i] * 0.01,
                max_relative = 1e-12
            );
        }
        // The Gauss-Markov part with sigma 0 stays at zero: biases are constant.
        let b0 = e.gyro_bias();
        e.corrupt(0.01, &dth, &dv, &mut rng).unwrap();
        assert_eq!(e.gyro_bias(), b0);
    }
}
