//! [`DynExperiment`]: the object-safe face of every [`Experiment`], and the pipeline
//! the driver runs through it (parse, override, check, prepare, Monte Carlo, analyse).

use rand_chacha::ChaCha8Rng;

use super::{Analysis, Batch, Environment, Experiment, Extras, ScenarioFile, Setup};
use crate::SimError;
use crate::cost::Cost;
use crate::montecarlo::try_run_indices;
use crate::progress::{Progress, ProgressEvent};
use crate::scenario::{ScenarioDoc, check_magnitudes, require_experiment, to_toml};
use fathom_report::output::Summary;

/// What the driver asks of one execution of an experiment.
#[derive(Debug, Clone)]
pub struct Job<'a> {
    /// The scenario text as the user wrote it.
    pub text: &'a str,
    /// Labels the scenario in error messages (the path as given).
    pub file: &'a str,
    /// `--runs`: replaces the scenario's `runs`.
    pub runs: Option<usize>,
    /// `--seed`: replaces the scenario's `base_seed` (an error for a deterministic
    /// experiment).
    pub seed: Option<u64>,
    /// Worker threads (`None` = all cores).
    pub threads: Option<usize>,
    /// Progress hook of the Monte Carlo batches.
    pub progress: Option<Progress>,
    /// Where data folders are looked up.
    pub env: Environment,
}

/// A checked scenario with the overrides applied.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// The scenario as TOML with every default filled in and the overrides applied:
    /// running it reproduces the run.
    pub toml: String,
    /// Monte Carlo runs of the main batch (`None`: deterministic).
    pub runs: Option<usize>,
    /// The base seed used (`None`: deterministic).
    pub base_seed: Option<u64>,
    /// How the rows summarize the runs (checked `[statistics]`, seeded from the base
    /// seed; the defaults for a deterministic job).
    pub statistics: fathom_stats::SummarySettings,
    /// How the scenario relates to the paper's setup (compared before
    /// [`Experiment::main_only`]).
    pub setup: Setup,
    /// Whether the paper's extras run ([`Extras`]): its sensitivity batches and claims.
    pub paper_extras: bool,
}

/// The outcome of [`DynExperiment::execute`].
#[derive(Debug, Clone, PartialEq)]
pub struct Executed {
    /// The resolved scenario.
    pub resolved: Resolved,
    /// The checked `summary.json` content.
    pub summary: Summary,
    /// Report text, figures, CSV files (rows, claims and extra keys are in `summary`).
    pub analysis: Analysis,
}

/// The resolved scenario and the batches of a prepared experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The resolved scenario.
    pub resolved: Resolved,
    /// The Monte Carlo batches, the main one first.
    pub batches: Vec<Batch>,
}

/// Shard `index` of `count` of a campaign: the run indices of a batch it executes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// This shard, `0 <= index < count`.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Run indices of a batch of `runs` runs: a contiguous block, the blocks of the
    /// shards covering `0..runs` once (uneven when `count` does not divide `runs`).
    pub fn range(&self, runs: usize) -> std::ops::Range<usize> {
        let at = |k: usize| (runs as u128 * k as u128 / self.count.max(1) as u128) as usize;
        at(self.index)..at(self.index + 1)
    }
}

/// Where a shard writes its records.
pub trait RecordSink {
    /// Batch `batch` starts; the shard runs its indices `range`.
    ///
    /// # Errors
    /// I/O errors.
    fn begin_batch(
        &mut self,
        batch: usize,
        info: &Batch,
        range: std::ops::Range<usize>,
    ) -> Result<(), SimError>;
    /// The record of run `index` of batch `batch`, as JSON.
    ///
    /// # Errors
    /// I/O errors.
    fn record(&mut self, batch: usize, index: usize, json: &str) -> Result<(), SimError>;
}

/// One record read back: its run index, its JSON and where it came from (for errors).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FoundRecord {
    /// Run index.
    pub index: usize,
    /// The record as JSON.
    pub json: String,
    /// File and line, for error messages.
    pub origin: String,
}

