//! The driver: runs any registered experiment through one pipeline and writes its
//! outputs. [`execute_into`] is what `cargo xtask paper` ([`run_paper`]) and `fathom
//! run` ([`crate::user_run`]) do per experiment:
//!
//! 1. [`DynExperiment::execute`]: parse the scenario, apply `--runs` / `--seed`,
//!    check, prepare, run the Monte Carlo batches, analyse;
//! 2. remove the stale outputs of an earlier run directly in the output directory
//!    (`*.svg`, `*.csv`, `*.json`, `*.md`; sub-directories are left alone);
//! 3. write the experiment's figures and CSV files, `summary.json` and `report.md`
//!    (header, the side-by-side table, the claims, the experiment's notes, links to
//!    the figures).

pub mod campaign;
mod paper;
mod report;
mod single_run;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::SimError;
use crate::experiment::{DynExperiment, Executed, Job};
use crate::output::{Summary, write_summary_json, write_text, write_with};

pub use paper::{PaperOptions, PaperResult, run_paper, run_paper_to};
pub use report::{TABLE_DECIMALS, console_section};
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
    /// Why the experiment was skipped, if it was (e.g. its data folder is absent).
    pub skipped: Option<String>,
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

/// Executes `exp` on `job` and writes every output into `out_dir` (created if
/// needed); `scenario_label` names the scenario in the report header.
///
/// # Errors
/// The experiment's errors, then I/O errors.
pub fn execute_into(
    exp: &dyn DynExperiment,
    job: &Job<'_>,
    out_dir: &Path,
) -> Result<ExperimentResult, SimError> {
    let start = Instant::now();
    let executed = exp.execute(job)?;
    let elapsed = start.elapsed();
    std::fs::create_dir_all(out_dir).map_err(|e| SimError::io("create directory", out_dir, e))?;
    clear_stale_outputs(out_dir)?;
    write_executed(&executed, job.file, out_dir, elapsed)
}

pub(crate) fn write_executed(
    executed: &Executed,
    scenario_label: &str,
    out_dir: &Path,
    elapsed: Duration,
) -> Result<ExperimentResult, SimError> {
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
    let md = report::experiment_report(summary, scenario_label, &executed.analysis, &figures);
    write_text(out_dir.join("report.md"), &md)?;
    Ok(ExperimentResult {
        name: summary.experiment.clone(),
        out_dir: out_dir.to_path_buf(),
        summary: summary.clone(),
        figures,
        elapsed,
        resolved_toml: executed.resolved.toml.clone(),
        skipped: executed.analysis.skipped.clone(),
    })
}

/// Writes a set of outputs into a fresh folder beside `out_dir` with `write`, then
/// moves it into place (an existing `out_dir` is replaced only after the new one is
/// complete), so an error or an interrupted write leaves `out_dir` as it was.
///
/// # Errors
/// `write`'s errors, I/O errors.
pub(crate) fn write_atomically<T>(
    out_dir: &Path,
    write: impl FnOnce(&Path) -> Result<T, SimError>,
) -> Result<T, SimError> {
    let name = out_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = out_dir.parent().filter(|p| !p.as_os_str().is_empty());
    let sibling = |tag: &str| {
        let n = format!(".{name}.{tag}-{}", std::process::id());
        parent.map_or_else(|| PathBuf::from(&n), |p| p.join(&n))
    };
    let tmp = sibling("partial");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(|e| SimError::io("remove", &tmp, e))?;
    }
    std::fs::create_dir_all(&tmp).map_err(|e| SimError::io("create directory", &tmp, e))?;
    let value = match write(&tmp) {
        Ok(v) => v,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
    };
    let old = sibling("old");
    if out_dir.exists() {
        std::fs::rename(out_dir, &old).map_err(|e| SimError::io("move aside", out_dir, e))?;
    }
    std::fs::rename(&tmp, out_dir).map_err(|e| SimError::io("move into place", out_dir, e))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(|e| SimError::io("remove", &old, e))?;
    }
    Ok(value)
}

/// Remove the outputs a previous run left directly in `dir`.
fn clear_stale_outputs(dir: &Path) -> Result<(), SimError> {
    let entries = std::fs::read_dir(dir).map_err(|e| SimError::io("list directory", dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| SimError::io("list directory", dir, e))?;
        let path = entry.path();
        let is_output = path.is_file()
            && path
                .extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| matches!(x, "svg" | "csv" | "json" | "md"));
        if is_output {
            std::fs::remove_file(&path).map_err(|e| SimError::io("remove", &path, e))?;
        }
    }
    Ok(())
}
