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

mod methods;
mod prepare;
mod ranges;
pub(crate) mod settings;
#[cfg(test)]
pub(crate) mod tests;

pub use methods::{
    MethodRun, SmoothedRun, Trace, run_dead_reckoning, run_variant, trace_dead_reckoning,
    trace_variant,
};
pub use prepare::{PreparedLog, PreparedRange};
pub use ranges::{RangeAnalysis, analyse_ranges, truth_at};
pub use settings::{
    AblationToml, Calibration, DataToml, InitialToml, OdometryToml, OutlierHandling, PlazaSettings,
    PlazaToml, RangeNoiseToml, RangesToml, RobustToml, SchemesToml, Variant, parse_settings,
};

use fathom_data::plaza::{BeaconSite, PlazaLog};
use fathom_sim::SimError;

/// Everything a Plaza replay produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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
