//! `fathom log example|from-plaza|from-ulog|check`: the commands that write and check
//! logs in fathom's CSV layout (`fathom replay range-beacon|ins-dvl|gnss-ins` replays
//! them, `replay.rs`).

use std::path::PathBuf;

use anyhow::anyhow;
use clap::{Args, Subcommand};
use fathom_data::layout::convert::range_beacon_from_plaza;
use fathom_data::layout::gnss_ins::GnssInsLog;
use fathom_data::layout::ins_dvl::InsDvlLog;
use fathom_data::layout::range_beacon::RangeBeaconLog;
use fathom_data::layout::{FileSet, LogKind, Manifest, write_log};
use fathom_data::plaza::PlazaLog;
use fathom_experiments::example_log::{ins_dvl_example, range_beacon_example};
use fathom_experiments::plaza::{Plaza, find_data_dir};
use fathom_replay::plaza::parse_settings;
use fathom_sim::user_run::one_line;
use fathom_sim::{Experiment, error_chain};

use crate::Failure;

/// The kinds of log `fathom log example` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum KindArg {
    /// Range-beacon localization.
    RangeBeacon,
    /// INS / DVL navigation.
    InsDvl,
}

impl KindArg {
    fn kind(self) -> LogKind {
        match self {
            KindArg::RangeBeacon => LogKind::RangeBeacon,
            KindArg::InsDvl => LogKind::InsDvl,
        }
    }
}

#[derive(Debug, Subcommand)]
pub(crate) enum LogCmd {
    /// Write a simulated example log (to see a valid log, or to try `fathom replay`).
    Example(ExampleArgs),
    /// Convert a CMU Plaza data set (`*_DR.txt`, `*_TD.txt`, `*_.mat`) into a
    /// range-beacon log.
    FromPlaza(FromPlazaArgs),
    /// Convert a PX4 ULog flight log (`*.ulg`) into a gnss-ins log (IMU, GNSS,
    /// baro, magnetometer, range sensor; PX4's EKF2 estimate as a reference track;
    /// the simulator's ground truth when the log has it).
    FromUlog(FromUlogArgs),
    /// Read every file of a log folder and report the first error (file, line, column).
    Check(LogCheckArgs),
}

#[derive(Debug, Args)]
pub(crate) struct FromUlogArgs {
    /// The ULog file.
    pub(crate) file: PathBuf,
    /// The new log folder, which must not hold a log (default
    /// `fathom-out/<file stem>-log`).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
}

/// The default folder of the log converted from `file`: `fathom-out/<stem>-log`.
pub(crate) fn ulog_out(file: &std::path::Path) -> PathBuf {
    let stem = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "ulog".into());
    log_out(&stem)
}

#[derive(Debug, Args)]
pub(crate) struct ExampleArgs {
    /// Which kind of log.
    pub(crate) kind: KindArg,
    /// The new log folder, which must not hold a log (default `fathom-out/<kind>-log`;
    /// replay it with `fathom replay <kind> <folder>`).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Length of the log, s.
    #[arg(long, value_name = "S", default_value_t = 300.0)]
    pub(crate) duration: f64,
    /// Seed of the simulated noise.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub(crate) seed: u64,
    /// Leave out `truth.csv` (the replay then reports innovations only).
    #[arg(long)]
    pub(crate) no_truth: bool,
}

#[derive(Debug, Args)]
pub(crate) struct FromPlazaArgs {
    /// Folder holding the Plaza data set's files (default: `data/plaza1`, looked up in
    /// the current directory and beside each of its ancestors: the repository's copy).
    pub(crate) plaza_dir: Option<PathBuf>,
    /// The new log folder (default `fathom-out/plaza-log`; the repository keeps the
    /// conversion of `data/plaza1` in `data/logs/plaza1-range-beacon`, the `[data] dir`
    /// of `scenarios/range-beacon-plaza.toml`).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
}

/// The default folder of a log: `fathom-out/<name>-log`.
fn log_out(name: &str) -> PathBuf {
    crate::default_out(&format!("{name}-log"))
}

#[derive(Debug, Args)]
pub(crate) struct LogCheckArgs {
    /// The log folder.
    pub(crate) dir: PathBuf,
}

/// The `plaza` preset's data folder (`data/plaza1`) found from the current directory
/// as `fathom run` finds it (inside it, then beside each of its ancestors).
fn default_plaza_dir(data_dir: &str) -> Result<PathBuf, Failure> {
    let cwd = std::env::current_dir()
        .map_err(|e| Failure::Run(anyhow!("cannot read the current directory: {e}")))?;
    find_data_dir(&cwd, data_dir).ok_or_else(|| {
        Failure::Usage(anyhow!(
            "no Plaza folder given and `{data_dir}` is not found in `{}` or beside any of its \
             ancestors; give the folder holding `*_DR.txt`, `*_TD.txt` and `*_.mat`",
            cwd.display()
        ))
    })
}

