//! The Plaza replay settings: the `plaza.toml` schema, its check into
//! [`PlazaSettings`], and the filter variants the settings ask for.

use fathom_estimators::{schemes::UpdateScheme, wheel_odometry::WheelOdometryParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use fathom_data::plaza::RangeOrder;
use fathom_sim::SimError;
use fathom_sim::scenario::{require_in_range, require_non_negative, require_positive};

/// Range-beacon localization on real data.
///
/// The CMU Plaza1 log (real odometry, ranges and ground truth): wheel-odometry EKF with
/// range offset/scale states, robust gating under AS / SC / SI, and ablations. One
/// deterministic replay, no Monte Carlo (so no `runs` or `base_seed`). The same file
/// configures `fathom replay plaza <dir> [--config FILE]`. Preset:
/// `scenarios/plaza.toml` (also the built-in settings of `fathom replay plaza`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlazaToml {
    /// The experiment this file is for.
    ///
    /// Range: `"plaza"`.
    pub experiment: String,
    /// Also run the fixed-interval RTS smoother over each filter's forward pass and
    /// report the smoothed errors beside the filtered ones (`<method>+RTS`,
    /// post-processing: every range of the log informs every instant).
    ///
    /// Range: `true` or `false`. Default: `false`.
    #[serde(default)]
    pub smooth: bool,
    /// Where the data is and how to read it.
    pub data: DataToml,
    /// Initial pose uncertainty.
    pub initial: InitialToml,
    /// Wheel-odometry noise, growing with distance and angle.
    pub odometry: OdometryToml,
    /// Range noise and calibration states.
    pub ranges: RangesToml,
    /// Outlier handling that cannot lock the filter out.
    pub robust: RobustToml,
    /// Update schemes.
    pub schemes: SchemesToml,
    /// Ablation runs.
    pub ablation: AblationToml,
}

/// `[data]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DataToml {
    /// The data folder for `cargo xtask paper` and `fathom run`: an absolute path, or a
    /// relative one looked up inside the workspace root (`fathom run`: the current
    /// directory), then beside each of its ancestors, nearest first; a folder that is
    /// not found is an error. `fathom replay plaza <dir>` ignores it (without `<dir>`
    /// it uses this folder).
    ///
    /// Range: a path.
    pub dir: String,
    /// Range rows whose time goes backwards: sort them by time (stable) and report the
    /// lines, or refuse the file.
    ///
    /// Range: `"sort"` or `"strict"`.
    pub range_order: String,
}

/// `[initial]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InitialToml {
    /// Position σ per axis (the position is the first ground-truth row).
    ///
    /// Unit: m. Range: > 0.
    pub position_sigma_m: f64,
    /// Heading σ (the heading is the first row of the data set's dead-reckoned path).
    ///
    /// Unit: rad. Range: > 0.
    pub heading_sigma_rad: f64,
}

/// `[odometry]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OdometryToml {
    /// Distance error: `var(dd) = s_d² abs(dd)`.
    ///
    /// Unit: m/√m. Range: ≥ 0.
    pub distance_sigma_per_sqrt_m: f64,
    /// Heading error per distance driven: `var(dθ) = s_hm² abs(dd) + s_hr² abs(dθ)`.
    ///
    /// Unit: rad/√m. Range: ≥ 0.
    pub heading_sigma_per_sqrt_m: f64,
    /// Heading error per angle turned (`s_hr` above).
    ///
    /// Unit: rad/√rad. Range: ≥ 0.
    pub heading_sigma_per_sqrt_rad: f64,
}

