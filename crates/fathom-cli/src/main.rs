//! `fathom`: the command-line tool.
//!
//! ```text
//! fathom run <scenario.toml> [--runs N] [--seed S] [--threads T] [--out DIR] [--force]
//!            [--max-memory-gb G] [--max-hours H]
//! fathom check <scenario.toml> [--max-memory-gb G] [--max-hours H]
//! fathom list
//! fathom replay plaza [DIR] [--config FILE] [--out DIR] [--force]
//! fathom replay range-beacon|ins-dvl [DIR] [--config FILE] [--out DIR] [--force]
//! fathom log example range-beacon|ins-dvl [--out DIR] [--duration S] [--seed S] [--no-truth]
//! fathom log from-plaza [PLAZA_DIR] [--out DIR]
//! fathom log check <DIR>
//! fathom merge <SHARD DIRS...> [--out DIR] [--force]
//! fathom pils FILE | pils sim|nav|offline|compare FILE [--out DIR]
//! fathom view DIR [--no-open]
//! ```
//!
//! **Where outputs go**, for every command: `fathom-out/<name>/` in the current
//! directory unless `--out DIR` ([`OUT_ROOT`]): `run` -> `fathom-out/<experiment>`
//! (`--shard K/M`: `<experiment>-shard-K-of-M`), `merge` -> `fathom-out/<experiment>`,
//! `replay <kind>` -> `fathom-out/<kind>-replay`, `log example <kind>` ->
//! `fathom-out/<kind>-log`, `log from-plaza` -> `fathom-out/plaza-log`, `pils` ->
//! `fathom-out/pils`, `pils sim|nav|offline|compare` -> `fathom-out/pils-<side>`.
//! A replay without `DIR` reads its settings' `[data] dir` (found in the current
//! directory or beside one of its ancestors): `data/plaza1` for `plaza`, the
//! repository's example logs `data/logs/<kind>-example` for the own-log kinds.
//!
//! `run` runs any scenario file of a registered experiment (the file's top-level
//! `experiment` key names it) and writes the experiment's outputs plus the scenario,
//! its resolved form and `run_info.json` into `--out` (default
//! `fathom-out/<experiment>`). `--runs` overrides the scenario's Monte Carlo count,
//! `--seed` its `base_seed` (the seed actually used is recorded in
//! `scenario.resolved.toml`, `run_info.json` and `summary.json`, so the resolved file
//! reproduces the run with the same `--runs`; a deterministic experiment such as
//! `plaza` has no seed and refuses `--seed` with exit code 2). The same scenario and seed give a byte-identical
//! `summary.json` for any `--threads`. `run` first prints the run's estimated cost,
//! then one line per finished Monte Carlo batch (also in a pipe), then every result
//! row with its unit and 95 % interval and the claims. On a terminal a progress bar on
//! standard error shows the current batch, runs done, rate and ETA; it is not drawn
//! when standard error is not a terminal (pipes, CI logs).
//!
//! Output folders never lose work: the outputs are written into a temporary folder
//! beside `--out` and moved into place once complete, so an interrupted or failed run
//! leaves the previous results as they were. A folder holding files fathom did not
//! write, or one another fathom process is writing, is refused (exit 2) before
//! anything is computed; `--force` writes anyway, keeping the user's files and
//! replacing only fathom's own. Where `--out` cannot be written is found before
//! computing too.
//!
//! `check` parses and validates any settings file fathom reads (a scenario of an
//! experiment, the settings of a replay, PILS settings: the kind comes from the
//! `experiment` key) without running it, loads what a run would load (the world and
//! its waypoints, a data folder, the PILS flight), so that a file `check` accepts is
//! one `run` starts, and estimates its cost (samples, memory, run time); `check` and `run` refuse a scenario beyond the
//! limits (`--max-memory-gb`, default 4; `--max-hours`, default 24) naming the key
//! that drives the cost. `list` shows the experiments and replays with the names their
//! files accept, then the estimators, update schemes and sensor models.
//!
//! `run` and `check` also take the settings file of a replay of one's own log
//! (`experiment = "range-beacon"` or `"ins-dvl"`, its `[data] dir` naming the log).
//!
//! `replay plaza|range-beacon|ins-dvl [DIR]` replays estimators on recorded data, a
//! job of the same driver as `run` (`run_info.json` says `command: "replay"`), with the
//! settings of `--config` or, by default, the built-in `scenarios/plaza.toml`,
//! `scenarios/range-beacon.toml` or `scenarios/ins-dvl.toml`, whose `[data] dir` is
//! replaced by `DIR` when given. `DIR` holds one CMU Plaza data set in its native files
//! (`*_DR.txt`, `*_TD.txt`, `*_.mat`: dead reckoning and the EKF under AS, SC and SI
//! plus ablations) or one's own log in fathom's CSV layout (`docs/own-data.md`, the
//! methods of the settings' `[[methods]]` list). Every replay writes, into `--out`
//! (default `fathom-out/<kind>-replay`), what `run` writes: `summary.json`
//! (rows `method, metric, value` of the shared format), `report.md` (every row with
//! its unit, the claims or checks, notes, links to the figures), the settings as
//! given and resolved (`scenario.toml`, `scenario.resolved.toml`: `fathom run
//! scenario.toml` replays again), `run_info.json`, CSV series (`estimates.csv`;
//! `ranges.csv` or `innovations.csv`) and the figures of every replay: the paths
//! against the truth (`estimate_vs_truth.svg`), the error with the filter's 3σ
//! (`error_3sigma.svg`), the innovations with ±3√S (`innovations*.svg`) and the NIS
//! against a consistent filter's interval (`nis*.svg`). It prints the rows with their
//! units and the claims or checks, as `run` does. `log example` writes a simulated
//! log of either kind, `log from-plaza` converts a CMU Plaza data set into the layout,
//! `log check` reads every file of a log and reports the first error (file, line,
//! column).
//!
//! Exit codes: 0 success; 2 for anything the user wrote (flags, the scenario or
//! settings file, a data folder or data file, the output folder); 1 for a failure of
//! fathom itself while running (an estimator failing on a checked scenario, an output
//! that cannot be written after the run). Errors are printed on one line with their
//! whole cause chain, naming the key or the option.

