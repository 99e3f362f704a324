//! The experiment abstraction: what an experiment owns (its science) and what the
//! driver owns (the pipeline).
//!
//! An experiment implements [`Experiment`]:
//!
//! 1. a scenario type ([`ScenarioFile`]: a serde struct with `deny_unknown_fields`
//!    and the common header keys `experiment`, `runs`, `base_seed`);
//! 2. [`Experiment::check`]: the scenario -> checked parameters (fast, no I/O; what
//!    `fathom check` runs), then [`Experiment::cost`]: samples, memory and time of the
//!    scenario, checked against the [`Limits`] before anything is allocated;
//! 3. [`Experiment::prepare`]: what every run shares and is costly to build (the
//!    truth, a data set read from disk);
//! 4. [`Experiment::batches`] and [`Experiment::run`]: the Monte Carlo batches and one
//!    run of a batch from a seeded RNG;
//! 5. [`Experiment::analyse`]: the runs' records -> rows, claims, figures, CSV files
//!    and report text, collected in an [`Analysis`].
//!
//! The driver ([`crate::driver`]) does everything else, the same way for every
//! experiment: it reads and parses the scenario, applies `--runs` and `--seed` to the
//! parsed scenario *before* the check (so an experiment cannot forget an override and
//! the resolved scenario records what ran), runs the batches on the requested threads
//! with the progress hook, builds and checks the `summary.json`, and writes every
//! output file.
//!
//! Every batch of an experiment uses the scenario's base seed: run `i` of any batch
//! draws from the stream `run_rng(base_seed, i)` (common random numbers across
//! batches), so a batch's result does not depend on the thread count, on the other
//! batches or on how the runs are split.
//!
//! [`DynExperiment`] is the object-safe face of an experiment, implemented for every
//! [`Experiment`]; the registry (`fathom_experiments::registry`, handed to the driver) is one list of
//! them, read by `fathom list / run / check`, `cargo xtask paper`, the benchmarks and
//! the fuzz targets.

mod analysis;
mod dynamic;
mod rows;
mod setup;

use std::path::PathBuf;

use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::SimError;
use crate::cost::{CostTerm, Limits};

pub use analysis::{Analysis, ColumnValues, FileContent, OutputFile};
pub use dynamic::{
    Assessed, DynExperiment, Executed, FoundRecord, Job, Plan, RecordSink, RecordSource, Resolved,
    Shard, SingleRunFn, check_overrides, prepare_typed,
};
pub use rows::{equivalence_claim, row_of_summary};
pub use setup::{Setup, differing_keys};

/// The header keys every scenario file has, read and overridden by the driver.
pub trait ScenarioFile: Serialize + DeserializeOwned + schemars::JsonSchema + Send + Sync {
    /// The `experiment` key as written in the file.
    fn experiment(&self) -> &str;
    /// Monte Carlo runs of the main batch; `None` for a deterministic experiment
    /// (no `runs` key: one run on recorded data).
    fn runs(&self) -> Option<usize>;
    /// Replaces `runs` (`--runs`); a deterministic experiment ignores it.
    fn set_runs(&mut self, runs: usize);
    /// The base seed; `None` for a deterministic experiment (no `base_seed` key).
    fn base_seed(&self) -> Option<u64>;
    /// Replaces `base_seed` (`--seed`); a deterministic experiment ignores it (the
    /// driver refuses `--seed` for it before calling this).
    fn set_base_seed(&mut self, seed: u64);
    /// The `[statistics]` settings (how rows summarize the runs); the defaults for a
    /// deterministic job.
    fn statistics(&self) -> crate::statistics::StatisticsParams {
        crate::statistics::StatisticsParams::default()
    }
}

/// Implements [`ScenarioFile`] for a scenario struct with the fields
/// `experiment: String`, `runs: usize`, `base_seed: u64` and
/// `statistics: StatisticsParams`.
#[macro_export]
macro_rules! monte_carlo_scenario {
    ($ty:ty) => {
        impl $crate::experiment::ScenarioFile for $ty {
            fn experiment(&self) -> &str {
                &self.experiment
            }
            fn runs(&self) -> Option<usize> {
                Some(self.runs)
            }
            fn set_runs(&mut self, runs: usize) {
                self.runs = runs;
            }
            fn base_seed(&self) -> Option<u64> {
                Some(self.base_seed)
            }
            fn set_base_seed(&mut self, seed: u64) {
                self.base_seed = seed;
            }
            fn statistics(&self) -> $crate::statistics::StatisticsParams {
                self.statistics.clone()
            }
        }
    };
}

