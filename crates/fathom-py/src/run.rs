//! `fathom.run`, `fathom.check`, `fathom.preset`, `fathom.experiments`: scenarios
//! through the experiment driver of `fathom-sim`, the same code path as `fathom run`
//! and `fathom check`.
//!
//! A scenario argument is a path (`str` or `os.PathLike`) or TOML text: a `str` that
//! contains a newline or `=` is TOML text (labelled `<scenario text>` in messages),
//! any other `str` a path. Invalid scenarios raise `ValueError` with the one line
//! `fathom check` prints for the same file; an unreadable file raises `OSError`
//! (`FileNotFoundError` when it does not exist); a failure while running raises
//! `RuntimeError`.

use std::path::PathBuf;

use fathom_experiments::{jobs, registry};
use fathom_report::output::Summary;
use fathom_sim::experiment::{Environment, Executed, Job, OutputFile};
use fathom_sim::user_run::{
    RunOptions, assess_scenario, check_command, check_scenario_text, one_line, run_scenario_text,
};
use fathom_sim::{SimError, error_chain};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::csv;

/// The label of a scenario given as text.
pub const TEXT_LABEL: &str = "<scenario text>";

/// A scenario argument resolved to its text and the label of its messages.
struct Scenario {
    text: String,
    label: String,
    /// The file, when given as a path.
    path: Option<PathBuf>,
}

/// The one-line message of a library error (as the CLI prints it, without `error: `).
fn message(e: &SimError) -> String {
    one_line(&error_chain(e))
}

/// `ValueError` for usage and scenario errors, `RuntimeError` for the rest (the CLI's
/// exit codes 2 and 1).
fn to_py_err(e: &SimError) -> PyErr {
    match e {
        SimError::Invalid { .. }
        | SimError::InvalidArgument { .. }
        | SimError::Toml { .. }
        | SimError::UnknownExperiment { .. } => PyValueError::new_err(message(e)),
        _ => PyRuntimeError::new_err(message(e)),
    }
}

fn read_scenario(obj: &Bound<'_, PyAny>) -> PyResult<Scenario> {
    let path = if obj.is_instance_of::<PyString>() {
        let s: String = obj.extract()?;
        if s.contains('\n') || s.contains('=') {
            return Ok(Scenario {
                text: s.to_string(),
                label: TEXT_LABEL.to_string(),
                path: None,
            });
        }
        PathBuf::from(s)
    } else {
        obj.extract::<PathBuf>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "scenario: expected a path (str or os.PathLike) or TOML text (str)",
            )
        })?
    };
    match std::fs::read_to_string(&path) {
        Ok(text) => Ok(Scenario {
            text,
            label: path.display().to_string(),
            path: Some(path),
        }),
        Err(e) => {
            let kind = e.kind();
            let msg = message(&SimError::io("read", &path, e));
            Err(if kind == std::io::ErrorKind::NotFound {
                PyFileNotFoundError::new_err(msg)
            } else {
                PyOSError::new_err(msg)
            })
        }
    }
}

/// Checks the scenario: `Ok(resolved TOML)` or the `fathom check` line as `ValueError`.
fn check_text(scenario: &Scenario) -> PyResult<String> {
    let reg = jobs();
    if let Some(path) = &scenario.path {
        // the CLI's own function, so the line is the CLI's to the byte
        let (code, line) = check_command(path, &reg);
        if code != 0 {
            return Err(PyValueError::new_err(line));
        }
    }
    check_scenario_text(&scenario.text, &scenario.label, &reg)
        .map(|c| c.resolved_toml)
        .map_err(|e| PyValueError::new_err(message(&e)))
}

/// Parse and validate a scenario without running it (`fathom check`).
///
/// Returns the resolved scenario (every default filled in) as TOML text. Raises
/// `ValueError` with the one line `fathom check` prints when the scenario is invalid.
#[pyfunction]
#[pyo3(signature = (scenario, /))]
pub fn check(scenario: &Bound<'_, PyAny>) -> PyResult<String> {
    let scenario = read_scenario(scenario)?;
    check_text(&scenario)
}

