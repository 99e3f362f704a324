//! Range-beacon localization replayed on a log in fathom's CSV layout (kind
//! `range-beacon`, [`fathom_data::layout::range_beacon`]): the methods of the
//! settings' `[[methods]]` list, each dead reckoning or the EKF under an update
//! scheme, on relative time `t - t0` (`t0` = the time of `initial.csv`).
//!
//! - Wheel-odometry logs run through the Plaza replay's engine
//!   ([`crate::plaza::trace_variant`]): the same events, filters and numbers,
//!   so a Plaza log converted into the layout (`fathom log from-plaza`) replays to the
//!   `plaza` experiment's numbers;
//! - DVL + heading logs run the 4-state beacon EKF with depth ([`dvl`]).
//!
//! Recording instants: every `truth.csv` row after the start (errors are then scored
//! against it: 2D for odometry logs, 3D for DVL logs whose truth has `down`), else
//! every `[output] period_s` from the start to the last stamp of the log. Every
//! range's innovation and NIS are kept ([`Innovation`]): without truth they are what
//! the report shows.
//!
//! [`RangeBeacon`] runs it as a job of the runner (`fathom replay range-beacon DIR`):
//! settings -> log -> replay ([`replay`]) -> rows, checks and CSV files -> figures ->
//! report notes, each step in its own file.

mod analysis;
pub mod dvl;
mod figures;
mod job;
mod report;
mod settings;
#[cfg(test)]
mod tests;

pub use crate::plaza::RangeNoiseToml;
pub use job::{Prepared, RangeBeacon};

pub use settings::{
    DepthNoiseToml, DvlMotionToml, InitialSigmaToml, LogDirToml, MethodKind, MethodSpec,
    OutputToml, RangeBeaconMethodToml, RangeBeaconSettings, RangeBeaconToml, default_methods,
    parse_settings,
};

use fathom_estimators::schemes::{ChannelCounts, Decision, Disposition};
use fathom_stats::RunStats;
use nalgebra::Vector2;

pub use crate::consistency::Innovation;

use crate::consistency::NisSummary;
use crate::plaza::{PreparedLog, trace_dead_reckoning, trace_variant};
use fathom_data::layout::range_beacon::{Beacon, Motion, RangeBeaconLog};
use fathom_sim::SimError;

/// The most recording instants a replay without truth makes (memory stays bounded
/// whatever `output.period_s` and the log's span).
pub const MAX_INSTANTS: usize = 10_000_000;

/// The recording instants of a replay, on relative time.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalPlan {
    /// Absolute times `t`, s, increasing (truth rows, or `t0 + k period`).
    pub absolute: Vec<f64>,
    /// `t - t0`, s.
    pub times: Vec<f64>,
    /// Truth `(north, east)` at each instant, when the log has truth.
    pub truth: Option<Vec<[f64; 2]>>,
    /// Truth `down` at each instant, when the truth has it.
    pub truth_down: Option<Vec<f64>>,
}

impl EvalPlan {
    /// The plan of `log` (module docs).
    ///
    /// # Errors
    /// [`SimError::InvalidArgument`] when no instant lies after the start (truth rows
    /// or data all at or before it).
    pub fn of(log: &RangeBeaconLog, period: f64) -> Result<Self, SimError> {
        let t0 = log.start.time;
        if let Some(truth) = &log.truth {
            let rows: Vec<_> = truth.iter().filter(|r| r.time > t0).collect();
            if rows.is_empty() {
                return Err(SimError::invalid_argument(
                    "log `truth.csv`",
                    format!("has no row after the start time {t0} s of `initial.csv`"),
                ));
            }
            let has_down = rows.iter().all(|r| r.down.is_some());
            return Ok(Self {
                absolute: rows.iter().map(|r| r.time).collect(),
                times: rows.iter().map(|r| r.time - t0).collect(),
                truth: Some(rows.iter().map(|r| r.north_east).collect()),
                truth_down: has_down.then(|| rows.iter().map(|r| r.down.unwrap_or(0.0)).collect()),
            });
        }
        let last = last_stamp(log);
        let n = ((last - t0) / period + 1e-9).floor();
        if n.is_nan() || n < 1.0 {
            return Err(SimError::invalid_argument(
                "log",
                format!(
                    "its data end at {last} s, less than one `output.period_s` ({period} s) after \
                     the start {t0} s: nothing to record"
                ),
            ));
        }
        if n > MAX_INSTANTS as f64 {
            return Err(SimError::invalid_argument(
                "output.period_s",
                format!(
                    "{period} s over the log's {} s gives {n:e} recording instants (at most \
                     {MAX_INSTANTS:e}); record less often",
                    last - t0
                ),
            ));
        }
        let n = n as usize;
        let absolute: Vec<f64> = (1..=n).map(|k| t0 + k as f64 * period).collect();
        Ok(Self {
            times: absolute.iter().map(|t| t - t0).collect(),
            absolute,
            truth: None,
            truth_down: None,
        })
    }
}

