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
//!
//! # Flicker bias instability (optional, [`FlickerBias`])
//!
//! An Allan-variance analysis reads the bias instability `B` from the flat bottom of
//! the Allan deviation, `sqrt(2 ln 2 / pi) B` (IEEE Std 952). A single first-order
//! Gauss-Markov process has no flat bottom (its Allan deviation rises as `sqrt(tau)`,
//! peaks at `tau = 1.89 T` and falls again), so a record made with it does not give
//! back `B` by that reading. Flicker (`1/f`) noise does, and a sum of Gauss-Markov
//! processes with correlation times one decade apart and equal variances
//!
//! ```text
//! sigma_j^2 = B^2 ln(10) / pi,   T_j = tau_min 10^j,  j = 0..components
//! ```
//!
//! has the flicker PSD `B^2 / (2 pi f)` between `1 / (2 pi T_max)` and
//! `1 / (2 pi tau_min)` (the Lorentzians summed with density `1 / ln 10` per unit
//! `ln T`), hence an Allan deviation within -2 % / +1 % of `0.664 B` for `tau` from
//! about `10 tau_min` to `T_max / 100`. Each component is stepped exactly like `m`
//! above and adds to the bias (`b + m + sum_j f_j`). With `B = 0` (the default of
//! [`ImuSpecParams::check`]) nothing is drawn, so the random stream of the existing
//! models is unchanged.

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
            gyro_flicker: FlickerBias::off(),
            accel_flicker: FlickerBias::off(),
        })
    }
}

/// Bias instability as flicker noise: a sum of first-order Gauss-Markov processes,
/// one per decade of correlation time (module docs). Same on the three axes.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct FlickerBias {
    /// Bias-instability coefficient `B` (IEEE 952): rad/s for gyros, m/s^2 for
    /// accelerometers; 0 = off.
    pub coefficient: f64,
    /// Correlation time of the fastest component, s.
    pub tau_min: f64,
    /// Number of components (correlation times `tau_min 10^j`, `j < components`).
    pub components: usize,
}

impl FlickerBias {
    /// No flicker part.
    pub fn off() -> Self {
        Self::default()
    }

    /// Flicker bias with coefficient `coefficient` over correlation times from
    /// `tau_min` to at least `tau_max` (one component per decade).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming `field` for a negative or non-finite
    /// coefficient, a non-positive `tau_min`, `tau_max < tau_min`, or more than 12
    /// decades.
    pub fn new(
        field: &str,
        coefficient: f64,
        tau_min: f64,
        tau_max: f64,
    ) -> Result<Self, SensorError> {
        let coefficient = check_sigma(field, coefficient)?;
        let tau_min = check_positive(&format!("{field} (flicker tau_min)"), tau_min)?;
        let tau_max = check_positive(&format!("{field} (flicker tau_max)"), tau_max)?;
        let decades = (tau_max / tau_min).log10();
        if !(0.0..=12.0).contains(&decades) {
            return Err(SensorError::InvalidParameter {
                field: format!("{field} (flicker tau_max)"),
                value: tau_max,
                reason: "must be between tau_min and 1e12 tau_min",
            });
        }
        Ok(Self {
            coefficient,
            tau_min,
            components: decades.ceil() as usize + 1,
        })
    }

    /// Whether the flicker part is present (non-zero coefficient and components).
    pub fn is_on(&self) -> bool {
        self.coefficient > 0.0 && self.components > 0
    }

    /// Standard deviation of each component, `B sqrt(ln 10 / pi)`.
    pub fn component_sigma(&self) -> f64 {
        self.coefficient * (std::f64::consts::LN_10 / std::f64::consts::PI).sqrt()
    }

    /// Correlation time of component `j`, `tau_min 10^j`, s.
    pub fn correlation_time(&self, j: usize) -> f64 {
        self.tau_min * 10f64.powi(j as i32)
    }

