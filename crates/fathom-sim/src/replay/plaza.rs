//! Range-beacon localization replayed on a CMU Plaza log: pure dead reckoning and the
//! EKF of [`fathom_estimators::wheel_odometry`] under the AS / SC / SI update schemes
//! of [`fathom_estimators::schemes`], with range calibration states and robust,
//! lock-out-free outlier handling ([`fathom_estimators::robust`]), plus ablations.
//!
//! # Time
//! Everything runs on **relative** time `t - t0`, `t0` = the first ground-truth time:
//! the sync epochs, the odometry rates and the evaluation instants depend only on
//! differences of the file's stamps, never on their absolute value. A log whose clock
//! is shifted by a constant gives the same errors (to the rounding of the shifted
//! stamps, ~1e-12 s).
//!
//! # Ids
//! Beacons are addressed by their row in the survey `TL` (the filter channel); their ids
//! are only used to look ranges up. Within an epoch the SC/SI updates are ordered by
//! channel, i.e. by survey row, not by id.
//!
//! # Events
//! - odometry row `k` (stamp `t_k`) covers `(t_{k-1}, t_k]`; its increments become rates
//!   held over that interval, i.e. an input event stamped `t_{k-1}` (for the first row:
//!   `t0`). The rates are thus used one odometry period (~0.2 s) before the row is
//!   logged, as a real-time filter does by buffering odometry. Rows at or before `t0`
//!   are already in the initial pose and skipped; after the last row the robot stands;
//! - range rows with `t > t0` are scalar observations on their beacon's channel;
//! - every ground-truth row with `t > t0` is an evaluation instant: the filter is
//!   brought to it (`advance_to`) and the 2D position error is recorded.
//!
//! Ties are ordered input, range, evaluation.

use fathom_core::Gaussian;
use fathom_estimators::{
    GateThreshold,
    ekf::Ekf,
    robust::{RecoveryParams, RobustParams},
    schemes::{Disposition, Event, Observation, SchemeFilter, SchemeParams, UpdateScheme},
    wheel_odometry::{CalibratedRange, OdometryRate, WheelOdometry, WheelOdometryParams},
};
use fathom_stats::RunStats;
use nalgebra::{DMatrix, SMatrix, SVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::SimError;
use crate::data::plaza::{BeaconSite, PlazaLog, PoseRecord, RangeOrder};
use crate::scenario::{require_non_negative, require_positive};

// ---------------------------------------------------------------------------
// Scenario schema
// ---------------------------------------------------------------------------

/// The `plaza.toml` settings file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlazaToml {
    /// The experiment this scenario is for: must be `"plaza"` (lets `fathom run`
    /// pick the experiment from the file).
    pub experiment: String,
    /// Where the data is and how to read it.
    pub data: DataToml,
    /// Initial pose uncertainty.
    pub initial: InitialToml,
    /// Odometry noise.
    pub odometry: OdometryToml,
    /// Range noise and calibration.
    pub ranges: RangesToml,
    /// Outlier handling.
    pub robust: RobustToml,
    /// Update schemes.
    pub schemes: SchemesToml,
    /// Ablation runs.
    pub ablation: AblationToml,
}

/// `[data]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataToml {
    /// Data folder for `cargo xtask paper` and `fathom run`: an absolute path, or a
    /// relative one looked up inside the workspace root (for `fathom run` the current
    /// directory), then beside each of its ancestors, nearest first. `fathom replay plaza
    /// <dir>` ignores it.
    pub dir: String,
    /// `"sort"` or `"strict"` ([`RangeOrder`]).
    pub range_order: String,
}

/// `[initial]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialToml {
    /// Initial position sigma per axis, m.
    pub position_sigma_m: f64,
    /// Initial heading sigma, rad.
    pub heading_sigma_rad: f64,
}

/// `[odometry]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OdometryToml {
    /// Distance error, m/sqrt(m).
    pub distance_sigma_per_sqrt_m: f64,
    /// Heading error per distance, rad/sqrt(m).
    pub heading_sigma_per_sqrt_m: f64,
    /// Heading error per angle turned, rad/sqrt(rad).
    pub heading_sigma_per_sqrt_rad: f64,
}

/// `[ranges]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangesToml {
    /// White range noise sigma, m.
    pub sigma_m: f64,
    /// Common-mode correlation sigma between beacons, m: SC's off-diagonal R, and
    /// added to every range's variance (`sigma_m^2 + correlation_sigma_m^2`) in all
    /// schemes.
    pub correlation_sigma_m: f64,
    /// `"none"`, `"offset"` or `"affine"` ([`Calibration`]).
    pub calibration: String,
    /// Prior sigma of the range offset (prior mean 0), m.
    pub offset_prior_sigma_m: f64,
    /// Prior sigma of the range scale error (prior mean 0).
    pub scale_prior_sigma: f64,
    /// Random walk of the offset, m/sqrt(s).
    pub offset_random_walk_m_per_sqrt_s: f64,
    /// Random walk of the scale error, 1/sqrt(s).
    pub scale_random_walk_per_sqrt_s: f64,
}

