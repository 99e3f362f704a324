//! [`DynExperiment`]: the object-safe face of every [`Experiment`], and the pipeline
//! the driver runs through it (parse, override, check, prepare, Monte Carlo, analyse).

use rand_chacha::ChaCha8Rng;

use super::{Analysis, Batch, Environment, Experiment, ScenarioFile};
use crate::SimError;
use crate::cost::Cost;
use crate::montecarlo::try_run_indices;
use crate::progress::{Progress, ProgressEvent};
use crate::scenario::{check_magnitudes, parse_toml, require_experiment, to_toml};
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
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Resolved {
    /// The scenario as TOML with every default filled in and the overrides applied:
    /// running it reproduces the run.
    pub toml: String,
    /// Monte Carlo runs of the main batch (`None`: deterministic).
    pub runs: Option<usize>,
    /// The base seed used (`None`: deterministic).
    pub base_seed: Option<u64>,
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
#[derive(Debug, Clone, PartialEq, Eq)]
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
    /// [`Experiment::PRESET`].
    fn preset(&self) -> &'static str;
    /// [`Experiment::PAPER`].
    fn paper(&self) -> bool;
    /// The JSON schema of the scenario file (field docs as descriptions), from which
    /// `docs/scenarios.md` is generated.
    fn schema(&self) -> schemars::Schema;

    /// Parses `text`, applies the overrides and checks it (`fathom check`).
    ///
    /// # Errors
    /// TOML and check errors naming `file` and the key; bad overrides.
    fn resolve(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
    ) -> Result<Resolved, SimError>;

    /// Parses `text`, applies the overrides, checks it and estimates its cost on
    /// `threads` worker threads (`None`: all cores); the cost is not checked against
    /// any limit here.
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

    /// What [`DynExperiment::execute`] checks before it prepares anything: the
    /// scenario with the job's overrides, its cost against `job.env.limits`, the
    /// job's options. `fathom run` calls it before it claims the output folder.
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`]; a cost beyond the limits ([`SimError::Invalid`]
    /// naming the key); bad `--threads` / `--runs`.
    fn assess(&self, job: &Job<'_>) -> Result<(Resolved, Cost), SimError>;

    /// Runs the whole pipeline and returns the summary and the analysis.
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`], then preparation, run and analysis errors.
    fn execute(&self, job: &Job<'_>) -> Result<Executed, SimError>;

    /// Parse, override, check and prepare: the resolved scenario and the batches.
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`], then preparation errors.
    fn plan(&self, job: &Job<'_>) -> Result<Plan, SimError>;

    /// Runs the run indices of `shard` in every batch and hands each run's record,
    /// serialized as JSON, to `sink` (a shard of a campaign: no analysis).
    ///
    /// # Errors
    /// As [`DynExperiment::execute`], then the sink's errors.
    fn execute_shard(
        &self,
        job: &Job<'_>,
        shard: Shard,
        sink: &mut dyn RecordSink,
    ) -> Result<Plan, SimError>;

    /// The analysis of records read back from `source` (merged shards): the same
    /// result as [`DynExperiment::execute`] on the same runs.
    ///
    /// # Errors
    /// A missing, duplicated, misplaced or corrupted record, then as
    /// [`DynExperiment::execute`].
    fn execute_from(
        &self,
        job: &Job<'_>,
        source: &mut dyn RecordSource,
    ) -> Result<Executed, SimError>;

    /// Prepares the scenario `text` and returns its main batch's run function (for
    /// the benchmarks: the run index and the RNG in, the record dropped).
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

fn parse_with_overrides<E: Experiment>(
    exp: &E,
    text: &str,
    file: &str,
    runs: Option<usize>,
    seed: Option<u64>,
) -> Result<(E::Scenario, E::Checked, Resolved), SimError> {
    let mut scenario: E::Scenario = parse_toml(text, file)?;
    require_experiment(file, scenario.experiment(), E::NAME)?;
    check_magnitudes(text, file)?;
    if let Some(n) = runs {
        if n == 0 {
            return Err(SimError::invalid_argument("--runs", "must be at least 1"));
        }
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
        let reason = format!(
            "must be at most {} (2^63 - 1, the largest TOML integer, so that the resolved \
             scenario can record it), got {s}",
            i64::MAX
        );
        return Err(match seed {
            Some(_) => SimError::invalid_argument("--seed", reason),
            None => SimError::invalid(file, "base_seed", reason),
        });
    }
    let checked = exp.check(&scenario, file).map_err(|e| match e {
        // A run count the user gave with --runs is reported as the option's.
        SimError::Invalid {
            key_path, reason, ..
        } if runs.is_some() && key_path == "runs" => SimError::invalid_argument("--runs", reason),
        other => other,
    })?;
    let resolved = Resolved {
        toml: to_toml(&scenario, file)?,
        runs: scenario.runs(),
        base_seed: scenario.base_seed(),
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

/// Parse, override, check, estimate the cost against the limits; what `fathom run`
/// checks before it touches the output folder.
fn assess<E: Experiment>(exp: &E, job: &Job<'_>) -> Result<(E::Checked, Resolved, Cost), SimError> {
    if job.threads == Some(0) {
        return Err(SimError::invalid_argument(
            "--threads",
            "must be at least 1",
        ));
    }
    let (scenario, checked, resolved) =
        parse_with_overrides(exp, job.text, job.file, job.runs, job.seed)?;
    let cost = cost_of(exp, &scenario, job.threads);
    cost.check(&job.env.limits, job.file)?;
    Ok((checked, resolved, cost))
}

/// Parse, override, check, cost and prepare; the batches of the prepared experiment.
/// Preparation errors (a data folder, the scenario's values in a model's checks) are
/// the user's input ([`SimError::Input`]).
fn plan<E: Experiment>(
    exp: &E,
    job: &Job<'_>,
) -> Result<(Resolved, E::Prepared, Vec<Batch>), SimError> {
    let (checked, resolved, _) = assess(exp, job)?;
    let prepared = exp.prepare(checked, &job.env).map_err(|e| match e {
        e if e.is_user_error() => e,
        e => SimError::Input(Box::new(e)),
    })?;
    let batches = exp.batches(&prepared);
    Ok((resolved, prepared, batches))
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
    let mut analysis = Analysis::new();
    exp.analyse(prepared, kept, folds, &mut analysis)?;
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

    fn preset(&self) -> &'static str {
        E::PRESET
    }

    fn paper(&self) -> bool {
        E::PAPER
    }

    fn schema(&self) -> schemars::Schema {
        schemars::schema_for!(E::Scenario)
    }

    fn resolve(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
    ) -> Result<Resolved, SimError> {
        parse_with_overrides(self, text, file, runs, seed).map(|(_, _, r)| r)
    }

    fn cost(
        &self,
        text: &str,
        file: &str,
        runs: Option<usize>,
        seed: Option<u64>,
        threads: Option<usize>,
    ) -> Result<Cost, SimError> {
        let (scenario, _, _) = parse_with_overrides(self, text, file, runs, seed)?;
        Ok(cost_of(self, &scenario, threads))
    }

    fn assess(&self, job: &Job<'_>) -> Result<(Resolved, Cost), SimError> {
        assess(self, job).map(|(_, r, c)| (r, c))
    }

    fn execute(&self, job: &Job<'_>) -> Result<Executed, SimError> {
        let (resolved, prepared, batches) = plan(self, job)?;
        let seed = resolved.base_seed.unwrap_or(0);
        let mut kept = Vec::with_capacity(batches.len());
        let mut folds = Vec::with_capacity(batches.len());
        for (b, batch) in batches.iter().enumerate() {
            let mut fold = E::Fold::default();
            let mut k = Vec::with_capacity(batch.runs);
            run_batch(
                self,
                job,
                &prepared,
                b,
                batch,
                0..batch.runs,
                seed,
                |i, record| {
                    k.push(self.fold(&prepared, b, i, record, &mut fold));
                    Ok(())
                },
            )?;
            kept.push(k);
            folds.push(fold);
        }
        finish(self, &prepared, resolved, &batches, kept, folds)
    }

    fn execute_shard(
        &self,
        job: &Job<'_>,
        shard: Shard,
        sink: &mut dyn RecordSink,
    ) -> Result<Plan, SimError> {
        let (resolved, prepared, batches) = plan(self, job)?;
        let seed = resolved.base_seed.unwrap_or(0);
        for (b, batch) in batches.iter().enumerate() {
            let range = shard.range(batch.runs);
            sink.begin_batch(b, batch, range.clone())?;
            run_batch(self, job, &prepared, b, batch, range, seed, |i, record| {
                let json = serde_json::to_string(&record).map_err(|e| SimError::Json {
                    path: format!("record of run {i} of batch `{}`", batch.label).into(),
                    source: e,
                })?;
                sink.record(b, i, &json)
            })?;
        }
        Ok(Plan { resolved, batches })
    }

    fn execute_from(
        &self,
        job: &Job<'_>,
        source: &mut dyn RecordSource,
    ) -> Result<Executed, SimError> {
        let (resolved, prepared, batches) = plan(self, job)?;
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
                let record: E::Record =
                    serde_json::from_str(&found.json).map_err(|e| SimError::Json {
                        path: found.origin.clone().into(),
                        source: e,
                    })?;
                k.push(self.fold(&prepared, b, i, record, &mut fold));
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
        finish(self, &prepared, resolved, &batches, kept, folds)
    }

    fn plan(&self, job: &Job<'_>) -> Result<Plan, SimError> {
        let (resolved, _, batches) = plan(self, job)?;
        Ok(Plan { resolved, batches })
    }

    fn single_run(
        &self,
        text: &str,
        file: &str,
        env: &Environment,
    ) -> Result<SingleRunFn, SimError> {
        let (_, checked, _) = parse_with_overrides(self, text, file, None, None)?;
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
