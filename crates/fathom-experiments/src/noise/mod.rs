//! The `noise` experiment: statistical verification of the range/depth noise
//! generator of the beacons paper (seed 003, section 4, eqs. 5-9).
//!
//! For each case (Gaussian only, common-mode correlation only at two levels, both)
//! the sensor suite samples four beacon ranges and a depth gauge synchronously
//! along the velocity-command motion; the 5x5 covariance of the realised noise
//! `[range1..4, depth]` is estimated per run and compared with the design
//!
//! ```text
//! Sigma = diag(sigma_r^2 x4, sigma_d^2) + sigma_c^2 * (ones(4,4) (+) 0)
//! ```
//!
//! Each run's covariance uses the known zero mean of the noise (`1/n sum x x^T`),
//! which is unbiased even though the common-mode noise is held for `t_gap`; the
//! value reported per entry is the mean over Monte Carlo runs with its 95 % CI.
//! A separate long run shows convergence to the design.
//!
//! Files: [`scenario`] (schema and check), `run` (one run, the long run),
//! `analysis` (per-entry statistics, rows and claims), `figures`, `report`, `paper`
//! (the printed matrices, reference only).

mod analysis;
mod cost;
mod figures;
mod paper;
mod report;
mod run;
pub mod scenario;

use nalgebra::DMatrix;
use rand_chacha::ChaCha8Rng;

use self::scenario::{Checked, NoiseScenario};
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// Labels of the five noise components, in matrix order.
const LABELS: [&str; 5] = ["range1", "range2", "range3", "range4", "depth"];

/// What the runs share: the checked scenario, the convergence run of each case and the
/// sample-time clocks of the diagram.
#[derive(Debug, Clone)]
pub struct Prepared {
    checked: Checked,
    long: Vec<run::LongRun>,
    sample_rows: Option<run::SampleRows>,
}

/// The `noise` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Noise;

impl Experiment for Noise {
    type Scenario = NoiseScenario;
    type Checked = Checked;
    type Prepared = Prepared;
    /// Per case, the run's 5x5 noise covariance.
    type Record = Vec<DMatrix<f64>>;
    type Kept = Self::Record;
    type Fold = ();

    const NAME: &'static str = "noise";
    const SEED_DOC: &'static str = "003_9d29f3a0492aaff3.txt";
    const DEFAULT_SCENARIO: &'static str = "scenarios/noise.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/noise.toml");
    const ABOUT: &'static str =
        "the range/depth noise generator produces the designed covariance (seed 003, eqs. 5-9)";

    fn check(&self, scenario: &NoiseScenario, file: &str) -> Result<Checked, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &NoiseScenario) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, checked: Checked, _env: &Environment) -> Result<Prepared, SimError> {
        // The convergence runs and the sample-time clocks draw from their own streams
        // (not the Monte Carlo runs'): drawn once here, so the analysis and the figures
        // only read.
        let long = checked
            .cases
            .iter()
            .map(|case| {
                let design = fathom_sensors::design_covariance(&case.config);
                run::long_run(&checked, case, &design, checked.period)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let sample_rows = run::sample_time_rows(&checked)?;
        Ok(Prepared {
            checked,
            long,
            sample_rows,
        })
    }

    fn batches(&self, p: &Prepared) -> Vec<Batch> {
        vec![Batch::new(Self::NAME, p.checked.runs)]
    }

    fn run(
        &self,
        p: &Prepared,
        _batch: usize,
        _index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self::Record, SimError> {
        run::one_run(&p.checked, rng)
    }

    fn fold(
        &self,
        _prepared: &Prepared,
        _batch: usize,
        _index: usize,
        record: Self::Record,
        _fold: &mut (),
    ) -> Self::Record {
        record
    }

    fn analyse(
        &self,
        p: &Prepared,
        mut records: Vec<Vec<Self::Record>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let per_run = records.swap_remove(0);
        // One direction: analysis (rows, claims), then figures, then report.
        let results = analysis::analyse(&p.checked, &p.long, &per_run, out)?;
        figures::write(
            &p.checked,
            &per_run,
            &results,
            p.sample_rows.as_deref(),
            out,
        )?;
        report::write(&p.checked, &results, out);
        Ok(())
    }
}