/// `[robust]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustToml {
    /// Huber threshold on the normalized innovation.
    pub huber_k: f64,
    /// Hard rejection threshold, innovation sigmas.
    pub reject_sigma: f64,
    /// Consecutive rejected or down-weighted ranges before covariance inflation.
    pub recovery_after: usize,
    /// Covariance inflation factor.
    pub recovery_inflation: f64,
}

/// `[schemes]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SchemesToml {
    /// Sync epoch period of SC / SI, s.
    pub epoch_s: f64,
}

/// `[ablation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AblationToml {
    /// `"AS"`, `"SC"` or `"SI"`.
    pub scheme: String,
    /// Gate of the hard-gating-only variant, innovation sigmas.
    pub hard_gate_sigma: f64,
}

/// The range calibration states of the filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
#[derive(Debug, Clone, PartialEq)]
pub struct PlazaSettings {
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

fn scheme_from_name(file: &str, key: &str, name: &str) -> Result<UpdateScheme, SimError> {
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

impl PlazaToml {
    /// Checks the values (errors name `file` and the key).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<PlazaSettings, SimError> {
        crate::scenario::require_experiment(file, &self.experiment, "plaza")?;
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
        let calibration = match self.ranges.calibration.as_str() {
            "none" => Calibration::None,
            "offset" => Calibration::Offset,
            "affine" => Calibration::Affine,
            other => {
                return Err(SimError::invalid(
                    file,
                    "ranges.calibration",
                    format!("must be \"none\", \"offset\" or \"affine\", got {other:?}"),
                ));
            }
        };
        let o = &self.odometry;
        let r = &self.ranges;
        let rb = &self.robust;
        if rb.recovery_after == 0 {
            return Err(SimError::invalid(
                file,
                "robust.recovery_after",
                "must be at least 1",
            ));
        }
        if !(rb.recovery_inflation.is_finite() && rb.recovery_inflation > 1.0) {
            return Err(SimError::invalid(
                file,
                "robust.recovery_inflation",
                format!("must be > 1, got {}", rb.recovery_inflation),
            ));
        }
        let huber_k = require_positive(file, "robust.huber_k", rb.huber_k)?;
        let reject_sigma = require_positive(file, "robust.reject_sigma", rb.reject_sigma)?;
        if reject_sigma < huber_k {
            return Err(SimError::invalid(
                file,
                "robust.reject_sigma",
                format!("must be >= robust.huber_k ({huber_k}), got {reject_sigma}"),
            ));
        }
        Ok(PlazaSettings {
            data_dir: self.data.dir.clone(),
            range_order,
            position_sigma: require_positive(
                file,
                "initial.position_sigma_m",
                self.initial.position_sigma_m,
            )?,
            heading_sigma: require_positive(
                file,
                "initial.heading_sigma_rad",
                self.initial.heading_sigma_rad,
            )?,
            odometry: WheelOdometryParams {
                distance_sigma_per_sqrt_m: require_non_negative(
                    file,
                    "odometry.distance_sigma_per_sqrt_m",
                    o.distance_sigma_per_sqrt_m,
                )?,
                heading_sigma_per_sqrt_m: require_non_negative(
                    file,
                    "odometry.heading_sigma_per_sqrt_m",
                    o.heading_sigma_per_sqrt_m,
                )?,
                heading_sigma_per_sqrt_rad: require_non_negative(
                    file,
                    "odometry.heading_sigma_per_sqrt_rad",
                    o.heading_sigma_per_sqrt_rad,
                )?,
                calibration_random_walk: Vec::new(),
            },
            range_sigma: require_positive(file, "ranges.sigma_m", r.sigma_m)?,
            correlation_sigma: require_non_negative(
                file,
                "ranges.correlation_sigma_m",
                r.correlation_sigma_m,
            )?,
            calibration,
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
            epoch: require_positive(file, "schemes.epoch_s", self.schemes.epoch_s)?,
            ablation_scheme: scheme_from_name(file, "ablation.scheme", &self.ablation.scheme)?,
            hard_gate_sigma: require_positive(
                file,
                "ablation.hard_gate_sigma",
                self.ablation.hard_gate_sigma,
            )?,
        })
    }
}

/// Parses and checks a settings text (`file` labels error messages).
///
/// # Errors
/// [`SimError::Toml`] for syntax / schema errors, [`SimError::Invalid`] for bad values.
pub fn parse_settings(text: &str, file: &str) -> Result<PlazaSettings, SimError> {
    let toml: PlazaToml = crate::scenario::parse_toml(text, file)?;
    toml.check(file)
}

// ---------------------------------------------------------------------------
// Variants
// ---------------------------------------------------------------------------

/// Outlier handling of a variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OutlierHandling {
    /// Huber down-weighting, hard rejection at `reject_sigma`, lock-out recovery.
    Robust,
    /// Paper B's gate only: reject beyond this many sigmas, nothing else.
    HardGate(f64),
}