/// The TOML text of a registered experiment's preset scenario (`scenarios/<name>.toml`,
/// built into the module).
#[pyfunction]
#[pyo3(signature = (name, /))]
pub fn preset(name: &str) -> PyResult<String> {
    let reg = registry();
    reg.iter()
        .find(|e| e.name() == name)
        .map(|e| e.preset().to_string())
        .ok_or_else(|| {
            let known: Vec<&str> = reg.iter().map(|e| e.name()).collect();
            PyValueError::new_err(format!(
                "unknown experiment {name:?}, expected one of {known:?}"
            ))
        })
}

/// The registered experiments: name -> one-line description (`fathom list`).
#[pyfunction]
pub fn experiments(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let dict = PyDict::new(py);
    for e in registry() {
        dict.set_item(e.name(), e.about())?;
    }
    Ok(dict)
}

/// The outcome of `fathom.run`: the summary (`summary.json` as Python objects) and
/// the run's CSV series as numpy arrays.
#[pyclass(module = "fathom", frozen, get_all)]
pub struct RunResult {
    /// Experiment name.
    experiment: String,
    /// The seed paper's file name.
    seed_doc: String,
    /// Monte Carlo runs of the main batch.
    runs: usize,
    /// Base seed of the runs.
    base_seed: u64,
    /// The whole `summary.json` content (a dict equal to `json.load` of the file).
    summary: Py<PyAny>,
    /// `summary["rows"]`: dicts with `method`, `metric`, `unit`, `paper`, `value`,
    /// `ci95` and, over runs, `ci_method`, `median`, `median_ci95`, `divergence`.
    rows: Py<PyAny>,
    /// `summary["claims"]`: dicts with `id`, `text`, `holds`, `detail`.
    claims: Py<PyAny>,
    /// The extra keys of `summary.json` (everything but the contract keys).
    extra: Py<PyAny>,
    /// CSV file name -> column name -> float64 array (text columns: list of str).
    series: Py<PyAny>,
    /// SVG file name -> SVG text.
    figures: Py<PyAny>,
    /// The resolved scenario (defaults filled in, overrides folded in) as TOML.
    resolved_toml: String,
    /// The output folder when `out` was given, else `None`.
    out_dir: Option<String>,
}

#[pymethods]
impl RunResult {
    fn __repr__(&self) -> String {
        format!(
            "RunResult(experiment={:?}, runs={}, base_seed={})",
            self.experiment, self.runs, self.base_seed
        )
    }
}

/// Contract keys of `summary.json` (the rest are extra keys).
const CONTRACT_KEYS: [&str; 6] = [
    "experiment",
    "seed_doc",
    "runs",
    "base_seed",
    "rows",
    "claims",
];

fn build_result(
    py: Python<'_>,
    summary: &Summary,
    files: &[&OutputFile],
    resolved_toml: String,
    out_dir: Option<String>,
) -> PyResult<RunResult> {
    // summary.json's own text through Python's json module: the dict is what
    // `json.load` gives for the file (key order and every float bit included)
    let text = summary
        .to_json_pretty()
        .map_err(|e| to_py_err(&SimError::from(e)))?;
    let summary_py = py.import("json")?.call_method1("loads", (text,))?;
    let dict = summary_py.cast::<PyDict>()?;
    let get = |k: &str| -> PyResult<Py<PyAny>> {
        dict.get_item(k)?
            .map(Bound::unbind)
            .ok_or_else(|| PyRuntimeError::new_err(format!("summary: no key `{k}`")))
    };
    let extra = PyDict::new(py);
    for (k, v) in dict.iter() {
        let key: String = k.extract()?;
        if !CONTRACT_KEYS.contains(&key.as_str()) {
            extra.set_item(k, v)?;
        }
    }
    let series = PyDict::new(py);
    let figures = PyDict::new(py);
    for f in files {
        if let Some(columns) = f.content.csv_columns() {
            series.set_item(&f.name, csv::columns(py, columns)?)?;
        } else if f.name.ends_with(".svg") {
            figures.set_item(&f.name, f.content.to_text())?;
        }
    }
    Ok(RunResult {
        experiment: summary.experiment.clone(),
        seed_doc: summary.seed_doc.clone(),
        runs: summary.runs,
        base_seed: summary.base_seed,
        rows: get("rows")?,
        claims: get("claims")?,
        extra: extra.into_any().unbind(),
        summary: summary_py.unbind(),
        series: series.into_any().unbind(),
        figures: figures.into_any().unbind(),
        resolved_toml,
        out_dir,
    })
}

