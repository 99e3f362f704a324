//! The `gnss-ins` replay settings: the schema of `scenarios/gnss-ins.toml` (IMU noise,
//! GNSS handling with outage windows, initial uncertainty, the optional world and the
//! map-aided filters' tuning, then a `[[methods]]` list) and its check into
//! [`GnssInsSettings`].

use fathom_estimators::map_aided::{ImuNoise, Ins12Params};

pub use super::map_settings::{MapAidedSettings, MapAidedToml, WorldSettings, WorldToml};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::range_beacon::LogDirToml;
use fathom_sim::SimError;
use fathom_sim::method_list::check_method_names;
use fathom_sim::parameter_key::parameter_invalid;
use fathom_sim::scenario::{
    require_experiment, require_in_range, require_non_negative, require_positive,
};

/// GNSS / INS navigation of a drone flight (a PX4 ULog, or a `gnss-ins` log).
///
/// Replays a strapdown INS (the local-level mechanization of `fathom_ins`) alone and
/// aided by the log's GNSS fixes, with the 12-state error-state filter of the `urban`
/// experiment (`[dp, dv, psi, b_a]`) and its 15-state extension with a gyro bias,
/// against the autopilot's own estimate (PX4's EKF2, `reference.csv`: "agreement with
/// EKF2") and, when the log has it, the simulator's ground truth. GNSS outages can be
/// injected (fixes dropped in given windows) to show dead-reckoning drift. One
/// deterministic replay. `fathom replay gnss-ins <dir>` or `fathom replay ulog
/// <file.ulg>` runs it. Preset: `scenarios/gnss-ins.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssInsToml {
    /// The experiment this file is for.
    ///
    /// Range: `"gnss-ins"`.
    pub experiment: String,
    /// Where the log is (a `gnss-ins` folder, or a `.ulg` file converted in memory).
    pub data: LogDirToml,
    /// The IMU noise the filters assume.
    pub imu: GnssInsImuToml,
    /// GNSS handling.
    pub gnss: GnssAidToml,
    /// Initial uncertainty of the filters.
    pub initial: GnssInsInitialToml,
    /// A world mesh for the map-aided filters (`--world FILE` sets `file`). With a
    /// world and range rows in the log, the methods `GREKF` and `MGPMF` run too
    /// (added when `[[methods]]` names no map-aided filter). Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world: Option<WorldToml>,
    /// Tuning of the map-aided filters (used only with a world).
    #[serde(default)]
    pub map_aided: MapAidedToml,
    /// The methods to run on the same log. Default: INS, GPS-INS-12, GPS-INS-15
    /// (and GREKF, MGPMF with a world).
    #[serde(default = "default_methods")]
    pub methods: Vec<GnssInsMethodToml>,
}

/// `[imu]`: white noise and bias random walks, SI.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssInsImuToml {
    /// Accelerometer white noise (velocity random walk).
    ///
    /// Unit: m/s/√s. Range: >= 0.
    pub velocity_random_walk_mps_per_sqrt_s: f64,
    /// Gyro white noise (angle random walk).
    ///
    /// Unit: rad/√s. Range: >= 0.
    pub angle_random_walk_rad_per_sqrt_s: f64,
    /// Accelerometer-bias random walk.
    ///
    /// Unit: m/s²/√s. Range: >= 0.
    pub accel_bias_random_walk_mps2_per_sqrt_s: f64,
    /// Gyro-bias random walk (the 15-state filter).
    ///
    /// Unit: rad/s/√s. Range: >= 0.
    pub gyro_bias_random_walk_radps_per_sqrt_s: f64,
}

/// `[gnss]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssAidToml {
    /// The lowest fix type used (PX4: 3 = 3D, 4 = DGPS, 5 RTK float, 6 RTK fixed).
    ///
    /// Range: 2 to 6.
    pub min_fix_type: u32,
    /// Floor of the horizontal and vertical σ of a fix (the receiver's `eph`, `epv`
    /// are used above it).
    ///
    /// Unit: m. Range: > 0.
    pub min_sigma_m: f64,
    /// Floor of the velocity σ (the receiver's speed accuracy above it).
    ///
    /// Unit: m/s. Range: > 0.
    pub min_speed_sigma_mps: f64,
    /// Whether the fixes' velocity is used too (6-dof updates).
    pub use_velocity: bool,
    /// Probability that a consistent fix passes the chi-square gate.
    ///
    /// Range: 0 to 1 (exclusive).
    pub gate_probability: f64,
    /// Re-acquisition: the fix that makes this many in a row rejected by the gate
    /// resets the filter onto the fixes: the position (and, with `use_velocity`, the
    /// velocity) covariance is widened by the outer product of the error the fix
    /// shows and the fix applied (it then passes the gate). Counted per method
    /// (`gnss_resets`). 0: never (a diverged filter rejects every fix for ever).
    ///
    /// Range: 0 to 1000.
    #[serde(default = "default_reacquire")]
    pub reacquire_after_rejections: usize,
    /// Outage windows: fixes in `[start_s, end_s)` (seconds from the replay's start)
    /// are dropped.
    #[serde(default)]
    pub outages: Vec<OutageToml>,
}