/// One filter configuration that is run.
#[derive(Debug, Clone, PartialEq)]
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

// ---------------------------------------------------------------------------
// Prepared log (relative time)
// ---------------------------------------------------------------------------

/// A range observation on relative time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedRange {
    /// `t - t0`, s.
    pub time: f64,
    /// Channel = row of the beacon in the survey.
    pub channel: usize,
    /// Measured range, m.
    pub value: f64,
    /// Index in [`PlazaLog::ranges`].
    pub index: usize,
}

/// The log turned into filter events on relative time (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedLog {
    /// Absolute start time `t0` (first ground-truth row), s.
    pub t0: f64,
    /// Initial pose `(x, y, heading)`: GT position, `DRp` heading.
    pub start: [f64; 3],
    /// Odometry rate changes `(t - t0, rate)`.
    pub inputs: Vec<(f64, OdometryRate)>,
    /// Ranges after `t0`.
    pub ranges: Vec<PreparedRange>,
    /// Evaluation instants `(t - t0, true x, true y)`.
    pub eval: Vec<(f64, f64, f64)>,
    /// Beacon positions by channel.
    pub beacons: Vec<Vector2<f64>>,
    /// Odometry rows skipped (at or before `t0`).
    pub skipped_odometry: usize,
    /// Ranges skipped (at or before `t0`).
    pub skipped_ranges: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Input(usize),
    Range(usize),
    Eval(usize),
}

impl PreparedLog {
    /// Prepares `log` (module docs).
    ///
    /// # Errors
    /// [`SimError::Model`] for an odometry row whose rate cannot be formed.
    pub fn new(log: &PlazaLog) -> Result<Self, SimError> {
        let gt0 = log.ground_truth[0];
        let t0 = gt0.time;
        let start = [gt0.x, gt0.y, log.dr_path[0].heading];
        let mut inputs = Vec::with_capacity(log.odometry.len() + 1);
        let mut prev = 0.0;
        let mut skipped_odometry = 0;
        for step in &log.odometry {
            let t = step.time - t0;
            if t <= 0.0 {
                skipped_odometry += 1;
                continue;
            }
            let rate =
                OdometryRate::from_increments(step.delta_distance, step.delta_heading, t - prev)
                    .map_err(|e| {
                        SimError::model(format!("odometry row at t = {} s", step.time), e)
                    })?;
            inputs.push((prev, rate));
            prev = t;
        }
        inputs.push((prev, OdometryRate::default()));
        let mut skipped_ranges = 0;
        let ranges = log
            .ranges
            .iter()
            .enumerate()
            .filter_map(|(index, r)| {
                let time = r.time - t0;
                if time <= 0.0 {
                    skipped_ranges += 1;
                    None
                } else {
                    Some(PreparedRange {
                        time,
                        channel: r.beacon,
                        value: r.range,
                        index,
                    })
                }
            })
            .collect();
        let eval = log.ground_truth[1..]
            .iter()
            .map(|g| (g.time - t0, g.x, g.y))
            .collect();
        Ok(PreparedLog {
            t0,
            start,
            inputs,
            ranges,
            eval,
            beacons: log.beacons.iter().map(|b| Vector2::new(b.x, b.y)).collect(),
            skipped_odometry,
            skipped_ranges,
        })
    }

    /// All events in processing order (module docs).
    fn events(&self, with_ranges: bool) -> Vec<(f64, Kind)> {
        let mut ev: Vec<(f64, Kind)> = self
            .inputs
            .iter()
            .enumerate()
            .map(|(k, i)| (i.0, Kind::Input(k)))
            .chain(
                self.eval
                    .iter()
                    .enumerate()
                    .map(|(k, e)| (e.0, Kind::Eval(k))),
            )
            .collect();
        if with_ranges {
            ev.extend(
                self.ranges
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (r.time, Kind::Range(k))),
            );
        }
        ev.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then_with(|| rank(a.1).cmp(&rank(b.1)))
                .then_with(|| a.1.cmp(&b.1))
        });
        ev
    }
}

fn rank(k: Kind) -> u8 {
    match k {
        Kind::Input(_) => 0,
        Kind::Range(_) => 1,
        Kind::Eval(_) => 2,
    }
}

// ---------------------------------------------------------------------------
// Runs
// ---------------------------------------------------------------------------