pub(crate) fn log_cmd(cmd: &LogCmd) -> Result<String, Failure> {
    let usage =
        |e: &(dyn std::error::Error + 'static)| Failure::Usage(anyhow!(one_line(&error_chain(e))));
    match cmd {
        LogCmd::Example(a) => {
            let kind = a.kind.kind();
            let dir = a.out.clone().unwrap_or_else(|| log_out(kind.name()));
            let (files, outliers) = match a.kind {
                KindArg::RangeBeacon => {
                    let ex = range_beacon_example(a.duration, a.seed, !a.no_truth)
                        .map_err(|e| usage(&e))?;
                    let note = format!(
                        "; {} range outlier{} of +{} m injected",
                        ex.outliers,
                        if ex.outliers == 1 { "" } else { "s" },
                        ex.outlier_m
                    );
                    (ex.log.to_files(), note)
                }
                KindArg::InsDvl => (
                    ins_dvl_example(a.duration, a.seed, !a.no_truth)
                        .map_err(|e| usage(&e))?
                        .to_files(),
                    String::new(),
                ),
            };
            let about = format!(
                "simulated example ({} s, seed {}{}{outliers}) written by `fathom log \
                 example` with the noise of the built-in scenarios/{}.toml",
                a.duration,
                a.seed,
                if a.no_truth { ", no truth" } else { "" },
                kind.name()
            );
            write_log(&dir, &Manifest::new(kind, about), &files).map_err(|e| usage(&e))?;
            Ok(format!(
                "wrote the {} log {} ({}{outliers}); replay it with `fathom replay {} {}`\n",
                kind.name(),
                dir.display(),
                files.iter().map(|f| f.0).collect::<Vec<_>>().join(", "),
                kind.name(),
                dir.display()
            ))
        }
        LogCmd::FromPlaza(a) => {
            let settings = parse_settings(
                <Plaza as Experiment>::PRESET,
                "built-in scenarios/plaza.toml",
            )
            .map_err(|e| Failure::Run(anyhow!(e)))?;
            let plaza_dir = match &a.plaza_dir {
                Some(d) if d.is_dir() => d.clone(),
                Some(d) => {
                    return Err(Failure::Usage(anyhow!(
                        "cannot read the Plaza data: `{}` is not a folder",
                        d.display()
                    )));
                }
                None => default_plaza_dir(&settings.data_dir)?,
            };
            let dir = a.out.clone().unwrap_or_else(|| log_out("plaza"));
            let log =
                PlazaLog::read_dir(&plaza_dir, settings.range_order).map_err(|e| usage(&e))?;
            let rb = range_beacon_from_plaza(&log);
            let about = format!(
                "CMU Plaza data converted from `{}` by `fathom log from-plaza`",
                plaza_dir.display()
            );
            write_log(
                &dir,
                &Manifest::new(LogKind::RangeBeacon, about),
                &rb.to_files(),
            )
            .map_err(|e| usage(&e))?;
            Ok(format!(
                "wrote the range-beacon log {} from {}; replay it with `fathom replay \
                 range-beacon {} --config scenarios/range-beacon-plaza.toml`\n",
                dir.display(),
                plaza_dir.display(),
                dir.display()
            ))
        }
        LogCmd::FromUlog(a) => {
            let c = fathom_data::ulog::convert_file(&a.file).map_err(|e| usage(&e))?;
            let dir = a.out.clone().unwrap_or_else(|| ulog_out(&a.file));
            let files = c.log.to_files();
            write_log(
                &dir,
                &Manifest::new(LogKind::GnssIns, c.description(&a.file)),
                &files,
            )
            .map_err(|e| usage(&e))?;
            Ok(format!(
                "wrote the gnss-ins log {} ({}; {} IMU rows, {} GNSS rows, EKF2 reference: {}, \
                 truth: {}); replay it with `fathom replay gnss-ins {}`\n",
                dir.display(),
                files.iter().map(|f| f.0).collect::<Vec<_>>().join(", "),
                c.log.imu.len(),
                c.log.gnss.len(),
                if c.log.reference.is_some() {
                    "yes"
                } else {
                    "no"
                },
                if c.log.truth.is_some() { "yes" } else { "no" },
                dir.display()
            ))
        }
        LogCmd::Check(a) => {
            let set = FileSet::read_dir(&a.dir).map_err(|e| usage(&e))?;
            let kind = set.manifest.kind;
            let rows = match kind {
                LogKind::RangeBeacon => {
                    let l = RangeBeaconLog::parse(&set).map_err(|e| usage(&e))?;
                    format!("{} beacons, {} ranges", l.beacons.len(), l.ranges.len())
                }
                LogKind::InsDvl => {
                    let l = InsDvlLog::parse(&set).map_err(|e| usage(&e))?;
                    format!("{} IMU rows, {} DVL rows", l.imu.len(), l.dvl.len())
                }
                LogKind::GnssIns => {
                    let l = GnssInsLog::parse(&set).map_err(|e| usage(&e))?;
                    format!("{} IMU rows, {} GNSS rows", l.imu.len(), l.gnss.len())
                }
            };
            Ok(format!(
                "ok: {} is a valid {} log ({}: {rows}; truth: {})\n",
                a.dir.display(),
                kind.name(),
                set.files.keys().copied().collect::<Vec<_>>().join(", "),
                if set.has("truth.csv") { "yes" } else { "no" }
            ))
        }
    }
}