/// Where merged records come from: per batch, in run-index order.
pub trait RecordSource {
    /// The next record of batch `batch`, or `None` when the batch has no more.
    ///
    /// # Errors
    /// I/O or format errors naming the file and line.
    fn next(&mut self, batch: usize) -> Result<Option<FoundRecord>, SimError>;
}

/// One prepared Monte Carlo run of an experiment's main batch (the benchmarks' unit).
pub type SingleRunFn = Box<dyn Fn(usize, &mut ChaCha8Rng) -> Result<(), SimError> + Send + Sync>;

/// The object-safe face of an [`Experiment`]; implemented for every experiment.
pub trait DynExperiment: Send + Sync {
    /// [`Experiment::NAME`].
    fn name(&self) -> &'static str;
    /// [`Experiment::SEED_DOC`].
    fn seed_doc(&self) -> &'static str;
    /// [`Experiment::DEFAULT_SCENARIO`].
    fn default_scenario(&self) -> &'static str;
    /// [`Experiment::ABOUT`].
    fn about(&self) -> &'static str;
    /// [`Experiment::METHODS`].
    fn methods(&self) -> &'static [&'static str];
    /// [`Experiment::CONSOLE_METRICS`].
    fn console_metrics(&self) -> &'static [&'static str];
    /// [`Experiment::PRESET`].
    fn preset(&self) -> &'static str;
    /// [`Experiment::PAPER`].
    fn paper(&self) -> bool;
    /// [`Experiment::CHECK_PREPARES`].
    fn check_prepares(&self) -> bool;
    /// The JSON schema of the scenario file (field docs as descriptions), from which
    /// `docs/scenarios.md` is generated.
    fn schema(&self) -> schemars::Schema;

    /// Assesses `job` once: parses its text ([`ScenarioDoc::parse`]), applies the
    /// overrides, checks the scenario and estimates its cost, checked against
    /// `job.env.limits`. Everything that runs is executed from the [`Assessed`] value, so
    /// the text is never parsed again; `fathom run` calls it before it claims the output
    /// folder.
    ///
    /// # Errors
    /// TOML and check errors naming `file` and the key; bad `--threads` / `--runs` /
    /// `--seed`; a cost beyond the limits ([`SimError::Invalid`] naming the key).
    fn assess<'j>(&self, job: &'j Job<'j>) -> Result<Assessed<'j>, SimError> {
        self.assess_doc(ScenarioDoc::parse(job.text, job.file)?, job)
    }

    /// [`DynExperiment::assess`] of a text already parsed into `doc` (the front end
    /// parsed it to pick the experiment).
    ///
    /// # Errors
    /// As [`DynExperiment::assess`].
    fn assess_doc<'j>(
        &self,
        doc: ScenarioDoc<'j>,
        job: &'j Job<'j>,
    ) -> Result<Assessed<'j>, SimError>;

    /// The resolved scenario of `text` with the overrides, without the cost limits
    /// (`fathom check` of a preset, the setup comparison, tests).
    ///
    /// # Errors
    /// As [`DynExperiment::assess`] but for the limits.
    fn resolve(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
    ) -> Result<Resolved, SimError>;

    /// The resolved preset as a TOML table (`None` when the preset does not check), the
    /// reference of [`crate::driver::Setup`].
    fn preset_table(&self) -> Option<toml::Table>;

    /// The cost of `text` on `threads` worker threads (`None`: all cores), not checked
    /// against any limit (the fuzz targets, the cost tests).
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`].
    fn cost(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
        threads: Option<usize>,
    ) -> Result<Cost, SimError>;

    /// Assesses `job` and runs the whole pipeline ([`Assessed::execute`]).
    ///
    /// # Errors
    /// As [`DynExperiment::assess`], then preparation, run and analysis errors.
    fn execute(&self, job: &Job<'_>) -> Result<Executed, SimError> {
        self.assess(job)?.execute()
    }

    /// Assesses `job` and prepares it ([`Assessed::plan`]).
    ///
    /// # Errors
    /// As [`DynExperiment::assess`], then preparation errors.
    fn plan(&self, job: &Job<'_>) -> Result<Plan, SimError> {
        self.assess(job)?.plan()
    }

    /// Prepares the scenario `text` and returns its main batch's run function (for
    /// the benchmarks: the run index and the RNG in, the record dropped); no cost
    /// limit applies.
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`], then preparation errors.
    fn single_run(
        &self,
        text: &str,
        file: &str,
        env: &Environment,
    ) -> Result<SingleRunFn, SimError>;
}

