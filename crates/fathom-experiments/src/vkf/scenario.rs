//! Scenario schema of the `vkf` experiment (`scenarios/vkf.toml`) and its conversion
//! into the checked parameter types of the library crates.

use fathom_estimators::GateThreshold;
use fathom_estimators::integrated_nav::IntegratedNavConfig;
use fathom_estimators::velocity_filter::{SwitchingBox, VelocityFilterConfig};
use fathom_ins::earth::Geodetic;
use fathom_ins::route::{Turn, TurningRoute};
use fathom_sensors::inertial::{ImuErrorSpec, ImuSpecParams};
use fathom_sensors::noise::RunConstantDist;
use fathom_sensors::underwater::{
    BottomLockDvlModel, BottomLockDvlParams, EchoSounder, PropellerRpm,
};
use fathom_traj::SeabedProfile;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use fathom_sim::SimError;
use fathom_sim::method_list::select;
use fathom_sim::parameter_key::parameter_invalid;
use fathom_sim::scenario::{require_in_range, require_non_negative, require_positive};

/// The compared methods, in output order.
pub const METHODS: [&str; 5] = ["PINS", "INS-DVL", "VKF", "INS-DVL-gated", "ESKF"];
/// Index of each method in [`METHODS`].
pub const PINS: usize = 0;
/// Index of `INS-DVL`.
pub const INS_DVL: usize = 1;
/// Index of `VKF`.
pub const VKF: usize = 2;
/// Index of `INS-DVL-gated`.
pub const GATED: usize = 3;
/// Index of `ESKF`.
pub const ESKF: usize = 4;

/// Velocity-filter-aided INS.
///
/// Paper C (2013, seed 002) §3.2, eqs. (5)-(12) as rebuilt in spec C: a strapdown INS
/// at 100 Hz and a DVL at 5 Hz that loses bottom lock over deep water; PINS, INS-DVL,
/// the velocity Kalman filter (VKF) with its switching box, a gated INS-DVL and a
/// 15-state ESKF. Data-sheet units (deg/h, mg, ppm, knots) are converted once when
/// checked. Preset: `scenarios/vkf.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VkfScenario {
    /// The experiment this file is for.
    ///
    /// Range: `"vkf"`.
    pub experiment: String,
    /// Monte Carlo runs (spec: ≥ 50); `--runs` overrides.
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// Run `i` uses ChaCha stream `i` of this seed.
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub base_seed: u64,
    /// Runs of the extra configuration with the literal ±0.5 m/s DVL bias
    /// (`dvl.literal_bias_half_width_mps`); 0 skips it; at most `runs` (after
    /// `--runs`).
    ///
    /// Range: 0 or ≥ 2.
    pub literal_bias_runs: usize,
    /// A run whose final horizontal error exceeds this counts in the rows
    /// `runs_final_h_beyond_threshold` (a method that loses lock in some runs has a
    /// heavy-tailed final error).
    ///
    /// Unit: m. Range: > 0.
    pub final_h_threshold_m: f64,
    /// Post-processing: also run the fixed-interval RTS smoother over the VKF-aided
    /// 9-state filter and the ESKF (main batch) and report `VKF+RTS` / `ESKF+RTS` rows
    /// (the same statistics and CIs; the horizontal error inside the DVL-invalid
    /// intervals) beside the filtered ones.
    ///
    /// Range: `true` or `false`. Default: `false`.
    #[serde(default)]
    pub smooth: bool,
    /// The methods to run, report and plot. With a subset only the main batch runs:
    /// the paper's claims, the literal-bias batch and the smoothed rows compare or
    /// need the methods together and are left out (the report says so). PINS runs
    /// in any case (its attitude feeds the other methods) and each selected method's
    /// results equal those of the full run with the same seed.
    ///
    /// Range: a list of `"PINS"`, `"INS-DVL"`, `"VKF"`, `"INS-DVL-gated"`,
    /// `"ESKF"`. Default: all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
    /// The route (paper §3.2).
    pub route: RouteToml,
    /// The seabed profile along the track.
    pub seabed: SeabedToml,
    /// IMU errors, 1 σ per axis (HG1700 figures ÷ 10, "0.1 deg/hr class").
    pub imu: ImuToml,
    /// Bottom-lock DVL, `v = (1 + sf) v_true + b + w` in NED.
    pub dvl: DvlToml,
    /// The echo sounder.
    pub echo_sounder: EchoSounderToml,
    /// Propeller RPM.
    pub rpm: RpmToml,
    /// Depth gauge.
    pub depth_gauge: DepthGaugeToml,
    /// Velocity Kalman filter `[V, sf, b]` (eq. 6; settings, the paper gives none).
    pub vkf: VkfToml,
    /// The 9-state `[p, v, accel bias]` filter, shared settings.
    pub nav_filter: NavFilterToml,
    /// The 15-state error-state filter.
    pub eskf: EskfToml,
    /// `[statistics]`: how the runs of each row are summarized (bootstrap resamples,
    /// divergence factor); defaults when absent.
    #[serde(default)]
    pub statistics: fathom_sim::statistics::StatisticsParams,
}