/// The checks `fathom run` makes on its options before anything runs (the runner's
/// one rule, [`fathom_sim::experiment::check_overrides`]).
fn check_options(runs: Option<usize>, seed: Option<u64>, threads: Option<usize>) -> PyResult<()> {
    fathom_sim::experiment::check_overrides(runs, seed, threads)
        .map_err(|e| PyValueError::new_err(message(&e)))
}

/// Run a scenario (a path or TOML text) like `fathom run` and return its results.
///
/// `runs` and `seed` override the scenario's `runs` and `base_seed`; `threads` is the
/// number of worker threads (default: all cores; the numbers do not depend on it).
/// Without `out`, nothing is written; with `out`, every output file of `fathom run`
/// (summary.json, report.md, CSV, SVG, the scenario, its resolved form and
/// run_info.json) is written there by the same writer. The GIL is released while the
/// scenario runs. Relative data folders of a scenario are looked up from the current
/// directory, as `fathom run` does.
#[pyfunction]
#[pyo3(signature = (scenario, runs=None, seed=None, threads=None, out=None))]
pub fn run(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    runs: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    out: Option<PathBuf>,
) -> PyResult<RunResult> {
    let scenario = read_scenario(scenario)?;
    check_options(runs, seed, threads)?;
    check_text(&scenario)?;
    let base_dir = std::env::current_dir()
        .map_err(|e| PyOSError::new_err(format!("cannot read the current directory: {e}")))?;
    match out {
        None => {
            let executed: Executed = py
                .detach(|| {
                    let job = Job {
                        text: &scenario.text,
                        file: &scenario.label,
                        runs,
                        seed,
                        threads,
                        progress: None,
                        env: Environment::new(base_dir),
                    };
                    assess_scenario(&job, &jobs())?.1.execute()
                })
                .map_err(|e| to_py_err(&e))?;
            let files: Vec<&OutputFile> = executed.analysis.files().iter().collect();
            build_result(py, &executed.summary, &files, executed.resolved.toml, None)
        }
        Some(out_dir) => {
            let options = RunOptions {
                scenario: scenario
                    .path
                    .clone()
                    .unwrap_or_else(|| PathBuf::from(TEXT_LABEL)),
                out_dir: Some(out_dir.clone()),
                runs,
                threads,
                seed,
                base_dir,
                force: false,
                limits: fathom_sim::cost::Limits::default(),
                extras: Default::default(),
                scene_page: true,
            };
            let (result, _) = py
                .detach(|| {
                    run_scenario_text(&scenario.text, &scenario.label, &options, &jobs(), None)
                })
                .map_err(|e| to_py_err(&e))?;
            // Sorted by name: the order `series` and `figures` had when the files were
            // read back from the folder.
            let mut files: Vec<&OutputFile> = result.files.iter().collect();
            files.sort_by(|a, b| a.name.cmp(&b.name));
            build_result(
                py,
                &result.summary,
                &files,
                result.resolved_toml,
                Some(result.out_dir.display().to_string()),
            )
        }
    }
}
