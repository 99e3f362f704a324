//! The paper-experiment registry and the driver behind `cargo xtask paper`.
//!
//! An [`Experiment`] is a name, the seed paper, a default scenario file and a run
//! function. [`run_paper`] runs the selected experiments, and for each one:
//!
//! 1. creates `<out_root>/<name>/` and removes stale outputs directly inside it
//!    (`*.svg`, `*.csv`, `*.json`, `*.md`; sub-directories are left alone);
//! 2. calls the run function with an [`ExperimentContext`] (the experiment writes its
//!    figures and CSV files into `ctx.out_dir`);
//! 3. checks the returned [`Summary`] (name and seed doc match the registry entry,
//!    finite numbers) and writes `summary.json` and `report.md` (header, the
//!    side-by-side table `method | metric | paper | reproduced | 95% CI`, the claims,
//!    the experiment's own `report_section`, links to every `.svg` in the directory);
//! 4. prints the table and the claims to the output stream.
//!
//! Finally it writes `<out_root>/REPORT.md`, which collects the `report.md` of every
//! registered experiment found on disk (those not run this time are marked as coming
//! from an earlier run), with headings demoted one level and relative links rebased.
//!
//! A failing experiment does not stop the others; its error chain is printed and
//! listed in `REPORT.md`, and `run_paper` then returns the first failure.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use rand_chacha::ChaCha8Rng;
use serde::de::DeserializeOwned;

use crate::error::SimError;
use crate::output::{
    Summary, claims_md_table, fmt_ci, fmt_num, fmt_opt, holds_word, md_table, read_summary_json,
    summary_md_table, text_table, write_summary_json, write_text,
};
use crate::progress::Progress;

/// Decimals used for numbers in the printed and Markdown tables.
pub const TABLE_DECIMALS: usize = 4;

/// A registered paper experiment.
#[derive(Debug, Clone, Copy)]
pub struct Experiment {
    /// Experiment name, also the output directory name (`[a-z0-9_-]+`).
    pub name: &'static str,
    /// The seed paper's file name (goes into `summary.json`).
    pub seed_doc: &'static str,
    /// Default scenario file, relative to the workspace root (e.g. `scenarios/noise.toml`).
    pub default_scenario: &'static str,
    /// Runs the experiment.
    pub run: fn(&ExperimentContext) -> Result<ExperimentOutput, SimError>,
}

/// What an experiment's run function gets.
#[derive(Debug, Clone)]
pub struct ExperimentContext {
    /// Experiment name.
    pub name: String,
    /// Workspace root (absolute when coming from `xtask`).
    pub workspace_root: PathBuf,
    /// The scenario file: `workspace_root / default_scenario`.
    pub scenario_path: PathBuf,
    /// Scenario path as written in the registry (short label for messages).
    pub scenario_label: String,
    /// Output directory `<out_root>/<name>/` (exists when `run` is called).
    pub out_dir: PathBuf,
    /// `--runs` override of the scenario's Monte Carlo run count.
    pub runs: Option<usize>,
    /// `--threads` (number of worker threads; `None` = all cores).
    pub threads: Option<usize>,
    /// `--seed` override of the scenario's `base_seed` (`fathom run --seed S`); `None`
    /// keeps the scenario's. Every experiment reads its base seed through
    /// [`ExperimentContext::seed_or`], so the main batch, auxiliary batches and the
    /// figure runs all follow it.
    pub seed: Option<u64>,
    /// Optional progress hook told about every Monte Carlo batch and run (the `fathom`
    /// binary draws a progress bar with it); it cannot change any result.
    pub progress: Option<Progress>,
}

impl ExperimentContext {
    /// Path of an output file in the experiment directory.
    pub fn out_file(&self, file_name: &str) -> PathBuf {
        self.out_dir.join(file_name)
    }

    /// The run count: the `--runs` override if given, else `scenario_default`.
    pub fn runs_or(&self, scenario_default: usize) -> usize {
        self.runs.unwrap_or(scenario_default)
    }

    /// The base seed: the `--seed` override if given, else `scenario_base_seed`.
    pub fn seed_or(&self, scenario_base_seed: u64) -> u64 {
        self.seed.unwrap_or(scenario_base_seed)
    }