/// A job assessed once ([`DynExperiment::assess`]): the scenario parsed, the overrides
/// applied, checked and costed. It runs in one of four ways, each consuming it.
pub struct Assessed<'j> {
    /// The resolved scenario.
    pub resolved: Resolved,
    /// The estimated cost on the job's threads.
    pub cost: Cost,
    /// The resolved scenario as a TOML table (the setup against the preset, the key
    /// counts of `fathom check`).
    pub table: toml::Table,
    run: Box<dyn Runnable + 'j>,
}

impl std::fmt::Debug for Assessed<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Assessed")
            .field("resolved", &self.resolved)
            .field("cost", &self.cost)
            .finish_non_exhaustive()
    }
}

impl Assessed<'_> {
    /// Prepares, runs every batch and analyses: the summary and the analysis.
    ///
    /// # Errors
    /// Preparation, run and analysis errors.
    pub fn execute(self) -> Result<Executed, SimError> {
        self.run.execute()
    }

    /// Prepares: the resolved scenario and the batches.
    ///
    /// # Errors
    /// Preparation errors.
    pub fn plan(self) -> Result<Plan, SimError> {
        self.run.plan()
    }

    /// Runs the run indices of `shard` in every batch and hands each run's record,
    /// serialized as JSON, to `sink` (a shard of a campaign: no analysis).
    ///
    /// # Errors
    /// As [`Assessed::execute`], then the sink's errors.
    pub fn execute_shard(self, shard: Shard, sink: &mut dyn RecordSink) -> Result<Plan, SimError> {
        self.run.execute_shard(shard, sink)
    }

    /// The analysis of records read back from `source` (merged shards): the same
    /// result as [`Assessed::execute`] on the same runs.
    ///
    /// # Errors
    /// A missing, duplicated, misplaced or corrupted record, then as
    /// [`Assessed::execute`].
    pub fn execute_from(self, source: &mut dyn RecordSource) -> Result<Executed, SimError> {
        self.run.execute_from(source)
    }
}

/// The typed side of an [`Assessed`] job.
trait Runnable {
    fn execute(self: Box<Self>) -> Result<Executed, SimError>;
    fn plan(self: Box<Self>) -> Result<Plan, SimError>;
    fn execute_shard(
        self: Box<Self>,
        shard: Shard,
        sink: &mut dyn RecordSink,
    ) -> Result<Plan, SimError>;
    fn execute_from(self: Box<Self>, source: &mut dyn RecordSource) -> Result<Executed, SimError>;
}

/// An experiment with its checked scenario and the job it came from.
struct Typed<'j, E: Experiment> {
    exp: E,
    job: &'j Job<'j>,
    checked: E::Checked,
    resolved: Resolved,
}

/// The overrides' own rules, the same for every front end: `--runs` and `--threads` at
/// least 1, `--seed` at most 2^63 - 1 (the largest TOML integer, so that the resolved
/// scenario can record it).
///
/// # Errors
/// [`SimError::InvalidArgument`] naming the option.
pub fn check_overrides(
    runs: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
) -> Result<(), SimError> {
    if runs == Some(0) {
        return Err(SimError::invalid_argument("--runs", "must be at least 1"));
    }
    if threads == Some(0) {
        return Err(SimError::invalid_argument(
            "--threads",
            "must be at least 1",
        ));
    }
    if let Some(s) = seed
        && i64::try_from(s).is_err()
    {
        return Err(SimError::invalid_argument("--seed", seed_too_large(s)));
    }
    Ok(())
}

fn seed_too_large(s: u64) -> String {
    format!(
        "must be at most {} (2^63 - 1, the largest TOML integer, so that the resolved \
         scenario can record it), got {s}",
        i64::MAX
    )
}