/// The result of one method on the log.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodRun {
    /// Method name (`DR`, `AS`, `SC-no-bias`, ...).
    pub name: String,
    /// The variant (`None` for dead reckoning).
    pub variant: Option<Variant>,
    /// Estimated `(x, y)` at the evaluation instants.
    pub est: Vec<[f64; 2]>,
    /// 2D position error at the evaluation instants, m.
    pub err: Vec<f64>,
    /// Statistics of `err`.
    pub stats: RunStats,
    /// `sqrt(P_xx + P_yy)` at the evaluation instants, m.
    pub pos_sigma: Vec<f64>,
    /// Estimated range offset and scale error at the evaluation instants (0 when not
    /// estimated).
    pub calibration: Vec<[f64; 2]>,
    /// Ranges applied.
    pub accepted: usize,
    /// Ranges rejected by the gate.
    pub rejected: usize,
    /// Ranges superseded or stale (SC / SI: an older sample of the same beacon in the
    /// same epoch window).
    pub dropped: usize,
    /// Ranges dropped because the value or the stamp is not finite (never applied;
    /// the filter's bad-data policy, `fathom_estimators` crate docs "Bad input").
    pub non_finite: usize,
    /// Ranges applied with an inflated variance (Huber).
    pub downweighted: usize,
    /// Covariance inflations after runs of rejected or down-weighted ranges.
    pub recoveries: usize,
    /// Per range of the log (index as in [`PlazaLog::ranges`]): the decision, if the
    /// range was processed.
    pub decisions: Vec<Option<Disposition>>,
}

fn finish(
    name: String,
    variant: Option<Variant>,
    prep: &PreparedLog,
    est: Vec<[f64; 2]>,
    pos_sigma: Vec<f64>,
    calibration: Vec<[f64; 2]>,
) -> Result<MethodRun, SimError> {
    let err: Vec<f64> = est
        .iter()
        .zip(&prep.eval)
        .map(|(e, g)| (e[0] - g.1).hypot(e[1] - g.2))
        .collect();
    let stats = RunStats::of(&err)
        .map_err(|e| SimError::model(format!("error statistics of `{name}`"), e))?;
    Ok(MethodRun {
        name,
        variant,
        est,
        err,
        stats,
        pos_sigma,
        calibration,
        accepted: 0,
        rejected: 0,
        dropped: 0,
        non_finite: 0,
        downweighted: 0,
        recoveries: 0,
        decisions: Vec::new(),
    })
}

fn prior<const N: usize>(
    prep: &PreparedLog,
    s: &PlazaSettings,
    cal: Calibration,
) -> Result<Gaussian<N>, SimError> {
    let mut mean = SVector::<f64, N>::zeros();
    mean[0] = prep.start[0];
    mean[1] = prep.start[1];
    mean[2] = prep.start[2];
    let mut cov = SMatrix::<f64, N, N>::zeros();
    cov[(0, 0)] = s.position_sigma.powi(2);
    cov[(1, 1)] = s.position_sigma.powi(2);
    cov[(2, 2)] = s.heading_sigma.powi(2);
    if cal.states() >= 1 {
        cov[(3, 3)] = s.offset_prior_sigma.powi(2);
    }
    if cal.states() >= 2 {
        cov[(4, 4)] = s.scale_prior_sigma.powi(2);
    }
    Gaussian::new(mean, cov).map_err(SimError::from)
}

fn motion(s: &PlazaSettings, cal: Calibration) -> Result<WheelOdometry, SimError> {
    let rw = [s.offset_random_walk, s.scale_random_walk];
    WheelOdometryParams {
        calibration_random_walk: rw[..cal.states()].to_vec(),
        ..s.odometry.clone()
    }
    .check()
    .map_err(|e| SimError::model("odometry parameters", e))
}

/// Pure dead reckoning: the wheel-odometry prediction without any update.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn run_dead_reckoning(prep: &PreparedLog, s: &PlazaSettings) -> Result<MethodRun, SimError> {
    let ctx = |e| SimError::model("dead reckoning", e);
    let mut ekf = Ekf::<3, _>::new(
        prior::<3>(prep, s, Calibration::None)?,
        0.0,
        motion(s, Calibration::None)?,
        OdometryRate::default(),
    )
    .map_err(ctx)?;
    let mut est = Vec::with_capacity(prep.eval.len());
    let mut sig = Vec::with_capacity(prep.eval.len());
    for (t, kind) in prep.events(false) {
        ekf.predict_to(t).map_err(ctx)?;
        match kind {
            Kind::Input(k) => ekf.apply_input(&prep.inputs[k].1),
            Kind::Eval(_) => {
                let (x, p) = (ekf.state(), ekf.covariance());
                est.push([x[0], x[1]]);
                sig.push((p[(0, 0)] + p[(1, 1)]).sqrt());
            }
            Kind::Range(_) => {}
        }
    }
    let n = est.len();
    finish("DR".into(), None, prep, est, sig, vec![[0.0, 0.0]; n])
}