mod campaign;
mod list;
mod own_logs;
mod pils;
mod pils_compare;
mod pils_session;
mod replay;
mod view;

use std::io::{IsTerminal, Write as _};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::Instant;

use campaign::{CampaignKind, MergeArgs, campaign_cmd, merge_cmd, run_shard_cmd};
use own_logs::{LogCmd, log_cmd};
use replay::{ReplayData, replay_cmd};

use anyhow::{Context, anyhow};
use clap::{Args, Parser, Subcommand};
use fathom_experiments::jobs;
use fathom_sim::cost::Limits;
use fathom_sim::driver::{console_claims, console_main_rows, console_setup};
use fathom_sim::echo::{echo_lines, echo_path};
use fathom_sim::experiment::{Extras, Shard};
use fathom_sim::progress::{Progress, ProgressEvent};
use fathom_sim::user_run::{
    RunOptions, assess_scenario, check_line, check_scenario_with, job_of, one_line, run_assessed,
};
use fathom_sim::{SimError, error_chain};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

#[derive(Debug, Parser)]
#[command(
    name = "fathom",
    version,
    about = "Run, compare and evaluate navigation estimators on recorded data.",
    after_help = "Outputs: every command writes into fathom-out/<name>/ of the current \
                  directory unless --out DIR (run: fathom-out/<experiment>, merge: \
                  fathom-out/<experiment>, replay: fathom-out/<kind>-replay, log: \
                  fathom-out/<kind>-log, pils: fathom-out/pils[-<side>])."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Replay estimators on a recorded data set (CMU Plaza, or your own log) and score
    /// them against ground truth or their innovations.
    #[command(subcommand)]
    Replay(ReplayData),
    /// Run a scenario file (copy one from `scenarios/`, change numbers, run it).
    Run(RunArgs),
    /// Validate any settings file fathom reads (a scenario, replay settings, PILS
    /// settings) and load what a run would load, without running; print it resolved.
    Check(CheckArgs),
    /// List the experiments and replays with the names their files accept, the
    /// estimators, update schemes and sensor models.
    List,
    /// Logs in fathom's CSV layout (docs/own-data.md): examples, conversion, checks.
    #[command(subcommand)]
    Log(LogCmd),
    /// Merge the shard folders of a campaign (`fathom run --shard K/M`) into the
    /// outputs of one run.
    Merge(MergeArgs),
    /// Write the launcher of a sharded campaign.
    #[command(subcommand)]
    Campaign(CampaignKind),
    /// Processor-in-the-loop: the simulator and the navigation as two processes over
    /// UDP with MAVLink 2 (`fathom pils FILE`, or `fathom pils sim|nav|offline`).
    Pils(pils::PilsArgs),
    /// Print the path of an output folder's 3D scene page (`scene.html`, written by
    /// every run with a world) and open it in a browser where one is available.
    View(view::ViewArgs),
}

