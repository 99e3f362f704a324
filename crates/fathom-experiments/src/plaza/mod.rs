//! The `plaza` experiment: range-beacon localization on real data, the CMU Plaza1 log
//! (`data/plaza1/README.md`: source and licence), with dead reckoning, AS / SC / SI and
//! ablations ([`fathom_replay::plaza`]).
//!
//! The data ships in the repository. The folder named by `[data] dir` in
//! `scenarios/plaza.toml` (default `data/plaza1`) is looked up inside the base
//! directory (the workspace root; the current directory for `fathom run`) and beside
//! each of its ancestors. When it is absent, `fathom run` and `cargo xtask paper`
//! refuse the scenario (a user error naming `data.dir`): the experiment is never
//! skipped.
//!
//! Files: `analysis` (rows and claims), `figures`, `report`; the replay itself lives in
//! [`fathom_replay::plaza`], shared with `fathom replay plaza`.

mod analysis;
mod cost;
mod figures;
mod report;

use std::path::PathBuf;

use rand_chacha::ChaCha8Rng;

use fathom_data::plaza::PlazaLog;
pub use fathom_replay::data_dir::find_data_dir;
use fathom_replay::plaza::{PlazaReplay, PlazaSettings, PlazaToml, replay};
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

pub use analysis::{
    GTSAM_BATCH_M, MAIN_METHODS, MAX_ERROR_LIMIT_M, REQUIRED_REDUCTION, SMOOTHED_TARGET_M,
    smoothed_name,
};

/// The settings and the log.
#[derive(Debug)]
pub struct Prepared {
    settings: PlazaSettings,
    data: (PathBuf, PlazaLog),
}

/// The `plaza` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Plaza;

impl Experiment for Plaza {
    type Scenario = PlazaToml;
    type Checked = PlazaSettings;
    type Prepared = Prepared;
    type Record = PlazaReplay;
    type Kept = Self::Record;
    type Fold = ();

    const NAME: &'static str = "plaza";
    const SEED_DOC: &'static str = "data/plaza1/README.md";
    const DEFAULT_SCENARIO: &'static str = "scenarios/plaza.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/plaza.toml");
    const CONSOLE_METRICS: &'static [&'static str] = &["rmse", "max"];
    const ABOUT: &'static str = "range-beacon localization on real data (CMU Plaza1): dead reckoning vs AS / SC / SI with range calibration and robust gating";
    // `check` reads the data folder as a run does.
    const CHECK_PREPARES: bool = true;

    fn check(&self, scenario: &PlazaToml, file: &str) -> Result<PlazaSettings, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &PlazaToml) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, settings: PlazaSettings, env: &Environment) -> Result<Prepared, SimError> {
        let dir = find_data_dir(&env.base_dir, &settings.data_dir).ok_or_else(|| {
            SimError::invalid_argument(
                "data folder",
                format!(
                    "`{}` (key `data.dir`) is not found in `{}` or beside any of its \
                     ancestors; put the data set's three files (`*_DR.txt`, `*_TD.txt`, \
                     `*_.mat`) there, or run `fathom replay plaza <dir>` on the folder \
                     holding them",
                    settings.data_dir,
                    env.base_dir.display()
                ),
            )
        })?;
        let log = PlazaLog::read_dir(&dir, settings.range_order).map_err(|e| {
            SimError::model(format!("reading the Plaza data in `{}`", dir.display()), e)
        })?;
        let data = (dir, log);
        Ok(Prepared { settings, data })
    }

    fn batches(&self, _p: &Prepared) -> Vec<Batch> {
        vec![Batch::new(Self::NAME, 1)]
    }

    fn run(
        &self,
        p: &Prepared,
        _batch: usize,
        _index: usize,
        _rng: &mut ChaCha8Rng,
    ) -> Result<PlazaReplay, SimError> {
        replay(&p.data.1, &p.settings)
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
        mut records: Vec<Vec<PlazaReplay>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let dir = &p.data.0;
        let Some(r) = records.first_mut().and_then(|b| b.pop()) else {
            return Err(SimError::invalid_argument(
                "plaza",
                "the replay did not run",
            ));
        };
        analysis::rows_and_claims(&r, out);
        figures::write(&r, out)?;
        out.report(&format!(
            "Real data, one deterministic replay (no Monte Carlo: `runs` = 1, no CIs, no \
             paper numbers{}). Data folder: `{}`.\n\n",
            if p.settings.smooth {
                "; the `paper` column of the smoothed rows holds the GTSAM batch reference"
            } else {
                ""
            },
            dir.display()
        ));
        out.report(&report::report_section(&r));
        Ok(())
    }
}
