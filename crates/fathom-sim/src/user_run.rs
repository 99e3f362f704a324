//! Running and checking a user's scenario file: the library side of `fathom run` and
//! `fathom check`.
//!
//! A scenario file names its experiment with a top-level key `experiment = "<name>"`.
//! The key is a field of every experiment's scenario struct (validated against the
//! experiment's name) rather than being stripped by the driver: the experiment then
//! reads the user's text unchanged, so line and column numbers in error messages stay
//! those of the user's file.
//!
//! Every front end goes the same way ([`assess_scenario`]): the flags into a [`Job`], the
//! text parsed once ([`ScenarioDoc`]), the experiment picked from its `experiment` key
//! ([`pick_experiment`]), then the experiment's assessment (overrides, check, cost); the
//! run executes that [`Assessed`] value ([`run_assessed`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::cost::{Cost, Limits};
use crate::driver::{ExperimentResult, WriteOptions, error_chain, execute_assessed_to};
use crate::error::SimError;
use crate::experiment::{Assessed, DynExperiment, Environment, Extras, Job};
use crate::progress::Progress;
use crate::scenario::ScenarioDoc;

pub use crate::driver::{RUN_INFO_FILE, RunInfo};

/// The top-level `experiment` key, read leniently (other keys are ignored here).
#[derive(Debug, Deserialize)]
struct Peek {
    experiment: Option<toml::Value>,
}

/// The experiment named by the scenario `text` (`file` labels errors).
///
/// # Errors
/// [`SimError::Toml`] for a TOML syntax error; [`SimError::Invalid`] (key
/// `experiment`) when the key is missing, not a string, or names no registered
/// experiment.
pub fn peek_experiment(
    text: &str,
    file: &str,
    registry: &[&'static dyn DynExperiment],
) -> Result<&'static dyn DynExperiment, SimError> {
    pick_experiment(&ScenarioDoc::parse(text, file)?, registry)
}

/// The experiment named by the parsed scenario `doc`.
///
/// # Errors
/// [`SimError::Invalid`] (key `experiment`) when the key is missing, not a string, or
/// names no registered experiment.
pub fn pick_experiment(
    doc: &ScenarioDoc<'_>,
    registry: &[&'static dyn DynExperiment],
) -> Result<&'static dyn DynExperiment, SimError> {
    let file = doc.file();
    let peek: Peek = doc.peek()?;
    let known = registry
        .iter()
        .map(|e| format!("\"{}\"", e.name()))
        .collect::<Vec<_>>()
        .join(", ");
    let name = match peek.experiment {
        None => {
            return Err(SimError::invalid(
                file,
                "experiment",
                format!("missing; the scenario must name its experiment, one of {known}"),
            ));
        }
        Some(toml::Value::String(s)) => s,
        Some(other) => {
            return Err(SimError::invalid(
                file,
                "experiment",
                format!("must be a string, one of {known}, got {other}"),
            ));
        }
    };
    registry
        .iter()
        .copied()
        .find(|e| e.name() == name)
        .ok_or_else(|| {
            SimError::invalid(
                file,
                "experiment",
                format!("unknown experiment {name:?}, expected one of {known}"),
            )
        })
}

/// The result of [`check_scenario`].
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedScenario {
    /// The experiment the scenario is for.
    pub experiment: String,
    /// The resolved scenario (defaults filled in) as TOML.
    pub resolved_toml: String,
    /// Number of leaf keys (values, counting array elements of tables) in the resolved
    /// scenario.
    pub keys: usize,
    /// Number of tables (including tables inside arrays of tables).
    pub tables: usize,
    /// The estimated cost (on all cores), within the limits.
    pub cost: Cost,
}