/// `[ranges]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangesToml {
    /// White range noise σ.
    ///
    /// Unit: m. Range: > 0.
    pub sigma_m: f64,
    /// Common-mode σ between beacons sampled together: SC's off-diagonal R; it also
    /// adds to every range's variance (σ² + this²) in all schemes.
    ///
    /// Unit: m. Range: ≥ 0.
    pub correlation_sigma_m: f64,
    /// Range model of the main runs: `h = d`, `h = d + o` or `h = (1 + s) d + o` (d =
    /// distance, o and s filter states from a zero prior).
    ///
    /// Range: `"none"`, `"offset"` or `"affine"`.
    pub calibration: String,
    /// Prior σ of the offset o (mean 0).
    ///
    /// Unit: m. Range: > 0.
    pub offset_prior_sigma_m: f64,
    /// Prior σ of the scale error s (mean 0).
    ///
    /// Range: > 0.
    pub scale_prior_sigma: f64,
    /// Random walk of o.
    ///
    /// Unit: m/√s. Range: ≥ 0.
    pub offset_random_walk_m_per_sqrt_s: f64,
    /// Random walk of s.
    ///
    /// Unit: 1/√s. Range: ≥ 0.
    pub scale_random_walk_per_sqrt_s: f64,
}

/// The range noise and the priors of the calibration states: the `[ranges]` table of
/// the range-beacon replay (whose methods choose their calibration each), and
/// [`RangesToml`] less its `calibration`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangeNoiseToml {
    /// White range noise σ.
    ///
    /// Unit: m. Range: > 0.
    pub sigma_m: f64,
    /// Common-mode σ between beacons sampled together: SC's off-diagonal R; it also
    /// adds to every range's variance (σ² + this²) in all schemes.
    ///
    /// Unit: m. Range: ≥ 0.
    pub correlation_sigma_m: f64,
    /// Prior σ of the range offset state (mean 0; methods with `calibration` "offset"
    /// or "affine").
    ///
    /// Unit: m. Range: > 0.
    pub offset_prior_sigma_m: f64,
    /// Prior σ of the range scale error state (mean 0; "affine").
    ///
    /// Range: > 0.
    pub scale_prior_sigma: f64,
    /// Random walk of the offset.
    ///
    /// Unit: m/√s. Range: ≥ 0.
    pub offset_random_walk_m_per_sqrt_s: f64,
    /// Random walk of the scale error.
    ///
    /// Unit: 1/√s. Range: ≥ 0.
    pub scale_random_walk_per_sqrt_s: f64,
}

impl RangesToml {
    /// The range noise and the calibration priors (all but `calibration`).
    pub fn noise(&self) -> RangeNoiseToml {
        RangeNoiseToml {
            sigma_m: self.sigma_m,
            correlation_sigma_m: self.correlation_sigma_m,
            offset_prior_sigma_m: self.offset_prior_sigma_m,
            scale_prior_sigma: self.scale_prior_sigma,
            offset_random_walk_m_per_sqrt_s: self.offset_random_walk_m_per_sqrt_s,
            scale_random_walk_per_sqrt_s: self.scale_random_walk_per_sqrt_s,
        }
    }
}

/// `[robust]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobustToml {
    /// Huber threshold k: a range with normalized innovation e = abs(ν)/√S > k is
    /// applied with its variance multiplied by e/k.
    ///
    /// Unit: innovation σ. Range: > 0.
    pub huber_k: f64,
    /// Hard rejection beyond this many innovation σ (gross errors only).
    ///
    /// Unit: innovation σ. Range: ≥ `huber_k`.
    pub reject_sigma: f64,
    /// After this many consecutive rejected or down-weighted ranges (overall, or of one
    /// beacon) the state covariance is inflated.
    ///
    /// Range: ≥ 1.
    pub recovery_after: usize,
    /// The factor on the whole state covariance, so the gate opens again.
    ///
    /// Range: > 1.
    pub recovery_inflation: f64,
}

/// `[schemes]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SchemesToml {
    /// Sync epoch period of SC and SI (paper B's AS / SC / SI reading).
    ///
    /// Unit: s. Range: 0.001 ... 3600 (every epoch is a filter update: a shorter
    /// period multiplies the updates, not the information).
    pub epoch_s: f64,
}

/// `[ablation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AblationToml {
    /// The scheme of the ablation runs (no calibration, offset only when `calibration =
    /// "affine"`, hard gating only, both).
    ///
    /// Range: `"AS"`, `"SC"` or `"SI"`.
    pub scheme: String,
    /// Gate of the "hard gating only" ablations: paper B's eq. (10) gate, no Huber, no
    /// recovery.
    ///
    /// Unit: innovation σ. Range: > 0.
    pub hard_gate_sigma: f64,
}