/// Reads the typed scenario from `doc`, applies the overrides and checks it.
fn read_checked<E: Experiment>(
    exp: &E,
    doc: ScenarioDoc<'_>,
    runs: Option<usize>,
    seed: Option<u64>,
    extras: Option<Extras>,
) -> Result<(E::Scenario, E::Checked, Resolved), SimError> {
    let file = doc.file();
    let as_written = doc.table().ok();
    let mut scenario: E::Scenario = doc.into_typed()?;
    require_experiment(file, scenario.experiment(), E::NAME)?;
    if let Some(table) = &as_written {
        check_magnitudes(table, file)?;
    }
    // and as read: a whole number written for a real-valued key
    // (`9223372036854775807`) is a float now, with the float's limits (found by
    // fuzzing: the resolved scenario did not check again)
    check_magnitudes(&table_of(&scenario, file)?, file)?;
    check_overrides(runs, seed, None)?;
    if let Some(n) = runs {
        // A deterministic experiment has no run count to replace (`cargo xtask paper
        // --runs N` applies to every experiment).
        scenario.set_runs(n);
    }
    if let Some(s) = seed {
        if scenario.base_seed().is_none() {
            return Err(SimError::invalid_argument(
                "--seed",
                format!(
                    "experiment `{}` is deterministic (its scenario has no `base_seed`), so \
                     there is no seed to set; run it without --seed",
                    E::NAME
                ),
            ));
        }
        scenario.set_base_seed(s);
    }
    if let Some(s) = scenario.base_seed()
        && i64::try_from(s).is_err()
    {
        return Err(SimError::invalid(file, "base_seed", seed_too_large(s)));
    }
    // The paper's setup is judged on the scenario as written (overrides applied, runs
    // and seeds aside); a variant drops the paper's extras unless they are asked for.
    // (`extras` is `None` only for the preset itself, which is not compared with
    // itself.)
    let setup = match extras {
        Some(_) => Setup::of_table(exp, &table_of(&scenario, file)?),
        None => Setup::Paper,
    };
    // (a job on the user's own data has no paper: its checks are its own and stay)
    let paper_extras = !E::PAPER || extras == Some(Extras::Always) || setup.is_paper();
    let setup = if paper_extras {
        setup
    } else {
        exp.main_only(&mut scenario);
        // The keys are named against the preset without its extras too, so that the
        // merge of a campaign (which reads this stripped scenario back) names the same
        // keys; a variant only in the extras keeps the keys found before.
        let mut preset: E::Scenario = ScenarioDoc::parse(E::PRESET, "preset")?.into_typed()?;
        exp.main_only(&mut preset);
        match Setup::between(&table_of(&preset, "preset")?, &table_of(&scenario, file)?) {
            Setup::Paper => setup,
            stripped => stripped,
        }
    };
    // A Monte Carlo experiment's main batch needs two runs for an interval: checked
    // here once for every experiment.
    let main_runs = match scenario.runs() {
        Some(n) if n < 2 => Err(SimError::invalid(
            file,
            "runs",
            format!("needs at least 2 Monte Carlo runs for a confidence interval, got {n}"),
        )),
        _ => Ok(()),
    };
    let checked = main_runs
        .and_then(|()| exp.check(&scenario, file))
        .map_err(|e| match e {
            // A run count the user gave with --runs is reported as the option's.
            SimError::Invalid {
                key_path, reason, ..
            } if runs.is_some() && key_path == "runs" => {
                SimError::invalid_argument("--runs", reason)
            }
            other => other,
        })?;
    let statistics = scenario
        .statistics()
        .check(scenario.base_seed().unwrap_or(0), file)?;
    let resolved = Resolved {
        toml: to_toml(&scenario, file)?,
        runs: scenario.runs(),
        base_seed: scenario.base_seed(),
        statistics,
        setup,
        paper_extras,
    };
    Ok((scenario, checked, resolved))
}

/// The cost of a checked scenario on `threads` worker threads (`None`: all cores).
fn cost_of<E: Experiment>(exp: &E, scenario: &E::Scenario, threads: Option<usize>) -> Cost {
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    Cost::new(exp.cost(scenario), threads)
}

/// The resolved scenario as a TOML table (the same table as the resolved text parsed
/// back: tested for every preset in `fathom-experiments`).
fn table_of<T: serde::Serialize>(scenario: &T, file: &str) -> Result<toml::Table, SimError> {
    toml::Table::try_from(scenario)
        .map_err(|e| SimError::invalid_argument(format!("scenario `{file}`"), e.to_string()))
}