/// `[route]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RouteToml {
    /// Start latitude (paper: 35 N).
    ///
    /// Unit: deg. Range: [-85, 85].
    pub lat_deg: f64,
    /// Start longitude (paper: 129 E).
    ///
    /// Unit: deg. Range: [-180, 180].
    pub lon_deg: f64,
    /// Constant vehicle depth.
    ///
    /// Unit: m. Range: ≥ 0.
    pub depth_m: f64,
    /// Initial heading, clockwise from north.
    ///
    /// Unit: deg. Range: finite.
    pub heading_deg: f64,
    /// Speed at t = 0; also the VKF's initial speed estimate.
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub initial_speed_mps: f64,
    /// Cruise speed (paper: 10).
    ///
    /// Unit: kn. Range: > 0.
    pub cruise_speed_kn: f64,
    /// Duration of the half-cosine speed ramp from the initial to the cruise speed.
    ///
    /// Unit: s. Range: > 0.
    pub accel_duration_s: f64,
    /// Mission length (paper: 27 min = 1620).
    ///
    /// Unit: s. Range: > 0, a whole number of IMU intervals, ≥ 200 of them.
    pub duration_s: f64,
    /// IMU and strapdown rate (paper: 100); errors are recorded every 1 s.
    ///
    /// Unit: Hz. Range: > 0, a whole number.
    pub imu_rate_hz: f64,
    /// Coordinated turns.
    pub turns: Vec<TurnToml>,
}

/// One `[[route.turns]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TurnToml {
    /// Start of a coordinated turn.
    ///
    /// Unit: s. Range: finite.
    pub start_s: f64,
    /// Total turn duration including both ramps.
    ///
    /// Unit: s. Range: ≥ 2 `ramp_s`.
    pub duration_s: f64,
    /// Length of each half-cosine rate ramp.
    ///
    /// Unit: s. Range: > 0.
    pub ramp_s: f64,
    /// Peak turn rate, positive to starboard (clockwise seen from above); overlapping
    /// turns add.
    ///
    /// Unit: deg/s. Range: finite.
    pub rate_deg_s: f64,
}

/// `[seabed]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SeabedToml {
    /// Seabed depth under the track `[time, depth]`, linear in between and held
    /// outside; altitude = seabed depth − `route.depth_m` (the paper's deep water:
    /// altitude > 100 m during 5-8 min and 15-16 min).
    ///
    /// Unit: s, m. Range: ≥ 2 knots, times strictly increasing, depths ≥ 0.
    pub knots: Vec<[f64; 2]>,
}

