//! The front end of `fathom replay range-beacon|ins-dvl <dir>` on one's own log in
//! fathom's CSV layout (`docs/own-data.md`): reads the settings and the log, runs
//! the replay ([`crate::range_beacon`], [`crate::ins_dvl`]) and
//! renders its outputs as texts, written through the same safe output folder as
//! `fathom run` ([`claim_output`], [`write_outputs`]): `report.md`, `summary.json`, `estimates.csv` (the
//! estimates, and the truth when the log has it, at the recording instants) and
//! `innovations.csv` (every tested measurement's innovation and NIS). With ground
//! truth the report scores the position error; without, it shows the innovations'
//! NIS against the chi-square interval of a consistent filter.
//!
//! Errors are split by who can fix them ([`OwnLogError`]): the log or the settings
//! (the user's) or the replay itself.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use fathom_stats::RunStats;
use serde::Serialize;

use crate::consistency::NisSummary;
use crate::{ins_dvl, range_beacon};
use fathom_data::layout::ins_dvl::InsDvlLog;
use fathom_data::layout::range_beacon::RangeBeaconLog;
use fathom_data::layout::{LogError, LogKind};
use fathom_report::outdir::{OutDir, RunInfo};
use fathom_sim::SimError;

/// The built-in settings of `fathom replay range-beacon` (`scenarios/range-beacon.toml`).
pub const RANGE_BEACON_PRESET: &str = include_str!("../../../scenarios/range-beacon.toml");
/// The built-in settings of `fathom replay ins-dvl` (`scenarios/ins-dvl.toml`).
pub const INS_DVL_PRESET: &str = include_str!("../../../scenarios/ins-dvl.toml");

/// Why a replay of one's own log failed.
#[derive(Debug, thiserror::Error)]
pub enum OwnLogError {
    /// The log folder or one of its files (the user's data): names file, line, column.
    #[error(transparent)]
    Log(Box<LogError>),
    /// The settings file or a log that cannot be replayed as asked (the user's).
    #[error("{0}")]
    Input(Box<SimError>),
    /// The replay itself failed (an estimator or statistics error).
    #[error("{0}")]
    Replay(Box<SimError>),
}

impl From<LogError> for OwnLogError {
    fn from(e: LogError) -> Self {
        Self::Log(Box::new(e))
    }
}

impl OwnLogError {
    fn input(e: SimError) -> Self {
        Self::Input(Box::new(e))
    }

    fn from_replay(e: SimError) -> Self {
        match e {
            SimError::Invalid { .. } | SimError::InvalidArgument { .. } | SimError::Toml { .. } => {
                Self::input(e)
            }
            other => Self::Replay(Box::new(other)),
        }
    }

    /// Whether the user can fix it (their log, settings or arguments).
    pub fn is_users(&self) -> bool {
        !matches!(self, Self::Replay(_))
    }
}

/// What a replay produced: the console summary and the output files.
#[derive(Debug, Clone, PartialEq)]
pub struct OwnReplay {
    /// The summary printed on the console.
    pub console: String,
    /// `(file name, content)` of every output file.
    pub files: Vec<(&'static str, String)>,
}

/// The built-in settings text of `kind`.
pub fn preset(kind: LogKind) -> &'static str {
    match kind {
        LogKind::RangeBeacon => RANGE_BEACON_PRESET,
        LogKind::InsDvl => INS_DVL_PRESET,
    }
}