/// The default of `gnss.reacquire_after_rejections`: 5 fixes (1 s of a 5 Hz
/// receiver). A consistent filter rejects a consistent fix with the probability
/// `1 - gnss.gate_probability` (1e-4 in the preset), five in a row practically
/// never: such a run means the filter diverged (or the receiver jumped for a
/// second and more, which the filter then follows).
pub fn default_reacquire() -> usize {
    5
}

/// One GNSS outage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutageToml {
    /// Start, seconds after the replay's start.
    ///
    /// Unit: s. Range: >= 0.
    pub start_s: f64,
    /// End (exclusive), seconds after the replay's start.
    ///
    /// Unit: s. Range: > start_s.
    pub end_s: f64,
}

/// `[initial]`: the filters' initial σ (the start state is EKF2's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssInsInitialToml {
    /// Position σ per axis.
    ///
    /// Unit: m. Range: > 0.
    pub sigma_pos_m: f64,
    /// Velocity σ per axis.
    ///
    /// Unit: m/s. Range: > 0.
    pub sigma_vel_mps: f64,
    /// Attitude σ per axis.
    ///
    /// Unit: rad. Range: > 0.
    pub sigma_att_rad: f64,
    /// Accelerometer-bias σ per axis.
    ///
    /// Unit: m/s². Range: > 0.
    pub sigma_accel_bias_mps2: f64,
    /// Gyro-bias σ per axis (the 15-state filter).
    ///
    /// Unit: rad/s. Range: > 0.
    pub sigma_gyro_bias_radps: f64,
}

/// One `[[methods]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssInsMethodToml {
    /// Name in tables, CSV headers and figures (unique).
    pub name: String,
    /// `"ins"` (strapdown alone), `"gps-ins-12"` (12-state filter), `"gps-ins-15"`
    /// (15-state filter with gyro bias), or with a world `"grekf"` / `"mgpmf"` (the
    /// 12-state filter switching to the map-aided range update while GNSS is away).
    pub filter: String,
}

/// The default methods.
pub fn default_methods() -> Vec<GnssInsMethodToml> {
    [
        ("INS", "ins"),
        ("GPS-INS-12", "gps-ins-12"),
        ("GPS-INS-15", "gps-ins-15"),
    ]
    .into_iter()
    .map(|(n, f)| GnssInsMethodToml {
        name: n.into(),
        filter: f.into(),
    })
    .collect()
}

/// What a method runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GnssInsFilter {
    /// The strapdown INS alone.
    Ins,
    /// The 12-state error-state filter `[dp, dv, psi, b_a]`.
    Ekf12,
    /// The 15-state filter `[dp, dv, psi, b_a, b_g]`.
    Ekf15,
    /// The 12-state filter with the GREKF range update while GNSS is away.
    Grekf,
    /// The 12-state filter with the MGPMF range update while GNSS is away.
    Mgpmf,
}

impl GnssInsFilter {
    /// Whether it is a map-aided filter (needs a world and range rows).
    pub fn is_map_aided(self) -> bool {
        matches!(self, Self::Grekf | Self::Mgpmf)
    }
}

/// The `filter` values.
pub const FILTERS: [(&str, GnssInsFilter); 5] = [
    ("ins", GnssInsFilter::Ins),
    ("gps-ins-12", GnssInsFilter::Ekf12),
    ("gps-ins-15", GnssInsFilter::Ekf15),
    ("grekf", GnssInsFilter::Grekf),
    ("mgpmf", GnssInsFilter::Mgpmf),
];

/// A checked method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GnssInsMethod {
    /// Its name.
    pub name: String,
    /// What it runs.
    pub filter: GnssInsFilter,
}

/// Checked settings.
#[derive(Debug, Clone, PartialEq)]
pub struct GnssInsSettings {
    /// The settings file's label (errors found later name it).
    pub file: String,
    /// `[data] dir`.
    pub data_dir: String,
    /// IMU noise PSDs of the 12-state model.
    pub noise: ImuNoise,
    /// Gyro-bias random-walk PSD, (rad/s)^2/s.
    pub gyro_bias_psd: f64,
    /// Lowest fix type used.
    pub min_fix_type: u32,
    /// σ floors: position m, velocity m/s.
    pub min_sigma: [f64; 2],
    /// Whether the fix velocity is used.
    pub use_velocity: bool,
    /// Gate probability.
    pub gate_probability: f64,
    /// Fixes rejected in a row before the re-acquisition (0: never).
    pub reacquire_after: usize,
    /// Outage windows `[start, end)`, s from the start, sorted.
    pub outages: Vec<[f64; 2]>,
    /// Initial σ: position, velocity, attitude, accel bias, gyro bias.
    pub sigma0: [f64; 5],
    /// The world, if any.
    pub world: Option<WorldSettings>,
    /// The map-aided filters' tuning.
    pub map_aided: MapAidedSettings,
    /// The methods.
    pub methods: Vec<GnssInsMethod>,
}