    /// Number of components actually simulated (0 when off).
    fn active_components(&self) -> usize {
        if self.is_on() { self.components } else { 0 }
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
    /// Gyro bias instability as flicker noise (off unless set; module docs).
    #[serde(default)]
    pub gyro_flicker: FlickerBias,
    /// Accelerometer bias instability as flicker noise (off unless set).
    #[serde(default)]
    pub accel_flicker: FlickerBias,
}

impl ImuErrorSpec {
    /// Draws one run's errors: turn-on biases, scale factors (3 + 3 + 3 + 3 standard
    /// normals), the stationary initial Gauss-Markov states (3 + 3), then, only when
    /// present, the stationary initial flicker components (3 per gyro component, then
    /// 3 per accelerometer component).
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
        let gyro_flicker = (0..self.gyro_flicker.active_components())
            .map(|_| v3(self.gyro_flicker.component_sigma()))
            .collect();
        let accel_flicker = (0..self.accel_flicker.active_components())
            .map(|_| v3(self.accel_flicker.component_sigma()))
            .collect();
        ImuErrors {
            spec: *self,
            gyro_turn_on,
            accel_turn_on,
            gyro_sf,
            accel_sf,
            gyro_gm,
            accel_gm,
            gyro_flicker,
            accel_flicker,
            cached_dt: f64::NAN,
            coeffs: [0.0; 4],
            flicker_coeffs: Vec::new(),
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
    /// Flicker components (empty when off).
    gyro_flicker: Vec<Vector3<f64>>,
    accel_flicker: Vec<Vector3<f64>>,
    cached_dt: f64,
    /// `[phi_g, sigma_w_g, phi_a, sigma_w_a]` of the Gauss-Markov steps for `cached_dt`.
    coeffs: [f64; 4],
    /// `[phi, sigma_w]` per flicker component (gyro components, then accelerometer).
    flicker_coeffs: Vec<[f64; 2]>,
}

/// `[phi, sigma_w]` of an exact Gauss-Markov step of length `dt`.
fn gm_step_coeffs(sigma: f64, tau: f64, dt: f64) -> [f64; 2] {
    [
        (-dt / tau).exp(),
        sigma * (-(-2.0 * dt / tau).exp_m1()).sqrt(),
    ]
}

impl ImuErrors {
    /// Current total gyro bias `b_g + m_g (+ flicker)`, rad/s.
    pub fn gyro_bias(&self) -> Vector3<f64> {
        self.gyro_flicker
            .iter()
            .fold(self.gyro_turn_on + self.gyro_gm, |acc, f| acc + f)
    }

