//! The `range-beacon` replay settings: the schema of `scenarios/range-beacon.toml`
//! (shared tuning, then a `[[methods]]` list with each method's own choices), and its
//! check into [`RangeBeaconSettings`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::plaza::settings::{SharedTuning, calibration_from_name, scheme_from_name};
use crate::plaza::{
    Calibration, OdometryToml, OutlierHandling, PlazaSettings, RangeNoiseToml, RobustToml,
    SchemesToml, Variant,
};
use fathom_sim::SimError;
use fathom_sim::method_list::check_method_names;
use fathom_sim::scenario::{
    require_experiment, require_in_range, require_non_negative, require_positive,
};

/// Range-beacon localization on your own log.
///
/// Replays dead reckoning and the range-beacon EKF under the AS / SC / SI update
/// schemes on a log in fathom's CSV layout (`docs/own-data.md`, kind `range-beacon`):
/// wheel odometry (2D, with optional range offset / scale states) or DVL + heading
/// (3D with depth), ranges to the beacons of a beacon table, optional ground truth.
/// With truth the report scores position errors; without, it shows the innovations,
/// their NIS and the filters' consistency. One deterministic replay (no `runs` or
/// `base_seed`). `fathom replay range-beacon <dir> [--config FILE]` runs it on a
/// folder. Preset: `scenarios/range-beacon.toml` (the `plaza` preset's tuning and
/// methods: a converted Plaza log replays to the `plaza` numbers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangeBeaconToml {
    /// The experiment this file is for.
    ///
    /// Range: `"range-beacon"`.
    pub experiment: String,
    /// Where the log is.
    pub data: LogDirToml,
    /// Initial pose uncertainty (the pose itself is the log's `initial.csv`).
    pub initial: InitialSigmaToml,
    /// Wheel-odometry noise, growing with distance and angle (logs with
    /// `odometry.csv`).
    pub odometry: OdometryToml,
    /// DVL + heading dead reckoning (logs with `dvl.csv` and `heading.csv`).
    pub dvl: DvlMotionToml,
    /// Range noise and the priors of the calibration states.
    pub ranges: RangeNoiseToml,
    /// Depth gauge (logs with `depth.csv`).
    pub depth: DepthNoiseToml,
    /// Robust outlier handling (methods with `outliers = "robust"`).
    pub robust: RobustToml,
    /// Update schemes.
    pub schemes: SchemesToml,
    /// Outputs.
    pub output: OutputToml,
    /// The methods to run, each with its own choices; every method of the list runs
    /// on the same log. Default: dead reckoning and the EKF under AS, SC and SI with
    /// robust gating (and, for odometry logs, affine range calibration).
    #[serde(default = "default_methods")]
    pub methods: Vec<RangeBeaconMethodToml>,
}

/// `[data]` of a replay of one's own log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LogDirToml {
    /// The log folder (fathom's CSV layout, `docs/own-data.md`): an absolute path, or
    /// a relative one looked up inside the current directory (`cargo xtask paper`:
    /// the workspace root), then beside each of its ancestors.
    /// `fathom replay <kind> <dir>` replaces it with `<dir>`. A folder that is not
    /// found is an error.
    ///
    /// Range: a path.
    pub dir: String,
}

/// `[initial]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InitialSigmaToml {
    /// Position σ per axis of the start in `initial.csv`.
    ///
    /// Unit: m. Range: > 0.
    pub position_sigma_m: f64,
    /// Heading σ of the start.
    ///
    /// Unit: rad. Range: > 0.
    pub heading_sigma_rad: f64,
}