impl GnssInsSettings {
    /// The world file as written (bounded for display), or `-` without one.
    pub fn world_file(&self) -> String {
        self.world
            .as_ref()
            .map_or_else(|| "-".into(), |w| fathom_core::echo::echo_file(&w.file))
    }

    /// Whether `t` (s from the start) is inside an outage.
    pub fn in_outage(&self, t: f64) -> bool {
        self.outages.iter().any(|w| t >= w[0] && t < w[1])
    }
}

impl GnssInsToml {
    /// Checks every value.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<GnssInsSettings, SimError> {
        require_experiment(file, &self.experiment, "gnss-ins")?;
        let i = &self.imu;
        let noise = Ins12Params {
            velocity_random_walk_mps_per_sqrt_s: i.velocity_random_walk_mps_per_sqrt_s,
            angle_random_walk_rad_per_sqrt_s: i.angle_random_walk_rad_per_sqrt_s,
            accel_bias_random_walk_mps2_per_sqrt_s: i.accel_bias_random_walk_mps2_per_sqrt_s,
        }
        .check()
        .map_err(|e| parameter_invalid(file, "imu", i, &e))?;
        let gbrw = require_non_negative(
            file,
            "imu.gyro_bias_random_walk_radps_per_sqrt_s",
            i.gyro_bias_random_walk_radps_per_sqrt_s,
        )?;
        let g = &self.gnss;
        require_in_range(
            file,
            "gnss.min_fix_type",
            f64::from(g.min_fix_type),
            2.0,
            6.0,
        )?;
        let p = g.gate_probability;
        if !(p > 0.0 && p < 1.0) {
            return Err(SimError::invalid(
                file,
                "gnss.gate_probability",
                format!("must be strictly between 0 and 1, got {p}"),
            ));
        }
        if g.reacquire_after_rejections > 1000 {
            return Err(SimError::invalid(
                file,
                "gnss.reacquire_after_rejections",
                format!(
                    "must be 0 (never) to 1000, got {}",
                    g.reacquire_after_rejections
                ),
            ));
        }
        let mut outages = Vec::with_capacity(g.outages.len());
        for (k, o) in g.outages.iter().enumerate() {
            let start =
                require_non_negative(file, &format!("gnss.outages[{k}].start_s"), o.start_s)?;
            let end = require_positive(file, &format!("gnss.outages[{k}].end_s"), o.end_s)?;
            if end <= start {
                return Err(SimError::invalid(
                    file,
                    format!("gnss.outages[{k}].end_s"),
                    format!("must be after start_s ({start} s), got {end} s"),
                ));
            }
            outages.push([start, end]);
        }
        outages.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let s = &self.initial;
        let pos = |k: &str, v: f64| require_positive(file, k, v);
        let sigma0 = [
            pos("initial.sigma_pos_m", s.sigma_pos_m)?,
            pos("initial.sigma_vel_mps", s.sigma_vel_mps)?,
            pos("initial.sigma_att_rad", s.sigma_att_rad)?,
            pos("initial.sigma_accel_bias_mps2", s.sigma_accel_bias_mps2)?,
            pos("initial.sigma_gyro_bias_radps", s.sigma_gyro_bias_radps)?,
        ];
        let names: Vec<&str> = self.methods.iter().map(|m| m.name.as_str()).collect();
        check_method_names(file, &names)?;
        let methods = self
            .methods
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let filter = FILTERS
                    .iter()
                    .find(|(n, _)| *n == m.filter)
                    .map(|f| f.1)
                    .ok_or_else(|| {
                        SimError::invalid(
                            file,
                            format!("methods[{k}].filter"),
                            format!(
                                "unknown filter \"{}\"; use one of: ins, gps-ins-12, gps-ins-15, \
                                 grekf, mgpmf",
                                fathom_core::echo::echo(&m.filter)
                            ),
                        )
                    })?;
                if filter.is_map_aided() && self.world.is_none() {
                    return Err(SimError::invalid(
                        file,
                        format!("methods[{k}].filter"),
                        format!(
                            "\"{}\" needs a world: give `--world FILE` (or `[world] file`)",
                            m.filter
                        ),
                    ));
                }
                Ok(GnssInsMethod {
                    name: m.name.clone(),
                    filter,
                })
            })
            .collect::<Result<Vec<GnssInsMethod>, SimError>>()?;
        let world = self.world.as_ref().map(|w| w.check(file)).transpose()?;
        let map_aided = self.map_aided.check(file)?;
        let mut methods = methods;
        if world.is_some() && !methods.iter().any(|m| m.filter.is_map_aided()) {
            for (name, filter) in [
                ("GREKF", GnssInsFilter::Grekf),
                ("MGPMF", GnssInsFilter::Mgpmf),
            ] {
                if methods.iter().any(|m| m.name == name) {
                    return Err(SimError::invalid(
                        file,
                        "methods",
                        format!(
                            "a method is named \"{name}\", the name of the map-aided method a \
                             world adds: rename it, or list the map-aided methods yourself"
                        ),
                    ));
                }
                methods.push(GnssInsMethod {
                    name: name.into(),
                    filter,
                });
            }
        }
        Ok(GnssInsSettings {
            file: file.to_string(),
            data_dir: self.data.dir.clone(),
            noise,
            gyro_bias_psd: gbrw * gbrw,
            min_fix_type: g.min_fix_type,
            min_sigma: [
                pos("gnss.min_sigma_m", g.min_sigma_m)?,
                pos("gnss.min_speed_sigma_mps", g.min_speed_sigma_mps)?,
            ],
            use_velocity: g.use_velocity,
            gate_probability: p,
            reacquire_after: g.reacquire_after_rejections,
            outages,
            sigma0,
            world,
            map_aided,
            methods,
        })
    }
}