/// Prepares the checked scenario: what the runs share and the batches. Preparation
/// errors (a data folder, the scenario's values in a model's checks) are the user's
/// input ([`SimError::Input`]).
fn prepare_with<E: Experiment>(
    exp: &E,
    job: &Job<'_>,
    checked: E::Checked,
) -> Result<(E::Prepared, Vec<Batch>), SimError> {
    let prepared = prepare_input(exp, checked, &job.env)?;
    let batches = exp.batches(&prepared);
    Ok((prepared, batches))
}

/// `exp.prepare`, its errors as the user's input unless they already are.
fn prepare_input<E: Experiment>(
    exp: &E,
    checked: E::Checked,
    env: &Environment,
) -> Result<E::Prepared, SimError> {
    exp.prepare(checked, env).map_err(|e| match e {
        e if e.is_user_error() => e,
        e => SimError::Input(Box::new(e)),
    })
}

/// Runs the indices `range` of batch `b` in chunks (parallel within a chunk) and hands
/// each record to `each` in run order. The chunking bounds the records held at once;
/// it changes nothing in the results.
#[allow(clippy::too_many_arguments)]
fn run_batch<E: Experiment>(
    exp: &E,
    job: &Job<'_>,
    prepared: &E::Prepared,
    b: usize,
    batch: &Batch,
    range: std::ops::Range<usize>,
    seed: u64,
    mut each: impl FnMut(usize, E::Record) -> Result<(), SimError>,
) -> Result<(), SimError> {
    let progress = job.progress.as_ref();
    if let Some(p) = progress {
        p.report(ProgressEvent::BatchStarted {
            label: batch.label.clone(),
            total: range.len(),
        });
    }
    let chunk = CHUNK_RUNS_PER_THREAD
        * job
            .threads
            .unwrap_or_else(rayon::current_num_threads)
            .max(1);
    let mut start = range.start;
    while start < range.end {
        let end = (start + chunk).min(range.end);
        let records = try_run_indices(start..end, seed, job.threads, progress, |i, rng| {
            exp.run(prepared, b, i, rng)
                .map_err(|e| SimError::model(format!("{}: run {i}", batch.label), e))
        })?;
        for (i, record) in (start..end).zip(records) {
            each(i, record)?;
        }
        start = end;
    }
    if let Some(p) = progress {
        p.report(ProgressEvent::BatchFinished {
            label: batch.label.clone(),
        });
    }
    Ok(())
}

/// Analysis and summary from what was kept and folded.
fn finish<E: Experiment>(
    exp: &E,
    prepared: &E::Prepared,
    resolved: Resolved,
    batches: &[Batch],
    kept: Vec<Vec<E::Kept>>,
    folds: Vec<E::Fold>,
) -> Result<Executed, SimError> {
    let mut analysis = Analysis::with_statistics(resolved.statistics);
    analysis.user_variant = !resolved.paper_extras;
    exp.analyse(prepared, kept, folds, &mut analysis)?;
    if !resolved.paper_extras {
        // The paper's claims are about its setup: not judged on a user's variant.
        analysis.claims.clear();
    }
    analysis.fill_units();
    analysis.check_non_negative_intervals()?;
    let runs = batches.first().map_or(0, |b| b.runs);
    let seed = resolved.base_seed.unwrap_or(0);
    let mut summary = Summary::new(E::NAME, E::SEED_DOC, runs, seed);
    summary.rows = std::mem::take(&mut analysis.rows);
    summary.claims = std::mem::take(&mut analysis.claims);
    summary.extra = std::mem::take(&mut analysis.extra);
    summary.check()?;
    Ok(Executed {
        resolved,
        summary,
        analysis,
    })
}

/// Runs per worker thread in one chunk of a batch.
const CHUNK_RUNS_PER_THREAD: usize = 32;

