//! The `urban` experiment: map-aided navigation of a quadrotor under a bridge and
//! around tall buildings (seed 004, spec D; Fig. 6, 8-10, Table 2).
//!
//! Per Monte Carlo run and scenario: the quadrotor flies its path on the truth
//! (`fathom_traj::quadrotor`, wind gusts drawn per run); the ADIS16448 IMU, GNSS with
//! the line of sight cast against the map, the scenario's range finders or lidar and
//! the barometer are simulated once ([`sense`]); every method ([`nav::Method`]) runs on
//! the same data, is evaluated at the evaluation rate ([`trace`]), and the per-run
//! statistics become rows with 95 % CIs over the runs, paired differences become the
//! claims' rows ([`claims`]). Ablation batches rerun one method on one scenario with
//! glass treated as opaque, another lidar step, or the controller on the estimate
//! ([`closed_loop`]), on the main batch's random numbers.
//!
//! | file | job |
//! | --- | --- |
//! | [`scenario`] | the TOML schema |
//! | [`check`], `check_scene`, `settings` | scenario -> checked library types; the settings the paper leaves open |
//! | [`world`] | worlds (presets, OBJ / STL files), path checks, satellites |
//! | [`sense`] | sensor data of a run |
//! | [`nav`] | the six methods |
//! | [`trace`] | errors and per-run statistics |
//! | [`run`], [`closed_loop`] | one run |
//! | [`record`] | records, kept values, the batch fold |
//! | `analysis`, [`claims`], `figures`, `report`, `paper` | rows, claims, SVG, notes, the printed numbers |
//! | [`scene_page`] | run 0 as the 3D scene page (`scene.html`) |
//! | [`export_log`] | one flight as a `gnss-ins` log with its world as OBJ (the replay's tests) |

mod analysis;
pub mod check;
mod check_scene;
mod check_sensors;
pub mod claims;
pub mod closed_loop;
mod cost;
pub mod export_log;
mod figures;
pub mod method;
pub mod nav;
mod paper;
pub mod record;
mod report;
pub mod run;
pub mod runner;
pub mod scenario;
pub mod scene_page;
pub mod sense;
mod settings;
pub mod trace;
pub mod world;

use rand_chacha::ChaCha8Rng;

use self::record::{BatchFold, KeptRun, RunRecord, fold_run};
use self::scenario::UrbanScenario;
use self::world::Prepared;
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// The `urban` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Urban;

impl Experiment for Urban {
    type Scenario = UrbanScenario;
    type Checked = check::Checked;
    type Prepared = Prepared;
    type Record = RunRecord;
    type Kept = KeptRun;
    type Fold = BatchFold;

    const NAME: &'static str = "urban";
    const SEED_DOC: &'static str = "004_a46751abbc309235.txt";
    const DEFAULT_SCENARIO: &'static str = "scenarios/urban.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/urban.toml");
    const METHODS: &'static [&'static str] = &[
        "INS-only",
        "GPS/INS",
        "GPS/INS-all-sats",
        "GREKF",
        "MGPMF",
        "PF",
    ];
    const CONSOLE_METRICS: &'static [&'static str] = &["rmse_3d", "rmse_h", "switches"];
    const ABOUT: &'static str = "map-aided quadrotor navigation under a bridge and around buildings: INS, GPS/INS with and without the LOS test, switching GREKF / MGPMF / particle filter (seed 004, Fig. 8-10, Table 2)";
    // `check` loads the worlds and tests the waypoints against them as a run does.
    const CHECK_PREPARES: bool = true;

    fn check(&self, scenario: &UrbanScenario, file: &str) -> Result<check::Checked, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &UrbanScenario) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, checked: check::Checked, env: &Environment) -> Result<Prepared, SimError> {
        world::prepare(checked, env)
    }

    fn batches(&self, prep: &Prepared) -> Vec<Batch> {
        let c = &prep.checked;
        let mut b = vec![Batch::new(Self::NAME, c.runs)];
        for a in &c.ablations {
            b.push(Batch::new(
                format!(
                    "urban: {}/{}@{}",
                    c.scenes[a.scene].name,
                    a.method.name(),
                    a.label()
                ),
                c.ablation_runs.min(c.runs),
            ));
        }
        b
    }

    fn run(
        &self,
        prep: &Prepared,
        batch: usize,
        index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunRecord, SimError> {
        match batch {
            0 => run::main_run(prep, index, rng),
            b => run::ablation_run(prep, &prep.checked.ablations[b - 1], rng),
        }
    }

    fn fold(
        &self,
        _prep: &Prepared,
        _batch: usize,
        _index: usize,
        record: RunRecord,
        fold: &mut BatchFold,
    ) -> KeptRun {
        fold_run(record, fold)
    }

    fn analyse(
        &self,
        prep: &Prepared,
        kept: Vec<Vec<KeptRun>>,
        folds: Vec<BatchFold>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        // One direction: analysis (rows, claims, per-run CSV), then figures, then report.
        analysis::analyse(prep, &kept, &folds, out)?;
        let (Some(main), Some(main_fold)) = (kept.first(), folds.first()) else {
            return Err(SimError::invalid_argument("urban", "no main batch"));
        };
        figures::write(prep, main_fold, out)?;
        if prep.scene_page
            && let Some(detail) = &main_fold.detail
        {
            let title = format!("urban: {} scenario(s), run 0", prep.scenes.len());
            out.page("scene.html", scene_page::page(prep, detail, &title)?)?;
        }
        report::write(prep, main, out);
        Ok(())
    }
}

#[cfg(test)]
mod method_tests {
    use super::*;
    use crate::urban::nav::Method;

    #[test]
    fn the_accepted_methods_are_the_method_names() {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(names, Urban::METHODS);
    }
}
