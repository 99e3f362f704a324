//! The `ins-dvl` replay settings: the schema of `scenarios/ins-dvl.toml` (the
//! filters' tuning, then a `[[methods]]` list) and its check into [`InsDvlSettings`].

use fathom_core::units::{
    deg_per_hour_to_rad_per_s, deg_per_sqrt_hour_to_rad_per_sqrt_s, milli_g_to_mps2,
};
use fathom_estimators::GateThreshold;
use fathom_estimators::integrated_nav::IntegratedNavConfig;
use fathom_estimators::velocity_filter::{SwitchingBox, VelocityFilterParams};
use fathom_ins::error_model::{BiasModel, ImuErrorModel, ImuErrorParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::range_beacon::{LogDirToml, OutputToml};
use fathom_sim::SimError;
use fathom_sim::method_list::check_method_names;
use fathom_sim::parameter_key::parameter_invalid;
use fathom_sim::scenario::{
    require_experiment, require_in_range, require_non_negative, require_positive,
};

/// INS / DVL navigation on your own log.
///
/// Replays a strapdown INS aided by DVL velocity and depth on a log in fathom's CSV
/// layout (`docs/own-data.md`, kind `ins-dvl`): pure INS (PINS), the 9-state
/// INS-DVL filter (optionally chi-square gated), the velocity-filter (VKF) aiding of
/// seed 002 that switches to the propeller-RPM speed when the DVL is invalid, and the
/// 15-state feedback ESKF with the same switching. With truth the report scores
/// horizontal position errors; without, it shows the velocity and depth innovations,
/// their NIS and the filters' consistency. One deterministic replay. `fathom replay
/// ins-dvl <dir> [--config FILE]` runs it on a folder. Preset:
/// `scenarios/ins-dvl.toml` (the `vkf` preset's filter tuning).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InsDvlToml {
    /// The experiment this file is for.
    ///
    /// Range: `"ins-dvl"`.
    pub experiment: String,
    /// Where the log is.
    pub data: LogDirToml,
    /// The IMU error model the ESKF assumes, in data-sheet units.
    pub imu: ImuModelToml,
    /// DVL handling.
    pub dvl: DvlAidToml,
    /// Depth gauge.
    pub depth: DepthSigmaToml,
    /// The velocity Kalman filter `[V, sf, b]` of the RPM speed (eq. 6 of seed 002).
    pub vkf: VkfTuningToml,
    /// The 9-state `[p, v, accel bias]` filter of PINS-based aiding.
    pub nav_filter: NavTuningToml,
    /// The 15-state error-state filter.
    pub eskf: EskfTuningToml,
    /// Outputs.
    pub output: OutputToml,
    /// The methods to run on the same log. Default: PINS, INS-DVL, VKF,
    /// INS-DVL-gated (gate 0.999) and ESKF.
    #[serde(default = "default_methods")]
    pub methods: Vec<InsDvlMethodToml>,
}

/// `[imu]`: what the ESKF assumes about the IMU (1 σ per axis).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImuModelToml {
    /// Gyro bias: the initial σ of the ESKF's gyro-bias estimate (with the
    /// instability).
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_bias_deg_per_hr: f64,
    /// Gyro bias instability; with its correlation time it sets the bias random walk
    /// `σ √(2/τ)`.
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_bias_instability_deg_per_hr: f64,
    /// Its correlation time.
    ///
    /// Unit: s. Range: > 0.
    pub gyro_bias_corr_time_s: f64,
    /// Gyro angle random walk.
    ///
    /// Unit: deg/√h. Range: ≥ 0.
    pub gyro_arw_deg_per_sqrt_hr: f64,
    /// Accelerometer bias: the initial σ of the ESKF's estimate (with the instability).
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_bias_mg: f64,
    /// Accelerometer bias instability.
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_bias_instability_mg: f64,
    /// Its correlation time.
    ///
    /// Unit: s. Range: > 0.
    pub accel_bias_corr_time_s: f64,
    /// Accelerometer velocity random walk.
    ///
    /// Unit: m/s/√s. Range: ≥ 0.
    pub accel_vrw_mps_per_sqrt_s: f64,
}