/// Parse and validate a scenario text without running it (`fathom check`), with the
/// default [`Limits`], then, for an experiment whose preparation reads the user's files
/// ([`crate::Experiment::CHECK_PREPARES`]), prepare it as a run would (load its world,
/// data folder or log, relative to the current directory), without running.
///
/// # Errors
/// As [`peek_experiment`], then the experiment's own parse and check errors
/// ([`SimError::Toml`] with key path and line, [`SimError::Invalid`] with key path),
/// then a cost beyond the limits ([`SimError::Invalid`] naming the key), then the
/// preparation's errors (the same as `fathom run`'s).
pub fn check_scenario_text(
    text: &str,
    file: &str,
    registry: &[&'static dyn DynExperiment],
) -> Result<CheckedScenario, SimError> {
    check_scenario_text_with(text, file, registry, &Limits::default())
}

/// [`check_scenario_text`] against `limits`.
///
/// # Errors
/// As [`check_scenario_text`].
pub fn check_scenario_text_with(
    text: &str,
    file: &str,
    registry: &[&'static dyn DynExperiment],
    limits: &Limits,
) -> Result<CheckedScenario, SimError> {
    let env = Environment {
        limits: *limits,
        // Data looked up as `fathom run` looks it up: from the current directory.
        ..Environment::new(std::env::current_dir().unwrap_or_else(|_| ".".into()))
    };
    check_scenario_text_in(text, file, registry, env)
}

/// [`check_scenario_text`] in `env`: its limits, its data folder (relative paths of
/// the scenario are looked up from `env.base_dir`) and its extras.
///
/// # Errors
/// As [`check_scenario_text`].
pub fn check_scenario_text_in(
    text: &str,
    file: &str,
    registry: &[&'static dyn DynExperiment],
    env: Environment,
) -> Result<CheckedScenario, SimError> {
    let job = Job {
        text,
        file,
        runs: None,
        seed: None,
        threads: None,
        progress: None,
        env,
    };
    let (exp, assessed) = assess_scenario(&job, registry)?;
    let (keys, tables) = count_keys(&toml::Value::Table(assessed.table.clone()));
    let checked = CheckedScenario {
        experiment: exp.name().to_string(),
        resolved_toml: assessed.resolved.toml.clone(),
        keys,
        tables,
        cost: assessed.cost.clone(),
    };
    // What a run loads before its first run (worlds, data folders, logs), so that a
    // scenario `check` accepts is one `run` starts.
    if exp.check_prepares() {
        assessed.plan()?;
    }
    Ok(checked)
}

/// Assesses a user's scenario once: the text of `job` parsed, its experiment picked
/// from `registry`, the overrides applied, checked and costed against the job's limits.
///
/// # Errors
/// A TOML error, the `experiment` key's errors ([`pick_experiment`]), then
/// [`DynExperiment::assess`]'s.
pub fn assess_scenario<'j>(
    job: &'j Job<'j>,
    registry: &[&'static dyn DynExperiment],
) -> Result<(&'static dyn DynExperiment, Assessed<'j>), SimError> {
    let doc = ScenarioDoc::parse(job.text, job.file)?;
    let exp = pick_experiment(&doc, registry)?;
    let assessed = exp.assess_doc(doc, job)?;
    Ok((exp, assessed))
}

/// [`check_scenario_text`] on a file (its path as given labels errors).
///
/// # Errors
/// [`SimError::Io`] if the file cannot be read, else as [`check_scenario_text`].
pub fn check_scenario(
    path: &Path,
    registry: &[&'static dyn DynExperiment],
) -> Result<CheckedScenario, SimError> {
    check_scenario_with(path, registry, &Limits::default())
}

/// [`check_scenario`] against `limits`.
///
/// # Errors
/// As [`check_scenario`].
pub fn check_scenario_with(
    path: &Path,
    registry: &[&'static dyn DynExperiment],
    limits: &Limits,
) -> Result<CheckedScenario, SimError> {
    let text = std::fs::read_to_string(path).map_err(|e| SimError::io("read", path, e))?;
    check_scenario_text_with(&text, &path.display().to_string(), registry, limits)
}

/// Exit code of `fathom check` / `fathom run` for an invalid scenario or bad arguments.
pub const EXIT_USAGE: u8 = 2;

/// `fathom check <file>`: the line to print and the exit code (0 = valid,
/// [`EXIT_USAGE`] = invalid). The error line names the file, the key path and, for
/// TOML errors, the line; it is always one line.
pub fn check_command(path: &Path, registry: &[&'static dyn DynExperiment]) -> (u8, String) {
    check_command_with(path, registry, &Limits::default())
}

/// [`check_command`] against `limits`; the OK line carries the cost estimate.
pub fn check_command_with(
    path: &Path,
    registry: &[&'static dyn DynExperiment],
    limits: &Limits,
) -> (u8, String) {
    match check_scenario_with(path, registry, limits) {
        Ok(c) => (0, check_line(path, &c)),
        Err(e) => (EXIT_USAGE, one_line(&error_chain(&e))),
    }
}

/// The line `fathom check` prints for a valid scenario: its experiment, its size and
/// the cost estimate.
pub fn check_line(path: &Path, c: &CheckedScenario) -> String {
    format!(
        "OK {}: experiment `{}`, {} keys in {} tables; {}",
        path.display(),
        c.experiment,
        c.keys,
        c.tables,
        c.cost.summary()
    )
}

/// `text` on one line (line breaks replaced by spaces), its numbers written out in
/// hundreds of digits in scientific notation ([`fathom_core::echo::compact_numbers`]).
pub fn one_line(text: &str) -> String {
    fathom_core::echo::compact_numbers(&text.split_whitespace().collect::<Vec<_>>().join(" "))
}

fn count_keys(v: &toml::Value) -> (usize, usize) {
    match v {
        toml::Value::Table(t) => t.values().fold((0, 1), |(k, n), v| {
            let (k2, n2) = count_keys(v);
            (k + k2, n + n2)
        }),
        toml::Value::Array(a) if a.iter().all(toml::Value::is_table) && !a.is_empty() => {
            a.iter().fold((0, 0), |(k, n), v| {
                let (k2, n2) = count_keys(v);
                (k + k2, n + n2)
            })
        }
        _ => (1, 0),
    }
}

/// Options of [`run_scenario`].
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    /// The scenario file.
    pub scenario: PathBuf,
    /// Output directory; `None` = `fathom-out/<experiment>`.
    pub out_dir: Option<PathBuf>,
    /// Override of the scenario's Monte Carlo run count (>= 1).
    pub runs: Option<usize>,
    /// Worker threads (>= 1; `None` = all cores).
    pub threads: Option<usize>,
    /// Override of the scenario's `base_seed` (at most `i64::MAX`, the largest TOML
    /// integer); an error for a deterministic experiment without one.
    pub seed: Option<u64>,
    /// Where relative data folders of a scenario are looked up (the experiment's
    /// `workspace_root`; `fathom run` passes the current directory).
    pub base_dir: PathBuf,
    /// Write into a folder holding files fathom did not write, keeping them
    /// (`--force`).
    pub force: bool,
    /// The limits the scenario's cost must fit (`--max-memory-gb`, `--max-hours`).
    pub limits: Limits,
    /// When the paper's sensitivity batches and claims run (`--paper-extras`: always).
    pub extras: Extras,
    /// Whether a run with a world writes its 3D scene page `scene.html`
    /// (`--no-scene`: no).
    pub scene_page: bool,
}

/// Check, then run a user's scenario file with its experiment; writes the experiment's
/// outputs (figures, CSV, `summary.json`, `report.md`) plus `scenario.toml` (the file
/// as given), `scenario.resolved.toml` (defaults filled in, `base_seed` = the seed
/// actually used, so running it reproduces the results) and `run_info.json` into the
/// output directory, through [`fathom_report::outdir`]: a folder holding files fathom
/// did not write is refused (kept with `force`), one that another process writes is
/// refused, and the previous outputs are replaced only once the new ones are
/// complete.
///
/// # Errors
/// Check errors as [`check_scenario`], bad `--runs` / `--threads` / `--seed`
/// ([`SimError::InvalidArgument`], also for `--seed` on a deterministic experiment), a
/// refused output directory, the experiment's failure, or I/O errors.
pub fn run_scenario(
    options: &RunOptions,
    registry: &[&'static dyn DynExperiment],
) -> Result<(ExperimentResult, RunInfo), SimError> {
    run_scenario_with_progress(options, registry, None)
}

/// [`run_scenario`] reporting the Monte Carlo batches and runs to `progress` (see
/// [`crate::progress`]); the results do not depend on it.
///
/// # Errors
/// As [`run_scenario`].
pub fn run_scenario_with_progress(
    options: &RunOptions,
    registry: &[&'static dyn DynExperiment],
    progress: Option<Progress>,
) -> Result<(ExperimentResult, RunInfo), SimError> {
    let path = &options.scenario;
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SimError::io("read", path, e))?;
    run_scenario_text(&text, &label, options, registry, progress)
}

/// [`run_scenario_with_progress`] on a scenario text (`label` names it in messages and
/// in `run_info.json`); `options.scenario` is not read.
///
/// # Errors
/// As [`run_scenario`].
pub fn run_scenario_text(
    text: &str,
    label: &str,
    options: &RunOptions,
    registry: &[&'static dyn DynExperiment],
    progress: Option<Progress>,
) -> Result<(ExperimentResult, RunInfo), SimError> {
    let job = job_of(text, label, options, progress);
    let (exp, assessed) = assess_scenario(&job, registry)?;
    run_assessed(exp, assessed, &job, options)
}

/// The job of a user's scenario `text` (labelled `label`) with the options' overrides,
/// limits and data folder.
pub fn job_of<'a>(
    text: &'a str,
    label: &'a str,
    options: &RunOptions,
    progress: Option<Progress>,
) -> Job<'a> {
    Job {
        text,
        file: label,
        runs: options.runs,
        seed: options.seed,
        threads: options.threads,
        progress,
        env: Environment {
            limits: options.limits,
            extras: options.extras,
            scene_page: options.scene_page,
            ..Environment::new(options.base_dir.clone())
        },
    }
}

/// Runs an assessed scenario of `exp` and writes its outputs into `options.out_dir`
/// (default `fathom-out/<experiment>`) as [`run_scenario`] does.
///
/// # Errors
/// As [`run_scenario`] after the check.
pub fn run_assessed(
    exp: &dyn DynExperiment,
    assessed: Assessed<'_>,
    job: &Job<'_>,
    options: &RunOptions,
) -> Result<(ExperimentResult, RunInfo), SimError> {
    let out_dir = options
        .out_dir
        .clone()
        .unwrap_or_else(|| Path::new("fathom-out").join(exp.name()));
    let write = WriteOptions {
        force: options.force,
        command: "run".into(),
        scenario_files: true,
    };
    execute_assessed_to(exp, assessed, job, &out_dir, &write)
}
