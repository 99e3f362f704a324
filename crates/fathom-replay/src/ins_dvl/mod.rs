//! INS / DVL navigation replayed on a log in fathom's CSV layout (kind `ins-dvl`,
//! [`fathom_data::layout::ins_dvl`]): the methods of the settings' `[[methods]]`
//! list side by side in one pass (`run`).
//!
//! Recording instants: every `truth.csv` row after the start (errors are then scored
//! against it: the horizontal position, and the horizontal velocity when the truth
//! has velocity columns), else every `[output] period_s` from the start to the last
//! IMU row. The filters are recorded after the last IMU row at or before an instant,
//! and the truth is interpolated linearly to that row's time. Every velocity and
//! depth update's innovation and NIS are kept ([`Update`]): without truth they are
//! what the report shows.
//!
//! [`InsDvl`] runs it as a job of the runner (`fathom replay ins-dvl DIR`): settings
//! -> log -> replay ([`replay`], `run`) -> rows, checks and CSV files -> figures ->
//! report notes, each step in its own file.

mod analysis;
mod figures;
pub mod filter_tables;
mod job;
mod report;
mod run;
mod settings;
#[cfg(test)]
mod tests;

pub use job::{InsDvl, Prepared};

pub use settings::{
    DepthSigmaToml, DvlAidToml, EskfTuningToml, ImuModelToml, InsDvlMethodToml, InsDvlSettings,
    InsDvlToml, InsFilter, InsMethod, NavTuningToml, VkfTuningToml, default_methods,
    parse_settings,
};

use fathom_stats::RunStats;

use crate::consistency::NisSummary;
use crate::range_beacon::MAX_INSTANTS;
use fathom_data::layout::ins_dvl::{InsDvlLog, InsTruthRow};
use fathom_sim::SimError;

/// One velocity (3 components) or depth (1) update.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Update {
    /// `t - t0` of the IMU row it was applied after, s.
    pub time: f64,
    /// `nu^T S^-1 nu`.
    pub nis: f64,
    /// Measurement minus prediction (velocity NED m/s, or `[depth m, 0, 0]`), when the
    /// update was applied.
    pub innovation: Option<[f64; 3]>,
    /// The square roots of the innovation covariance's diagonal, `sqrt(S_ii)`, in the
    /// innovation's units (`[sqrt(S), 0, 0]` for depth), when the update was applied.
    #[serde(default)]
    pub innovation_sigma: Option<[f64; 3]>,
    /// Whether it passed the gate.
    pub accepted: bool,
    /// Whether the aid was the RPM speed (the switching box's choice).
    pub rpm: bool,
}

impl Update {
    /// A depth update (always applied) with innovation variance `s`.
    pub fn depth(time: f64, innovation: f64, s: f64, nis: f64) -> Self {
        Self {
            time,
            nis,
            innovation: Some([innovation, 0.0, 0.0]),
            innovation_sigma: Some([s.max(0.0).sqrt(), 0.0, 0.0]),
            accepted: true,
            rpm: false,
        }
    }
}

/// What one method produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InsMethodTrace {
    /// The method.
    pub method: InsMethod,
    /// North and east from the start position at the instants, m.
    pub north_east: Vec<[f64; 2]>,
    /// Depth at the instants, m.
    pub depth: Vec<f64>,
    /// NED velocity at the instants, m/s.
    pub vel_in_nav: Vec<[f64; 3]>,
    /// `sqrt(P_nn + P_ee)` at the instants (filters only), m.
    pub sigma_h: Option<Vec<f64>>,
    /// The VKF's scale factor (m/s per rpm) and offset (m/s) at the instants
    /// (`vkf` / `eskf` methods of logs with RPM).
    pub vkf_calibration: Option<Vec<[f64; 2]>>,
    /// Every velocity update.
    pub velocity_updates: Vec<Update>,
    /// Every depth update.
    pub depth_updates: Vec<Update>,
}

impl InsMethodTrace {
    fn with_capacity(method: InsMethod, n: usize, vkf: bool) -> Self {
        let filter = method.filter != InsFilter::Pins;
        let switching = matches!(method.filter, InsFilter::Vkf | InsFilter::Eskf);
        Self {
            method,
            north_east: Vec::with_capacity(n),
            depth: Vec::with_capacity(n),
            vel_in_nav: Vec::with_capacity(n),
            sigma_h: filter.then(|| Vec::with_capacity(n)),
            vkf_calibration: (vkf && switching).then(|| Vec::with_capacity(n)),
            velocity_updates: Vec::new(),
            depth_updates: Vec::new(),
        }
    }
}