/// The range calibration states of the filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Calibration {
    /// `h = |p - b|`: ranges taken at face value.
    None,
    /// `h = |p - b| + o`.
    Offset,
    /// `h = (1 + s) |p - b| + o`.
    Affine,
}

impl Calibration {
    /// Number of calibration states.
    pub fn states(self) -> usize {
        match self {
            Calibration::None => 0,
            Calibration::Offset => 1,
            Calibration::Affine => 2,
        }
    }

    /// The TOML spelling.
    pub fn name(self) -> &'static str {
        match self {
            Calibration::None => "none",
            Calibration::Offset => "offset",
            Calibration::Affine => "affine",
        }
    }
}

/// Checked settings of a Plaza replay.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlazaSettings {
    /// Smooth every filter's forward pass (RTS).
    #[serde(default)]
    pub smooth: bool,
    /// `[data] dir`.
    pub data_dir: String,
    /// `[data] range_order`.
    pub range_order: RangeOrder,
    /// Initial position sigma, m.
    pub position_sigma: f64,
    /// Initial heading sigma, rad.
    pub heading_sigma: f64,
    /// Odometry noise (calibration random walks are filled in per variant).
    pub odometry: WheelOdometryParams,
    /// Range sigma, m.
    pub range_sigma: f64,
    /// Common-mode range correlation sigma, m.
    pub correlation_sigma: f64,
    /// Calibration of the main runs.
    pub calibration: Calibration,
    /// Offset prior sigma, m.
    pub offset_prior_sigma: f64,
    /// Scale prior sigma.
    pub scale_prior_sigma: f64,
    /// Offset random walk, m/sqrt(s).
    pub offset_random_walk: f64,
    /// Scale random walk, 1/sqrt(s).
    pub scale_random_walk: f64,
    /// Huber threshold.
    pub huber_k: f64,
    /// Hard rejection, sigmas.
    pub reject_sigma: f64,
    /// Consecutive rejected or down-weighted ranges before inflation.
    pub recovery_after: usize,
    /// Inflation factor.
    pub recovery_inflation: f64,
    /// Epoch period, s.
    pub epoch: f64,
    /// Scheme of the ablation runs.
    pub ablation_scheme: UpdateScheme,
    /// Gate of the hard-gating-only ablation, sigmas.
    pub hard_gate_sigma: f64,
}

pub(crate) fn scheme_from_name(
    file: &str,
    key: &str,
    name: &str,
) -> Result<UpdateScheme, SimError> {
    UpdateScheme::ALL
        .into_iter()
        .find(|s| s.short_name() == name)
        .ok_or_else(|| {
            SimError::invalid(
                file,
                key,
                format!("must be \"AS\", \"SC\" or \"SI\", got {name:?}"),
            )
        })
}

/// The calibration spelled `name` (the value of key `key`).
pub(crate) fn calibration_from_name(
    file: &str,
    key: &str,
    name: &str,
) -> Result<Calibration, SimError> {
    match name {
        "none" => Ok(Calibration::None),
        "offset" => Ok(Calibration::Offset),
        "affine" => Ok(Calibration::Affine),
        other => Err(SimError::invalid(
            file,
            key,
            format!("must be \"none\", \"offset\" or \"affine\", got {other:?}"),
        )),
    }
}

/// The tuning both range replays' settings files have (the Plaza replay's and the
/// range-beacon replay's), borrowed from either: the `[initial]` σ, `[odometry]`, the
/// range noise of `[ranges]`, `[robust]` and `[schemes]`.
pub(crate) struct SharedTuning<'a> {
    /// `[data] dir`.
    pub data_dir: &'a str,
    /// `[initial] position_sigma_m`.
    pub position_sigma_m: f64,
    /// `[initial] heading_sigma_rad`.
    pub heading_sigma_rad: f64,
    /// `[odometry]`.
    pub odometry: &'a OdometryToml,
    /// `[ranges]` but its `calibration`.
    pub ranges: &'a RangeNoiseToml,
    /// `[robust]`.
    pub robust: &'a RobustToml,
    /// `[schemes]`.
    pub schemes: &'a SchemesToml,
}