/// Reads the log of `kind` in `dir`, checks `settings` (TOML text, `label` in
/// messages; its `[data] dir` is replaced by `dir`) and replays it.
///
/// # Errors
/// [`OwnLogError::Log`] for a missing folder, a log of another kind or a bad file
/// (file, line, column); [`OwnLogError::Input`] for bad settings;
/// [`OwnLogError::Replay`] for a failing estimator.
pub fn replay_dir(
    kind: LogKind,
    dir: &Path,
    settings: &str,
    label: &str,
) -> Result<OwnReplay, OwnLogError> {
    let header = |rows: String| {
        format!(
            "log: {} (kind {}); settings: {label}; rows read: {rows}\n",
            dir.display(),
            kind.name()
        )
    };
    match kind {
        LogKind::RangeBeacon => {
            let s = range_beacon::parse_settings(settings, label).map_err(OwnLogError::input)?;
            let log = RangeBeaconLog::read_dir(dir)?;
            let r = range_beacon::replay(&log, &s).map_err(OwnLogError::from_replay)?;
            let rows = format!(
                "{} motion, {} ranges, {} depth, {} truth",
                r.rows[0], r.rows[1], r.rows[2], r.rows[3]
            );
            Ok(range_beacon_outputs(&r, &header(rows)))
        }
        LogKind::InsDvl => {
            let s = ins_dvl::parse_settings(settings, label).map_err(OwnLogError::input)?;
            let log = InsDvlLog::read_dir(dir)?;
            let r = ins_dvl::replay(&log, &s).map_err(OwnLogError::from_replay)?;
            let rows = format!(
                "{} IMU, {} DVL, {} depth, {} altitude, {} RPM, {} truth",
                r.rows[0], r.rows[1], r.rows[2], r.rows[3], r.rows[4], r.rows[5]
            );
            Ok(ins_dvl_outputs(&r, &header(rows)))
        }
    }
}

/// Claims the output folder `out` before anything is computed, as `fathom run` does
/// ([`OutDir::claim`]: a lock file, a folder holding files fathom did not write refused
/// unless `force`, a fresh temporary folder beside it that proves it writable).
///
/// # Errors
/// [`fathom_report::ReportError::InvalidArgument`] naming `--out` (the user's); I/O errors.
pub fn claim_output(out: &Path, force: bool) -> Result<OutDir, SimError> {
    Ok(OutDir::claim(out, force)?)
}