fn run_filter<const N: usize>(
    prep: &PreparedLog,
    s: &PlazaSettings,
    v: &Variant,
    n_log_ranges: usize,
) -> Result<MethodRun, SimError> {
    let ctx = |e| SimError::model(format!("filter `{}`", v.name), e);
    let cal = v.calibration;
    let ekf = Ekf::<N, _>::new(
        prior::<N>(prep, s, cal)?,
        0.0,
        motion(s, cal)?,
        OdometryRate::default(),
    )
    .map_err(ctx)?;
    let c = prep.beacons.len();
    let var = s.range_sigma.powi(2);
    let cov = s.correlation_sigma.powi(2);
    let channel_cov = DMatrix::from_fn(c, c, |i, j| if i == j { var + cov } else { cov });
    let gate_sigma = match v.outliers {
        OutlierHandling::Robust => s.reject_sigma,
        OutlierHandling::HardGate(g) => g,
    };
    let gate = GateThreshold::from_sigma_distance(gate_sigma).map_err(ctx)?;
    let config = SchemeParams {
        scheme: v.scheme,
        epoch_period: s.epoch,
        stale_tolerance: 0.0,
        channel_cov,
        gates: vec![Some(gate); c],
    }
    .check()
    .map_err(ctx)?;
    let mut filter = SchemeFilter::new(ekf, config);
    if v.outliers == OutlierHandling::Robust {
        let policy = RobustParams {
            huber_k: Some(s.huber_k),
            recovery: Some(RecoveryParams {
                after_rejections: s.recovery_after,
                inflation: s.recovery_inflation,
            }),
        }
        .check()
        .map_err(ctx)?;
        filter = filter.with_robust(policy);
    }
    let (offset_state, scale_state) = match cal {
        Calibration::None => (None, None),
        Calibration::Offset => (Some(3), None),
        Calibration::Affine => (Some(3), Some(4)),
    };
    let mut est = Vec::with_capacity(prep.eval.len());
    let mut sig = Vec::with_capacity(prep.eval.len());
    let mut calib = Vec::with_capacity(prep.eval.len());
    for (t, kind) in prep.events(true) {
        match kind {
            Kind::Input(k) => filter
                .process(Event::Input {
                    stamp: t,
                    sample: prep.inputs[k].1,
                })
                .map_err(ctx)?,
            Kind::Range(k) => {
                let r = prep.ranges[k];
                filter
                    .process(Event::Measurement(Observation {
                        channel: r.channel,
                        stamp: t,
                        value: r.value,
                        model: CalibratedRange {
                            beacon: prep.beacons[r.channel],
                            offset_state,
                            scale_state,
                        },
                        tag: r.index,
                    }))
                    .map_err(ctx)?;
            }
            Kind::Eval(_) => {
                filter.advance_to(t).map_err(ctx)?;
                let (x, p) = (filter.ekf().state(), filter.ekf().covariance());
                est.push([x[0], x[1]]);
                sig.push((p[(0, 0)] + p[(1, 1)]).sqrt());
                calib.push([
                    offset_state.map_or(0.0, |i| x[i]),
                    scale_state.map_or(0.0, |i| x[i]),
                ]);
            }
        }
    }
    let mut run = finish(v.name.clone(), Some(v.clone()), prep, est, sig, calib)?;
    let mut decisions = vec![None; n_log_ranges];
    for d in filter.decisions() {
        match d.disposition {
            Disposition::Accepted => run.accepted += 1,
            Disposition::Rejected => run.rejected += 1,
            Disposition::Stale | Disposition::Superseded => run.dropped += 1,
            Disposition::NonFinite => run.non_finite += 1,
        }
        if let Some(slot) = decisions.get_mut(d.tag) {
            *slot = Some(d.disposition);
        }
    }
    run.decisions = decisions;
    run.downweighted = filter.downweighted();
    run.recoveries = filter.recoveries();
    Ok(run)
}

/// Runs one variant.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn run_variant(
    prep: &PreparedLog,
    s: &PlazaSettings,
    v: &Variant,
    n_log_ranges: usize,
) -> Result<MethodRun, SimError> {
    match v.calibration {
        Calibration::None => run_filter::<3>(prep, s, v, n_log_ranges),
        Calibration::Offset => run_filter::<4>(prep, s, v, n_log_ranges),
        Calibration::Affine => run_filter::<5>(prep, s, v, n_log_ranges),
    }
}

// ---------------------------------------------------------------------------
// Range errors against ground truth (analysis for the report only)
// ---------------------------------------------------------------------------

/// Range errors measured against ground truth. Used only to describe the data in the
/// report; the filters never see it.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeAnalysis {
    /// Ranges inside the ground-truth time span.
    pub n: usize,
    /// Mean of `range - true distance`, m.
    pub mean: f64,
    /// Population std, m.
    pub std: f64,
    /// Median, m.
    pub median: f64,
    /// 1.4826 x median absolute deviation from the median, m.
    pub robust_sigma: f64,
    /// Smallest and largest error, m.
    pub min_max: (f64, f64),
    /// Least-squares fit `error = a + b d`: `(a, b)`.
    pub fit: (f64, f64),
    /// Std of the fit residuals, m.
    pub fit_std: f64,
    /// Kurtosis of the fit residuals (3 for a Gaussian).
    pub fit_kurtosis: f64,
    /// Fraction of fit residuals beyond 3 fit-stds.
    pub fit_beyond_3sigma: f64,
    /// Median error per beacon: `(id, count, median)`, survey order.
    pub per_beacon: Vec<(i64, usize, f64)>,
    /// `(time - t0, true distance, error, beacon row)` per range.
    pub samples: Vec<(f64, f64, f64, usize)>,
}

