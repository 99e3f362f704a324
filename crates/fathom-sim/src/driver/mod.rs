//! The driver: runs any registered experiment through one pipeline and writes its
//! outputs. [`execute_to`] is what `cargo xtask paper` ([`run_paper`]), `fathom run`
//! and `fathom replay` ([`crate::user_run`]) do per experiment, and `fathom merge`
//! ([`campaign`]) writes the same way:
//!
//! 1. [`DynExperiment::assess`]: parse the scenario (once: nothing after this step reads
//!    the text), apply `--runs` / `--seed`, check, estimate the cost against the limits;
//! 2. [`OutDir::claim`]: lock the output folder, refuse one holding files fathom did
//!    not write (unless forced) and check that it can be written ([`fathom_report::outdir`]);
//! 3. [`Assessed::execute`]: prepare, run the Monte Carlo batches, analyse;
//! 4. write the experiment's figures and CSV files, `summary.json` and `report.md`
//!    (header, the table, the claims, the experiment's notes, links to the figures)
//!    into the claimed temporary folder, then [`OutDir::commit`] moves it into place
//!    with its `run_info.json`.
//!
//! Nothing is written before step 2 and the previous outputs are replaced only in
//! step 4, once everything is written.

pub mod campaign;
mod paper;
mod report;
mod single_run;
#[cfg(test)]
mod tests;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::SimError;
use crate::experiment::{Assessed, DynExperiment, Executed, Job, OutputFile};
use fathom_report::output::{Summary, write_summary_json, write_text, write_with};

pub use crate::experiment::Setup;
pub use fathom_report::outdir::{OutDir, RUN_INFO_FILE, RunInfo, write_file_atomically};

pub use paper::{PaperOptions, PaperResult, run_paper, run_paper_to};
pub use report::{
    TABLE_DECIMALS, console_claims, console_main_rows, console_rows, console_section,
    console_setup, fmt_value,
};
pub use single_run::SingleRun;

/// The outcome of one experiment written by [`execute_into`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentResult {
    /// Experiment name.
    pub name: String,
    /// Its output directory.
    pub out_dir: PathBuf,
    /// The summary that was written.
    pub summary: Summary,
    /// The `.svg` files written, sorted by name.
    pub figures: Vec<PathBuf>,
    /// Wall-clock time of the execution (check to analysis).
    pub elapsed: Duration,
    /// The resolved scenario (TOML) with the overrides applied.
    pub resolved_toml: String,
    /// The unit of each metric, as the experiment declared it.
    pub units: BTreeMap<String, String>,
    /// Whether the scenario is the paper's setup, or which keys differ from it.
    pub setup: Setup,
    /// The figure and CSV files written, as the analysis made them (in its order):
    /// what the Python bindings hand on without reading the files back.
    pub files: Vec<OutputFile>,
    /// Whether the experiment reproduces a paper ([`DynExperiment::paper`]); a job on
    /// the user's own data compares its settings with the built-in ones instead.
    pub paper: bool,
    /// Whether the job is deterministic (no Monte Carlo runs, no seed: a replay of
    /// recorded data).
    pub deterministic: bool,
}

/// The whole error chain of `e` joined with `": "` (like anyhow's `{:#}`).
pub fn error_chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut cur = e.source();
    while let Some(s) = cur {
        out.push_str(": ");
        out.push_str(&s.to_string());
        cur = s.source();
    }
    out
}

/// How [`execute_to`] writes its outputs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteOptions {
    /// Write into a folder holding files fathom did not write, keeping them (only
    /// fathom's own files are replaced).
    pub force: bool,
    /// The command recorded in `run_info.json` (`run`, `replay`, `paper`, ...).
    pub command: String,
    /// Also write the scenario as given (`scenario.toml`) and resolved
    /// (`scenario.resolved.toml`, defaults, `--runs` and `--seed` folded in).
    pub scenario_files: bool,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            force: false,
            command: "run".into(),
            scenario_files: false,
        }
    }
}

/// Executes `exp` on `job` and writes every output into `out_dir` (see the module
/// docs; [`execute_to`] with the default [`WriteOptions`]).
///
/// # Errors
/// As [`execute_to`].
pub fn execute_into(
    exp: &dyn DynExperiment,
    job: &Job<'_>,
    out_dir: &Path,
) -> Result<ExperimentResult, SimError> {
    execute_to(exp, job, out_dir, &WriteOptions::default()).map(|(r, _)| r)
}

