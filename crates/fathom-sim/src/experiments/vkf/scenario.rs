//! Scenario schema of the `vkf` experiment (`scenarios/vkf.toml`) and its conversion
//! into the checked parameter types of the library crates.

use fathom_estimators::GateThreshold;
use fathom_estimators::integrated_nav::{AccelBiasFrame, IntegratedNavConfig, IntegratedNavParams};
use fathom_estimators::velocity_filter::{
    SwitchingBox, VelocityFilterConfig, VelocityFilterParams,
};
use fathom_ins::earth::Geodetic;
use fathom_ins::route::{Turn, TurningRoute};
use fathom_sensors::inertial::{ImuErrorSpec, ImuSpecParams};
use fathom_sensors::noise::RunConstantDist;
use fathom_sensors::underwater::{
    BottomLockDvlModel, BottomLockDvlParams, EchoSounder, PropellerRpm,
};
use fathom_traj::SeabedProfile;
use serde::{Deserialize, Serialize};

use crate::SimError;
use crate::scenario::{require_in_range, require_non_negative, require_positive};

/// The `vkf` scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VkfScenario {
    /// The experiment this scenario is for: must be `"vkf"` (lets `fathom run`
    /// pick the experiment from the file).
    pub experiment: String,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed; run `i` uses ChaCha stream `i`.
    pub base_seed: u64,
    /// Runs of the literal-bias configuration (0 = skip it).
    pub literal_bias_runs: usize,
    /// The route.
    pub route: RouteToml,
    /// The seabed profile.
    pub seabed: SeabedToml,
    /// IMU error figures (data-sheet units).
    pub imu: ImuToml,
    /// DVL.
    pub dvl: DvlToml,
    /// Echo sounder.
    pub echo_sounder: EchoSounderToml,
    /// Propeller RPM.
    pub rpm: RpmToml,
    /// Depth gauge.
    pub depth_gauge: DepthGaugeToml,
    /// Velocity Kalman filter.
    pub vkf: VkfToml,
    /// 9-state filter (and shared filter settings).
    pub nav_filter: NavFilterToml,
    /// 15-state ESKF.
    pub eskf: EskfToml,
}

/// `[route]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RouteToml {
    /// Start latitude, deg.
    pub lat_deg: f64,
    /// Start longitude, deg.
    pub lon_deg: f64,
    /// Constant depth, m.
    pub depth_m: f64,
    /// Initial heading, deg.
    pub heading_deg: f64,
    /// Initial speed, m/s.
    pub initial_speed_mps: f64,
    /// Cruise speed, kn.
    pub cruise_speed_kn: f64,
    /// Acceleration (half-cosine ramp) duration, s.
    pub accel_duration_s: f64,
    /// Mission duration, s.
    pub duration_s: f64,
    /// IMU / computation rate, Hz (a whole number: errors are recorded every 1 s).
    pub imu_rate_hz: f64,
    /// Coordinated turns.
    pub turns: Vec<TurnToml>,
}

/// One `[[route.turns]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurnToml {
    /// Start, s.
    pub start_s: f64,
    /// Total duration including ramps, s.
    pub duration_s: f64,
    /// Ramp length, s.
    pub ramp_s: f64,
    /// Peak turn rate, deg/s (positive to starboard).
    pub rate_deg_s: f64,
}

/// `[seabed]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeabedToml {
    /// `[time s, seabed depth m]` knots.
    pub knots: Vec<[f64; 2]>,
}

/// `[imu]`: 1-sigma figures per axis in data-sheet units (converted once by
/// [`ImuSpecParams::check`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuToml {
    /// Gyro turn-on bias, deg/hr.
    pub gyro_bias_deg_per_hr: f64,
    /// Gyro bias instability (Gauss-Markov sigma), deg/hr.
    pub gyro_bias_instability_deg_per_hr: f64,
    /// Its correlation time, s.
    pub gyro_bias_corr_time_s: f64,
    /// Gyro angle random walk, deg/sqrt(hr).
    pub gyro_arw_deg_per_sqrt_hr: f64,
    /// Gyro scale factor, ppm.
    pub gyro_scale_factor_ppm: f64,
    /// Accelerometer turn-on bias, mg.
    pub accel_bias_mg: f64,
    /// Accelerometer bias instability (Gauss-Markov sigma), mg.
    pub accel_bias_instability_mg: f64,
    /// Its correlation time, s.
    pub accel_bias_corr_time_s: f64,
    /// Velocity random walk, m/s/sqrt(s).
    pub accel_vrw_mps_per_sqrt_s: f64,
    /// Accelerometer scale factor, ppm.
    pub accel_scale_factor_ppm: f64,
}