/// `[dvl]`: dead reckoning from DVL body velocity and heading.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DvlMotionToml {
    /// Error σ of a DVL sample `(u, v, w)`, held until the next one (the hold time is
    /// the log's median DVL interval).
    ///
    /// Unit: m/s. Range: each ≥ 0.
    pub velocity_sigma_mps: [f64; 3],
    /// Error σ of the yaw rate formed from consecutive headings, held over their
    /// interval (the median heading interval).
    ///
    /// Unit: rad/s. Range: ≥ 0.
    pub yaw_rate_sigma_rad_per_s: f64,
    /// Error σ of each heading row used also as an absolute heading measurement (a
    /// compass or AHRS heading: corrects the drift of the integrated yaw rate). Unset:
    /// headings enter only as yaw rates.
    ///
    /// Unit: rad. Range: > 0. Default: unset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading_sigma_rad: Option<f64>,
}

/// `[depth]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DepthNoiseToml {
    /// Depth-gauge noise σ (never gated).
    ///
    /// Unit: m. Range: > 0.
    pub sigma_m: f64,
}

/// `[output]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputToml {
    /// Without `truth.csv`: the estimates are recorded every this many seconds from
    /// the start (with truth: at every truth row after the start).
    ///
    /// Unit: s. Range: 0.001 ... 86400 (a shorter period than 1 ms records nothing a
    /// log's sensors resolve, and would only multiply the rows).
    pub period_s: f64,
}

impl OutputToml {
    /// `period_s`, checked.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming `output.period_s` outside 0.001 ... 86400 s.
    pub fn period(&self, file: &str) -> Result<f64, SimError> {
        require_in_range(file, "output.period_s", self.period_s, 1e-3, 86_400.0)
    }
}

/// One `[[methods]]` entry of a range-beacon replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangeBeaconMethodToml {
    /// Name in tables, CSV headers and figures (unique).
    ///
    /// Range: letters, digits, `_` and `-`.
    pub name: String,
    /// `"dead-reckoning"` (the motion alone) or `"ekf"` (the range-beacon EKF).
    ///
    /// Range: `"ekf"` or `"dead-reckoning"`. Default: `"ekf"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter: Option<String>,
    /// Update scheme of an `"ekf"` method.
    ///
    /// Range: `"AS"`, `"SC"` or `"SI"`; required for `"ekf"`, not allowed for
    /// `"dead-reckoning"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scheme: Option<String>,
    /// Range calibration states of an `"ekf"` method: `h = d`, `h = d + o`, `h = (1 +
    /// s) d + o` (`d` the distance, `o` and `s` filter states from a zero prior). Only
    /// the 2D odometry model has them; left out, a method uses `"affine"` on odometry
    /// logs and `"none"` on DVL logs.
    ///
    /// Range: `"none"`, `"offset"` or `"affine"` (DVL logs: `"none"`). Default: by log.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<String>,
    /// Outlier handling of an `"ekf"` method: Huber down-weighting with hard rejection
    /// at `robust.reject_sigma` and lock-out recovery (`"robust"`), or only a gate at
    /// `gate_sigma` innovation σ (`"gate"`).
    ///
    /// Range: `"robust"` or `"gate"`. Default: `"robust"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outliers: Option<String>,
    /// The gate of `outliers = "gate"`.
    ///
    /// Unit: innovation σ. Range: > 0; required with `"gate"`, not allowed otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gate_sigma: Option<f64>,
}

fn method(name: &str, scheme: Option<&str>, calibration: Option<&str>) -> RangeBeaconMethodToml {
    RangeBeaconMethodToml {
        name: name.into(),
        filter: scheme.is_none().then(|| "dead-reckoning".into()),
        scheme: scheme.map(Into::into),
        calibration: calibration.map(Into::into),
        outliers: None,
        gate_sigma: None,
    }
}

/// The default `methods`: DR and AS / SC / SI with robust gating and the log's
/// calibration (affine on odometry logs, none on DVL logs).
pub fn default_methods() -> Vec<RangeBeaconMethodToml> {
    vec![
        method("DR", None, None),
        method("AS", Some("AS"), None),
        method("SC", Some("SC"), None),
        method("SI", Some("SI"), None),
    ]
}