    /// Current total accelerometer bias `b_a + m_a (+ flicker)`, m/s^2.
    pub fn accel_bias(&self) -> Vector3<f64> {
        self.accel_flicker
            .iter()
            .fold(self.accel_turn_on + self.accel_gm, |acc, f| acc + f)
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
    /// the Gauss-Markov states first (6 standard normals), then the flicker components
    /// if any (3 per component, gyro then accelerometer), then draws the white noise
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
            let (gf, af) = (s.gyro_flicker, s.accel_flicker);
            self.flicker_coeffs = (0..self.gyro_flicker.len())
                .map(|j| gm_step_coeffs(gf.component_sigma(), gf.correlation_time(j), dt))
                .chain(
                    (0..self.accel_flicker.len())
                        .map(|j| gm_step_coeffs(af.component_sigma(), af.correlation_time(j), dt)),
                )
                .collect();
            self.cached_dt = dt;
        }
        let [phi_g, w_g, phi_a, w_a] = self.coeffs;
        for i in 0..3 {
            self.gyro_gm[i] = phi_g * self.gyro_gm[i] + gauss(rng, w_g);
        }
        for i in 0..3 {
            self.accel_gm[i] = phi_a * self.accel_gm[i] + gauss(rng, w_a);
        }
        let n_gyro = self.gyro_flicker.len();
        for (j, [phi, w]) in self.flicker_coeffs.iter().copied().enumerate() {
            let f = if j < n_gyro {
                &mut self.gyro_flicker[j]
            } else {
                &mut self.accel_flicker[j - n_gyro]
            };
            for i in 0..3 {
                f[i] = phi * f[i] + gauss(rng, w);
            }
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

    fn flicker_only(b: f64) -> ImuErrorSpec {
        let mut spec = ImuSpecParams {
            gyro_bias_deg_per_hr: 0.0,
            gyro_bias_instability_deg_per_hr: 0.0,
            gyro_arw_deg_per_sqrt_hr: 0.0,
            gyro_scale_factor_ppm: 0.0,
            ..ImuSpecParams::hg1700()
        }
        .check()
        .unwrap();
        spec.gyro_flicker = FlickerBias::new("gyro", b, 0.1, 1e5).unwrap();
        spec
    }

    /// Without flicker the model draws exactly 18 normals per run and 12 per
    /// increment, as before the flicker part existed; with flicker the first 18 draws
    /// (turn-on biases, scale factors, Gauss-Markov states) are unchanged.
    #[test]
    fn flicker_leaves_the_existing_random_stream_alone() {
        use rand::RngCore;
        use rand_distr::StandardNormal;
        let spec = ImuSpecParams::hg1700().check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut e = spec.draw(&mut rng);
        e.corrupt(0.01, &Vector3::zeros(), &Vector3::zeros(), &mut rng)
            .unwrap();
        let mut reference = ChaCha8Rng::seed_from_u64(21);
        for _ in 0..30 {
            let _: f64 = reference.sample(StandardNormal);
        }
        assert_eq!(rng.next_u64(), reference.next_u64());

        let mut with = spec;
        with.gyro_flicker = FlickerBias::new("gyro", 1e-5, 0.1, 1e5).unwrap();
        let a = spec.draw(&mut ChaCha8Rng::seed_from_u64(5));
        let b = with.draw(&mut ChaCha8Rng::seed_from_u64(5));
        assert_eq!(a.accel_bias(), b.accel_bias());
        assert_eq!(a.gyro_scale_factor(), b.gyro_scale_factor());
        assert_ne!(a.gyro_bias(), b.gyro_bias());
    }

    /// The flicker components start stationary: over 3000 runs the initial bias
    /// variance per axis is `components * sigma_j^2` within a 4.5-sigma chi-square
    /// band (normal approximation, 9000 axis samples). Negative control: 6 components'
    /// worth is rejected.
    #[test]
    fn flicker_components_start_stationary() {
        let b = 1e-4;
        let spec = flicker_only(b);
        let f = spec.gyro_flicker;
        assert_eq!(f.components, 7);
        let expected = f.components as f64 * f.component_sigma().powi(2);
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let n = 3000;
        let mut sum_sq = 0.0;
        for _ in 0..n {
            sum_sq += spec.draw(&mut rng).gyro_bias().norm_squared();
        }
        let var = sum_sq / (3.0 * n as f64);
        let band = 4.5 * (2.0 / (3.0 * n as f64)).sqrt();
        assert!((var / expected - 1.0).abs() < band, "{var} vs {expected}");
        let six = 6.0 * f.component_sigma().powi(2);
        assert!((var / six - 1.0).abs() > band, "negative control");
    }

    #[test]
    fn flicker_parameters_are_checked() {
        assert!(FlickerBias::new("gyro", -1.0, 0.1, 10.0).is_err());
        let e = FlickerBias::new("imu.gyro_bi", 1.0, 0.0, 10.0).unwrap_err();
        assert!(e.to_string().contains("imu.gyro_bi"), "{e}");
        assert!(FlickerBias::new("gyro", 1.0, 10.0, 1.0).is_err());
        assert!(FlickerBias::new("gyro", 1.0, 1.0, 1e13).is_err());
        assert_eq!(
            FlickerBias::new("gyro", 1.0, 1.0, 1.0).unwrap().components,
            1
        );
        assert_eq!(
            FlickerBias::new("gyro", 1.0, 0.1, 2e4).unwrap().components,
            7
        );
        assert!(!FlickerBias::off().is_on());
        assert!(!FlickerBias::new("gyro", 0.0, 0.1, 10.0).unwrap().is_on());
    }
}