    /// Load the scenario file into `T` (errors name the file as registered, e.g.
    /// `scenarios/noise.toml`).
    ///
    /// # Errors
    /// [`SimError::Io`] / [`SimError::Toml`] as [`crate::scenario::parse_toml`].
    pub fn load_scenario<T: DeserializeOwned>(&self) -> Result<T, SimError> {
        let text = std::fs::read_to_string(&self.scenario_path)
            .map_err(|e| SimError::io("read", &self.scenario_path, e))?;
        crate::scenario::parse_toml(&text, &self.scenario_label)
    }

    /// [`crate::montecarlo::run_monte_carlo`] with this context's thread setting,
    /// reporting to the progress hook (if any) under the experiment's name.
    pub fn monte_carlo<T, F>(&self, runs: usize, base_seed: u64, f: F) -> Vec<T>
    where
        T: Send,
        F: Fn(usize, &mut ChaCha8Rng) -> T + Sync,
    {
        crate::montecarlo::run_monte_carlo_with_progress(
            runs,
            base_seed,
            self.threads,
            self.progress.as_ref(),
            &self.name,
            f,
        )
    }

    /// [`crate::montecarlo::try_run_monte_carlo`] with this context's thread setting,
    /// reporting to the progress hook (if any) under the experiment's name.
    ///
    /// # Errors
    /// The error of the first (by run index) failing run.
    pub fn try_monte_carlo<T, E, F>(&self, runs: usize, base_seed: u64, f: F) -> Result<Vec<T>, E>
    where
        T: Send,
        E: Send,
        F: Fn(usize, &mut ChaCha8Rng) -> Result<T, E> + Sync,
    {
        self.try_monte_carlo_labeled(&self.name, runs, base_seed, f)
    }

    /// [`ExperimentContext::try_monte_carlo`] with the batch `label` shown by the
    /// progress hook (for experiments running several batches).
    ///
    /// # Errors
    /// The error of the first (by run index) failing run.
    pub fn try_monte_carlo_labeled<T, E, F>(
        &self,
        label: &str,
        runs: usize,
        base_seed: u64,
        f: F,
    ) -> Result<Vec<T>, E>
    where
        T: Send,
        E: Send,
        F: Fn(usize, &mut ChaCha8Rng) -> Result<T, E> + Sync,
    {
        crate::montecarlo::try_run_monte_carlo_with_progress(
            runs,
            base_seed,
            self.threads,
            self.progress.as_ref(),
            label,
            f,
        )
    }
}

/// What an experiment returns.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentOutput {
    /// The `summary.json` content.
    pub summary: Summary,
    /// Free Markdown appended to `report.md` after the generated tables: interpretation
    /// decisions, the paper's inconsistencies, extra tables. Use `###` or deeper
    /// headings (the generated sections use `##`).
    pub report_section: String,
}

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
}

/// The outcome of one experiment run by [`run_paper`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentResult {
    /// Experiment name.
    pub name: String,
    /// Its output directory.
    pub out_dir: PathBuf,
    /// The summary that was written.
    pub summary: Summary,
    /// The `.svg` files found in the output directory, sorted by name.
    pub figures: Vec<PathBuf>,
    /// Wall-clock time of the run function.
    pub elapsed: Duration,
}

