//! The `vkf` experiment: strapdown INS, DVL bottom-lock loss, RPM velocity filter;
//! PINS vs INS-DVL vs VKF-aided navigation, plus a gated INS-DVL and a 15-state
//! ESKF as modern references (seed 002, spec C).
//!
//! Per run: the IMU errors and sensor constants are drawn, the error-free IMU
//! increments of the shared truth are corrupted, and the five methods run side by
//! side on the same IMU and sensor data (common random numbers). The truth and the
//! error-free increments are computed once for all runs. A second batch with the
//! literal "+-0.5 m/s" DVL bias reuses the same run streams.
//!
//! Files: `scenario` (schema and check), `sim` (the shared truth and one run),
//! `analysis` (rows and claims), `figures`, `report`, `smoothed` (`smooth = true`:
//! the RTS-smoothed VKF-aided filter and ESKF), `subset` (the analysis of a run of
//! some of the methods, `methods = [...]`).

mod analysis;
mod cost;
mod figures;
mod report;
pub(crate) mod scenario;
pub(crate) mod sim;
mod smoothed;
mod subset;

use rand_chacha::ChaCha8Rng;

use self::scenario::{Checked, VkfScenario};
use self::sim::{RunOutput, Shared};
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The checked scenario and the truth every run shares.
#[derive(Debug)]
pub struct Prepared {
    c: Checked,
    shared: Shared,
}

/// The `vkf` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Vkf;

/// Index of the literal-bias batch.
const LITERAL: usize = 1;

impl Experiment for Vkf {
    type Scenario = VkfScenario;
    type Checked = Checked;
    type Prepared = Prepared;
    type Record = RunOutput;
    type Kept = Self::Record;
    type Fold = ();

    const NAME: &'static str = "vkf";
    const SEED_DOC: &'static str = "002_cdb9d2284a7eb080.txt";
    const DEFAULT_SCENARIO: &'static str = "scenarios/vkf.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/vkf.toml");
    const METHODS: &'static [&'static str] = &sim::METHODS;
    const CONSOLE_METRICS: &'static [&'static str] = &["rms_h", "final_h"];
    const ABOUT: &'static str = "strapdown INS with DVL bottom-lock loss: pure INS vs INS-DVL vs the RPM velocity filter (seed 002)";

    /// The literal-bias batch replays the paper's printed DVL bias (an erratum
    /// reading): a user's variant runs its own configuration only.
    fn main_only(&self, scenario: &mut VkfScenario) {
        scenario.literal_bias_runs = 0;
    }

    fn check(&self, scenario: &VkfScenario, file: &str) -> Result<Checked, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &VkfScenario) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, c: Checked, _env: &Environment) -> Result<Prepared, SimError> {
        let shared = sim::build_shared(&c)?;
        Ok(Prepared { c, shared })
    }

    fn batches(&self, p: &Prepared) -> Vec<Batch> {
        let mut b = vec![Batch::new(Self::NAME, p.c.runs)];
        // A subset of the methods runs the main batch only (`methods` docs).
        if p.c.literal_bias_runs > 0 && p.c.all_methods() {
            b.push(Batch::new("vkf: literal DVL bias", p.c.literal_bias_runs));
        }
        b
    }

    fn run(
        &self,
        p: &Prepared,
        batch: usize,
        index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunOutput, SimError> {
        if batch == LITERAL {
            sim::one_run(&p.c, &p.shared, &p.c.dvl_literal, rng, false, false)
        } else {
            let smooth = p.c.smooth && p.c.all_methods();
            sim::one_run(&p.c, &p.shared, &p.c.dvl, rng, index == 0, smooth)
        }
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
        mut records: Vec<Vec<RunOutput>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let literal = if records.len() > LITERAL {
            records.swap_remove(LITERAL)
        } else {
            Vec::new()
        };
        let runs = records.swap_remove(0);
        if p.c.all_methods() {
            // One direction: analysis (rows, claims), then figures, then report.
            let tables = analysis::analyse(p, &runs, &literal, out)?;
            figures::write(&p.c, &p.shared, &runs, out)?;
            report::write(p, &tables, out);
            if p.c.smooth {
                let md = smoothed::section(p, &runs, out)?;
                out.report(&md);
            }
            Ok(())
        } else {
            subset::analyse(p, &runs, out)
        }
    }
}