/// Implements [`ScenarioFile`] for the scenario struct of a deterministic job (one
/// replay of recorded data) with the field `experiment: String` and no `runs` or
/// `base_seed` key.
#[macro_export]
macro_rules! deterministic_scenario {
    ($ty:ty) => {
        impl $crate::experiment::ScenarioFile for $ty {
            fn experiment(&self) -> &str {
                &self.experiment
            }
            fn runs(&self) -> Option<usize> {
                None
            }
            fn set_runs(&mut self, _runs: usize) {}
            fn base_seed(&self) -> Option<u64> {
                None
            }
            fn set_base_seed(&mut self, _seed: u64) {}
        }
    };
}

/// One Monte Carlo batch of an experiment.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Batch {
    /// What the batch computes, shown by the progress hook (e.g. `beacons`,
    /// `fusion: sensitivity dvl_vel_noise_mps = 0.1`).
    pub label: String,
    /// Number of runs.
    pub runs: usize,
}

impl Batch {
    /// A batch of `runs` runs labelled `label`.
    pub fn new(label: impl Into<String>, runs: usize) -> Self {
        Self {
            label: label.into(),
            runs,
        }
    }
}

/// What an execution takes from outside the scenario file: where data folders are
/// and the limits a scenario must fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Relative data folders of a scenario are looked up here and beside each of its
    /// ancestors (the workspace root for `cargo xtask paper`, the current directory
    /// for `fathom run`).
    pub base_dir: PathBuf,
    /// The limits the scenario's estimated cost must fit ([`crate::cost`]).
    pub limits: Limits,
    /// When the paper's extras run: its sensitivity batches (see
    /// [`Experiment::main_only`]) and its claims.
    pub extras: Extras,
    /// Whether an experiment with a world writes its 3D scene page `scene.html`
    /// (`fathom run --no-scene`: no).
    pub scene_page: bool,
}

/// When an experiment runs what belongs to its paper rather than to a scenario: the
/// sensitivity batches on the paper's own layouts and readings, and the paper's
/// claims.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Extras {
    /// Only on the paper's setup ([`Setup::Paper`]): a user's variant is reported as
    /// the user's (main batch, rows, figures), without the paper's claims.
    #[default]
    WhenPaper,
    /// Always (`fathom run --paper-extras`): the paper's claims judged on any scenario.
    Always,
}

impl Environment {
    /// Data looked up from `base_dir`, a missing data folder an error, default limits.
    pub fn new(base_dir: impl Into<PathBuf>) -> Self {
        Environment {
            base_dir: base_dir.into(),
            limits: Limits::default(),
            extras: Extras::default(),
            scene_page: true,
        }
    }
}