/// The limits a scenario's estimated cost must fit.
#[derive(Debug, Args)]
struct LimitArgs {
    /// Refuse a scenario estimated to need more memory than this, in GiB (default 4).
    #[arg(long, value_name = "G")]
    max_memory_gb: Option<f64>,
    /// Refuse a scenario estimated to run longer than this, in hours (default 24).
    #[arg(long, value_name = "H")]
    max_hours: Option<f64>,
}

impl LimitArgs {
    fn limits(&self) -> Result<Limits, Failure> {
        Limits::from_options(self.max_memory_gb, self.max_hours).map_err(failure)
    }
}

#[derive(Debug, Args)]
struct RunArgs {
    /// Scenario file (TOML with a top-level `experiment = "<name>"`).
    scenario: PathBuf,
    /// Override the scenario's Monte Carlo run count.
    #[arg(long, value_name = "N")]
    runs: Option<usize>,
    /// Override the scenario's base seed, 0 to 2^63 - 1 (run i uses ChaCha stream i
    /// of it).
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// Output folder (default `fathom-out/<experiment>`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Write into a folder holding files fathom did not write (they are kept; only
    /// fathom's own files are replaced).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    limits: LimitArgs,
    /// Also on a scenario that differs from the paper's setup: run the paper's
    /// sensitivity batches (its beacon layouts, the literal-bias reading) and judge
    /// its claims (by default only the paper's setup gets them).
    #[arg(long, conflicts_with = "shard")]
    paper_extras: bool,
    /// Do not write the 3D scene page `scene.html` (runs with a world write it).
    #[arg(long)]
    no_scene: bool,
    /// Run only shard K of M of every batch and write its records and manifest into
    /// `--out` (no analysis; `fathom merge` combines the shards).
    #[arg(long, value_name = "K/M", value_parser = parse_shard)]
    shard: Option<Shard>,
}

/// `K/M` with `0 <= K < M`.
fn parse_shard(text: &str) -> Result<Shard, String> {
    let (k, m) = text
        .split_once('/')
        .ok_or_else(|| format!("expected K/M (e.g. 0/4), got `{text}`"))?;
    let index: usize = k
        .trim()
        .parse()
        .map_err(|_| format!("shard index `{k}` is not a number"))?;
    let count: usize = m
        .trim()
        .parse()
        .map_err(|_| format!("shard count `{m}` is not a number"))?;
    if count == 0 || index >= count {
        return Err(format!("needs 0 <= K < M, got {index}/{count}"));
    }
    Ok(Shard { index, count })
}

#[derive(Debug, Args)]
struct CheckArgs {
    /// Settings file: a scenario, replay settings or PILS settings (the kind is read
    /// from its `experiment` key).
    scenario: PathBuf,
    /// Print only the OK line, not the resolved scenario.
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    limits: LimitArgs,
}

/// A failure and its exit code.
#[derive(Debug)]
enum Failure {
    /// Anything the user wrote (flags, scenario, data, output folder): exit code 2.
    Usage(anyhow::Error),
    /// A failure of fathom itself: exit code 1.
    Run(anyhow::Error),
}

/// The one exit-code rule: [`SimError::is_user_error`] decides; the message is the
/// whole cause chain on one line.
pub(crate) fn failure(e: impl Into<SimError>) -> Failure {
    let e: SimError = e.into();
    let line = anyhow!(one_line(&error_chain(&e)));
    if e.is_user_error() {
        Failure::Usage(line)
    } else {
        Failure::Run(line)
    }
}

