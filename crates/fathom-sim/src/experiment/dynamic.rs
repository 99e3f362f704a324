//! [`DynExperiment`]: the object-safe face of every [`Experiment`], and the pipeline
//! the driver runs through it (parse, override, check, prepare, Monte Carlo, analyse).

use rand_chacha::ChaCha8Rng;

use super::{Analysis, Environment, Experiment, ScenarioFile};
use crate::SimError;
use crate::montecarlo::try_run_monte_carlo_with_progress;
use crate::output::Summary;
use crate::progress::Progress;
use crate::scenario::{parse_toml, require_experiment, to_toml};

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
    /// [`Experiment::PRESET`].
    fn preset(&self) -> &'static str;
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

    /// Runs the whole pipeline and returns the summary and the analysis.
    ///
    /// # Errors
    /// As [`DynExperiment::resolve`], then preparation, run and analysis errors.
    fn execute(&self, job: &Job<'_>) -> Result<Executed, SimError>;

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
    if let Some(n) = runs {
        if n == 0 {
            return Err(SimError::invalid_argument("--runs", "must be at least 1"));
        }
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
    let checked = exp.check(&scenario, file)?;
    let resolved = Resolved {
        toml: to_toml(&scenario, file)?,
        runs: scenario.runs(),
        base_seed: scenario.base_seed(),
    };
    Ok((scenario, checked, resolved))
}

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

    fn preset(&self) -> &'static str {
        E::PRESET
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

    fn execute(&self, job: &Job<'_>) -> Result<Executed, SimError> {
        if job.threads == Some(0) {
            return Err(SimError::invalid_argument(
                "--threads",
                "must be at least 1",
            ));
        }
        let (_, checked, resolved) =
            parse_with_overrides(self, job.text, job.file, job.runs, job.seed)?;
        let prepared = self.prepare(checked, &job.env)?;
        let batches = self.batches(&prepared);
        let seed = resolved.base_seed.unwrap_or(0);
        let mut records = Vec::with_capacity(batches.len());
        for (b, batch) in batches.iter().enumerate() {
            let prepared = &prepared;
            let runs = try_run_monte_carlo_with_progress(
                batch.runs,
                seed,
                job.threads,
                job.progress.as_ref(),
                &batch.label,
                |i, rng| {
                    self.run(prepared, b, i, rng)
                        .map_err(|e| SimError::model(format!("{}: run {i}", batch.label), e))
                },
            )?;
            records.push(runs);
        }
        let mut analysis = Analysis::new();
        self.analyse(&prepared, records, &mut analysis)?;
        let runs = batches.first().map_or(0, |b| b.runs);
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