/// Writes `files` into the claimed folder and moves it into place
/// ([`OutDir::commit`]); `kind` and `settings` (the settings file as given) go into
/// its `run_info.json`. Returns the final folder.
///
/// # Errors
/// [`SimError::Io`] naming the file; a forced write whose new file has the name of
/// one of the user's files.
pub fn write_outputs(
    claim: OutDir,
    kind: LogKind,
    settings: &str,
    files: &[(&'static str, String)],
    elapsed_s: f64,
) -> Result<PathBuf, SimError> {
    for (name, text) in files {
        let path = claim.dir().join(name);
        std::fs::write(&path, text).map_err(|source| SimError::Io {
            action: "write",
            path: path.clone(),
            source,
        })?;
    }
    let out = claim.path().to_path_buf();
    claim.commit(RunInfo {
        fathom_version: env!("CARGO_PKG_VERSION").to_string(),
        command: "replay".into(),
        experiment: kind.name().to_string(),
        scenario: settings.to_string(),
        runs: None,
        threads: None,
        seed: None,
        base_seed: None,
        elapsed_s,
        files: Vec::new(),
    })?;
    Ok(out)
}

/// The report's `## Methods` list: each method's name and what it is.
fn methods_section(report: &mut String, methods: &[MethodSummary<'_>]) {
    let _ = writeln!(report, "## Methods\n");
    for m in methods {
        let _ = writeln!(report, "- `{}`: {}", m.name, m.what);
    }
    report.push('\n');
}

/// One method's numbers in `summary.json`.
#[derive(Debug, Clone, Serialize)]
struct MethodSummary<'a> {
    name: &'a str,
    what: String,
    /// Position error statistics (with truth), m.
    position_error_m: Option<RunStats>,
    /// Horizontal velocity error RMSE (INS logs whose truth has velocity), m/s.
    velocity_error_rmse_mps: Option<f64>,
    nis: Vec<(&'static str, NisSummary)>,
    accepted: Option<usize>,
    rejected: Option<usize>,
}

#[derive(Debug, Clone, Serialize)]
struct Summary<'a> {
    kind: &'static str,
    with_truth: bool,
    error: &'static str,
    instants: usize,
    methods: Vec<MethodSummary<'a>>,
}

fn fmt_stats(s: Option<&RunStats>) -> String {
    s.map_or("| - | - | - | - ".into(), |s| {
        format!(
            "| {:.3} | {:.3} | {:.3} | {:.3} ",
            s.mean, s.std, s.max, s.rmse
        )
    })
}

fn nis_rows(text: &mut String, name: &str, list: &[(&'static str, NisSummary)]) {
    for (what, n) in list {
        let _ = writeln!(
            text,
            "| {name} | {what} | {} | {:.3} | {:.3}-{:.3} | {} | {:.1} |",
            n.count,
            n.mean,
            n.bounds.0,
            n.bounds.1,
            if n.consistent() { "yes" } else { "no" },
            100.0 * n.beyond_95
        );
    }
}

const NIS_HEAD: &str = "| method | measurements | count | mean NIS (per dof: 1 ideal) | 95 % interval of a consistent filter | consistent | beyond chi-square 95 % quantile (%) |\n|---|---|---|---|---|---|---|\n";

fn nis_note(with_truth: bool) -> &'static str {
    if with_truth {
        "\nNIS: normalized innovation squared divided by its degrees of freedom; a \
         consistent filter gives 1 on average and about 5 % of values beyond the \
         chi-square 95 % quantile.\n"
    } else {
        "\nThe log has no `truth.csv`: no errors can be scored. The innovations show \
         whether each filter's model fits the data: the NIS (normalized innovation \
         squared, per degree of freedom) of a consistent filter averages 1, inside \
         the interval given, with about 5 % of values beyond the chi-square 95 % \
         quantile. Much larger values: the filter trusts its sensors or model too \
         much; much smaller: too little.\n"
    }
}

/// The NIS summary scaled per degree of freedom (what the report prints).
fn per_dof(n: NisSummary) -> NisSummary {
    let d = n.dof as f64;
    NisSummary {
        mean: n.mean / d,
        median: n.median / d,
        bounds: (n.bounds.0 / d, n.bounds.1 / d),
        ..n
    }
}

/// The NIS summaries a method has, per degree of freedom, labelled.
fn nis_list<const N: usize>(
    all: [(&'static str, Option<NisSummary>); N],
) -> Vec<(&'static str, NisSummary)> {
    all.into_iter()
        .filter_map(|(what, n)| n.map(|n| (what, per_dof(n))))
        .collect()
}

fn range_beacon_outputs(r: &range_beacon::RangeBeaconReplay, header: &str) -> OwnReplay {
    let with_truth = r.truth.is_some();
    let error = if r.error_dims == 3 {
        "3D"
    } else {
        "horizontal"
    };
    let mut methods = Vec::new();
    for m in &r.methods {
        let nis = nis_list([("ranges", m.range_nis), ("depth", m.depth_nis)]);
        methods.push(MethodSummary {
            name: &m.spec.name,
            what: m.spec.describe(),
            position_error_m: m.stats,
            velocity_error_rmse_mps: None,
            nis,
            accepted: m.is_filter().then_some(m.trace.counts.accepted),
            rejected: m.is_filter().then_some(m.trace.counts.rejected),
        });
    }
    let mut report = format!("# Range-beacon replay of your log\n\n{header}\n");
    let mut console = header.to_string();
    let _ = writeln!(
        report,
        "Motion: {}. {} beacons, {} recording instants.\n",
        if r.odometry {
            "wheel odometry (2D)"
        } else {
            "DVL + heading (3D with depth)"
        },
        r.beacons.len(),
        r.times.len()
    );
    methods_section(&mut report, &methods);
    if with_truth {
        let _ = writeln!(
            report,
            "## Position error against `truth.csv` ({error}, m)\n\n| method | mean | std | max | rmse | ranges accepted | rejected |\n|---|---|---|---|---|---|---|"
        );
        let _ = writeln!(
            console,
            "\n{:<22} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "method", "mean [m]", "std [m]", "max [m]", "rmse [m]", "rejected"
        );
        for m in &methods {
            let _ = writeln!(
                report,
                "| {} {}| {} | {} |",
                m.name,
                fmt_stats(m.position_error_m.as_ref()),
                m.accepted.map_or("-".into(), |v| v.to_string()),
                m.rejected.map_or("-".into(), |v| v.to_string())
            );
            if let Some(s) = m.position_error_m {
                let _ = writeln!(
                    console,
                    "{:<22} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9}",
                    m.name,
                    s.mean,
                    s.std,
                    s.max,
                    s.rmse,
                    m.rejected.map_or("-".into(), |v| v.to_string())
                );
            }
        }
        report.push('\n');
    }
    console_nis(&mut console, &methods);
    let _ = write!(report, "## Innovations\n\n{NIS_HEAD}");
    for m in &methods {
        nis_rows(&mut report, m.name, &m.nis);
    }
    report.push_str(nis_note(with_truth));
    report.push_str(
        "\nFiles: `estimates.csv` (estimates and truth at the instants), `innovations.csv` \
         (every tested range and depth), `summary.json`.\n",
    );
    // estimates.csv
    let mut head = vec!["time[s]".to_string()];
    if r.truth.is_some() {
        head.extend(["true_north[m]".into(), "true_east[m]".into()]);
        if r.truth_down.is_some() {
            head.push("true_down[m]".into());
        }
    }
    for m in &r.methods {
        let n = &m.spec.name;
        head.extend([format!("{n}_north[m]"), format!("{n}_east[m]")]);
        if m.trace.down.is_some() {
            head.push(format!("{n}_down[m]"));
        }
        head.extend([format!("{n}_heading[rad]"), format!("{n}_sigma_h[m]")]);
    }
    let mut est = head.join(",");
    est.push('\n');
    for (k, t) in r.times.iter().enumerate() {
        let mut row = vec![*t];
        if let Some(g) = &r.truth {
            row.extend(g[k]);
            if let Some(d) = &r.truth_down {
                row.push(d[k]);
            }
        }
        for m in &r.methods {
            let tr = &m.trace;
            row.extend(tr.est[k]);
            if let Some(d) = &tr.down {
                row.push(d[k]);
            }
            row.extend([tr.heading[k], tr.pos_sigma[k]]);
        }
        push_row(&mut est, &row);
    }
    // innovations.csv
    let mut inn = String::from(
        "method,measurement,time[s],beacon_row,file_row,value[m],innovation[m],nis,accepted\n",
    );
    for m in &r.methods {
        for (what, list) in [("range", &m.trace.ranges), ("depth", &m.trace.depths)] {
            for i in list {
                let _ = writeln!(
                    inn,
                    "{},{what},{},{},{},{},{},{},{}",
                    m.spec.name,
                    i.time,
                    i.channel,
                    i.row,
                    i.value,
                    i.innovation,
                    i.nis,
                    u8::from(i.disposition == fathom_estimators::schemes::Disposition::Accepted)
                );
            }
        }
    }
    let summary = Summary {
        kind: "range-beacon",
        with_truth,
        error,
        instants: r.times.len(),
        methods,
    };
    OwnReplay {
        console,
        files: vec![
            ("report.md", report),
            ("summary.json", json(&summary)),
            ("estimates.csv", est),
            ("innovations.csv", inn),
        ],
    }
}

fn console_nis(console: &mut String, methods: &[MethodSummary<'_>]) {
    let _ = writeln!(
        console,
        "\n{:<22} {:<12} {:>8} {:>10} {:>15} {:>10}",
        "method", "innovations", "count", "mean NIS", "consistent band", "consistent"
    );
    for m in methods {
        for (what, n) in &m.nis {
            let _ = writeln!(
                console,
                "{:<22} {:<12} {:>8} {:>10.3} {:>7.3}-{:<7.3} {:>10}",
                m.name,
                what,
                n.count,
                n.mean,
                n.bounds.0,
                n.bounds.1,
                if n.consistent() { "yes" } else { "no" }
            );
        }
    }
}

fn ins_dvl_outputs(r: &ins_dvl::InsDvlReplay, header: &str) -> OwnReplay {
    let with_truth = r.truth.is_some();
    let mut methods = Vec::new();
    for m in &r.methods {
        let nis = nis_list([
            ("velocity", m.velocity_nis),
            ("DVL velocity", m.dvl_nis),
            ("depth", m.depth_nis),
        ]);
        let vel_rmse = m
            .vel_errors_h
            .as_deref()
            .and_then(|v| RunStats::of(v).ok().map(|s| s.rmse));
        methods.push(MethodSummary {
            name: m.name(),
            what: format!(
                "filter `{}`{}",
                m.trace.method.filter.name(),
                m.trace
                    .method
                    .gate_probability
                    .map_or(String::new(), |p| format!(
                        ", velocity gate at probability {p}"
                    ))
            ),
            position_error_m: m.stats,
            velocity_error_rmse_mps: vel_rmse,
            nis,
            accepted: None,
            rejected: None,
        });
    }
    let mut report = format!("# INS / DVL replay of your log\n\n{header}\n");
    let mut console = header.to_string();
    let _ = writeln!(
        report,
        "IMU {}; {} recording instants; {} DVL rows invalid (flag 0 or altitude beyond the DVL's range).\n",
        if r.imu_increments {
            "increments"
        } else {
            "rates"
        },
        r.times.len(),
        r.invalid_dvl_rows
    );
    methods_section(&mut report, &methods);
    if with_truth {
        let _ = writeln!(
            report,
            "## Horizontal position error against `truth.csv` (m)\n\n| method | mean | std | max | rmse | velocity rmse (m/s) |\n|---|---|---|---|---|---|"
        );
        let _ = writeln!(
            console,
            "\n{:<22} {:>9} {:>9} {:>9} {:>9} {:>13}",
            "method", "mean [m]", "std [m]", "max [m]", "rmse [m]", "vel rmse [m/s]"
        );
        for m in &methods {
            let vel = m
                .velocity_error_rmse_mps
                .map_or("-".into(), |v| format!("{v:.4}"));
            let _ = writeln!(
                report,
                "| {} {}| {vel} |",
                m.name,
                fmt_stats(m.position_error_m.as_ref())
            );
            if let Some(s) = m.position_error_m {
                let _ = writeln!(
                    console,
                    "{:<22} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>13}",
                    m.name, s.mean, s.std, s.max, s.rmse, vel
                );
            }
        }
        report.push('\n');
    }
    console_nis(&mut console, &methods);
    let _ = write!(report, "## Innovations\n\n{NIS_HEAD}");
    for m in &methods {
        nis_rows(&mut report, m.name, &m.nis);
    }
    report.push_str(nis_note(with_truth));
    report.push_str(
        "\nFiles: `estimates.csv` (estimates and truth at the instants), `innovations.csv` \
         (every velocity and depth update), `summary.json`.\n",
    );
    let mut head = vec!["time[s]".to_string()];
    if r.truth.is_some() {
        head.extend(["true_north[m]", "true_east[m]", "true_down[m]"].map(String::from));
    }
    for m in &r.methods {
        let n = m.name();
        for c in [
            "north[m]",
            "east[m]",
            "down[m]",
            "vel_north[m/s]",
            "vel_east[m/s]",
            "vel_down[m/s]",
        ] {
            head.push(format!("{n}_{c}"));
        }
    }
    let mut est = head.join(",");
    est.push('\n');
    for (k, t) in r.times.iter().enumerate() {
        let mut row = vec![*t];
        if let Some(g) = &r.truth {
            row.extend(g[k]);
        }
        for m in &r.methods {
            let tr = &m.trace;
            row.extend(tr.north_east[k]);
            row.push(tr.depth[k]);
            row.extend(tr.vel_in_nav[k]);
        }
        push_row(&mut est, &row);
    }
    let mut inn = String::from(
        "method,measurement,time[s],innovation_1,innovation_2,innovation_3,nis,accepted,rpm_aided\n",
    );
    for m in &r.methods {
        for (what, list) in [
            ("velocity[m/s]", &m.trace.velocity_updates),
            ("depth[m]", &m.trace.depth_updates),
        ] {
            for u in list {
                let i = u
                    .innovation
                    .map_or([String::new(), String::new(), String::new()], |v| {
                        v.map(|x| x.to_string())
                    });
                let _ = writeln!(
                    inn,
                    "{},{what},{},{},{},{},{},{},{}",
                    m.name(),
                    u.time,
                    i[0],
                    i[1],
                    i[2],
                    u.nis,
                    u8::from(u.accepted),
                    u8::from(u.rpm)
                );
            }
        }
    }
    let summary = Summary {
        kind: "ins-dvl",
        with_truth,
        error: "horizontal",
        instants: r.times.len(),
        methods,
    };
    OwnReplay {
        console,
        files: vec![
            ("report.md", report),
            ("summary.json", json(&summary)),
            ("estimates.csv", est),
            ("innovations.csv", inn),
        ],
    }
}

fn push_row(out: &mut String, row: &[f64]) {
    let cells: Vec<String> = row.iter().map(|v| v.to_string()).collect();
    out.push_str(&cells.join(","));
    out.push('\n');
}

fn json<T: Serialize>(v: &T) -> String {
    let mut s =
        serde_json::to_string_pretty(v).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    s.push('\n');
    s
}