impl ImuToml {
    fn to_params(self) -> ImuSpecParams {
        ImuSpecParams {
            gyro_bias_deg_per_hr: self.gyro_bias_deg_per_hr,
            gyro_bias_instability_deg_per_hr: self.gyro_bias_instability_deg_per_hr,
            gyro_bias_corr_time_s: self.gyro_bias_corr_time_s,
            gyro_arw_deg_per_sqrt_hr: self.gyro_arw_deg_per_sqrt_hr,
            gyro_scale_factor_ppm: self.gyro_scale_factor_ppm,
            accel_bias_mg: self.accel_bias_mg,
            accel_bias_instability_mg: self.accel_bias_instability_mg,
            accel_bias_corr_time_s: self.accel_bias_corr_time_s,
            accel_vrw_mps_per_sqrt_s: self.accel_vrw_mps_per_sqrt_s,
            accel_scale_factor_ppm: self.accel_scale_factor_ppm,
        }
    }
}

/// `[dvl]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DvlToml {
    /// Output rate, Hz: a whole number that divides the IMU rate. The echo sounder,
    /// RPM and depth gauge sample at the same epochs, where the filters update.
    pub rate_hz: f64,
    /// Bottom-lock range, m.
    pub range_m: f64,
    /// Half width of the uniform scale-factor error, a fraction (0.002 = 0.2 %), drawn
    /// per run and common to the axes.
    pub scale_factor_half_width: f64,
    /// Half width of the uniform bias per axis, m/s (the paper reading, 0.005).
    pub bias_half_width_mps: f64,
    /// Half width of the literal-reading bias, m/s (0.5).
    pub literal_bias_half_width_mps: f64,
    /// White noise sigma, m/s.
    pub sigma_mps: f64,
    /// Half width of the uniform error beyond range, m/s.
    pub garbage_half_width_mps: f64,
}

/// `[echo_sounder]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EchoSounderToml {
    /// Noise sigma, m.
    pub sigma_m: f64,
}

/// `[rpm]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RpmToml {
    /// True speed constant, m/s per rpm.
    pub k_mps_per_rpm: f64,
    /// True speed offset, m/s.
    pub b_mps: f64,
    /// Revolution noise sigma, rpm (the VKF assumes the same value).
    pub sigma_rpm: f64,
}

/// `[depth_gauge]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthGaugeToml {
    /// Noise sigma, m; also the depth measurement sigma of every filter.
    pub sigma_m: f64,
}

/// `[vkf]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VkfToml {
    /// Initial scale factor, m/s per rpm.
    pub sf0: f64,
    /// Initial bias, m/s.
    pub b0: f64,
    /// Initial speed sigma, m/s.
    pub sigma_speed0_mps: f64,
    /// Initial scale-factor sigma, m/s per rpm.
    pub sigma_sf0: f64,
    /// Initial bias sigma, m/s.
    pub sigma_b0_mps: f64,
    /// Extra forward-speed process noise sigma per VKF step (one per DVL epoch), m/s.
    pub speed_process_sigma_mps: f64,
    /// Scale-factor random-walk PSD, (m/s/rpm)^2/s.
    pub sf_rw_psd: f64,
    /// Bias random-walk PSD, (m/s)^2/s.
    pub bias_rw_psd: f64,
    /// DVL forward-speed sigma assumed by the VKF, m/s.
    pub dvl_sigma_mps: f64,
    /// Sigma of the zero lateral / vertical body speed in RPM aiding, m/s.
    pub lateral_sigma_mps: f64,
}

/// `[nav_filter]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NavFilterToml {
    /// Covariance propagation rate of the 9- and 15-state filters, Hz (divides the IMU rate).
    pub covariance_rate_hz: f64,
    /// White acceleration PSD of the 9-state filter, m^2/s^3.
    pub accel_psd: f64,
    /// Accelerometer-bias random-walk PSD of the 9-state filter, (m/s^2)^2/s.
    pub accel_bias_rw_psd: f64,
    /// Initial position sigma of the 9-state filters and the ESKF, m.
    pub sigma0_pos_m: f64,
    /// Initial velocity sigma of the 9-state filters and the ESKF, m/s.
    pub sigma0_vel_mps: f64,
    /// Initial accelerometer-bias sigma of the 9-state filter, m/s^2.
    pub sigma0_accel_bias_mps2: f64,
    /// Frame of the 9-state filter's acceleration bias: `"body"` or `"nav"`.
    pub accel_bias_frame: String,
    /// DVL velocity sigma assumed by the 9-state filters and the ESKF, m/s.
    pub dvl_sigma_mps: f64,
    /// Gate probability of `INS-DVL-gated` (chi-square, 3 dof).
    pub gate_probability: f64,
}