/// One method's result.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InsMethodResult {
    /// What it produced.
    pub trace: InsMethodTrace,
    /// Horizontal position error at the instants (with truth), m.
    pub errors_h: Option<Vec<f64>>,
    /// Its statistics.
    pub stats: Option<RunStats>,
    /// Horizontal velocity error (truth with velocity), m/s.
    pub vel_errors_h: Option<Vec<f64>>,
    /// NIS of the velocity updates (3 dof, accepted and rejected).
    pub velocity_nis: Option<NisSummary>,
    /// NIS of the velocity updates from a valid DVL.
    pub dvl_nis: Option<NisSummary>,
    /// NIS of the depth updates (1 dof).
    pub depth_nis: Option<NisSummary>,
}

impl InsMethodResult {
    /// The method's name.
    pub fn name(&self) -> &str {
        &self.trace.method.name
    }
}

/// Everything an INS / DVL replay produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InsDvlReplay {
    /// Absolute start time, s.
    pub t0: f64,
    /// The instants recorded at (`t - t0` of the IMU row), s.
    pub times: Vec<f64>,
    /// Truth north, east, depth at the recorded times.
    pub truth: Option<Vec<[f64; 3]>>,
    /// Truth NED velocity at the recorded times.
    pub truth_vel: Option<Vec<[f64; 3]>>,
    /// The methods, in the settings' order.
    pub methods: Vec<InsMethodResult>,
    /// Rows read: IMU, DVL, depth, altitude, RPM, truth.
    pub rows: [usize; 6],
    /// Whether the IMU file gives increments (else rates).
    pub imu_increments: bool,
    /// DVL rows judged invalid (flag 0 or altitude beyond range).
    pub invalid_dvl_rows: usize,
}

impl InsDvlReplay {
    /// The method named `name`.
    pub fn method(&self, name: &str) -> Option<&InsMethodResult> {
        self.methods.iter().find(|m| m.name() == name)
    }
}

/// Linear interpolation of the truth rows at absolute time `t` (inside their span).
fn truth_at(rows: &[InsTruthRow], t: f64) -> Option<([f64; 3], Option<[f64; 3]>)> {
    let i = rows.partition_point(|r| r.time <= t);
    if i == 0 {
        return None;
    }
    let a = rows[i - 1];
    if a.time == t || i == rows.len() {
        return (a.time == t).then_some((a.pos_in_nav, a.vel_in_nav));
    }
    let b = rows[i];
    let u = (t - a.time) / (b.time - a.time);
    let lerp = |x: [f64; 3], y: [f64; 3]| std::array::from_fn(|k| x[k] + u * (y[k] - x[k]));
    Some((
        lerp(a.pos_in_nav, b.pos_in_nav),
        a.vel_in_nav.zip(b.vel_in_nav).map(|(x, y)| lerp(x, y)),
    ))
}

/// The recording instants `t - t0` (module docs).
fn instants(log: &InsDvlLog, period: f64) -> Result<Vec<f64>, SimError> {
    let t0 = log.start.time;
    if let Some(truth) = &log.truth {
        let v: Vec<f64> = truth
            .iter()
            .filter(|r| r.time > t0)
            .map(|r| r.time - t0)
            .collect();
        if v.is_empty() {
            return Err(SimError::invalid_argument(
                "log `truth.csv`",
                format!("has no row after the start time {t0} s of `initial.csv`"),
            ));
        }
        return Ok(v);
    }
    let last = log.imu.last().map_or(t0, |r| r.0);
    let n = ((last - t0) / period + 1e-9).floor();
    if n.is_nan() || n < 1.0 {
        return Err(SimError::invalid_argument(
            "log",
            format!(
                "its IMU ends at {last} s, less than one `output.period_s` ({period} s) after the start {t0} s"
            ),
        ));
    }
    if n > MAX_INSTANTS as f64 {
        return Err(SimError::invalid_argument(
            "output.period_s",
            format!(
                "{period} s gives {n:e} recording instants (at most {MAX_INSTANTS:e}); record less often"
            ),
        ));
    }
    Ok((1..=n as usize)
        .map(|k| (t0 + k as f64 * period) - t0)
        .collect())
}

/// `truth.csv` does not cover the IMU rows the filters are recorded after.
fn truth_not_covering() -> SimError {
    SimError::invalid_argument(
        "log `truth.csv`",
        "does not cover the IMU data it is compared with: its first row must be at or \
         before the first IMU row after the start",
    )
}