/// The outcome of [`run_paper`].
#[derive(Debug, Clone, PartialEq)]
pub struct PaperResult {
    /// The experiments run, in registry order.
    pub experiments: Vec<ExperimentResult>,
    /// Path of the collected `REPORT.md`.
    pub report_path: PathBuf,
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

/// Run the selected experiments, print their tables to stdout and write all outputs
/// (see the module docs).
///
/// # Errors
/// Bad options or registry, unknown `--only` name ([`SimError::UnknownExperiment`]),
/// I/O failures, or the first failing experiment ([`SimError::Experiment`]).
pub fn run_paper(options: PaperOptions, registry: &[Experiment]) -> Result<PaperResult, SimError> {
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
    registry: &[Experiment],
    out: &mut dyn Write,
) -> Result<PaperResult, SimError> {
    check_registry(registry)?;
    if options.runs == Some(0) {
        return Err(SimError::invalid_argument("--runs", "must be at least 1"));
    }
    if options.threads == Some(0) {
        return Err(SimError::invalid_argument(
            "--threads",
            "must be at least 1",
        ));
    }
    let selected: Vec<&Experiment> = match &options.only {
        Some(name) => match registry.iter().find(|e| e.name == name) {
            Some(e) => vec![e],
            None => {
                return Err(SimError::UnknownExperiment {
                    name: name.clone(),
                    known: registry.iter().map(|e| e.name.to_string()).collect(),
                });
            }
        },
        None => registry.iter().collect(),
    };
    std::fs::create_dir_all(&options.out_root)
        .map_err(|e| SimError::io("create directory", &options.out_root, e))?;

    let mut results = Vec::new();
    let mut failures: Vec<(String, SimError)> = Vec::new();
    for exp in selected {
        say(out, &format!("== {} ({}) ==\n", exp.name, exp.seed_doc))?;
        match run_one(options, exp) {
            Ok(res) => {
                say(out, &console_section(&res))?;
                results.push(res);
            }
            Err(e) => {
                let e = SimError::Experiment {
                    name: exp.name.to_string(),
                    source: Box::new(e),
                };
                say(out, &format!("FAILED: {}\n\n", error_chain(&e)))?;
                failures.push((exp.name.to_string(), e));
            }
        }
    }

    let report_path = options.out_root.join("REPORT.md");
    let report = collected_report(options, registry, &results, &failures);
    write_text(&report_path, &report)?;
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

fn check_registry(registry: &[Experiment]) -> Result<(), SimError> {
    for (i, e) in registry.iter().enumerate() {
        let ok = !e.name.is_empty()
            && e.name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_' || c == '-');
        if !ok {
            return Err(SimError::invalid_argument(
                format!("registry entry {i}"),
                format!("name `{}` must match [a-z0-9_-]+", e.name),
            ));
        }
        if registry[..i].iter().any(|d| d.name == e.name) {
            return Err(SimError::invalid_argument(
                "registry",
                format!("duplicate experiment name `{}`", e.name),
            ));
        }
    }
    Ok(())
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

/// The `.svg` files directly in `dir`, sorted.
fn figures_in(dir: &Path) -> Result<Vec<PathBuf>, SimError> {
    let entries = std::fs::read_dir(dir).map_err(|e| SimError::io("list directory", dir, e))?;
    let mut figs = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| SimError::io("list directory", dir, e))?
            .path();
        if path.is_file() && path.extension().and_then(|x| x.to_str()) == Some("svg") {
            figs.push(path);
        }
    }
    figs.sort();
    Ok(figs)
}

fn run_one(options: &PaperOptions, exp: &Experiment) -> Result<ExperimentResult, SimError> {
    let out_dir = options.out_root.join(exp.name);
    std::fs::create_dir_all(&out_dir).map_err(|e| SimError::io("create directory", &out_dir, e))?;
    clear_stale_outputs(&out_dir)?;
    let ctx = ExperimentContext {
        name: exp.name.to_string(),
        workspace_root: options.workspace_root.clone(),
        scenario_path: options.workspace_root.join(exp.default_scenario),
        scenario_label: exp.default_scenario.to_string(),
        out_dir: out_dir.clone(),
        runs: options.runs,
        threads: options.threads,
        // `cargo xtask paper` always uses the scenario seeds.
        seed: None,
        progress: None,
    };
    run_in_context(exp, &ctx)
}

/// Run one experiment with a prepared context (its `out_dir` must exist) and write
/// `summary.json` and `report.md` into `ctx.out_dir`; what [`run_paper`] does per
/// experiment, also used by [`crate::user_run::run_scenario`] (`fathom run`).
///
/// # Errors
/// The experiment's error, a summary naming another experiment, or I/O failures.
pub fn run_in_context(
    exp: &Experiment,
    ctx: &ExperimentContext,
) -> Result<ExperimentResult, SimError> {
    let out_dir = ctx.out_dir.clone();
    let start = Instant::now();
    let output = (exp.run)(ctx)?;
    let elapsed = start.elapsed();
    let summary = output.summary;
    if summary.experiment != exp.name || summary.seed_doc != exp.seed_doc {
        return Err(SimError::invalid_argument(
            format!("summary of experiment `{}`", exp.name),
            format!(
                "names experiment `{}` / seed doc `{}`, registry says `{}` / `{}`",
                summary.experiment, summary.seed_doc, exp.name, exp.seed_doc
            ),
        ));
    }
    write_summary_json(out_dir.join("summary.json"), &summary)?;
    let figures = figures_in(&out_dir)?;
    let report = experiment_report(ctx, &summary, &output.report_section, &figures);
    write_text(out_dir.join("report.md"), &report)?;
    Ok(ExperimentResult {
        name: exp.name.to_string(),
        out_dir,
        summary,
        figures,
        elapsed,
    })
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The per-experiment `report.md`.
fn experiment_report(
    ctx: &ExperimentContext,
    s: &Summary,
    section: &str,
    figures: &[PathBuf],
) -> String {
    let mut md = format!(
        "# {}\n\nSeed paper: `{}` · Monte Carlo runs: {} · base seed: {} · scenario: `{}`\n\n",
        s.experiment, s.seed_doc, s.runs, s.base_seed, ctx.scenario_label,
    );
    md.push_str("## Paper versus reproduced\n\n");
    md.push_str(&summary_md_table(s, TABLE_DECIMALS));
    md.push_str("\n## Claims\n\n");
    if s.claims.is_empty() {
        md.push_str("(no claims evaluated)\n");
    } else {
        md.push_str(&claims_md_table(s));
    }
    if !section.trim().is_empty() {
        md.push_str("\n## Notes\n\n");
        md.push_str(section.trim());
        md.push('\n');
    }
    md.push_str("\n## Figures\n\n");
    if figures.is_empty() {
        md.push_str("(none)\n");
    }
    for f in figures {
        let n = file_name(f);
        md.push_str(&format!("- [{n}]({n})\n"));
    }
    md
}

/// Stdout section: aligned table and claims.
fn console_section(r: &ExperimentResult) -> String {
    let s = &r.summary;
    let mut t = format!(
        "{} runs, base seed {}, {:.1} s\n",
        s.runs,
        s.base_seed,
        r.elapsed.as_secs_f64()
    );
    let rows: Vec<Vec<String>> = s
        .rows
        .iter()
        .map(|row| {
            vec![
                row.method.clone(),
                row.metric.clone(),
                fmt_opt(row.paper, TABLE_DECIMALS),
                fmt_num(row.value, TABLE_DECIMALS),
                fmt_ci(row.ci95, TABLE_DECIMALS),
            ]
        })
        .collect();
    t.push_str(&text_table(
        &["method", "metric", "paper", "reproduced", "95% CI"],
        &rows,
    ));
    if !s.claims.is_empty() {
        t.push_str("claims:\n");
        for c in &s.claims {
            t.push_str(&format!(
                "  [{}] {}: {} ({})\n",
                holds_word(c.holds),
                c.id,
                c.text,
                c.detail
            ));
        }
    }
    t.push('\n');
    t
}

/// Demote Markdown headings by one level (outside code fences).
fn demote_headings(md: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        if !fenced && line.starts_with('#') {
            out.push('#');
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// Prefix relative Markdown link targets `](target)` with `prefix/`.
fn rebase_links(md: &str, prefix: &str) -> String {
    let mut out = String::with_capacity(md.len());
    let mut rest = md;
    while let Some(i) = rest.find("](") {
        out.push_str(&rest[..i + 2]);
        rest = &rest[i + 2..];
        let relative = !(rest.starts_with('/')
            || rest.starts_with('#')
            || rest.starts_with("http://")
            || rest.starts_with("https://")
            || rest.starts_with(')'));
        if relative {
            out.push_str(prefix);
            out.push('/');
        }
    }
    out.push_str(rest);
    out
}

/// `target/paper/REPORT.md`.
fn collected_report(
    options: &PaperOptions,
    registry: &[Experiment],
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
        let dir = options.out_root.join(exp.name);
        let ran = results.iter().any(|r| r.name == exp.name);
        let failed = failures.iter().find(|(n, _)| n == exp.name);
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
            format!("[{0}](#{0})", exp.name),
            format!("`{}`", exp.seed_doc),
            runs,
            claims,
            status.clone(),
        ]);
        if failed.is_some() {
            if let Some((_, e)) = failed {
                sections.push_str(&format!(
                    "## {}\n\n**Failed:** {}\n\n",
                    exp.name,
                    error_chain(e)
                ));
            }
            continue;
        }
        if let Ok(text) = std::fs::read_to_string(dir.join("report.md")) {
            if !ran {
                sections.push_str(&format!("<!-- {}: from an earlier run -->\n", exp.name));
            }
            sections.push_str(&rebase_links(&demote_headings(&text), exp.name));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{Claim, Row};
    use crate::plot::{LinePlot, Series};
    use rand::Rng;

    fn dummy(ctx: &ExperimentContext) -> Result<ExperimentOutput, SimError> {
        let runs = ctx.runs_or(10);
        let draws = ctx.monte_carlo(runs, 5, |_, rng| rng.random::<f64>());
        let mean = draws.iter().sum::<f64>() / runs as f64;
        let mut s = Summary::new("dummy", "seed.txt", runs, 5);
        s.push_row(
            Row::new("U01", "mean", mean)
                .with_paper(0.5)
                .with_ci95(mean - 0.1, mean + 0.1),
        );
        s.push_claim(Claim::new(
            "mean_near_half",
            "mean is near 0.5",
            (mean - 0.5).abs() < 0.2,
            format!("{mean:.3}"),
        ));
        LinePlot::new("Draws", "run", "value")
            .with_series(Series::new(
                "u",
                draws
                    .iter()
                    .enumerate()
                    .map(|(i, &d)| (i as f64, d))
                    .collect(),
            ))
            .write_svg(ctx.out_file("draws.svg"))?;
        Ok(ExperimentOutput {
            summary: s,
            report_section: "### Decisions\n\nNone.".into(),
        })
    }

    fn failing(ctx: &ExperimentContext) -> Result<ExperimentOutput, SimError> {
        let _: toml::Value = ctx.load_scenario()?;
        unreachable!("scenario does not exist")
    }

    fn wrong_name(_: &ExperimentContext) -> Result<ExperimentOutput, SimError> {
        Ok(ExperimentOutput {
            summary: Summary::new("other", "seed.txt", 1, 1),
            report_section: String::new(),
        })
    }

    fn reg() -> Vec<Experiment> {
        vec![
            Experiment {
                name: "dummy",
                seed_doc: "seed.txt",
                default_scenario: "scenarios/dummy.toml",
                run: dummy,
            },
            Experiment {
                name: "broken",
                seed_doc: "seed.txt",
                default_scenario: "scenarios/missing.toml",
                run: failing,
            },
            Experiment {
                name: "misnamed",
                seed_doc: "seed.txt",
                default_scenario: "x.toml",
                run: wrong_name,
            },
        ]
    }

    fn opts(tag: &str, only: Option<&str>) -> PaperOptions {
        let root = std::env::temp_dir()
            .join("fathom-sim-tests")
            .join("paper")
            .join(tag);
        let _ = std::fs::remove_dir_all(&root);
        PaperOptions {
            only: only.map(str::to_string),
            runs: Some(20),
            threads: Some(2),
            out_root: root.join("target/paper"),
            workspace_root: root,
        }
    }

    #[test]
    fn runs_dummy_and_writes_all_outputs() {
        let o = opts("ok", Some("dummy"));
        // A stale file from an earlier run is removed.
        std::fs::create_dir_all(o.out_root.join("dummy")).unwrap();
        std::fs::write(o.out_root.join("dummy/old.svg"), "<svg/>").unwrap();
        let mut buf = Vec::new();
        let res = run_paper_to(&o, &reg(), &mut buf).unwrap();
        let printed = String::from_utf8(buf).unwrap();
        assert_eq!(res.experiments.len(), 1);
        let r = &res.experiments[0];
        assert_eq!(r.summary.runs, 20);
        assert_eq!(r.figures, vec![o.out_root.join("dummy/draws.svg")]);
        assert!(printed.contains("== dummy (seed.txt) =="), "{printed}");
        assert!(
            printed.contains("method | metric | paper  | reproduced | 95% CI")
                || printed.contains("reproduced"),
            "{printed}"
        );
        assert!(printed.contains("[holds] mean_near_half"), "{printed}");
        let back = read_summary_json(o.out_root.join("dummy/summary.json")).unwrap();
        assert_eq!(back, r.summary);
        let rep = std::fs::read_to_string(o.out_root.join("dummy/report.md")).unwrap();
        assert!(
            rep.contains("| method | metric | paper | reproduced | 95% CI |"),
            "{rep}"
        );
        assert!(rep.contains("- [draws.svg](draws.svg)"), "{rep}");
        assert!(rep.contains("### Decisions"), "{rep}");
        let all = std::fs::read_to_string(&res.report_path).unwrap();
        assert!(all.contains("## dummy"), "{all}");
        assert!(all.contains("#### Decisions"), "{all}");
        assert!(all.contains("- [draws.svg](dummy/draws.svg)"), "{all}");
        assert!(all.contains("| not run |"), "{all}");
        assert!(!o.out_root.join("dummy/old.svg").exists());
    }

    #[test]
    fn same_numbers_for_one_and_two_threads() {
        let mut a = opts("threads1", Some("dummy"));
        a.threads = Some(1);
        let mut b = opts("threads2", Some("dummy"));
        b.threads = Some(2);
        let ra = run_paper_to(&a, &reg(), &mut Vec::new()).unwrap();
        let rb = run_paper_to(&b, &reg(), &mut Vec::new()).unwrap();
        assert_eq!(ra.experiments[0].summary, rb.experiments[0].summary);
    }

    #[test]
    fn unknown_only_lists_known_names() {
        let e =
            run_paper_to(&opts("unknown", Some("fusion")), &reg(), &mut Vec::new()).unwrap_err();
        let s = e.to_string();
        assert!(s.contains("unknown experiment `fusion`"), "{s}");
        assert!(s.contains("dummy, broken, misnamed"), "{s}");
    }

    #[test]
    fn failures_are_reported_and_others_still_run() {
        let o = opts("fail", None);
        let mut buf = Vec::new();
        let e = run_paper_to(&o, &reg(), &mut buf).unwrap_err();
        let chain = error_chain(&e);
        assert!(
            chain.starts_with("experiment `broken` failed: cannot read"),
            "{chain}"
        );
        assert!(chain.contains("missing.toml"), "{chain}");
        let printed = String::from_utf8(buf).unwrap();
        assert!(
            printed.contains("FAILED: experiment `misnamed` failed"),
            "{printed}"
        );
        assert!(o.out_root.join("dummy/summary.json").exists());
        let all = std::fs::read_to_string(o.out_root.join("REPORT.md")).unwrap();
        assert!(
            all.contains("**Failed:** experiment `broken` failed"),
            "{all}"
        );
        assert!(all.contains("| failed |"), "{all}");
    }

    #[test]
    fn earlier_results_stay_in_collected_report() {
        let mut o = opts("earlier", Some("dummy"));
        run_paper_to(&o, &reg(), &mut Vec::new()).unwrap();
        // A second, different selection keeps dummy's section from disk.
        let reg2 = vec![
            reg()[0],
            Experiment {
                name: "second",
                ..reg()[0]
            },
        ];
        o.only = None;
        let _ = std::fs::remove_dir_all(o.out_root.join("second"));
        let e = run_paper_to(
            &PaperOptions {
                only: Some("second".into()),
                ..o.clone()
            },
            &reg2,
            &mut Vec::new(),
        );
        assert!(e.is_err(), "summary names `dummy`, registry says `second`");
        let all = std::fs::read_to_string(o.out_root.join("REPORT.md")).unwrap();
        assert!(all.contains("results from an earlier run"), "{all}");
        assert!(all.contains("| earlier run |"), "{all}");
    }

    #[test]
    fn bad_options_and_registry_are_rejected() {
        let mut o = opts("badopts", None);
        o.runs = Some(0);
        assert!(run_paper_to(&o, &reg(), &mut Vec::new()).is_err());
        let mut o = opts("badopts2", None);
        o.threads = Some(0);
        assert!(run_paper_to(&o, &reg(), &mut Vec::new()).is_err());
        let dup = vec![reg()[0], reg()[0]];
        assert!(run_paper_to(&opts("dup", None), &dup, &mut Vec::new()).is_err());
        let bad = vec![Experiment {
            name: "Bad/Name",
            ..reg()[0]
        }];
        assert!(run_paper_to(&opts("badname", None), &bad, &mut Vec::new()).is_err());
    }

    #[test]
    fn empty_registry_writes_report() {
        let o = opts("empty", None);
        let r = run_paper_to(&o, &[], &mut Vec::new()).unwrap();
        assert!(r.experiments.is_empty());
        let all = std::fs::read_to_string(&r.report_path).unwrap();
        assert!(all.contains("No experiments are registered."));
    }

    #[test]
    fn markdown_rewriting() {
        assert_eq!(
            demote_headings("# a\n```\n# b\n```\n"),
            "## a\n```\n# b\n```\n"
        );
        assert_eq!(
            rebase_links("[f](f.svg) [w](https://x) [h](#x)", "e"),
            "[f](e/f.svg) [w](https://x) [h](#x)"
        );
    }
}