/// Linear interpolation of the ground-truth position at `t` (inside its span).
pub fn truth_at(gt: &[PoseRecord], t: f64) -> Option<(f64, f64)> {
    let i = gt.partition_point(|p| p.time <= t);
    if i == 0 || i >= gt.len() {
        return (i > 0 && gt[i - 1].time == t).then(|| (gt[i - 1].x, gt[i - 1].y));
    }
    let (a, b) = (gt[i - 1], gt[i]);
    let u = (t - a.time) / (b.time - a.time);
    Some((a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)))
}

fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if !n.is_multiple_of(2) {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    }
}

/// Analyses the range errors of `log` against its ground truth.
///
/// # Errors
/// [`SimError::InvalidArgument`] when fewer than 3 ranges fall in the ground-truth span.
pub fn analyse_ranges(log: &PlazaLog) -> Result<RangeAnalysis, SimError> {
    let t0 = log.ground_truth[0].time;
    let samples: Vec<(f64, f64, f64, usize)> = log
        .ranges
        .iter()
        .filter_map(|r| {
            let (x, y) = truth_at(&log.ground_truth, r.time)?;
            let b: &BeaconSite = &log.beacons[r.beacon];
            let d = (x - b.x).hypot(y - b.y);
            Some((r.time - t0, d, r.range - d, r.beacon))
        })
        .collect();
    let n = samples.len();
    if n < 3 {
        return Err(SimError::invalid_argument(
            "range analysis",
            format!("only {n} ranges inside the ground-truth time span"),
        ));
    }
    let nf = n as f64;
    let errs: Vec<f64> = samples.iter().map(|s| s.2).collect();
    let mean = errs.iter().sum::<f64>() / nf;
    let std = (errs.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / nf).sqrt();
    let mut sorted = errs.clone();
    sorted.sort_by(f64::total_cmp);
    let med = median(&sorted);
    let mut dev: Vec<f64> = sorted.iter().map(|e| (e - med).abs()).collect();
    dev.sort_by(f64::total_cmp);
    let robust_sigma = 1.4826 * median(&dev);
    let dm = samples.iter().map(|s| s.1).sum::<f64>() / nf;
    let sxx = samples.iter().map(|s| (s.1 - dm).powi(2)).sum::<f64>();
    let sxy = samples
        .iter()
        .map(|s| (s.1 - dm) * (s.2 - mean))
        .sum::<f64>();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let a = mean - b * dm;
    let res: Vec<f64> = samples.iter().map(|s| s.2 - a - b * s.1).collect();
    let fit_std = (res.iter().map(|r| r * r).sum::<f64>() / nf).sqrt();
    let fit_kurtosis = if fit_std > 0.0 {
        res.iter().map(|r| r.powi(4)).sum::<f64>() / nf / fit_std.powi(4)
    } else {
        0.0
    };
    let fit_beyond_3sigma = res.iter().filter(|r| r.abs() > 3.0 * fit_std).count() as f64 / nf;
    let per_beacon = log
        .beacons
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let mut e: Vec<f64> = samples.iter().filter(|s| s.3 == k).map(|s| s.2).collect();
            e.sort_by(f64::total_cmp);
            let m = if e.is_empty() { 0.0 } else { median(&e) };
            (b.id, e.len(), m)
        })
        .collect();
    Ok(RangeAnalysis {
        n,
        mean,
        std,
        median: med,
        robust_sigma,
        min_max: (sorted[0], sorted[n - 1]),
        fit: (a, b),
        fit_std,
        fit_kurtosis,
        fit_beyond_3sigma,
        per_beacon,
        samples,
    })
}

// ---------------------------------------------------------------------------
// The whole replay
// ---------------------------------------------------------------------------

/// Everything a Plaza replay produced.
#[derive(Debug, Clone, PartialEq)]
pub struct PlazaReplay {
    /// The settings used.
    pub settings: PlazaSettings,
    /// The prepared log (relative time).
    pub prepared: PreparedLog,
    /// `DR`, the main methods, then the ablations.
    pub methods: Vec<MethodRun>,
    /// Range errors against ground truth.
    pub analysis: RangeAnalysis,
    /// Surveyed beacons.
    pub beacons: Vec<BeaconSite>,
    /// Range-file lines where time went backwards.
    pub range_order_breaks: Vec<usize>,
    /// The log's ranges `(absolute time, beacon row, range)`, in [`PlazaLog::ranges`]
    /// order.
    pub log_ranges: Vec<(f64, usize, f64)>,
    /// Counts of rows read: odometry, ranges, ground truth.
    pub rows: (usize, usize, usize),
    /// Name of the data set (file-name prefix of the `.mat` file).
    pub data_name: String,
}

impl PlazaReplay {
    /// The log's ranges `(absolute time, beacon row, range)`.
    pub fn ranges_in_log(&self) -> &[(f64, usize, f64)] {
        &self.log_ranges
    }

