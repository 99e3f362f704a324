//! The range-beacon replay as a job of the runner ([`RangeBeacon`], experiment
//! `range-beacon`): `fathom replay range-beacon DIR` and `fathom run` on its settings
//! file go through the driver like every experiment (module docs of
//! [`crate::own_log`]).

use rand_chacha::ChaCha8Rng;

use super::{
    RangeBeaconReplay, RangeBeaconSettings, RangeBeaconToml, analysis, check, figures, replay,
    report,
};
use crate::own_log::{self, RANGE_BEACON_PRESET, SEED_DOC};
use fathom_data::layout::range_beacon::RangeBeaconLog;
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The settings, the log folder and the log, read and checked.
pub type Prepared = own_log::PreparedLog<RangeBeaconSettings, RangeBeaconLog>;

/// The `range-beacon` replay of one's own log.
#[derive(Debug, Clone, Copy, Default)]
pub struct RangeBeacon;

impl Experiment for RangeBeacon {
    type Scenario = RangeBeaconToml;
    type Checked = RangeBeaconSettings;
    type Prepared = Prepared;
    type Record = RangeBeaconReplay;
    type Kept = RangeBeaconReplay;
    type Fold = ();

    const NAME: &'static str = "range-beacon";
    const SEED_DOC: &'static str = SEED_DOC;
    const DEFAULT_SCENARIO: &'static str = "scenarios/range-beacon.toml";
    const PRESET: &'static str = RANGE_BEACON_PRESET;
    const ABOUT: &'static str = "range-beacon localization on your own log (docs/own-data.md): dead reckoning and the EKF under AS / SC / SI, with or without ground truth";
    const PAPER: bool = false;
    // `check` reads the log as a replay does.
    const CHECK_PREPARES: bool = true;

    fn check(
        &self,
        scenario: &RangeBeaconToml,
        file: &str,
    ) -> Result<RangeBeaconSettings, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &RangeBeaconToml) -> Vec<CostTerm> {
        own_log::cost_terms(scenario.methods.len())
    }

    fn prepare(
        &self,
        settings: RangeBeaconSettings,
        env: &Environment,
    ) -> Result<Prepared, SimError> {
        let data_dir = settings.data_dir.clone();
        own_log::prepare_log(
            settings,
            &data_dir,
            env,
            |d| RangeBeaconLog::read_dir(d),
            check,
        )
    }

    fn batches(&self, _prepared: &Prepared) -> Vec<Batch> {
        vec![Batch::new(Self::NAME, 1)]
    }

    fn run(
        &self,
        p: &Prepared,
        _batch: usize,
        _index: usize,
        _rng: &mut ChaCha8Rng,
    ) -> Result<RangeBeaconReplay, SimError> {
        replay(&p.log, &p.settings)
    }

    fn fold(
        &self,
        _prepared: &Prepared,
        _batch: usize,
        _index: usize,
        record: RangeBeaconReplay,
        _fold: &mut (),
    ) -> RangeBeaconReplay {
        record
    }

    fn analyse(
        &self,
        p: &Prepared,
        mut kept: Vec<Vec<RangeBeaconReplay>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let r = kept.first_mut().and_then(Vec::pop).ok_or_else(|| {
            SimError::invalid_argument("range-beacon replay", "the replay did not run")
        })?;
        analysis::rows(&r, out);
        analysis::csv_files(&r, out)?;
        figures::write(&r, out)?;
        out.report(&report::notes(&r, &p.dir));
        Ok(())
    }
}
