//! What the two replays of one's own log share (`fathom replay range-beacon|ins-dvl
//! DIR`, or `fathom run` on their settings files): the built-in settings, where the
//! log folder is and how a bad one is reported, the cost estimate, the `summary.json`
//! rows and checks of errors and NIS ([`rows`]) and the report's notes ([`notes`]).
//!
//! Each replay is a deterministic job of the runner ([`crate::range_beacon::RangeBeacon`],
//! [`crate::ins_dvl::InsDvl`]): its settings file is the scenario (no `runs`, no
//! `base_seed`), `prepare` reads and checks the log (a bad log or a log the settings
//! cannot replay is the user's error, exit code 2), one batch of one run replays it,
//! and the analysis hands rows with units, checks, CSV files, figures and notes to the
//! driver, which writes `summary.json`, `report.md`, `run_info.json` and the rest
//! through the same output folder as `fathom run`.

pub mod notes;
pub mod rows;

use std::path::PathBuf;

use fathom_data::layout::LogError;
use fathom_sim::SimError;
use fathom_sim::cost::{CostTerm, Held};
use fathom_sim::experiment::Environment;

use crate::data_dir::find_data_dir;

/// The built-in settings of `fathom replay range-beacon` (`scenarios/range-beacon.toml`).
pub const RANGE_BEACON_PRESET: &str = include_str!("../../../../scenarios/range-beacon.toml");
/// The built-in settings of `fathom replay ins-dvl` (`scenarios/ins-dvl.toml`).
pub const INS_DVL_PRESET: &str = include_str!("../../../../scenarios/ins-dvl.toml");
/// The built-in settings of `fathom replay gnss-ins|ulog` (`scenarios/gnss-ins.toml`).
pub const GNSS_INS_PRESET: &str = include_str!("../../../../scenarios/gnss-ins.toml");
/// The document the replays' `summary.json` names as their source (`seed_doc`).
pub const SEED_DOC: &str = "docs/own-data.md";

/// The log folder `dir` (`[data] dir`): absolute, or found inside `env.base_dir` or
/// beside one of its ancestors; a folder that is not found is returned as it would be
/// inside the base directory, so that reading it names it.
pub fn log_dir(env: &Environment, dir: &str) -> PathBuf {
    find_data_dir(&env.base_dir, dir).unwrap_or_else(|| env.base_dir.join(dir))
}

/// What an own-log job prepares: its settings, the log folder and the log, read and
/// checked against the settings.
#[derive(Debug)]
pub struct PreparedLog<S, L> {
    /// The checked settings.
    pub(crate) settings: S,
    /// The log folder as found.
    pub(crate) dir: PathBuf,
    /// The log.
    pub(crate) log: L,
}

/// Reads the log of `settings` (its `[data] dir`, found with [`log_dir`]) with `read`
/// and checks it against the settings with `check`: what both own-log jobs prepare.
///
/// # Errors
/// A log that cannot be read ([`log_error`]); `check`'s errors.
pub fn prepare_log<S, L>(
    settings: S,
    data_dir: &str,
    env: &Environment,
    read: impl FnOnce(&std::path::Path) -> Result<L, LogError>,
    check: impl FnOnce(&L, &S) -> Result<(), SimError>,
) -> Result<PreparedLog<S, L>, SimError> {
    let dir = log_dir(env, data_dir);
    let log = read(&dir).map_err(log_error)?;
    check(&log, &settings)?;
    Ok(PreparedLog { settings, dir, log })
}

/// A log that cannot be read (the user's data: missing folder, a log of the other
/// kind, a bad file naming its line and column).
pub fn log_error(e: LogError) -> SimError {
    SimError::Input(Box::new(SimError::model("reading the log", e)))
}

/// Samples of a log of a few hours (10⁵ rows of each sensor) times the methods.
const SAMPLES: f64 = 5e6;
/// Single-core time per sample and method, s.
const SAMPLE_S: f64 = 2e-6;
/// Memory of the log and the replays' series, bytes.
const BYTES: f64 = 256e6;

/// The cost of one replay of a log with `methods` methods: its size is only known
/// once the files are read, so the estimate is that of a log of a few hours.
pub fn cost_terms(methods: usize) -> Vec<CostTerm> {
    vec![CostTerm::new(
        "one replay of your log (a few hours of data assumed; the files decide)",
        SAMPLES * methods.max(1) as f64,
        SAMPLE_S,
        BYTES,
        Held::Once,
    )]
}