    /// The method named `name`.
    pub fn method(&self, name: &str) -> Option<&MethodRun> {
        self.methods.iter().find(|m| m.name == name)
    }
}

/// Runs dead reckoning, every variant and the range analysis on `log`.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors, [`SimError::InvalidArgument`] for a
/// log too short to evaluate.
pub fn replay(log: &PlazaLog, settings: &PlazaSettings) -> Result<PlazaReplay, SimError> {
    if log.ground_truth.len() < 2 {
        return Err(SimError::invalid_argument(
            "Plaza log",
            "needs at least two ground-truth rows",
        ));
    }
    let prepared = PreparedLog::new(log)?;
    let mut methods = vec![run_dead_reckoning(&prepared, settings)?];
    for v in settings.variants() {
        methods.push(run_variant(&prepared, settings, &v, log.ranges.len())?);
    }
    let data_name = log
        .files
        .mat
        .file_name()
        .map(|n| n.to_string_lossy().trim_end_matches("_.mat").to_string())
        .unwrap_or_default();
    Ok(PlazaReplay {
        settings: settings.clone(),
        analysis: analyse_ranges(log)?,
        prepared,
        methods,
        beacons: log.beacons.clone(),
        range_order_breaks: log.range_order_breaks.clone(),
        log_ranges: log
            .ranges
            .iter()
            .map(|r| (r.time, r.beacon, r.range))
            .collect(),
        rows: (log.odometry.len(), log.ranges.len(), log.ground_truth.len()),
        data_name,
    })
}