/// A paper experiment (see the module docs for the division of work).
pub trait Experiment: Clone + Send + Sync + 'static {
    /// The scenario file's schema.
    type Scenario: ScenarioFile;
    /// The checked scenario (every value validated and converted into the library
    /// crates' checked types).
    type Checked: Send + Sync;
    /// What all runs share (built once per execution).
    type Prepared: Send + Sync;
    /// What one run returns: serializable, so that a shard of a campaign can write it
    /// to disk and `fathom merge` read it back ([`crate::driver::campaign`]).
    type Record: Send + Serialize + DeserializeOwned;
    /// What the analysis keeps of each run (the per-run scalars), made by
    /// [`Experiment::fold`].
    type Kept: Send;
    /// What the analysis accumulates over a batch in run order (sums of per-time
    /// series, counts): its size does not grow with the number of runs.
    type Fold: Default + Send;

    /// Name, also the output directory and the scenario's `experiment` value
    /// (`[a-z0-9_-]+`).
    const NAME: &'static str;
    /// The seed paper's file name (or the data set's README), for `summary.json`.
    const SEED_DOC: &'static str;
    /// The preset scenario, relative to the workspace root.
    const DEFAULT_SCENARIO: &'static str;
    /// The preset's text as built into the binary (`include_str!` of
    /// `DEFAULT_SCENARIO`), for front ends without the source tree (the fuzz targets,
    /// `fathom replay`'s default settings).
    const PRESET: &'static str;
    /// One line for `fathom list`.
    const ABOUT: &'static str;
    /// The names the scenario's `methods = [...]` key accepts, in report order (shown
    /// by `fathom list`); empty when the experiment has no `methods` key.
    const METHODS: &'static [&'static str] = &[];
    /// The metrics of the short table `fathom run` prints (every method's row of each);
    /// empty: every row. The report and `summary.json` always hold every row.
    const CONSOLE_METRICS: &'static [&'static str] = &[];
    /// Whether the experiment reproduces a paper (its preset is the paper's setup, its
    /// rows may carry the paper's numbers and its claims are the paper's). `false` for
    /// a job on the user's own data (the own-log replays): its preset is only the
    /// built-in settings, and the report and console say so instead of comparing with
    /// a paper.
    const PAPER: bool = true;
    /// Whether [`Experiment::prepare`] reads the user's files (a world, a data folder,
    /// a log) and is cheap: `fathom check` then prepares the scenario too, so that a
    /// file it accepts is one `fathom run` starts. Experiments whose preparation only
    /// computes (and may take long) leave it `false`.
    const CHECK_PREPARES: bool = false;

    /// Removes from a scenario that is not the paper's setup what only the paper's
    /// setup runs by default (the paper's own sensitivity layouts or readings), so that
    /// the check, the cost and the resolved scenario are those of what runs. Called
    /// before [`Experiment::check`]; the default keeps everything.
    fn main_only(&self, scenario: &mut Self::Scenario) {
        let _ = scenario;
    }

    /// Validates `scenario` (`file` labels error messages). Fast and free of I/O.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    fn check(&self, scenario: &Self::Scenario, file: &str) -> Result<Self::Checked, SimError>;

    /// The cost of the checked `scenario` ([`crate::cost`]): its samples, memory and
    /// time, each part with the keys that drive it. Computed from the scenario values
    /// alone (no allocation that grows with them), before anything is prepared. The
    /// default gives no estimate; every registered experiment overrides it (a test
    /// checks that).
    fn cost(&self, scenario: &Self::Scenario) -> Vec<CostTerm> {
        let _ = scenario;
        Vec::new()
    }

    /// Builds what the runs share.
    ///
    /// # Errors
    /// Model or I/O errors (a data folder that cannot be read, ...).
    fn prepare(
        &self,
        checked: Self::Checked,
        env: &Environment,
    ) -> Result<Self::Prepared, SimError>;

    /// The Monte Carlo batches, the main one first (its run count is the summary's
    /// `runs`); none when there is nothing to run.
    fn batches(&self, prepared: &Self::Prepared) -> Vec<Batch>;

    /// Run `index` of batch `batch`, drawing from `rng` only.
    ///
    /// # Errors
    /// Model errors of the run.
    fn run(
        &self,
        prepared: &Self::Prepared,
        batch: usize,
        index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self::Record, SimError>;

    /// Folds run `index` of batch `batch` into the batch's accumulator and returns what
    /// the analysis keeps of it. The driver calls it for every run in run order, whatever
    /// the thread count or the sharding, so sums come out bit-identical; the record is
    /// dropped afterwards, so a campaign's memory does not grow with its run count
    /// beyond what is kept.
    fn fold(
        &self,
        prepared: &Self::Prepared,
        batch: usize,
        index: usize,
        record: Self::Record,
        fold: &mut Self::Fold,
    ) -> Self::Kept;

    /// Turns what was kept of every batch (`kept[batch][run]`, in run order) and the
    /// batches' accumulators into rows, claims, figures, CSV files and report text.
    ///
    /// # Errors
    /// Statistics, figure or model errors.
    fn analyse(
        &self,
        prepared: &Self::Prepared,
        kept: Vec<Vec<Self::Kept>>,
        folds: Vec<Self::Fold>,
        out: &mut Analysis,
    ) -> Result<(), SimError>;
}