/// What a method runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum MethodKind {
    /// The motion alone.
    DeadReckoning,
    /// The EKF variant (scheme, calibration, outlier handling; its `name` is the
    /// method's).
    Ekf(Variant),
}

/// A checked method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodSpec {
    /// Its name.
    pub name: String,
    /// What it runs.
    pub kind: MethodKind,
    /// Whether the calibration was left out (then it follows the log: affine on
    /// odometry logs, none on DVL logs; see [`MethodSpec::for_log`]).
    pub calibration_by_log: bool,
}

impl MethodSpec {
    /// The method as it runs on an odometry (`odometry`) or DVL log: a calibration
    /// left out becomes affine or none.
    pub fn for_log(&self, odometry: bool) -> MethodSpec {
        let mut m = self.clone();
        if let (true, MethodKind::Ekf(v)) = (m.calibration_by_log, &mut m.kind) {
            v.calibration = if odometry {
                Calibration::Affine
            } else {
                Calibration::None
            };
        }
        m
    }

    /// One line saying what the method is (`EKF, SC, affine calibration, robust`).
    pub fn describe(&self) -> String {
        match &self.kind {
            MethodKind::DeadReckoning => "dead reckoning".into(),
            MethodKind::Ekf(v) => format!(
                "EKF, {}, {}, {}",
                v.scheme.short_name(),
                match v.calibration {
                    Calibration::None => "no range calibration".to_string(),
                    c => format!("{} range calibration", c.name()),
                },
                match v.outliers {
                    OutlierHandling::Robust => "robust outlier handling".to_string(),
                    OutlierHandling::HardGate(g) => format!("gate at {g} σ"),
                }
            ),
        }
    }
}

/// Checked settings of a range-beacon replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RangeBeaconSettings {
    /// `[data] dir`.
    pub data_dir: String,
    /// The shared tuning in the form of the Plaza replay's engine (the wheel-odometry
    /// filter runs through it; `calibration`, `ablation_scheme` and `hard_gate_sigma`
    /// are per method here and unused).
    pub engine: PlazaSettings,
    /// DVL velocity error σ `(u, v, w)`, m/s.
    pub dvl_velocity_sigma: [f64; 3],
    /// Yaw-rate error σ, rad/s.
    pub yaw_rate_sigma: f64,
    /// Absolute heading error σ, rad (`None`: no absolute heading update).
    pub heading_sigma: Option<f64>,
    /// Depth σ, m.
    pub depth_sigma: f64,
    /// Recording period without truth, s.
    pub output_period: f64,
    /// The methods, in the file's order.
    pub methods: Vec<MethodSpec>,
}

impl RangeBeaconToml {
    /// Checks every value (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key (`methods[2].scheme`, ...).
    pub fn check(&self, file: &str) -> Result<RangeBeaconSettings, SimError> {
        require_experiment(file, &self.experiment, "range-beacon")?;
        let engine = SharedTuning {
            data_dir: &self.data.dir,
            position_sigma_m: self.initial.position_sigma_m,
            heading_sigma_rad: self.initial.heading_sigma_rad,
            odometry: &self.odometry,
            ranges: &self.ranges,
            robust: &self.robust,
            schemes: &self.schemes,
        }
        .check(file)?;
        let mut dvl_velocity_sigma = [0.0; 3];
        for (i, s) in self.dvl.velocity_sigma_mps.iter().enumerate() {
            dvl_velocity_sigma[i] =
                require_non_negative(file, &format!("dvl.velocity_sigma_mps[{i}]"), *s)?;
        }
        let names: Vec<&str> = self.methods.iter().map(|m| m.name.as_str()).collect();
        check_method_names(file, &names)?;
        let methods = self
            .methods
            .iter()
            .enumerate()
            .map(|(i, m)| check_method(file, i, m))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(RangeBeaconSettings {
            data_dir: self.data.dir.clone(),
            engine,
            dvl_velocity_sigma,
            yaw_rate_sigma: require_non_negative(
                file,
                "dvl.yaw_rate_sigma_rad_per_s",
                self.dvl.yaw_rate_sigma_rad_per_s,
            )?,
            heading_sigma: self
                .dvl
                .heading_sigma_rad
                .map(|v| require_positive(file, "dvl.heading_sigma_rad", v))
                .transpose()?,
            depth_sigma: require_positive(file, "depth.sigma_m", self.depth.sigma_m)?,
            output_period: self.output.period(file)?,
            methods,
        })
    }
}