fn run_scenario_cmd(args: &RunArgs) -> Result<String, Failure> {
    if let Some(shard) = args.shard {
        return run_shard_cmd(args, shard);
    }
    let registry = jobs();
    let limits = args.limits.limits()?;
    let label = args.scenario.display().to_string();
    let text = std::fs::read_to_string(&args.scenario)
        .map_err(|e| failure(SimError::io("read", &args.scenario, e)))?;
    let options = RunOptions {
        scenario: args.scenario.clone(),
        out_dir: args.out.clone(),
        runs: args.runs,
        threads: args.threads,
        seed: args.seed,
        base_dir: crate::current_dir()?,
        force: args.force,
        limits,
        extras: if args.paper_extras {
            Extras::Always
        } else {
            Extras::WhenPaper
        },
        scene_page: !args.no_scene,
    };
    // Assessed once (scenario, overrides, cost against the limits) before anything
    // runs; the estimate is printed first. The bar stays hidden until a batch starts.
    let bar = progress_bar();
    let job = job_of(&text, &label, &options, Some(run_hook(bar.clone(), false)));
    let (exp, assessed) = assess_scenario(&job, &registry).map_err(failure)?;
    let what = match (assessed.resolved.runs, assessed.resolved.base_seed) {
        (Some(n), Some(seed)) => format!("{n} runs, base seed {seed}"),
        _ => "one deterministic replay".to_string(),
    };
    // The seed paper is named for its own setup; a variant is the user's scenario.
    let source = if assessed.resolved.setup.is_paper() {
        exp.seed_doc().to_string()
    } else {
        format!("your scenario {}", echo_path(&args.scenario))
    };
    say(&format!(
        "{} ({source}): {what}; estimate: {}\n",
        exp.name(),
        assessed.cost.summary()
    ));
    let outcome = run_assessed(exp, assessed, &job, &options);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (result, info) = outcome.map_err(failure)?;
    let mut text = format!(
        "done in {:.1} s (fathom {})\n",
        result.elapsed.as_secs_f64(),
        info.fathom_version
    );
    text.push_str(&console_setup(&result));
    text.push_str(&console_main_rows(&result, exp.console_metrics()));
    text.push_str(&console_claims(&result));
    text.push_str(&format!(
        "outputs: {} ({} figures, report.md, summary.json)\n",
        result.out_dir.display(),
        result.figures.len()
    ));
    Ok(text)
}

/// Where every command writes by default: `fathom-out/<name>` in the current directory.
pub(crate) const OUT_ROOT: &str = "fathom-out";

/// The current directory (relative settings paths and data folders are found from
/// it).
pub(crate) fn current_dir() -> Result<PathBuf, Failure> {
    std::env::current_dir()
        .context("cannot read the current directory")
        .map_err(Failure::Run)
}

/// The default output folder `fathom-out/<name>` of a command.
pub(crate) fn default_out(name: &str) -> PathBuf {
    PathBuf::from(OUT_ROOT).join(name)
}

/// Prints `text` on standard output at once (also into a pipe).
pub(crate) fn say(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes());
    let _ = out.flush();
}

/// Progress lines per batch when no bar is drawn (a Slurm log, a pipe): one line per
/// this fraction of the batch's runs.
const LINES_PER_BATCH: usize = 10;

/// What the hook of `fathom run` tracks across events.
struct HookState {
    batches_done: usize,
    batch_start: Instant,
    batch_runs: usize,
    runs_done: usize,
}