impl SharedTuning<'_> {
    /// Checks the keys into the engine's settings; the keys only the Plaza replay has
    /// get the values the range-beacon replay runs with (no smoothing, strict range
    /// order, no calibration, SC ablations behind a 1 σ gate: its methods bring their
    /// own), which the Plaza replay replaces.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key (`robust.*` first, then in file order).
    pub(crate) fn check(&self, file: &str) -> Result<PlazaSettings, SimError> {
        let r = self.ranges;
        let rb = self.robust;
        let (huber_k, reject_sigma) = rb.check(file)?;
        Ok(PlazaSettings {
            smooth: false,
            data_dir: self.data_dir.to_string(),
            range_order: RangeOrder::Strict,
            position_sigma: require_positive(
                file,
                "initial.position_sigma_m",
                self.position_sigma_m,
            )?,
            heading_sigma: require_positive(
                file,
                "initial.heading_sigma_rad",
                self.heading_sigma_rad,
            )?,
            odometry: self.odometry.check(file)?,
            range_sigma: require_positive(file, "ranges.sigma_m", r.sigma_m)?,
            correlation_sigma: require_non_negative(
                file,
                "ranges.correlation_sigma_m",
                r.correlation_sigma_m,
            )?,
            calibration: Calibration::None,
            offset_prior_sigma: require_positive(
                file,
                "ranges.offset_prior_sigma_m",
                r.offset_prior_sigma_m,
            )?,
            scale_prior_sigma: require_positive(
                file,
                "ranges.scale_prior_sigma",
                r.scale_prior_sigma,
            )?,
            offset_random_walk: require_non_negative(
                file,
                "ranges.offset_random_walk_m_per_sqrt_s",
                r.offset_random_walk_m_per_sqrt_s,
            )?,
            scale_random_walk: require_non_negative(
                file,
                "ranges.scale_random_walk_per_sqrt_s",
                r.scale_random_walk_per_sqrt_s,
            )?,
            huber_k,
            reject_sigma,
            recovery_after: rb.recovery_after,
            recovery_inflation: rb.recovery_inflation,
            epoch: require_in_range(file, "schemes.epoch_s", self.schemes.epoch_s, 1e-3, 3600.0)?,
            ablation_scheme: UpdateScheme::SynchronousCollective,
            hard_gate_sigma: 1.0,
        })
    }
}

impl PlazaToml {
    /// Checks the values (errors name `file` and the key).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<PlazaSettings, SimError> {
        fathom_sim::scenario::require_experiment(file, &self.experiment, "plaza")?;
        let range_order = match self.data.range_order.as_str() {
            "sort" => RangeOrder::Sort,
            "strict" => RangeOrder::Strict,
            other => {
                return Err(SimError::invalid(
                    file,
                    "data.range_order",
                    format!("must be \"sort\" or \"strict\", got {other:?}"),
                ));
            }
        };
        let calibration =
            calibration_from_name(file, "ranges.calibration", &self.ranges.calibration)?;
        let tuning = SharedTuning {
            data_dir: &self.data.dir,
            position_sigma_m: self.initial.position_sigma_m,
            heading_sigma_rad: self.initial.heading_sigma_rad,
            odometry: &self.odometry,
            ranges: &self.ranges.noise(),
            robust: &self.robust,
            schemes: &self.schemes,
        }
        .check(file)?;
        Ok(PlazaSettings {
            smooth: self.smooth,
            range_order,
            calibration,
            ablation_scheme: scheme_from_name(file, "ablation.scheme", &self.ablation.scheme)?,
            hard_gate_sigma: require_positive(
                file,
                "ablation.hard_gate_sigma",
                self.ablation.hard_gate_sigma,
            )?,
            ..tuning
        })
    }
}