/// `[eskf]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EskfToml {
    /// Initial attitude-error sigma, rad.
    pub sigma0_att_rad: f64,
}

crate::monte_carlo_scenario!(VkfScenario);

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct Checked {
    pub runs: usize,
    pub base_seed: u64,
    pub literal_bias_runs: usize,
    pub route: TurningRoute,
    pub duration: f64,
    pub dt: f64,
    pub n_steps: usize,
    /// IMU steps per DVL / sensor epoch.
    pub sensor_every: usize,
    /// IMU steps per covariance propagation.
    pub cov_every: usize,
    /// IMU steps per recorded error sample (1 s).
    pub record_every: usize,
    pub seabed: SeabedProfile,
    pub imu_params: ImuSpecParams,
    pub imu: ImuErrorSpec,
    pub dvl: BottomLockDvlModel,
    pub dvl_literal: BottomLockDvlModel,
    pub echo: EchoSounder,
    pub rpm: PropellerRpm,
    pub depth_sigma: f64,
    pub vkf: VelocityFilterConfig,
    pub switch: SwitchingBox,
    pub nav: IntegratedNavConfig,
    pub filter_dvl_sigma: f64,
    pub gate: GateThreshold,
    pub gate_probability: f64,
    pub eskf_sigma0_att: f64,
    /// The scenario as written (for the report's description of the setup).
    pub scenario: VkfScenario,
}

/// An integer ratio `a / b` (both rates in Hz), or an error naming `key`.
fn integer_ratio(file: &str, key: &str, a: f64, b: f64) -> Result<usize, SimError> {
    require_positive(file, key, b)?;
    let r = a / b;
    // Not finite (a NaN or zero rate): NaN compares false below and would cast to 0.
    if !r.is_finite() || (r - r.round()).abs() > 1e-9 || r.round() < 1.0 {
        return Err(SimError::invalid(
            file,
            key,
            format!("{b} Hz must divide the IMU rate {a} Hz"),
        ));
    }
    Ok(r.round() as usize)
}