/// The hook of `fathom run`: one line per finished Monte Carlo batch on standard
/// output (printed above the progress bar, if one is drawn), and the bar. With
/// `lines` and no bar, also a line every tenth of a batch's runs (a shard of 25,000
/// runs in a Slurm log shows it is alive).
fn run_hook(bar: Option<ProgressBar>, lines: bool) -> Progress {
    let bar_hook = bar.as_ref().map(|b| progress_hook(b, true));
    let run_lines = lines && bar.is_none();
    let state = Mutex::new(HookState {
        batches_done: 0,
        batch_start: Instant::now(),
        batch_runs: 0,
        runs_done: 0,
    });
    Progress::new(move |event| {
        let line = match &event {
            ProgressEvent::BatchStarted { total, .. } => {
                if let Ok(mut s) = state.lock() {
                    s.batch_start = Instant::now();
                    s.batch_runs = *total;
                    s.runs_done = 0;
                }
                None
            }
            ProgressEvent::BatchFinished { label } => state.lock().ok().map(|mut s| {
                s.batches_done += 1;
                batch_line(
                    s.batches_done,
                    label,
                    s.batch_runs,
                    s.batch_start.elapsed().as_secs_f64(),
                )
            }),
            ProgressEvent::RunFinished { .. } if run_lines => {
                state.lock().ok().and_then(|mut s| {
                    s.runs_done += 1;
                    let step = s.batch_runs.div_ceil(LINES_PER_BATCH).max(1);
                    (s.runs_done % step == 0 && s.runs_done < s.batch_runs).then(|| {
                        let secs = s.batch_start.elapsed().as_secs_f64();
                        let left = secs / s.runs_done as f64 * (s.batch_runs - s.runs_done) as f64;
                        format!(
                            "    {}/{} runs of batch {}, {secs:.1} s, about {} left\n",
                            s.runs_done,
                            s.batch_runs,
                            s.batches_done + 1,
                            fathom_sim::cost::duration(left)
                        )
                    })
                })
            }
            ProgressEvent::RunFinished { .. } => None,
        };
        if let Some(h) = &bar_hook {
            h.report(event);
        }
        if let Some(line) = line {
            match &bar {
                Some(b) => b.suspend(|| say(&line)),
                None => say(&line),
            }
        }
    })
}

/// `  batch 2 (beacons: layout far): 100 runs in 3.1 s`
fn batch_line(n: usize, label: &str, runs: usize, seconds: f64) -> String {
    format!(
        "  batch {n} ({label}): {runs} run{} in {seconds:.1} s\n",
        if runs == 1 { "" } else { "s" }
    )
}

/// The progress bar of `fathom run` on standard error; `None` (nothing drawn) when
/// standard error is not a terminal. It stays hidden until the first batch starts.
fn progress_bar() -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::hidden();
    let style = ProgressStyle::with_template(
        "{msg:.bold} [{bar:30}] {pos}/{len} runs, {per_sec}, elapsed {elapsed}, ETA {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar())
    .progress_chars("=> ");
    bar.set_style(style);
    Some(bar)
}