fn check_method(file: &str, i: usize, m: &RangeBeaconMethodToml) -> Result<MethodSpec, SimError> {
    let key = |k: &str| format!("methods[{i}].{k}");
    let not_for = |k: &str, what: &str| {
        SimError::invalid(file, key(k), format!("does not apply to {what}; remove it"))
    };
    let filter = m.filter.as_deref().unwrap_or("ekf");
    let kind = match filter {
        "dead-reckoning" => {
            let dr = "a dead-reckoning method";
            if m.scheme.is_some() {
                return Err(not_for("scheme", dr));
            }
            if m.calibration.is_some() {
                return Err(not_for("calibration", dr));
            }
            if m.outliers.is_some() {
                return Err(not_for("outliers", dr));
            }
            if m.gate_sigma.is_some() {
                return Err(not_for("gate_sigma", dr));
            }
            MethodKind::DeadReckoning
        }
        "ekf" => {
            let Some(scheme) = m.scheme.as_deref() else {
                return Err(SimError::invalid(
                    file,
                    key("scheme"),
                    "an \"ekf\" method needs its update scheme: \"AS\", \"SC\" or \"SI\"",
                ));
            };
            let scheme = scheme_from_name(file, &key("scheme"), scheme)?;
            let calibration = calibration_from_name(
                file,
                &key("calibration"),
                m.calibration.as_deref().unwrap_or("none"),
            )?;
            let outliers = match (m.outliers.as_deref().unwrap_or("robust"), m.gate_sigma) {
                ("robust", None) => OutlierHandling::Robust,
                ("robust", Some(_)) => {
                    return Err(not_for(
                        "gate_sigma",
                        "outliers = \"robust\" (it uses robust.reject_sigma)",
                    ));
                }
                ("gate", Some(g)) => {
                    OutlierHandling::HardGate(require_positive(file, &key("gate_sigma"), g)?)
                }
                ("gate", None) => {
                    return Err(SimError::invalid(
                        file,
                        key("gate_sigma"),
                        "outliers = \"gate\" needs its gate in innovation σ, e.g. gate_sigma = 2.5",
                    ));
                }
                (other, _) => {
                    return Err(SimError::invalid(
                        file,
                        key("outliers"),
                        format!("must be \"robust\" or \"gate\", got {other:?}"),
                    ));
                }
            };
            MethodKind::Ekf(Variant {
                name: m.name.clone(),
                scheme,
                calibration,
                outliers,
                ablation: false,
            })
        }
        other => {
            return Err(SimError::invalid(
                file,
                key("filter"),
                format!("must be \"ekf\" or \"dead-reckoning\", got {other:?}"),
            ));
        }
    };
    Ok(MethodSpec {
        name: m.name.clone(),
        calibration_by_log: m.calibration.is_none() && matches!(kind, MethodKind::Ekf(_)),
        kind,
    })
}

// A deterministic scenario: no `runs`, no `base_seed` (one replay of a recorded log).
fathom_sim::deterministic_scenario!(RangeBeaconToml);

/// Parses and checks a settings text (`file` labels error messages).
///
/// # Errors
/// [`SimError::Toml`] for syntax / schema errors, [`SimError::Invalid`] for bad values.
pub fn parse_settings(text: &str, file: &str) -> Result<RangeBeaconSettings, SimError> {
    let toml: RangeBeaconToml = fathom_sim::scenario::parse_toml(text, file)?;
    toml.check(file)
}