/// Executes `exp` on `job` and writes every output into `out_dir`: assess, claim the
/// folder, execute, write, commit (see the module docs).
///
/// # Errors
/// The scenario's and the options' errors and a refused output folder (all before
/// anything is computed or written), then the experiment's errors, then I/O errors.
pub fn execute_to(
    exp: &dyn DynExperiment,
    job: &Job<'_>,
    out_dir: &Path,
    options: &WriteOptions,
) -> Result<(ExperimentResult, RunInfo), SimError> {
    execute_assessed_to(exp, exp.assess(job)?, job, out_dir, options)
}

/// [`execute_to`] of a job already assessed (`fathom run` assessed it to print the
/// estimate): the scenario is not parsed again.
///
/// # Errors
/// A refused output folder (before anything is computed or written), then the
/// experiment's errors, then I/O errors.
pub fn execute_assessed_to(
    exp: &dyn DynExperiment,
    assessed: Assessed<'_>,
    job: &Job<'_>,
    out_dir: &Path,
    options: &WriteOptions,
) -> Result<(ExperimentResult, RunInfo), SimError> {
    let claim = OutDir::claim(out_dir, options.force)?;
    let setup = assessed.resolved.setup.clone();
    let start = Instant::now();
    let executed = assessed.execute()?;
    let elapsed = start.elapsed();
    let mut result = write_executed(exp, &executed, job.file, &setup, claim.dir(), elapsed)?;
    if options.scenario_files {
        write_text(claim.dir().join("scenario.toml"), job.text)?;
        write_text(
            claim.dir().join("scenario.resolved.toml"),
            &(resolved_header(exp.name()) + &result.resolved_toml),
        )?;
    }
    let deterministic = executed.resolved.base_seed.is_none();
    result.files = executed.analysis.files;
    let mut info = RunInfo {
        fathom_version: env!("CARGO_PKG_VERSION").to_string(),
        command: options.command.clone(),
        experiment: exp.name().to_string(),
        scenario: job.file.to_string(),
        runs: job.runs,
        threads: job.threads,
        seed: job.seed,
        base_seed: (!deterministic).then_some(result.summary.base_seed),
        elapsed_s: elapsed.as_secs_f64(),
        files: Vec::new(),
    };
    result.relocate(&claim);
    info.files = claim.commit(info.clone())?;
    Ok((result, info))
}

/// The comment lines written above the resolved scenario: where it comes from and the
/// command that reproduces the run (the overrides are folded into the file).
fn resolved_header(experiment: &str) -> String {
    format!(
        "# Resolved `{experiment}` scenario written by fathom {}: defaults filled\n\
         # in, `--runs` and `--seed` folded in. Reproduce the run with\n\
         #   fathom run scenario.resolved.toml\n\n",
        env!("CARGO_PKG_VERSION")
    )
}

impl ExperimentResult {
    /// Points the paths written into a claimed folder at their place after the commit.
    pub(crate) fn relocate(&mut self, claim: &OutDir) {
        self.out_dir = claim.path().to_path_buf();
        for f in &mut self.figures {
            *f = claim.final_path(f);
        }
    }
}

/// Writes the figures, CSV files, `summary.json` and `report.md` of `executed` (an
/// execution of `exp`) into `out_dir`.
pub(crate) fn write_executed(
    exp: &dyn DynExperiment,
    executed: &Executed,
    scenario_label: &str,
    setup: &Setup,
    out_dir: &Path,
    elapsed: Duration,
) -> Result<ExperimentResult, SimError> {
    let framing = report::Framing {
        paper: exp.paper(),
        deterministic: executed.resolved.base_seed.is_none(),
    };
    let mut figures = Vec::new();
    for f in executed.analysis.files() {
        let path = out_dir.join(&f.name);
        write_with(&path, |w| f.content.write_to(w))?;
        if f.name.ends_with(".svg") {
            figures.push(path);
        }
    }
    figures.sort();
    let summary = &executed.summary;
    write_summary_json(out_dir.join("summary.json"), summary)?;
    let md = report::experiment_report(
        summary,
        scenario_label,
        &executed.analysis,
        setup,
        framing,
        &figures,
    );
    write_text(out_dir.join("report.md"), &md)?;
    Ok(ExperimentResult {
        name: summary.experiment.clone(),
        out_dir: out_dir.to_path_buf(),
        summary: summary.clone(),
        figures,
        elapsed,
        resolved_toml: executed.resolved.toml.clone(),
        units: executed.analysis.units.clone(),
        setup: setup.clone(),
        paper: framing.paper,
        deterministic: framing.deterministic,
        // Moved in by the caller, which owns the analysis (no copy of the tables).
        files: Vec::new(),
    })
}