/// The library's progress hook drawing on `bar`: one bar per Monte Carlo batch. With
/// `draw`, the first batch attaches the bar to standard error.
fn progress_hook(bar: &ProgressBar, draw: bool) -> Progress {
    let bar = bar.clone();
    Progress::new(move |event| match event {
        ProgressEvent::BatchStarted { label, total } => {
            bar.reset();
            bar.set_length(total as u64);
            bar.set_message(label);
            if draw && bar.is_hidden() {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        }
        ProgressEvent::RunFinished { .. } => bar.inc(1),
        ProgressEvent::BatchFinished { .. } => {}
    })
}

/// The top-level `experiment` key of a settings file, if it is readable TOML with one.
fn experiment_key(path: &std::path::Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    let table: toml::Table = toml::from_str(&text).ok()?;
    Some(table.get("experiment")?.as_str()?.to_string())
}

/// `fathom check FILE`: the kind of file from its `experiment` key: PILS settings
/// (`"pils"`) are checked and flown as `fathom pils` does before any socket; every
/// other file is a scenario or replay settings file of [`jobs`], checked and prepared
/// as `fathom run` does.
fn check_cmd(args: &CheckArgs) -> Result<String, Failure> {
    if experiment_key(&args.scenario).as_deref() == Some(pils::EXPERIMENT) {
        return pils::check(&args.scenario, args.quiet);
    }
    let registry = jobs();
    let limits = args.limits.limits()?;
    let resolved = check_scenario_with(&args.scenario, &registry, &limits)
        .map_err(|e| Failure::Usage(anyhow!(one_line(&error_chain(&e)))))?;
    let line = check_line(&args.scenario, &resolved);
    if args.quiet {
        return Ok(format!("{line}\n"));
    }
    Ok(format!(
        "# {line}\n# resolved scenario (defaults filled in):\n{}",
        resolved.resolved_toml
    ))
}

fn run(cli: &Cli) -> Result<String, Failure> {
    match &cli.command {
        Command::Replay(cmd) => replay_cmd(cmd),
        Command::Log(cmd) => log_cmd(cmd),
        Command::Run(args) => run_scenario_cmd(args),
        Command::Check(args) => check_cmd(args),
        Command::List => Ok(list::list_cmd()),
        Command::Merge(args) => merge_cmd(args),
        Command::Campaign(kind) => campaign_cmd(kind),
        Command::Pils(args) => pils::pils_cmd(args),
        Command::View(args) => view::view_cmd(args),
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with success; usage errors exit with 2.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(&cli) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        // Every line bounded, whichever crate's message it carries (issue #38).
        Err(Failure::Usage(e)) => {
            eprintln!("error: {}", echo_lines(&format!("{e:#}")));
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {}", echo_lines(&format!("{e:#}")));
            ExitCode::from(1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_valid() {
        Cli::command().debug_assert();
    }

    #[test]
    fn progress_hook_counts_runs_per_batch() {
        let bar = ProgressBar::hidden();
        let hook = progress_hook(&bar, false);
        hook.report(ProgressEvent::BatchStarted {
            label: "a".into(),
            total: 3,
        });
        for index in 0..3 {
            hook.report(ProgressEvent::RunFinished { index });
        }
        assert_eq!((bar.position(), bar.length()), (3, Some(3)));
        hook.report(ProgressEvent::BatchStarted {
            label: "b".into(),
            total: 5,
        });
        hook.report(ProgressEvent::RunFinished { index: 0 });
        assert_eq!((bar.position(), bar.length()), (1, Some(5)));
        assert_eq!(bar.message(), "b");
    }

    #[test]
    fn parses_replay_plaza() {
        let cli = Cli::try_parse_from([
            "fathom", "replay", "plaza", "data/p1", "--config", "c.toml", "--out", "o",
        ])
        .unwrap();
        let Command::Replay(ReplayData::Plaza(a)) = cli.command else {
            panic!("not replay")
        };
        assert_eq!(a.dir, Some(PathBuf::from("data/p1")));
        assert_eq!(a.config, Some(PathBuf::from("c.toml")));
        assert_eq!(a.out, Some(PathBuf::from("o")));
        // Without a folder: the settings' `[data] dir` (data/plaza1), default output.
        let cli = Cli::try_parse_from(["fathom", "replay", "plaza"]).unwrap();
        let Command::Replay(ReplayData::Plaza(a)) = cli.command else {
            panic!("not replay")
        };
        assert_eq!((a.dir, a.out), (None, None));
        assert!(a.config.is_none());
    }

    #[test]
    fn parses_run_check_list() {
        let cli = Cli::try_parse_from([
            "fathom",
            "run",
            "s.toml",
            "--runs",
            "5",
            "--threads",
            "2",
            "--out",
            "o",
            "--seed",
            "11",
        ])
        .unwrap();
        let Command::Run(a) = cli.command else {
            panic!("not run")
        };
        assert_eq!(
            (a.scenario, a.runs, a.threads, a.out, a.seed),
            (
                PathBuf::from("s.toml"),
                Some(5),
                Some(2),
                Some(PathBuf::from("o")),
                Some(11)
            )
        );
        for bad in ["-1", "x", "1.5"] {
            assert!(Cli::try_parse_from(["fathom", "run", "s.toml", "--seed", bad]).is_err());
        }
        assert!(matches!(
            Cli::try_parse_from(["fathom", "check", "s.toml"])
                .unwrap()
                .command,
            Command::Check(_)
        ));
        assert!(matches!(
            Cli::try_parse_from(["fathom", "list"]).unwrap().command,
            Command::List
        ));
        let l = list::list_cmd();
        for name in [
            "fusion",
            "noise",
            "beacons",
            "vkf",
            "plaza",
            "SC",
            "dvl",
            "range-beacon",
            "eskf",
        ] {
            assert!(l.contains(name), "{l}");
        }
    }

    #[test]
    fn usage_errors_are_reported() {
        for args in [
            vec!["fathom"],
            vec!["fathom", "replay"],
            vec!["fathom", "replay", "other", "d"],
            vec!["fathom", "replay", "plaza", "d", "--fast"],
        ] {
            let e = Cli::try_parse_from(&args).unwrap_err();
            assert!(e.use_stderr(), "{args:?}");
        }
    }
}