impl VkfScenario {
    /// Checks every value and builds the checked parameters.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<Checked, SimError> {
        let runs = self.runs;
        if runs < 2 {
            return Err(SimError::invalid(
                file,
                "runs",
                format!("needs at least 2 runs for a confidence interval, got {runs}"),
            ));
        }
        let literal_bias_runs = match self.literal_bias_runs {
            0 => 0,
            1 => {
                return Err(SimError::invalid(
                    file,
                    "literal_bias_runs",
                    "needs 0 (skip) or at least 2 runs",
                ));
            }
            n => n.min(runs),
        };
        let r = &self.route;
        require_in_range(file, "route.lat_deg", r.lat_deg, -85.0, 85.0)?;
        require_in_range(file, "route.lon_deg", r.lon_deg, -180.0, 180.0)?;
        require_non_negative(file, "route.depth_m", r.depth_m)?;
        require_non_negative(file, "route.initial_speed_mps", r.initial_speed_mps)?;
        require_positive(file, "route.cruise_speed_kn", r.cruise_speed_kn)?;
        require_positive(file, "route.accel_duration_s", r.accel_duration_s)?;
        require_positive(file, "route.duration_s", r.duration_s)?;
        require_positive(file, "route.imu_rate_hz", r.imu_rate_hz)?;
        if !r.heading_deg.is_finite() {
            return Err(SimError::invalid(
                file,
                "route.heading_deg",
                "must be finite",
            ));
        }
        let dt = 1.0 / r.imu_rate_hz;
        let n_steps = (r.duration_s / dt).round() as usize;
        if n_steps < 200 || ((n_steps as f64) * dt - r.duration_s).abs() > 1e-6 {
            return Err(SimError::invalid(
                file,
                "route.duration_s",
                format!(
                    "must be a whole number of IMU intervals and at least 200 of them, got {} s",
                    r.duration_s
                ),
            ));
        }
        let d = f64::to_radians;
        let turns = r
            .turns
            .iter()
            .enumerate()
            .map(|(i, t)| {
                for (k, v) in [
                    ("start_s", t.start_s),
                    ("duration_s", t.duration_s),
                    ("ramp_s", t.ramp_s),
                    ("rate_deg_s", t.rate_deg_s),
                ] {
                    if !v.is_finite() {
                        return Err(SimError::invalid(
                            file,
                            format!("route.turns[{i}].{k}"),
                            format!("must be finite, got {v}"),
                        ));
                    }
                }
                Ok(Turn {
                    start: t.start_s,
                    duration: t.duration_s,
                    ramp: t.ramp_s,
                    rate: d(t.rate_deg_s),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let route = TurningRoute {
            start: Geodetic::new(d(r.lat_deg), d(r.lon_deg), -r.depth_m),
            initial_heading: d(r.heading_deg),
            initial_speed: r.initial_speed_mps,
            cruise_speed: fathom_core::units::knots_to_mps(r.cruise_speed_kn),
            accel_duration: r.accel_duration_s,
            turns,
        };
        route
            .check()
            .map_err(|e| SimError::invalid(file, "route", e.to_string()))?;

        let knots: Vec<(f64, f64)> = self.seabed.knots.iter().map(|k| (k[0], k[1])).collect();
        let seabed = SeabedProfile::new(&knots)
            .map_err(|e| SimError::invalid(file, "seabed.knots", e.to_string()))?;

        let imu_params = self.imu.to_params();
        let imu = imu_params
            .check()
            .map_err(|e| SimError::invalid(file, "imu", e.to_string()))?;

        let v = &self.dvl;
        let sensor_every = integer_ratio(file, "dvl.rate_hz", r.imu_rate_hz, v.rate_hz)?;
        require_non_negative(
            file,
            "dvl.literal_bias_half_width_mps",
            v.literal_bias_half_width_mps,
        )?;
        let dvl_params = BottomLockDvlParams {
            scale_factor: RunConstantDist::Uniform {
                half_width: v.scale_factor_half_width,
            },
            bias: RunConstantDist::Uniform {
                half_width: v.bias_half_width_mps,
            },
            sigma: v.sigma_mps,
            range: v.range_m,
            garbage_half_width: v.garbage_half_width_mps,
        };
        let dvl = dvl_params
            .check()
            .map_err(|e| SimError::invalid(file, "dvl", e.to_string()))?;
        let dvl_literal = BottomLockDvlParams {
            bias: RunConstantDist::Uniform {
                half_width: v.literal_bias_half_width_mps,
            },
            ..dvl_params
        }
        .check()
        .map_err(|e| SimError::invalid(file, "dvl.literal_bias_half_width_mps", e.to_string()))?;
        let echo = EchoSounder::new(self.echo_sounder.sigma_m)
            .map_err(|e| SimError::invalid(file, "echo_sounder.sigma_m", e.to_string()))?;
        let rpm = PropellerRpm::new(self.rpm.k_mps_per_rpm, self.rpm.b_mps, self.rpm.sigma_rpm)
            .map_err(|e| SimError::invalid(file, "rpm", e.to_string()))?;
        let depth_sigma = require_positive(file, "depth_gauge.sigma_m", self.depth_gauge.sigma_m)?;

        let k = &self.vkf;
        let speed_sigma = require_non_negative(
            file,
            "vkf.speed_process_sigma_mps",
            k.speed_process_sigma_mps,
        )?;
        let vkf = VelocityFilterParams {
            speed0: r.initial_speed_mps,
            sf0: k.sf0,
            b0: k.b0,
            sigma0: [k.sigma_speed0_mps, k.sigma_sf0, k.sigma_b0_mps],
            rpm_sigma: self.rpm.sigma_rpm,
            speed_process_var: speed_sigma * speed_sigma,
            sf_rw_psd: k.sf_rw_psd,
            bias_rw_psd: k.bias_rw_psd,
            dvl_sigma: k.dvl_sigma_mps,
        }
        .check()
        .map_err(|e| SimError::invalid(file, "vkf", e.to_string()))?;
        let switch = SwitchingBox::new(v.range_m, k.lateral_sigma_mps)
            .map_err(|e| SimError::invalid(file, "vkf.lateral_sigma_mps", e.to_string()))?;

        let n = &self.nav_filter;
        let cov_every = integer_ratio(
            file,
            "nav_filter.covariance_rate_hz",
            r.imu_rate_hz,
            n.covariance_rate_hz,
        )?;
        let nav = IntegratedNavParams {
            accel_psd: n.accel_psd,
            accel_bias_rw_psd: n.accel_bias_rw_psd,
            sigma0: [n.sigma0_pos_m, n.sigma0_vel_mps, n.sigma0_accel_bias_mps2],
            bias_frame: match n.accel_bias_frame.as_str() {
                "body" => AccelBiasFrame::Body,
                "nav" => AccelBiasFrame::Nav,
                other => {
                    return Err(SimError::invalid(
                        file,
                        "nav_filter.accel_bias_frame",
                        format!("must be \"body\" or \"nav\", got {other:?}"),
                    ));
                }
            },
        }
        .check()
        .map_err(|e| SimError::invalid(file, "nav_filter", e.to_string()))?;
        let filter_dvl_sigma = require_positive(file, "nav_filter.dvl_sigma_mps", n.dvl_sigma_mps)?;
        let gate = GateThreshold::from_chi_square_probability(n.gate_probability, 3)
            .map_err(|e| SimError::invalid(file, "nav_filter.gate_probability", e.to_string()))?;
        let eskf_sigma0_att =
            require_positive(file, "eskf.sigma0_att_rad", self.eskf.sigma0_att_rad)?;
        let record_every = integer_ratio(file, "route.imu_rate_hz", r.imu_rate_hz, 1.0)?;
        if record_every % sensor_every != 0 {
            return Err(SimError::invalid(
                file,
                "dvl.rate_hz",
                "must be a whole multiple of 1 Hz (error samples are taken at sensor epochs)",
            ));
        }
        if sensor_every % cov_every != 0 {
            return Err(SimError::invalid(
                file,
                "nav_filter.covariance_rate_hz",
                "must be a whole multiple of the DVL rate (updates happen at covariance epochs)",
            ));
        }
        Ok(Checked {
            runs,
            base_seed: self.base_seed,
            literal_bias_runs,
            route,
            duration: r.duration_s,
            dt,
            n_steps,
            sensor_every,
            cov_every,
            record_every,
            seabed,
            imu_params,
            imu,
            dvl,
            dvl_literal,
            echo,
            rpm,
            depth_sigma,
            vkf,
            switch,
            nav,
            filter_dvl_sigma,
            gate,
            gate_probability: n.gate_probability,
            eskf_sigma0_att,
            scenario: self.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/vkf.toml"),
        )
        .unwrap()
    }

    fn parse(t: &str) -> Result<VkfScenario, SimError> {
        crate::scenario::parse_toml(t, "vkf.toml")
    }

    #[test]
    fn preset_parses_and_checks() {
        let c = parse(&text()).unwrap().check("vkf.toml").unwrap();
        assert!(c.runs >= 50);
        assert_eq!(c.n_steps, 162_000);
        assert_eq!(c.sensor_every, 20);
        assert_eq!(c.record_every, 100);
        assert!(c.route.turns.len() >= 4);
        // 0.1 deg/hr class, converted once.
        assert!((c.imu.gyro_bias - 0.1f64.to_radians() / 3600.0).abs() < 1e-15);
        // --runs caps the literal configuration.
        let mut s = parse(&text()).unwrap();
        s.runs = 3;
        let c = s.check("vkf.toml").unwrap();
        assert_eq!((c.runs, c.literal_bias_runs), (3, 3));
    }

    #[test]
    fn bad_values_name_their_key() {
        let cases = [
            ("sigma_mps = 0.02", "sigma_mps = -0.02", "dvl"),
            ("rate_hz = 5.0", "rate_hz = 7.0", "dvl.rate_hz"),
            (
                "accel_bias_frame = \"nav\"",
                "accel_bias_frame = \"ned\"",
                "nav_filter.accel_bias_frame",
            ),
            (
                "gate_probability = 0.999",
                "gate_probability = 1.5",
                "nav_filter.gate_probability",
            ),
            (
                "accel_bias_mg = 0.1",
                "accel_bias_mg = -0.1",
                "imu.accel_bias_mg",
            ),
            (
                "duration_s = 1620.0",
                "duration_s = 1620.005",
                "route.duration_s",
            ),
            ("[0.0, 110.0], [290.0", "[0.0, 110.0], [0.0", "seabed.knots"),
        ];
        for (from, to, key) in cases {
            let t = text().replacen(from, to, 1);
            assert_ne!(t, text(), "{from}");
            let err = parse(&t)
                .unwrap()
                .check("vkf.toml")
                .unwrap_err()
                .to_string();
            assert!(err.contains(key), "{key}: {err}");
        }
        let t = text().replacen("sigma_m = 0.5", "sigma_m = 0.5\nsigma_x = 1.0", 1);
        let err = parse(&t).unwrap_err().to_string();
        assert!(err.contains("sigma_x"), "{err}");
    }
}
