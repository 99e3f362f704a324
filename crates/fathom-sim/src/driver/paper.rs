//! `cargo xtask paper`: every registered experiment on its preset scenario, the
//! console tables, and the collected `target/paper/REPORT.md`.
//!
//! A failing experiment does not stop the others; its error chain is printed and
//! listed in `REPORT.md`, and [`run_paper`] then returns the first failure.
//! `REPORT.md` collects the `report.md` of every registered experiment found on disk
//! (those not run this time are marked as coming from an earlier run), with headings
//! demoted one level and relative links rebased.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::report::{console_section, demote_headings, rebase_links};
use super::{ExperimentResult, WriteOptions, error_chain, execute_to, write_file_atomically};
use crate::SimError;
use crate::experiment::{DynExperiment, Environment, Extras, Job};
use fathom_report::output::{md_table, read_summary_json};

/// Options of [`run_paper`] (the `cargo xtask paper` flags).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PaperOptions {
    /// Run only this experiment.
    pub only: Option<String>,
    /// Override every experiment's Monte Carlo run count (must be >= 1).
    pub runs: Option<usize>,
    /// Worker threads (must be >= 1; `None` = all cores).
    pub threads: Option<usize>,
    /// Workspace root; scenario paths are relative to it.
    pub workspace_root: PathBuf,
    /// Output root, normally `<workspace_root>/target/paper`.
    pub out_root: PathBuf,
    /// Write an experiment's folder even when it holds files fathom did not write
    /// (they are kept; only fathom's own files are replaced).
    pub force: bool,
}

/// The outcome of [`run_paper`].
#[derive(Debug, Clone, PartialEq)]
pub struct PaperResult {
    /// The experiments run, in registry order.
    pub experiments: Vec<ExperimentResult>,
    /// Path of the collected `REPORT.md`.
    pub report_path: PathBuf,
}

/// Run the selected experiments, print their tables to stdout and write all outputs.
///
/// # Errors
/// Bad options or registry, unknown `--only` name ([`SimError::UnknownExperiment`]),
/// I/O failures, or the first failing experiment ([`SimError::Experiment`]).
pub fn run_paper(
    options: PaperOptions,
    registry: &[&dyn DynExperiment],
) -> Result<PaperResult, SimError> {
    let stdout = std::io::stdout();
    let mut lock = stdout.lock();
    run_paper_to(&options, registry, &mut lock)
}

/// [`run_paper`] printing to `out` instead of stdout.
///
/// # Errors
/// As [`run_paper`].
pub fn run_paper_to(
    options: &PaperOptions,
    registry: &[&dyn DynExperiment],
    out: &mut dyn Write,
) -> Result<PaperResult, SimError> {
    check_registry(registry)?;
    crate::experiment::check_overrides(options.runs, None, options.threads)?;
    let selected: Vec<&dyn DynExperiment> = match &options.only {
        Some(name) => match registry.iter().find(|e| e.name() == name) {
            Some(e) => vec![*e],
            None => {
                return Err(SimError::UnknownExperiment {
                    name: name.clone(),
                    known: registry.iter().map(|e| e.name().to_string()).collect(),
                });
            }
        },
        None => registry.to_vec(),
    };
    std::fs::create_dir_all(&options.out_root)
        .map_err(|e| SimError::io("create directory", &options.out_root, e))?;

    let mut results = Vec::new();
    let mut failures: Vec<(String, SimError)> = Vec::new();
    for exp in selected {
        say(out, &format!("== {} ({}) ==\n", exp.name(), exp.seed_doc()))?;
        match run_one(options, exp) {
            Ok(res) => {
                say(out, &console_section(&res))?;
                results.push(res);
            }
            Err(e) => {
                let e = SimError::Experiment {
                    name: exp.name().to_string(),
                    source: Box::new(e),
                };
                say(out, &format!("FAILED: {}\n\n", error_chain(&e)))?;
                failures.push((exp.name().to_string(), e));
            }
        }
    }

    let report_path = options.out_root.join("REPORT.md");
    let report = collected_report(options, registry, &results, &failures);
    write_file_atomically(&report_path, &report)?;
    say(out, &format!("report: {}\n", report_path.display()))?;

    if let Some((_, first)) = failures.into_iter().next() {
        return Err(first);
    }
    Ok(PaperResult {
        experiments: results,
        report_path,
    })
}