/// Parses and checks a `plaza` scenario text without running it (`fathom check`);
/// returns the resolved scenario re-serialized as TOML.
///
/// # Errors
/// As the experiment's own loading: [`SimError::Toml`] or [`SimError::Invalid`].
pub fn check_scenario_text(text: &str, file: &str) -> Result<String, SimError> {
    crate::scenario::resolve_scenario_text(text, file, |s: &PlazaToml, f| s.check(f))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::plaza::{OdometryStep, PlazaFiles, RangeRecord};

    fn preset() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/plaza.toml"),
        )
        .unwrap()
    }

    #[test]
    fn settings_parse_and_bad_values_name_the_key() {
        let s = parse_settings(&preset(), "plaza.toml").unwrap();
        assert_eq!(s.calibration, Calibration::Affine);
        assert_eq!(s.ablation_scheme, UpdateScheme::SynchronousCollective);
        let names: Vec<String> = s.variants().into_iter().map(|v| v.name).collect();
        assert_eq!(
            names,
            [
                "AS",
                "SC",
                "SI",
                "SC-no-bias",
                "SC-offset-only",
                "SC-hard-gate",
                "SC-no-bias-hard-gate"
            ]
        );
        for (from, to, key) in [
            (
                "calibration = \"affine\"",
                "calibration = \"cubic\"",
                "ranges.calibration",
            ),
            (
                "range_order = \"sort\"",
                "range_order = \"x\"",
                "data.range_order",
            ),
            ("scheme = \"SC\"", "scheme = \"XX\"", "ablation.scheme"),
            (
                "recovery_after = 5",
                "recovery_after = 0",
                "robust.recovery_after",
            ),
            (
                "recovery_inflation = 4.0",
                "recovery_inflation = 1.0",
                "robust.recovery_inflation",
            ),
            (
                "reject_sigma = 6.0",
                "reject_sigma = 1.0",
                "robust.reject_sigma",
            ),
            ("epoch_s = 0.1", "epoch_s = 0.0", "schemes.epoch_s"),
            ("epoch_s = 0.1", "epoch_s = 0.1\nextra = 1", "schemes.extra"),
        ] {
            let text = preset().replace(from, to);
            let e = parse_settings(&text, "plaza.toml").unwrap_err().to_string();
            assert!(e.contains(key) && e.starts_with("plaza.toml"), "{key}: {e}");
        }
    }

    /// A synthetic log: a 60 m x 40 m loop driven at 1 m/s for 600 s, odometry with a
    /// 1 % distance scale error and a heading-rate bias, ranges `1.05 d + 0.4` with a
    /// deterministic +-0.3 m pattern, ground truth every odometry step.
    fn synthetic_log() -> PlazaLog {
        let t0 = 1000.0;
        let dt = 0.2;
        let beacons = vec![
            BeaconSite {
                id: 10,
                x: -10.0,
                y: -10.0,
            },
            BeaconSite {
                id: 20,
                x: 70.0,
                y: -5.0,
            },
            BeaconSite {
                id: 30,
                x: 65.0,
                y: 50.0,
            },
            BeaconSite {
                id: 40,
                x: -5.0,
                y: 45.0,
            },
        ];
        let (mut x, mut y, mut th) = (0.0f64, 0.0f64, 0.0f64);
        let mut gt = vec![PoseRecord {
            time: t0,
            x,
            y,
            heading: th,
        }];
        let mut odometry = Vec::new();
        let mut ranges = Vec::new();
        for k in 1..=3000 {
            let t = t0 + k as f64 * dt;
            // Turn left 90 degrees over 3 s every 50 s or 30 s (a rounded rectangle).
            let phase = (k as f64 * dt) % 160.0;
            let turning = [(50.0, 53.0), (80.0, 83.0), (130.0, 133.0), (157.0, 160.0)]
                .iter()
                .any(|&(a, b)| phase >= a && phase < b);
            let dth = if turning {
                std::f64::consts::FRAC_PI_2 / 15.0
            } else {
                0.0
            };
            let dd = 1.0 * dt;
            let m = th + dth / 2.0;
            x += dd * m.cos();
            y += dd * m.sin();
            th += dth;
            gt.push(PoseRecord {
                time: t,
                x,
                y,
                heading: th,
            });
            odometry.push(OdometryStep {
                time: t,
                delta_distance: dd * 1.01,
                delta_heading: dth + 0.0005 * dt,
            });
            if k % 2 == 0 {
                let c = (k / 2) % 4;
                let b = beacons[c];
                let d = (x - b.x).hypot(y - b.y);
                let wiggle = 0.3 * ((k as f64) * 0.7).sin();
                ranges.push(RangeRecord {
                    time: t + 0.05,
                    sender: 2,
                    beacon_id: b.id,
                    beacon: c,
                    range: 1.05 * d + 0.4 + wiggle,
                    line: ranges.len() + 1,
                });
            }
        }
        ranges.pop(); // the last one lies after the last ground-truth row
        PlazaLog {
            files: PlazaFiles {
                odometry: "S_DR.txt".into(),
                ranges: "S_TD.txt".into(),
                mat: "S_.mat".into(),
            },
            odometry,
            ranges,
            range_order_breaks: vec![],
            dr_path: vec![gt[0]],
            ground_truth: gt,
            beacons,
        }
    }

    #[test]
    fn prepared_log_uses_relative_time_and_interval_rates() {
        let log = synthetic_log();
        let p = PreparedLog::new(&log).unwrap();
        assert_eq!(p.t0, 1000.0);
        assert_eq!(p.inputs.len(), log.odometry.len() + 1);
        assert_eq!(p.inputs[0].0, 0.0);
        approx::assert_relative_eq!(p.inputs[1].0, 0.2, epsilon = 1e-12);
        approx::assert_relative_eq!(p.inputs[0].1.speed, 1.01, epsilon = 1e-9);
        assert_eq!(p.inputs.last().unwrap().1, OdometryRate::default());
        assert_eq!(p.eval.len(), log.ground_truth.len() - 1);
        approx::assert_relative_eq!(p.ranges[0].time, 0.45, epsilon = 1e-12);
        let ev = p.events(true);
        assert!(ev.windows(2).all(|w| w[0].0 <= w[1].0));
        assert_eq!(ev.len(), p.inputs.len() + p.eval.len() + p.ranges.len());
    }

    #[test]
    fn synthetic_replay_beats_dead_reckoning_and_learns_the_calibration() {
        let log = synthetic_log();
        let settings = parse_settings(&preset(), "plaza.toml").unwrap();
        let r = replay(&log, &settings).unwrap();
        let dr = r.method("DR").unwrap().stats;
        for name in ["AS", "SC", "SI"] {
            let m = r.method(name).unwrap();
            assert!(
                m.stats.mean < 0.5 * dr.mean,
                "{name}: {} vs DR {}",
                m.stats.mean,
                dr.mean
            );
            assert!(m.stats.max < 1.5, "{name}: {}", m.stats.max);
            let last = m.calibration.last().unwrap();
            assert!((last[1] - 0.05).abs() < 0.01, "{name} scale {}", last[1]);
            assert!((last[0] - 0.4).abs() < 0.5, "{name} offset {}", last[0]);
        }
        // Without calibration the 5 % long ranges pull the estimate off.
        let nb = r.method("SC-no-bias").unwrap().stats;
        assert!(nb.mean > 2.0 * r.method("SC").unwrap().stats.mean);
        // The analysis recovers the synthetic range model.
        approx::assert_relative_eq!(r.analysis.fit.1, 0.05, epsilon = 0.005);
        approx::assert_relative_eq!(r.analysis.fit.0, 0.4, epsilon = 0.2);
    }

    #[test]
    fn truth_is_interpolated_inside_the_span_only() {
        let gt = [
            PoseRecord {
                time: 1.0,
                x: 0.0,
                y: 0.0,
                heading: 0.0,
            },
            PoseRecord {
                time: 2.0,
                x: 2.0,
                y: -2.0,
                heading: 0.0,
            },
        ];
        assert_eq!(truth_at(&gt, 1.5), Some((1.0, -1.0)));
        assert_eq!(truth_at(&gt, 2.0), Some((2.0, -2.0)));
        assert_eq!(truth_at(&gt, 0.5), None);
        assert_eq!(truth_at(&gt, 2.5), None);
    }
}