/// `[imu]`: 1-sigma figures per axis in data-sheet units (converted once by
/// [`ImuSpecParams::check`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImuToml {
    /// Gyro turn-on bias, drawn per run.
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_bias_deg_per_hr: f64,
    /// Gyro bias instability (first-order Gauss-Markov σ; not in the paper).
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_bias_instability_deg_per_hr: f64,
    /// Its correlation time (not in the paper).
    ///
    /// Unit: s. Range: > 0.
    pub gyro_bias_corr_time_s: f64,
    /// Gyro angle random walk.
    ///
    /// Unit: deg/√h. Range: ≥ 0.
    pub gyro_arw_deg_per_sqrt_hr: f64,
    /// Gyro scale-factor error σ.
    ///
    /// Unit: ppm. Range: ≥ 0.
    pub gyro_scale_factor_ppm: f64,
    /// Accelerometer turn-on bias, drawn per run.
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_bias_mg: f64,
    /// Accelerometer bias instability (Gauss-Markov σ; not in the paper).
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_bias_instability_mg: f64,
    /// Its correlation time (not in the paper).
    ///
    /// Unit: s. Range: > 0.
    pub accel_bias_corr_time_s: f64,
    /// Accelerometer velocity random walk (HG1700: 0.065 ft/s/√h = 3.3e-4 m/s/√s).
    ///
    /// Unit: m/s/√s. Range: ≥ 0.
    pub accel_vrw_mps_per_sqrt_s: f64,
    /// Accelerometer scale-factor error σ.
    ///
    /// Unit: ppm. Range: ≥ 0.
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DvlToml {
    /// Output rate (paper: 5); the echo sounder, RPM and depth gauge sample at the same
    /// epochs, where the filters update.
    ///
    /// Unit: Hz. Range: a whole number of Hz that divides `route.imu_rate_hz`.
    pub rate_hz: f64,
    /// Bottom-lock range: largest altitude with valid output (paper: 100); also the
    /// switching box's threshold on the measured altitude.
    ///
    /// Unit: m. Range: > 0.
    pub range_m: f64,
    /// Half width of the uniform scale-factor error `sf`, drawn per run, common to the
    /// axes (0.002 = ±0.2 %).
    ///
    /// Unit: - (fraction). Range: ≥ 0.
    pub scale_factor_half_width: f64,
    /// Half width of the uniform bias `b`, drawn per run and axis; the paper's "±0.5
    /// m/s" read as ±0.5 cm/s = 0.005.
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub bias_half_width_mps: f64,
    /// The same for the extra configuration with the literal reading (0.5), run
    /// `literal_bias_runs` times.
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub literal_bias_half_width_mps: f64,
    /// σ of the white noise `w` per axis (spec C: 0.02).
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub sigma_mps: f64,
    /// Beyond the range, `U(-g, g)` is added to each component (bottom lock lost,
    /// output not flagged; spec C: 5).
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub garbage_half_width_mps: f64,
}

/// `[echo_sounder]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EchoSounderToml {
    /// Altitude noise σ; the measured altitude drives the switching box.
    ///
    /// Unit: m. Range: ≥ 0.
    pub sigma_m: f64,
}

/// `[rpm]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RpmToml {
    /// True speed constant k: `rpm = (V_fwd - b) / k + N(0, σ²)` (spec C: 0.01).
    ///
    /// Unit: m/s per rpm. Range: > 0.
    pub k_mps_per_rpm: f64,
    /// True speed offset b (spec C: 0.05).
    ///
    /// Unit: m/s. Range: finite.
    pub b_mps: f64,
    /// Revolution noise σ; the VKF assumes the same value.
    ///
    /// Unit: rpm. Range: ≥ 0.
    pub sigma_rpm: f64,
}

/// `[depth_gauge]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DepthGaugeToml {
    /// Depth noise σ; also the depth measurement σ of every filter (damps the vertical
    /// channel).
    ///
    /// Unit: m. Range: > 0.
    pub sigma_m: f64,
}

fathom_replay::vkf_toml! {
    /// `[vkf]`.
    pub struct VkfToml {
        ..
    }
}

fathom_replay::nav_filter_toml! {
    /// `[nav_filter]`.
    pub struct NavFilterToml {
        /// Covariance propagation rate of the 9- and 15-state filters (the state runs at
        /// the IMU rate).
        ///
        /// Unit: Hz. Range: divides `route.imu_rate_hz`, a whole multiple of `dvl.rate_hz`.
        pub covariance_rate_hz: f64,
        ..
        /// DVL velocity σ assumed by the 9-state filters and the ESKF.
        ///
        /// Unit: m/s. Range: > 0.
        pub dvl_sigma_mps: f64,
        /// Gate probability of `INS-DVL-gated` (chi-square, 3 degrees of freedom).
        ///
        /// Range: (0, 1).
        pub gate_probability: f64,
    }
}

