//! The `beacons` experiment: EKF range-beacon localization with the AS / SC / SI
//! update schemes and chi-square outlier gating (seed 003, section 5, Tables 12-14).
//!
//! Per Monte Carlo run: one velocity-command motion (Tables 1, 9), one initial
//! estimation error drawn from `N(0, P0)`, and per case the sensor suite of the
//! `noise` experiment (common random numbers: every case starts from the same RNG
//! state). Each case's data are filtered by the same 4-state EKF
//! ([`fathom_estimators::beacon_ekf`]) under the three schemes
//! ([`fathom_estimators::schemes`]). The 3D position error is evaluated every epoch
//! period (0.1 s) after all measurements stamped up to that instant were processed;
//! per run its mean, population std, max and RMSE are taken, then averaged over runs
//! with 95 % CIs. Outlier recall = injected outliers rejected by the gate / injected.
//!
//! The number of beacons `K` is the length of the scenario's `beacons.positions`
//! (the paper has 4; any `K >= 1` runs): the suite simulates `K` ranges, `R` is the
//! `(K+1) x (K+1)` design covariance of `[range_1..K, depth]`, each range is gated as a
//! 1-dof scalar, and the figures, CSV columns and report tables have one entry per
//! beacon. With fewer than 3 beacons the horizontal position is only weakly observable
//! (the filter leans on dead reckoning and the initial estimate); it still runs.
//!
//! Files: [`scenario`] (schema and check), [`filter`] (the EKF glue, public for the
//! end-to-end tests), `run` (one run), `analysis` (rows and claims), `figures`,
//! `report`, `paper` (the printed tables, reference only).

mod analysis;
mod cost;
mod detail;
mod figures;
pub mod filter;
mod paper;
mod report;
mod run;
pub mod scenario;

use fathom_estimators::schemes::UpdateScheme;
use rand_chacha::ChaCha8Rng;

pub use self::filter::{EkfSettings, FilterSetup, SchemeRun, events, run_scheme};
pub use self::run::{BatchSums, KeptStats, SchemeStats};
use self::scenario::{BeaconsScenario, Checked};
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The main case (Table 13).
const MAIN_CASE: &str = "high";

/// Method name of a scheme on a case (`SC/high`).
fn method(scheme: UpdateScheme, case: &str) -> String {
    format!("{}/{case}", scheme.short_name())
}

/// The `beacons` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Beacons;

impl Experiment for Beacons {
    type Scenario = BeaconsScenario;
    type Checked = Checked;
    type Prepared = Checked;
    /// Per case, per scheme (AS, SC, SI): the run's statistics (a layout batch has
    /// the main case only).
    type Record = run::RunRecord;
    type Kept = Vec<Vec<KeptStats>>;
    type Fold = BatchSums;

    const NAME: &'static str = "beacons";
    const SEED_DOC: &'static str = "003_9d29f3a0492aaff3.txt";
    const DEFAULT_SCENARIO: &'static str = "scenarios/beacons.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/beacons.toml");
    const METHODS: &'static [&'static str] = &["AS", "SC", "SI"];
    const CONSOLE_METRICS: &'static [&'static str] = &["rmse", "outlier_recall"];
    const ABOUT: &'static str = "EKF range-beacon localization under the AS / SC / SI update schemes with chi-square gating (seed 003, Tables 12-14)";

    /// The `[[geometry]]` layouts are the paper's sensitivity (4 beacons each): a
    /// user's variant runs its own beacons only, unless the extras are asked for.
    fn main_only(&self, scenario: &mut BeaconsScenario) {
        scenario.geometry.clear();
    }

    fn check(&self, scenario: &BeaconsScenario, file: &str) -> Result<Checked, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &BeaconsScenario) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, checked: Checked, _env: &Environment) -> Result<Checked, SimError> {
        Ok(checked)
    }

    fn batches(&self, checked: &Checked) -> Vec<Batch> {
        let mut b = vec![Batch::new(Self::NAME, checked.runs)];
        for layout in &checked.layouts {
            b.push(Batch::new(
                format!("beacons: layout {}", layout.name),
                checked.runs,
            ));
        }
        b
    }

    fn run(
        &self,
        checked: &Checked,
        batch: usize,
        index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self::Record, SimError> {
        match batch {
            0 => run::one_run(checked, index, rng),
            layout => run::one_layout_run(checked, layout - 1, rng),
        }
    }

    fn fold(
        &self,
        _checked: &Checked,
        _batch: usize,
        _index: usize,
        record: Self::Record,
        sums: &mut BatchSums,
    ) -> Self::Kept {
        run::fold_run(record, sums)
    }

    fn analyse(
        &self,
        checked: &Checked,
        kept: Vec<Vec<Self::Kept>>,
        folds: Vec<BatchSums>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let main = (kept.first(), folds.first());
        let (Some(per_run), Some(sums)) = main else {
            return Err(SimError::invalid_argument("beacons", "no main batch"));
        };
        let layouts: Vec<(&[Self::Kept], &BatchSums)> = kept[1..]
            .iter()
            .map(Vec::as_slice)
            .zip(&folds[1..])
            .collect();
        // One direction: analysis (rows, claims), then figures, then report.
        let a = analysis::analyse(checked, per_run, sums, &layouts, out)?;
        figures::write(checked, per_run, sums, out)?;
        if a.all_schemes {
            report::write(checked, &a.table, per_run, sums, &a.layout_tables, out);
        } else {
            report::write_subset(checked, &a.table, &a.layout_tables, out);
        }
        out.report(&a.smoothed_md);
        Ok(())
    }
}