/// What [`replay`] refuses about `log` before it runs a filter (the user's log or
/// settings, not a failing filter): nothing to record, or a `truth.csv` that starts
/// after the first IMU row the filters are recorded after (`run::run`: the last IMU
/// row after the start at or before the first instant, else the start).
///
/// # Errors
/// [`SimError::InvalidArgument`] naming the file or key.
pub fn check(log: &InsDvlLog, settings: &InsDvlSettings) -> Result<(), SimError> {
    let record = instants(log, settings.output_period)?;
    if let (Some(rows), Some(&first)) = (&log.truth, record.first()) {
        let t0 = log.start.time;
        let recorded = log
            .imu
            .iter()
            .filter(|r| r.0 > t0)
            .map(|r| r.0 - t0)
            .take_while(|&t| t <= first)
            .last()
            .unwrap_or(0.0);
        if truth_at(rows, recorded + t0).is_none() {
            return Err(truth_not_covering());
        }
    }
    Ok(())
}

/// Replays every method of `settings` on `log`.
///
/// # Errors
/// As [`check`]; [`SimError::Model`] naming the method, component and time of a
/// failing step.
pub fn replay(log: &InsDvlLog, settings: &InsDvlSettings) -> Result<InsDvlReplay, SimError> {
    check(log, settings)?;
    let record = instants(log, settings.output_period)?;
    let (traces, times) = run::run(log, settings, &record)?;
    let t0 = log.start.time;
    let (truth, truth_vel) = match &log.truth {
        None => (None, None),
        Some(rows) => {
            let at: Vec<_> = times.iter().map(|t| truth_at(rows, t + t0)).collect();
            if at.iter().all(Option::is_some) {
                let pos: Vec<[f64; 3]> = at.iter().flatten().map(|a| a.0).collect();
                let vel: Option<Vec<[f64; 3]>> = at.iter().flatten().map(|a| a.1).collect();
                (Some(pos), vel)
            } else {
                return Err(truth_not_covering());
            }
        }
    };
    let mut methods = Vec::with_capacity(traces.len());
    for trace in traces {
        let errors_h: Option<Vec<f64>> = truth.as_ref().map(|g| {
            trace
                .north_east
                .iter()
                .zip(g)
                .map(|(e, g)| (e[0] - g[0]).hypot(e[1] - g[1]))
                .collect()
        });
        let stats = errors_h
            .as_deref()
            .map(|e| {
                RunStats::of(e).map_err(|er| {
                    SimError::model(format!("error statistics of `{}`", trace.method.name), er)
                })
            })
            .transpose()?;
        let vel_errors_h = truth_vel.as_ref().map(|g| {
            trace
                .vel_in_nav
                .iter()
                .zip(g)
                .map(|(e, g)| (e[0] - g[0]).hypot(e[1] - g[1]))
                .collect()
        });
        let nis = |u: &[Update], keep: &dyn Fn(&Update) -> bool, dof| {
            let v: Vec<f64> = u.iter().filter(|x| keep(x)).map(|x| x.nis).collect();
            NisSummary::of(&v, dof)
        };
        methods.push(InsMethodResult {
            velocity_nis: nis(&trace.velocity_updates, &|_| true, 3),
            dvl_nis: nis(&trace.velocity_updates, &|u| !u.rpm, 3),
            depth_nis: nis(&trace.depth_updates, &|_| true, 1),
            trace,
            errors_h,
            stats,
            vel_errors_h,
        });
    }
    let invalid_dvl_rows = log
        .dvl
        .iter()
        .filter(|d| d.time > t0)
        .filter(|d| {
            d.bottom_lock == Some(false)
                || log.altitude.as_ref().is_some_and(|alt| {
                    let i = alt.partition_point(|a| a.0 <= d.time);
                    i > 0 && !settings.switch.dvl_valid(alt[i - 1].1)
                })
        })
        .count();
    Ok(InsDvlReplay {
        t0,
        times,
        truth,
        truth_vel,
        methods,
        rows: [
            log.imu.len(),
            log.dvl.len(),
            log.depth.as_ref().map_or(0, Vec::len),
            log.altitude.as_ref().map_or(0, Vec::len),
            log.rpm.as_ref().map_or(0, Vec::len),
            log.truth.as_ref().map_or(0, Vec::len),
        ],
        imu_increments: log.imu_form == fathom_data::layout::ins_dvl::ImuForm::Increments,
        invalid_dvl_rows,
    })
}