/// `[eskf]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EskfToml {
    /// Initial attitude-error σ (its bias σ come from `[imu]`, its position and
    /// velocity σ from `[nav_filter]`).
    ///
    /// Unit: rad. Range: > 0.
    pub sigma0_att_rad: f64,
}

fathom_sim::monte_carlo_scenario!(VkfScenario);

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct Checked {
    /// `methods`: indices into [`super::sim::METHODS`], in its order.
    pub methods: Vec<usize>,
    /// `smooth`.
    pub smooth: bool,
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
    /// `final_h_threshold_m`.
    pub final_h_threshold: f64,
    /// The scenario as written (for the report's description of the setup).
    pub scenario: VkfScenario,
}

impl Checked {
    /// Whether `methods` selects every method (the paper's full experiment).
    pub fn all_methods(&self) -> bool {
        self.methods.len() == METHODS.len()
    }

    /// Whether method `m` (an index into [`METHODS`]) is selected.
    pub fn selected(&self, m: usize) -> bool {
        self.methods.contains(&m)
    }
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
                    "must be a whole number of IMU intervals (1 / route.imu_rate_hz = {} s) and \
                     at least 200 of them, got {} s",
                    dt, r.duration_s
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
                require_positive(file, &format!("route.turns[{i}].ramp_s"), t.ramp_s)?;
                if t.duration_s < 2.0 * t.ramp_s {
                    return Err(SimError::invalid(
                        file,
                        format!("route.turns[{i}].duration_s"),
                        format!(
                            "must be at least 2 x route.turns[{i}].ramp_s = {} s, got {} s",
                            2.0 * t.ramp_s,
                            t.duration_s
                        ),
                    ));
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
            .map_err(|e| parameter_invalid(file, "imu", &self.imu, &e))?;

        let v = &self.dvl;
        let sensor_every = integer_ratio(file, "dvl.rate_hz", r.imu_rate_hz, v.rate_hz)?;
        require_non_negative(
            file,
            "dvl.literal_bias_half_width_mps",
            v.literal_bias_half_width_mps,
        )?;
        require_non_negative(
            file,
            "dvl.scale_factor_half_width",
            v.scale_factor_half_width,
        )?;
        require_non_negative(file, "dvl.bias_half_width_mps", v.bias_half_width_mps)?;
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
            .map_err(|e| parameter_invalid(file, "dvl", v, &e))?;
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
            .map_err(|e| parameter_invalid(file, "rpm", &self.rpm, &e))?;
        let depth_sigma = require_positive(file, "depth_gauge.sigma_m", self.depth_gauge.sigma_m)?;

        let k = &self.vkf;
        require_non_negative(
            file,
            "vkf.speed_process_sigma_mps",
            k.speed_process_sigma_mps,
        )?;
        let vkf = k.velocity_filter_config(file, r.initial_speed_mps, self.rpm.sigma_rpm)?;
        let switch = SwitchingBox::new(v.range_m, k.lateral_sigma_mps)
            .map_err(|e| SimError::invalid(file, "vkf.lateral_sigma_mps", e.to_string()))?;

        let n = &self.nav_filter;
        let cov_every = integer_ratio(
            file,
            "nav_filter.covariance_rate_hz",
            r.imu_rate_hz,
            n.covariance_rate_hz,
        )?;
        let nav = n.integrated_nav_config(file)?;
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
        let indices: Vec<usize> = (0..METHODS.len()).collect();
        let methods = select(file, "vkf", self.methods.as_deref(), &indices, |m| {
            METHODS[m]
        })?;
        Ok(Checked {
            methods,
            smooth: self.smooth,
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
            final_h_threshold: require_positive(
                file,
                "final_h_threshold_m",
                self.final_h_threshold_m,
            )?,
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
        fathom_sim::scenario::parse_toml(t, "vkf.toml")
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
