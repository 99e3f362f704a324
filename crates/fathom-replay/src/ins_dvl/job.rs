//! The INS / DVL replay as a job of the runner ([`InsDvl`], experiment `ins-dvl`):
//! `fathom replay ins-dvl DIR` and `fathom run` on its settings file go through the
//! driver like every experiment (module docs of [`crate::own_log`]).

use rand_chacha::ChaCha8Rng;

use super::{InsDvlReplay, InsDvlSettings, InsDvlToml, analysis, check, figures, replay, report};
use crate::own_log::{self, INS_DVL_PRESET, SEED_DOC};
use fathom_data::layout::ins_dvl::InsDvlLog;
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The settings, the log folder and the log, read and checked.
pub type Prepared = own_log::PreparedLog<InsDvlSettings, InsDvlLog>;

/// The `ins-dvl` replay of one's own log.
#[derive(Debug, Clone, Copy, Default)]
pub struct InsDvl;

impl Experiment for InsDvl {
    type Scenario = InsDvlToml;
    type Checked = InsDvlSettings;
    type Prepared = Prepared;
    type Record = InsDvlReplay;
    type Kept = InsDvlReplay;
    type Fold = ();

    const NAME: &'static str = "ins-dvl";
    const SEED_DOC: &'static str = SEED_DOC;
    const DEFAULT_SCENARIO: &'static str = "scenarios/ins-dvl.toml";
    const PRESET: &'static str = INS_DVL_PRESET;
    const ABOUT: &'static str = "INS / DVL navigation on your own log (docs/own-data.md): pure INS, INS-DVL, the RPM velocity filter and the 15-state ESKF, with or without ground truth";
    const PAPER: bool = false;
    // `check` reads the log as a replay does.
    const CHECK_PREPARES: bool = true;

    fn check(&self, scenario: &InsDvlToml, file: &str) -> Result<InsDvlSettings, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &InsDvlToml) -> Vec<CostTerm> {
        own_log::cost_terms(scenario.methods.len())
    }

    fn prepare(&self, settings: InsDvlSettings, env: &Environment) -> Result<Prepared, SimError> {
        let data_dir = settings.data_dir.clone();
        own_log::prepare_log(settings, &data_dir, env, |d| InsDvlLog::read_dir(d), check)
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
    ) -> Result<InsDvlReplay, SimError> {
        replay(&p.log, &p.settings)
    }

    fn fold(
        &self,
        _prepared: &Prepared,
        _batch: usize,
        _index: usize,
        record: InsDvlReplay,
        _fold: &mut (),
    ) -> InsDvlReplay {
        record
    }

    fn analyse(
        &self,
        p: &Prepared,
        mut kept: Vec<Vec<InsDvlReplay>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let r = kept.first_mut().and_then(Vec::pop).ok_or_else(|| {
            SimError::invalid_argument("ins-dvl replay", "the replay did not run")
        })?;
        analysis::rows(&r, out);
        analysis::csv_files(&r, out)?;
        figures::write(&r, out)?;
        out.report(&report::notes(&r, &p.dir));
        Ok(())
    }
}