// A deterministic scenario: no `runs`, no `base_seed` (one replay of a recorded log).
fathom_sim::deterministic_scenario!(GnssInsToml);

/// Parses and checks a settings text (`file` labels errors).
///
/// # Errors
/// The TOML's or the check's [`SimError`].
pub fn parse_settings(text: &str, file: &str) -> Result<GnssInsSettings, SimError> {
    let toml: GnssInsToml = fathom_sim::scenario::parse_toml(text, file)?;
    toml.check(file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::own_log::GNSS_INS_PRESET;

    #[test]
    fn the_preset_checks_and_bad_values_name_their_key() {
        let s = parse_settings(GNSS_INS_PRESET, "p.toml").unwrap();
        assert_eq!(s.methods.len(), 3);
        assert!(s.outages.is_empty() && !s.in_outage(5.0));
        let with_outage = GNSS_INS_PRESET.replace(
            "gate_probability = 0.9999\n",
            "gate_probability = 0.9999\n[[gnss.outages]]\nstart_s = 10.0\nend_s = 30.0\n",
        );
        let s = parse_settings(&with_outage, "p.toml").unwrap();
        assert!(s.in_outage(10.0) && s.in_outage(29.9) && !s.in_outage(30.0) && !s.in_outage(9.9));
        let e = |text: String| parse_settings(&text, "p.toml").unwrap_err().to_string();
        let backwards = with_outage.replace("end_s = 30.0", "end_s = 5.0");
        assert!(e(backwards).contains("gnss.outages[0].end_s"));
        let unknown = GNSS_INS_PRESET.replace(
            "use_velocity = true",
            "use_velocity = true\nlatency_s = 0.1",
        );
        assert!(e(unknown).contains("latency_s"));
        let gate = GNSS_INS_PRESET.replace("gate_probability = 0.9999", "gate_probability = 1.0");
        assert!(e(gate).contains("gnss.gate_probability"));
        let fix = GNSS_INS_PRESET.replace("min_fix_type = 3", "min_fix_type = 9");
        assert!(e(fix).contains("gnss.min_fix_type"));
        let sigma = GNSS_INS_PRESET.replace("sigma_att_rad = 0.05", "sigma_att_rad = 0.0");
        assert!(e(sigma).contains("initial.sigma_att_rad"));
        // re-acquisition: 5 built in, 0 (never) accepted, beyond 1000 refused, the
        // default when the key is left out
        assert_eq!(s.reacquire_after, 5);
        let key = "reacquire_after_rejections = 5 ";
        assert!(GNSS_INS_PRESET.contains(key));
        let never = GNSS_INS_PRESET.replace(key, "reacquire_after_rejections = 0 ");
        assert_eq!(parse_settings(&never, "p.toml").unwrap().reacquire_after, 0);
        let huge = GNSS_INS_PRESET.replace(key, "reacquire_after_rejections = 5000 ");
        assert!(e(huge).contains("gnss.reacquire_after_rejections"));
        let line = GNSS_INS_PRESET
            .lines()
            .find(|l| l.starts_with(key))
            .unwrap()
            .to_string();
        let left_out = GNSS_INS_PRESET.replace(&format!("{line}\n"), "");
        let d = parse_settings(&left_out, "p.toml").unwrap();
        assert_eq!(d.reacquire_after, default_reacquire());
    }
}
