//! `fathom log example|from-plaza|check`: the commands that write and check logs in
//! fathom's CSV layout (`fathom replay range-beacon|ins-dvl` replays them, `replay.rs`).

use std::path::PathBuf;

use anyhow::anyhow;
use clap::{Args, Subcommand};
use fathom_data::layout::convert::range_beacon_from_plaza;
use fathom_data::layout::ins_dvl::InsDvlLog;
use fathom_data::layout::range_beacon::RangeBeaconLog;
use fathom_data::layout::{FileSet, LogKind, Manifest, write_log};
use fathom_data::plaza::PlazaLog;
use fathom_experiments::example_log::{ins_dvl_example, range_beacon_example};
use fathom_experiments::plaza::Plaza;
use fathom_replay::plaza::parse_settings;
use fathom_sim::user_run::one_line;
use fathom_sim::{Experiment, error_chain};

use crate::Failure;

/// The two kinds of log.
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
    /// Read every file of a log folder and report the first error (file, line, column).
    Check(LogCheckArgs),
}

#[derive(Debug, Args)]
pub(crate) struct ExampleArgs {
    /// Which kind of log.
    pub(crate) kind: KindArg,
    /// The new log folder (must not hold a log).
    pub(crate) dir: PathBuf,
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
    /// Folder holding the Plaza data set's files.
    pub(crate) plaza_dir: PathBuf,
    /// The new log folder.
    pub(crate) dir: PathBuf,
}

#[derive(Debug, Args)]
pub(crate) struct LogCheckArgs {
    /// The log folder.
    pub(crate) dir: PathBuf,
}

pub(crate) fn log_cmd(cmd: &LogCmd) -> Result<String, Failure> {
    let usage =
        |e: &(dyn std::error::Error + 'static)| Failure::Usage(anyhow!(one_line(&error_chain(e))));
    match cmd {
        LogCmd::Example(a) => {
            let kind = a.kind.kind();
            let files = match kind {
                LogKind::RangeBeacon => range_beacon_example(a.duration, a.seed, !a.no_truth)
                    .map_err(|e| usage(&e))?
                    .to_files(),
                LogKind::InsDvl => ins_dvl_example(a.duration, a.seed, !a.no_truth)
                    .map_err(|e| usage(&e))?
                    .to_files(),
            };
            let about = format!(
                "simulated example ({} s, seed {}{}) written by `fathom log example`",
                a.duration,
                a.seed,
                if a.no_truth { ", no truth" } else { "" }
            );
            write_log(&a.dir, &Manifest::new(kind, about), &files).map_err(|e| usage(&e))?;
            Ok(format!(
                "wrote a {} log into {} ({}); replay it with `fathom replay {} {}`\n",
                kind.name(),
                a.dir.display(),
                files.iter().map(|f| f.0).collect::<Vec<_>>().join(", "),
                kind.name(),
                a.dir.display()
            ))
        }
        LogCmd::FromPlaza(a) => {
            let settings = parse_settings(
                <Plaza as Experiment>::PRESET,
                "built-in scenarios/plaza.toml",
            )
            .map_err(|e| Failure::Run(anyhow!(e)))?;
            if !a.plaza_dir.is_dir() {
                return Err(Failure::Usage(anyhow!(
                    "cannot read the Plaza data: `{}` is not a folder",
                    a.plaza_dir.display()
                )));
            }
            let log =
                PlazaLog::read_dir(&a.plaza_dir, settings.range_order).map_err(|e| usage(&e))?;
            let rb = range_beacon_from_plaza(&log);
            let about = format!(
                "CMU Plaza data converted from `{}` by `fathom log from-plaza`",
                a.plaza_dir.display()
            );
            write_log(
                &a.dir,
                &Manifest::new(LogKind::RangeBeacon, about),
                &rb.to_files(),
            )
            .map_err(|e| usage(&e))?;
            Ok(format!(
                "wrote a range-beacon log into {}; replay it with `fathom replay range-beacon {} \
                 --config scenarios/range-beacon-plaza.toml`\n",
                a.dir.display(),
                a.dir.display()
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