/// `[dvl]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DvlAidToml {
    /// Velocity noise σ per axis the filters assume for a DVL update.
    ///
    /// Unit: m/s. Range: > 0.
    pub sigma_mps: f64,
    /// Bottom-lock range: a DVL row is judged invalid when the latest echo-sounder
    /// altitude (`altitude.csv`) exceeds it (and when its `bottom_lock` flag is 0).
    ///
    /// Unit: m. Range: > 0.
    pub range_m: f64,
    /// A DVL silent for longer than this counts as lost: each `rpm.csv` row after
    /// that is an aiding epoch of its own (RPM speed for VKF and ESKF).
    ///
    /// Unit: s. Range: > 0.
    pub timeout_s: f64,
}

/// `[depth]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DepthSigmaToml {
    /// Depth noise σ of every filter's depth update.
    ///
    /// Unit: m. Range: > 0.
    pub sigma_m: f64,
}

crate::vkf_toml! {
    /// `[vkf]`: the `vkf` experiment's keys (their docs name its true values; a log's
    /// are unknown), and the noise of `rpm.csv`.
    pub struct VkfTuningToml {
        ..
        /// Revolution noise σ of `rpm.csv`.
        ///
        /// Unit: rpm. Range: ≥ 0.
        pub rpm_sigma: f64,
    }
}

crate::nav_filter_toml! {
    /// `[nav_filter]`.
    pub struct NavTuningToml {
        /// The filters' covariances are propagated every this many seconds of IMU data
        /// (and before every update); the states at every IMU row.
        ///
        /// Unit: s. Range: > 0.
        pub covariance_period_s: f64,
        ..
    }
}

/// `[eskf]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EskfTuningToml {
    /// Initial attitude σ.
    ///
    /// Unit: rad. Range: > 0.
    pub sigma0_att_rad: f64,
}

/// One `[[methods]]` entry of an INS / DVL replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InsDvlMethodToml {
    /// Name in tables, CSV headers and figures (unique).
    ///
    /// Range: letters, digits, `_` and `-`.
    pub name: String,
    /// `"pins"` (the strapdown alone, depth held), `"ins-dvl"` (9-state filter on
    /// every DVL row), `"vkf"` (9-state filter aided by the switching box: DVL when
    /// valid, else the VKF's RPM speed) or `"eskf"` (15-state feedback filter, same
    /// switching).
    ///
    /// Range: `"pins"`, `"ins-dvl"`, `"vkf"` or `"eskf"`.
    pub filter: String,
    /// Chi-square gate on the velocity updates: a DVL (or RPM) velocity whose NIS
    /// exceeds the quantile of this probability (3 dof) is not applied.
    ///
    /// Range: (0, 1); not for `"pins"`. Default: no gate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gate_probability: Option<f64>,
}

fn method(name: &str, filter: &str, gate: Option<f64>) -> InsDvlMethodToml {
    InsDvlMethodToml {
        name: name.into(),
        filter: filter.into(),
        gate_probability: gate,
    }
}

/// The default `methods` (the `vkf` experiment's five).
pub fn default_methods() -> Vec<InsDvlMethodToml> {
    vec![
        method("PINS", "pins", None),
        method("INS-DVL", "ins-dvl", None),
        method("VKF", "vkf", None),
        method("INS-DVL-gated", "ins-dvl", Some(0.999)),
        method("ESKF", "eskf", None),
    ]
}

/// What a method runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum InsFilter {
    /// The strapdown alone.
    Pins,
    /// 9-state filter on every DVL row.
    InsDvl,
    /// 9-state filter with the switching box.
    Vkf,
    /// 15-state feedback filter with the switching box.
    Eskf,
}

impl InsFilter {
    /// The TOML spelling.
    pub fn name(self) -> &'static str {
        match self {
            InsFilter::Pins => "pins",
            InsFilter::InsDvl => "ins-dvl",
            InsFilter::Vkf => "vkf",
            InsFilter::Eskf => "eskf",
        }
    }
}

/// A checked method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InsMethod {
    /// Its name.
    pub name: String,
    /// What it runs.
    pub filter: InsFilter,
    /// The probability of the chi-square gate on velocity updates (checked: a
    /// threshold exists), if gated.
    pub gate_probability: Option<f64>,
}