impl OdometryToml {
    /// Checks the noise densities (every key ≥ 0) into the filter's parameters.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming `odometry.<key>`.
    pub fn check(&self, file: &str) -> Result<WheelOdometryParams, SimError> {
        Ok(WheelOdometryParams {
            distance_sigma_per_sqrt_m: require_non_negative(
                file,
                "odometry.distance_sigma_per_sqrt_m",
                self.distance_sigma_per_sqrt_m,
            )?,
            heading_sigma_per_sqrt_m: require_non_negative(
                file,
                "odometry.heading_sigma_per_sqrt_m",
                self.heading_sigma_per_sqrt_m,
            )?,
            heading_sigma_per_sqrt_rad: require_non_negative(
                file,
                "odometry.heading_sigma_per_sqrt_rad",
                self.heading_sigma_per_sqrt_rad,
            )?,
            calibration_random_walk: Vec::new(),
        })
    }
}

impl RobustToml {
    /// Checks the robust handling's keys; returns the Huber threshold and the
    /// rejection threshold (`huber_k <= reject_sigma`).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming `robust.<key>`.
    pub fn check(&self, file: &str) -> Result<(f64, f64), SimError> {
        if self.recovery_after == 0 {
            return Err(SimError::invalid(
                file,
                "robust.recovery_after",
                "must be at least 1",
            ));
        }
        if !(self.recovery_inflation.is_finite() && self.recovery_inflation > 1.0) {
            return Err(SimError::invalid(
                file,
                "robust.recovery_inflation",
                format!("must be > 1, got {}", self.recovery_inflation),
            ));
        }
        let huber_k = require_positive(file, "robust.huber_k", self.huber_k)?;
        let reject_sigma = require_positive(file, "robust.reject_sigma", self.reject_sigma)?;
        if reject_sigma < huber_k {
            return Err(SimError::invalid(
                file,
                "robust.reject_sigma",
                format!("must be >= robust.huber_k ({huber_k}), got {reject_sigma}"),
            ));
        }
        Ok((huber_k, reject_sigma))
    }
}

/// Parses and checks a settings text (`file` labels error messages).
///
/// # Errors
/// [`SimError::Toml`] for syntax / schema errors, [`SimError::Invalid`] for bad values.
pub fn parse_settings(text: &str, file: &str) -> Result<PlazaSettings, SimError> {
    let toml: PlazaToml = fathom_sim::scenario::parse_toml(text, file)?;
    toml.check(file)
}

/// Outlier handling of a variant.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum OutlierHandling {
    /// Huber down-weighting, hard rejection at `reject_sigma`, lock-out recovery.
    Robust,
    /// Paper B's gate only: reject beyond this many sigmas, nothing else.
    HardGate(f64),
}

/// One filter configuration that is run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Variant {
    /// Method name in the summary (`AS`, `SC-no-bias`, ...).
    pub name: String,
    /// Update scheme.
    pub scheme: UpdateScheme,
    /// Calibration states.
    pub calibration: Calibration,
    /// Outlier handling.
    pub outliers: OutlierHandling,
    /// Whether this is an ablation (not a main method).
    pub ablation: bool,
}

impl PlazaSettings {
    /// The main runs (AS, SC, SI with the configured calibration and robust handling)
    /// followed by the ablations of [`PlazaSettings::ablation_scheme`]: no calibration,
    /// offset only, hard gating only, and both.
    pub fn variants(&self) -> Vec<Variant> {
        let mut v: Vec<Variant> = UpdateScheme::ALL
            .into_iter()
            .map(|scheme| Variant {
                name: scheme.short_name().to_string(),
                scheme,
                calibration: self.calibration,
                outliers: OutlierHandling::Robust,
                ablation: false,
            })
            .collect();
        let s = self.ablation_scheme;
        let base = s.short_name();
        let hard = OutlierHandling::HardGate(self.hard_gate_sigma);
        let mut add = |suffix: &str, calibration, outliers| {
            v.push(Variant {
                name: format!("{base}-{suffix}"),
                scheme: s,
                calibration,
                outliers,
                ablation: true,
            });
        };
        add("no-bias", Calibration::None, OutlierHandling::Robust);
        if self.calibration == Calibration::Affine {
            add("offset-only", Calibration::Offset, OutlierHandling::Robust);
        }
        add("hard-gate", self.calibration, hard);
        add("no-bias-hard-gate", Calibration::None, hard);
        v
    }
}

// A deterministic scenario: no `runs`, no `base_seed` (one replay of a recorded log).
fathom_sim::deterministic_scenario!(PlazaToml);