impl<E: Experiment> DynExperiment for E {
    fn name(&self) -> &'static str {
        E::NAME
    }

    fn seed_doc(&self) -> &'static str {
        E::SEED_DOC
    }

    fn default_scenario(&self) -> &'static str {
        E::DEFAULT_SCENARIO
    }

    fn about(&self) -> &'static str {
        E::ABOUT
    }

    fn methods(&self) -> &'static [&'static str] {
        E::METHODS
    }

    fn console_metrics(&self) -> &'static [&'static str] {
        E::CONSOLE_METRICS
    }

    fn preset(&self) -> &'static str {
        E::PRESET
    }

    fn paper(&self) -> bool {
        E::PAPER
    }

    fn check_prepares(&self) -> bool {
        E::CHECK_PREPARES
    }

    fn schema(&self) -> schemars::Schema {
        schemars::schema_for!(E::Scenario)
    }

    fn assess_doc<'j>(
        &self,
        doc: ScenarioDoc<'j>,
        job: &'j Job<'j>,
    ) -> Result<Assessed<'j>, SimError> {
        check_overrides(job.runs, job.seed, job.threads)?;
        let (scenario, checked, resolved) =
            read_checked(self, doc, job.runs, job.seed, Some(job.env.extras))?;
        let table = table_of(&scenario, job.file)?;
        let cost = cost_of(self, &scenario, job.threads);
        cost.check(&job.env.limits, job.file)?;
        Ok(Assessed {
            resolved: resolved.clone(),
            cost,
            table,
            run: Box::new(Typed {
                exp: self.clone(),
                job,
                checked,
                resolved,
            }),
        })
    }

    fn resolve(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
    ) -> Result<Resolved, SimError> {
        read_checked(
            self,
            ScenarioDoc::parse(text, file)?,
            runs,
            seed,
            Some(Extras::WhenPaper),
        )
        .map(|(_, _, r)| r)
    }

    fn preset_table(&self) -> Option<toml::Table> {
        let doc = ScenarioDoc::parse(E::PRESET, "preset").ok()?;
        let (scenario, _, _) = read_checked(self, doc, None, None, None).ok()?;
        table_of(&scenario, "preset").ok()
    }

    fn cost(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
        threads: Option<usize>,
    ) -> Result<Cost, SimError> {
        let (scenario, _, _) = read_checked(
            self,
            ScenarioDoc::parse(text, file)?,
            runs,
            seed,
            Some(Extras::WhenPaper),
        )?;
        Ok(cost_of(self, &scenario, threads))
    }

    fn single_run(
        &self,
        text: &str,
        file: &str,
        env: &Environment,
    ) -> Result<SingleRunFn, SimError> {
        let (_, checked, _) = read_checked(
            self,
            ScenarioDoc::parse(text, file)?,
            None,
            None,
            Some(env.extras),
        )?;
        let prepared = self.prepare(checked, env)?;
        if self.batches(&prepared).is_empty() {
            return Err(SimError::invalid_argument(
                format!("experiment `{}`", E::NAME),
                "has no Monte Carlo batch to run",
            ));
        }
        let exp = self.clone();
        Ok(Box::new(move |i, rng| {
            exp.run(&prepared, 0, i, rng).map(|_| ())
        }))
    }
}

/// Reads, checks (cost limits included) and prepares the scenario `text` of the typed
/// experiment `exp` exactly as `fathom run` does, and returns what its runs share:
/// for a front end that drives the experiment's own simulation in another way (the
/// processor-in-the-loop flies one run of `urban` through two processes).
///
/// # Errors
/// The scenario's errors, as `fathom run` reports them (usage errors name the key).
pub fn prepare_typed<E: Experiment>(
    exp: &E,
    text: &str,
    file: &str,
    env: &Environment,
) -> Result<(E::Prepared, Resolved), SimError> {
    let (scenario, checked, resolved) = read_checked(
        exp,
        ScenarioDoc::parse(text, file)?,
        None,
        None,
        Some(env.extras),
    )?;
    cost_of(exp, &scenario, None).check(&env.limits, file)?;
    Ok((prepare_input(exp, checked, env)?, resolved))
}

/// A typed job prepared: what its runs share and its batches.
struct Ready<'j, E: Experiment> {
    exp: E,
    job: &'j Job<'j>,
    resolved: Resolved,
    prepared: E::Prepared,
    batches: Vec<Batch>,
}