/// Checked settings of an INS / DVL replay.
#[derive(Debug, Clone, PartialEq)]
pub struct InsDvlSettings {
    /// `[data] dir`.
    pub data_dir: String,
    /// The ESKF's IMU error model.
    pub imu_model: ImuErrorModel,
    /// Initial σ of the ESKF's accelerometer and gyro biases (SI).
    pub bias_sigma0: [f64; 2],
    /// DVL velocity σ, m/s.
    pub dvl_sigma: f64,
    /// DVL timeout, s.
    pub dvl_timeout: f64,
    /// The switching box (range, lateral σ).
    pub switch: SwitchingBox,
    /// Depth σ, m.
    pub depth_sigma: f64,
    /// VKF parameters (`speed0` is set from the log's start).
    pub vkf: VelocityFilterParams,
    /// The 9-state filter's configuration.
    pub nav: IntegratedNavConfig,
    /// Covariance period, s.
    pub covariance_period: f64,
    /// ESKF initial attitude σ, rad.
    pub sigma0_att: f64,
    /// Recording period without truth, s.
    pub output_period: f64,
    /// The methods.
    pub methods: Vec<InsMethod>,
}

impl InsDvlToml {
    /// Checks every value (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<InsDvlSettings, SimError> {
        require_experiment(file, &self.experiment, "ins-dvl")?;
        let i = &self.imu;
        let nn = |k: &str, v: f64| require_non_negative(file, k, v);
        let pos = |k: &str, v: f64| require_positive(file, k, v);
        let gyro_bi = deg_per_hour_to_rad_per_s(nn(
            "imu.gyro_bias_instability_deg_per_hr",
            i.gyro_bias_instability_deg_per_hr,
        )?);
        let accel_bi = milli_g_to_mps2(nn(
            "imu.accel_bias_instability_mg",
            i.accel_bias_instability_mg,
        )?);
        let gyro_tau = pos("imu.gyro_bias_corr_time_s", i.gyro_bias_corr_time_s)?;
        let accel_tau = pos("imu.accel_bias_corr_time_s", i.accel_bias_corr_time_s)?;
        let gyro_bias =
            deg_per_hour_to_rad_per_s(nn("imu.gyro_bias_deg_per_hr", i.gyro_bias_deg_per_hr)?);
        let accel_bias = milli_g_to_mps2(nn("imu.accel_bias_mg", i.accel_bias_mg)?);
        let imu_model = ImuErrorParams {
            accel_vrw: nn("imu.accel_vrw_mps_per_sqrt_s", i.accel_vrw_mps_per_sqrt_s)?,
            gyro_arw: deg_per_sqrt_hour_to_rad_per_sqrt_s(nn(
                "imu.gyro_arw_deg_per_sqrt_hr",
                i.gyro_arw_deg_per_sqrt_hr,
            )?),
            accel_bias: BiasModel::RandomWalk {
                sigma_rate: accel_bi * (2.0 / accel_tau).sqrt(),
            },
            gyro_bias: BiasModel::RandomWalk {
                sigma_rate: gyro_bi * (2.0 / gyro_tau).sqrt(),
            },
        }
        .check()
        .map_err(|e| parameter_invalid(file, "imu", i, &e))?;
        let bias_sigma0 = [accel_bias.hypot(accel_bi), gyro_bias.hypot(gyro_bi)];
        for (k, v) in [
            ("imu.accel_bias_mg", bias_sigma0[0]),
            ("imu.gyro_bias_deg_per_hr", bias_sigma0[1]),
        ] {
            if v.is_nan() || v <= 0.0 {
                return Err(SimError::invalid(
                    file,
                    k,
                    "the bias and its instability are both 0: the ESKF needs an initial bias σ > 0",
                ));
            }
        }
        let d = &self.dvl;
        let switch = SwitchingBox::new(
            pos("dvl.range_m", d.range_m)?,
            pos("vkf.lateral_sigma_mps", self.vkf.lateral_sigma_mps)?,
        )
        .map_err(|e| SimError::invalid(file, "dvl.range_m", e.to_string()))?;
        let k = &self.vkf;
        for (key, v) in [("vkf.sf0", k.sf0), ("vkf.b0", k.b0)] {
            if !v.is_finite() {
                return Err(SimError::invalid(
                    file,
                    key,
                    format!("must be finite, got {v}"),
                ));
            }
        }
        nn("vkf.speed_process_sigma_mps", k.speed_process_sigma_mps)?;
        for (key, v) in [
            ("vkf.sigma_speed0_mps", k.sigma_speed0_mps),
            ("vkf.sigma_sf0", k.sigma_sf0),
            ("vkf.sigma_b0_mps", k.sigma_b0_mps),
        ] {
            pos(key, v)?;
        }
        let rpm_sigma = nn("vkf.rpm_sigma", k.rpm_sigma)?;
        nn("vkf.sf_rw_psd", k.sf_rw_psd)?;
        nn("vkf.bias_rw_psd", k.bias_rw_psd)?;
        pos("vkf.dvl_sigma_mps", k.dvl_sigma_mps)?;
        let vkf = *k.velocity_filter_config(file, 0.0, rpm_sigma)?.params();
        let n = &self.nav_filter;
        pos("nav_filter.accel_psd", n.accel_psd)?;
        nn("nav_filter.accel_bias_rw_psd", n.accel_bias_rw_psd)?;
        for (key, v) in [
            ("nav_filter.sigma0_pos_m", n.sigma0_pos_m),
            ("nav_filter.sigma0_vel_mps", n.sigma0_vel_mps),
            (
                "nav_filter.sigma0_accel_bias_mps2",
                n.sigma0_accel_bias_mps2,
            ),
        ] {
            pos(key, v)?;
        }
        let nav = n.integrated_nav_config(file)?;
        let names: Vec<&str> = self.methods.iter().map(|m| m.name.as_str()).collect();
        check_method_names(file, &names)?;
        let methods = self
            .methods
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let filter = match m.filter.as_str() {
                    "pins" => InsFilter::Pins,
                    "ins-dvl" => InsFilter::InsDvl,
                    "vkf" => InsFilter::Vkf,
                    "eskf" => InsFilter::Eskf,
                    other => {
                        return Err(SimError::invalid(
                            file,
                            format!("methods[{i}].filter"),
                            format!(
                                "must be \"pins\", \"ins-dvl\", \"vkf\" or \"eskf\", got {other:?}"
                            ),
                        ));
                    }
                };
                let key = format!("methods[{i}].gate_probability");
                let gate = match (m.gate_probability, filter) {
                    (None, _) => None,
                    (Some(_), InsFilter::Pins) => {
                        return Err(SimError::invalid(
                            file,
                            key,
                            "does not apply to \"pins\" (no updates); remove it",
                        ));
                    }
                    (Some(p), _) => {
                        if !(p > 0.0 && p < 1.0) {
                            return Err(SimError::invalid(
                                file,
                                key,
                                format!("must be in (0, 1), got {p}"),
                            ));
                        }
                        GateThreshold::from_chi_square_probability(p, 3)
                            .map_err(|e| SimError::invalid(file, &key, e.to_string()))?;
                        Some(p)
                    }
                };
                Ok(InsMethod {
                    name: m.name.clone(),
                    filter,
                    gate_probability: gate,
                })
            })
            .collect::<Result<Vec<_>, SimError>>()?;
        Ok(InsDvlSettings {
            data_dir: self.data.dir.clone(),
            imu_model,
            bias_sigma0,
            dvl_sigma: pos("dvl.sigma_mps", d.sigma_mps)?,
            dvl_timeout: pos("dvl.timeout_s", d.timeout_s)?,
            switch,
            depth_sigma: pos("depth.sigma_m", self.depth.sigma_m)?,
            vkf,
            nav,
            covariance_period: require_in_range(
                file,
                "nav_filter.covariance_period_s",
                n.covariance_period_s,
                1e-6,
                3600.0,
            )?,
            sigma0_att: pos("eskf.sigma0_att_rad", self.eskf.sigma0_att_rad)?,
            output_period: self.output.period(file)?,
            methods,
        })
    }
}

// A deterministic scenario: no `runs`, no `base_seed` (one replay of a recorded log).
fathom_sim::deterministic_scenario!(InsDvlToml);

/// Parses and checks a settings text (`file` labels error messages).
///
/// # Errors
/// [`SimError::Toml`] for syntax / schema errors, [`SimError::Invalid`] for bad values.
pub fn parse_settings(text: &str, file: &str) -> Result<InsDvlSettings, SimError> {
    let toml: InsDvlToml = fathom_sim::scenario::parse_toml(text, file)?;
    toml.check(file)
}