/// The last time stamp of any motion, range or depth row.
fn last_stamp(log: &RangeBeaconLog) -> f64 {
    let motion = match &log.motion {
        Motion::Odometry(r) => r.last().map(|r| r.0),
        Motion::Dvl { dvl, heading } => dvl
            .last()
            .map(|r| r.0)
            .into_iter()
            .chain(heading.last().map(|r| r.0))
            .reduce(f64::max),
    };
    [
        motion,
        log.ranges.last().map(|r| r.time),
        log.depth.as_ref().and_then(|d| d.last()).map(|r| r.0),
    ]
    .into_iter()
    .flatten()
    .fold(log.start.time, f64::max)
}

/// What one method produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodTrace {
    /// Estimated `(north, east)` at the instants, m.
    pub est: Vec<[f64; 2]>,
    /// Estimated down at the instants (DVL logs), m.
    pub down: Option<Vec<f64>>,
    /// Estimated heading, rad.
    pub heading: Vec<f64>,
    /// `sqrt(P_nn + P_ee)`, m.
    pub pos_sigma: Vec<f64>,
    /// Range offset (m) and scale error at the instants (0 when not estimated).
    pub calibration: Vec<[f64; 2]>,
    /// Range dispositions summed over the beacons.
    pub counts: ChannelCounts,
    /// Depth dispositions (DVL logs).
    pub depth_counts: Option<ChannelCounts>,
    /// Ranges applied with an inflated variance.
    pub downweighted: usize,
    /// Covariance inflations.
    pub recoveries: usize,
    /// Every tested range, in processing order.
    pub ranges: Vec<Innovation>,
    /// Every tested depth (DVL logs).
    pub depths: Vec<Innovation>,
}

impl MethodTrace {
    /// An empty trace for `n` instants (`with_down` for DVL logs).
    pub fn with_capacity(n: usize, with_down: bool) -> Self {
        Self {
            est: Vec::with_capacity(n),
            down: with_down.then(|| Vec::with_capacity(n)),
            heading: Vec::with_capacity(n),
            pos_sigma: Vec::with_capacity(n),
            calibration: Vec::with_capacity(n),
            counts: ChannelCounts::default(),
            depth_counts: None,
            downweighted: 0,
            recoveries: 0,
            ranges: Vec::new(),
            depths: Vec::new(),
        }
    }

    /// Keeps the tested decisions (with a NIS) as innovations; channel `depth_channel`
    /// is depth.
    pub fn set_decisions(&mut self, decisions: &[Decision], depth_channel: usize) {
        for d in decisions {
            let Some(i) = Innovation::of_decision(d) else {
                continue;
            };
            if d.channel == depth_channel {
                self.depths.push(i);
            } else if d.channel < depth_channel {
                self.ranges.push(i);
            }
            // (a channel after depth is the absolute heading: not a range innovation)
        }
    }
}

/// One method's result.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodResult {
    /// The method.
    pub spec: MethodSpec,
    /// What it produced.
    pub trace: MethodTrace,
    /// Position error at the instants (2D or 3D, [`RangeBeaconReplay::error_dims`]),
    /// when the log has truth, m.
    pub errors: Option<Vec<f64>>,
    /// Statistics of `errors`.
    pub stats: Option<RunStats>,
    /// NIS of every tested range (1 dof).
    pub range_nis: Option<NisSummary>,
    /// NIS of the accepted ranges.
    pub accepted_nis: Option<NisSummary>,
    /// NIS of every depth (DVL logs).
    pub depth_nis: Option<NisSummary>,
}

impl MethodResult {
    /// Whether the method updates with measurements (not dead reckoning).
    pub fn is_filter(&self) -> bool {
        !matches!(self.spec.kind, MethodKind::DeadReckoning)
    }
}

/// Everything a range-beacon replay produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RangeBeaconReplay {
    /// The settings used.
    pub settings: RangeBeaconSettings,
    /// Absolute start time `t0`, s.
    pub t0: f64,
    /// Whether the motion is wheel odometry (2D) or DVL + heading (3D).
    pub odometry: bool,
    /// The beacon table.
    pub beacons: Vec<Beacon>,
    /// Recording instants `t - t0`, s.
    pub times: Vec<f64>,
    /// Truth `(north, east)` at the instants.
    pub truth: Option<Vec<[f64; 2]>>,
    /// Truth down at the instants.
    pub truth_down: Option<Vec<f64>>,
    /// 2 (horizontal) or 3: the dimension of the scored error.
    pub error_dims: usize,
    /// The methods in the settings' order.
    pub methods: Vec<MethodResult>,
    /// Rows read: motion, ranges, depth, truth.
    pub rows: [usize; 4],
}

impl RangeBeaconReplay {
    /// The method named `name`.
    pub fn method(&self, name: &str) -> Option<&MethodResult> {
        self.methods.iter().find(|m| m.spec.name == name)
    }
}