fn say(out: &mut dyn Write, text: &str) -> Result<(), SimError> {
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| SimError::io("write", "<output stream>", e))
}

/// Names are `[a-z0-9_-]+` and unique.
pub(crate) fn check_registry(registry: &[&dyn DynExperiment]) -> Result<(), SimError> {
    for (i, e) in registry.iter().enumerate() {
        let name = e.name();
        let ok = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_' || c == '-');
        if !ok {
            return Err(SimError::invalid_argument(
                format!("registry entry {i}"),
                format!("name `{name}` must match [a-z0-9_-]+"),
            ));
        }
        if registry[..i].iter().any(|d| d.name() == name) {
            return Err(SimError::invalid_argument(
                "registry",
                format!("duplicate experiment name `{name}`"),
            ));
        }
    }
    Ok(())
}

fn run_one(options: &PaperOptions, exp: &dyn DynExperiment) -> Result<ExperimentResult, SimError> {
    let label = exp.default_scenario();
    let path = options.workspace_root.join(label);
    let text = std::fs::read_to_string(&path).map_err(|e| SimError::io("read", &path, e))?;
    let job = Job {
        text: &text,
        file: label,
        runs: options.runs,
        // `cargo xtask paper` always uses the scenario seeds.
        seed: None,
        threads: options.threads,
        progress: None,
        // The paper run judges the paper's claims on whatever the workspace's
        // scenario files say (a reduced copy in a test, the presets otherwise).
        env: Environment {
            extras: Extras::Always,
            ..Environment::new(options.workspace_root.clone())
        },
    };
    let write = WriteOptions {
        force: options.force,
        command: "paper".into(),
        scenario_files: false,
    };
    execute_to(exp, &job, &options.out_root.join(exp.name()), &write).map(|(r, _)| r)
}

fn dir_of(options: &PaperOptions, name: &str) -> PathBuf {
    options.out_root.join(name)
}

fn read_report(dir: &Path) -> Option<String> {
    std::fs::read_to_string(dir.join("report.md")).ok()
}

/// `target/paper/REPORT.md`.
fn collected_report(
    options: &PaperOptions,
    registry: &[&dyn DynExperiment],
    results: &[ExperimentResult],
    failures: &[(String, SimError)],
) -> String {
    let mut md = String::from(
        "# fathom: paper reproduction report\n\n\
         Generated by `cargo xtask paper`. Per experiment: the paper's numbers next to the \
         reproduced ones with 95 % confidence intervals over Monte Carlo runs, the paper's \
         claims with their verdict, notes, and links to the figures \
         (all files in `<experiment>/`).\n\n",
    );
    let mut overview = Vec::new();
    let mut sections = String::new();
    for exp in registry {
        let name = exp.name();
        let dir = dir_of(options, name);
        let ran = results.iter().any(|r| r.name == name);
        let failed = failures.iter().find(|(n, _)| n == name);
        let summary = read_summary_json(dir.join("summary.json")).ok();
        let status = match (ran, failed) {
            (_, Some(_)) => "failed".to_string(),
            (true, None) => "run now".to_string(),
            (false, None) if summary.is_some() => "earlier run".to_string(),
            (false, None) => "not run".to_string(),
        };
        let (runs, claims) = summary.as_ref().map_or(("—".into(), "—".into()), |s| {
            let held = s.claims.iter().filter(|c| c.holds).count();
            (s.runs.to_string(), format!("{held}/{}", s.claims.len()))
        });
        overview.push(vec![
            format!("[{name}](#{name})"),
            format!("`{}`", exp.seed_doc()),
            runs,
            claims,
            status.clone(),
        ]);
        if let Some((_, e)) = failed {
            sections.push_str(&format!("## {name}\n\n**Failed:** {}\n\n", error_chain(e)));
            continue;
        }
        if let Some(text) = read_report(&dir) {
            if !ran {
                sections.push_str(&format!("<!-- {name}: from an earlier run -->\n"));
            }
            sections.push_str(&rebase_links(&demote_headings(&text), name));
            if !ran {
                sections.push_str("\n*(results from an earlier run)*\n");
            }
            sections.push('\n');
        }
    }
    if registry.is_empty() {
        md.push_str("No experiments are registered.\n");
    } else {
        md.push_str(&md_table(
            &[
                "experiment",
                "seed paper",
                "runs",
                "claims holding",
                "status",
            ],
            &overview,
        ));
        md.push('\n');
        md.push_str(&sections);
    }
    md
}