impl<'j, E: Experiment> Typed<'j, E> {
    fn ready(self) -> Result<Ready<'j, E>, SimError> {
        let Typed {
            exp,
            job,
            checked,
            resolved,
        } = self;
        let (prepared, batches) = prepare_with(&exp, job, checked)?;
        Ok(Ready {
            exp,
            job,
            resolved,
            prepared,
            batches,
        })
    }
}

impl<E: Experiment> Runnable for Typed<'_, E> {
    fn execute(self: Box<Self>) -> Result<Executed, SimError> {
        let Ready {
            exp,
            job,
            resolved,
            prepared,
            batches,
        } = (*self).ready()?;
        let seed = resolved.base_seed.unwrap_or(0);
        let mut kept = Vec::with_capacity(batches.len());
        let mut folds = Vec::with_capacity(batches.len());
        for (b, batch) in batches.iter().enumerate() {
            let mut fold = E::Fold::default();
            let mut k = Vec::with_capacity(batch.runs);
            run_batch(
                &exp,
                job,
                &prepared,
                b,
                batch,
                0..batch.runs,
                seed,
                |i, record| {
                    k.push(exp.fold(&prepared, b, i, record, &mut fold));
                    Ok(())
                },
            )?;
            kept.push(k);
            folds.push(fold);
        }
        finish(&exp, &prepared, resolved, &batches, kept, folds)
    }

    fn plan(self: Box<Self>) -> Result<Plan, SimError> {
        let Ready {
            resolved, batches, ..
        } = (*self).ready()?;
        Ok(Plan { resolved, batches })
    }

    fn execute_shard(
        self: Box<Self>,
        shard: Shard,
        sink: &mut dyn RecordSink,
    ) -> Result<Plan, SimError> {
        let Ready {
            exp,
            job,
            resolved,
            prepared,
            batches,
        } = (*self).ready()?;
        let seed = resolved.base_seed.unwrap_or(0);
        for (b, batch) in batches.iter().enumerate() {
            let range = shard.range(batch.runs);
            sink.begin_batch(b, batch, range.clone())?;
            run_batch(&exp, job, &prepared, b, batch, range, seed, |i, record| {
                let json = serde_json::to_string(&record).map_err(|e| SimError::Json {
                    path: format!("record of run {i} of batch `{}`", batch.label).into(),
                    source: e,
                })?;
                sink.record(b, i, &json)
            })?;
        }
        Ok(Plan { resolved, batches })
    }

    fn execute_from(self: Box<Self>, source: &mut dyn RecordSource) -> Result<Executed, SimError> {
        let Ready {
            exp,
            resolved,
            prepared,
            batches,
            ..
        } = (*self).ready()?;
        let mut kept = Vec::with_capacity(batches.len());
        let mut folds = Vec::with_capacity(batches.len());
        for (b, batch) in batches.iter().enumerate() {
            let mut fold = E::Fold::default();
            let mut k = Vec::with_capacity(batch.runs);
            for i in 0..batch.runs {
                let Some(found) = source.next(b)? else {
                    return Err(SimError::invalid_argument(
                        format!("records of batch `{}`", batch.label),
                        format!("run {i} is missing ({} runs expected)", batch.runs),
                    ));
                };
                if found.index != i {
                    return Err(SimError::invalid_argument(
                        format!("records of batch `{}` ({})", batch.label, found.origin),
                        format!("expected run {i}, found run {}", found.index),
                    ));
                }
                // a record the user gave us that is not one: the user's file
                let record: E::Record = serde_json::from_str(&found.json).map_err(|e| {
                    SimError::Input(Box::new(SimError::Json {
                        path: found.origin.clone().into(),
                        source: e,
                    }))
                })?;
                k.push(exp.fold(&prepared, b, i, record, &mut fold));
            }
            if let Some(extra) = source.next(b)? {
                return Err(SimError::invalid_argument(
                    format!("records of batch `{}` ({})", batch.label, extra.origin),
                    format!(
                        "run {} is beyond the {} runs of the batch",
                        extra.index, batch.runs
                    ),
                ));
            }
            kept.push(k);
            folds.push(fold);
        }
        finish(&exp, &prepared, resolved, &batches, kept, folds)
    }
}