/// The odometry path: the Plaza engine on the log's rows.
fn run_odometry(
    log: &RangeBeaconLog,
    s: &RangeBeaconSettings,
    method: &MethodSpec,
    plan: &EvalPlan,
) -> Result<MethodTrace, SimError> {
    let Motion::Odometry(rows) = &log.motion else {
        return Err(SimError::invalid_argument(
            "odometry replay",
            "the log's motion is DVL",
        ));
    };
    let st = &log.start;
    let truth = plan.truth.as_deref();
    let prep = PreparedLog::from_rows(
        st.time,
        [st.north_east[0], st.north_east[1], st.heading],
        rows.iter().copied(),
        log.ranges.iter().map(|r| (r.time, r.beacon, r.range)),
        plan.absolute.iter().enumerate().map(|(k, &t)| {
            let g = truth.map_or([f64::NAN; 2], |g| g[k]);
            (t, g[0], g[1])
        }),
        log.beacons
            .iter()
            .map(|b| Vector2::new(b.pos_in_nav[0], b.pos_in_nav[1]))
            .collect(),
    )?;
    let t = match &method.kind {
        MethodKind::DeadReckoning => trace_dead_reckoning(&prep, &s.engine)?,
        MethodKind::Ekf(v) => trace_variant(&prep, &s.engine, v)?,
    };
    let mut out = MethodTrace::with_capacity(0, false);
    out.est = t.est;
    out.heading = t.heading;
    out.pos_sigma = t.pos_sigma;
    out.calibration = t.calibration;
    out.counts = t.counts;
    out.downweighted = t.downweighted;
    out.recoveries = t.recoveries;
    out.set_decisions(&t.decisions, usize::MAX);
    Ok(out)
}

/// What [`replay`] refuses about `log` before it runs an estimator (the user's log or
/// settings, not a failing estimator): nothing to record, or a method the log cannot
/// run ([`dvl::check_method`]).
///
/// # Errors
/// [`SimError::InvalidArgument`] naming the file, key or method.
pub fn check(log: &RangeBeaconLog, settings: &RangeBeaconSettings) -> Result<(), SimError> {
    EvalPlan::of(log, settings.output_period)?;
    if !matches!(log.motion, Motion::Odometry(_)) {
        for spec in &settings.methods {
            dvl::check_method(log, settings, &spec.for_log(false))?;
        }
    }
    Ok(())
}

/// Replays every method of `settings` on `log`.
///
/// # Errors
/// As [`check`]; [`SimError::Model`] wrapping estimator errors with the method's
/// name.
pub fn replay(
    log: &RangeBeaconLog,
    settings: &RangeBeaconSettings,
) -> Result<RangeBeaconReplay, SimError> {
    let plan = EvalPlan::of(log, settings.output_period)?;
    let odometry = matches!(log.motion, Motion::Odometry(_));
    let error_dims = if !odometry && plan.truth_down.is_some() {
        3
    } else {
        2
    };
    let mut methods = Vec::with_capacity(settings.methods.len());
    for spec in &settings.methods {
        let spec = &spec.for_log(odometry);
        let trace = if odometry {
            run_odometry(log, settings, spec, &plan)?
        } else {
            dvl::run_method(log, settings, spec, &plan)?
        };
        let errors = plan.truth.as_ref().map(|truth| {
            trace
                .est
                .iter()
                .zip(truth)
                .enumerate()
                .map(|(k, (e, g))| {
                    let h = (e[0] - g[0]).hypot(e[1] - g[1]);
                    match (error_dims, &trace.down, &plan.truth_down) {
                        (3, Some(d), Some(gd)) => h.hypot(d[k] - gd[k]),
                        _ => h,
                    }
                })
                .collect::<Vec<f64>>()
        });
        let stats = errors
            .as_deref()
            .map(|e| {
                RunStats::of(e).map_err(|err| {
                    SimError::model(format!("error statistics of `{}`", spec.name), err)
                })
            })
            .transpose()?;
        let nis = |v: &[Innovation], accepted_only: bool| {
            let n: Vec<f64> = v
                .iter()
                .filter(|i| !accepted_only || i.disposition == Disposition::Accepted)
                .map(|i| i.nis)
                .collect();
            NisSummary::of(&n, 1)
        };
        methods.push(MethodResult {
            range_nis: nis(&trace.ranges, false),
            accepted_nis: nis(&trace.ranges, true),
            depth_nis: nis(&trace.depths, false),
            spec: spec.clone(),
            trace,
            errors,
            stats,
        });
    }
    let motion_rows = match &log.motion {
        Motion::Odometry(r) => r.len(),
        Motion::Dvl { dvl, heading } => dvl.len() + heading.len(),
    };
    Ok(RangeBeaconReplay {
        settings: settings.clone(),
        t0: log.start.time,
        odometry,
        beacons: log.beacons.clone(),
        times: plan.times,
        truth: plan.truth,
        truth_down: plan.truth_down,
        error_dims,
        methods,
        rows: [
            motion_rows,
            log.ranges.len(),
            log.depth.as_ref().map_or(0, Vec::len),
            log.truth.as_ref().map_or(0, Vec::len),
        ],
    })
}
