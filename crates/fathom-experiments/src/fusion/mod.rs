//! The `fusion` experiment: INS + DVL fusion architectures of Lee & Yoon 2011
//! (seed 000, spec A) — measurement fusion (MF), track-to-track fusion (T2T) and
//! the proposed equalize-fuse-feedback filter (EFF) — with the ablations
//! `EFF-no-feedback` and `EFF-no-equalization`, two further track-to-track rules
//! (`T2T-BC`, `T2T-CI`), the raw sensors as references, the course-change analysis
//! and a sensitivity sweep over the DVL noise and the filters' `v_DVL`.
//!
//! One mission (fixed trajectory seed), many noise realizations: run `i` draws the
//! INS and DVL seeds from ChaCha stream `i` of the base seed, and every method of a
//! run sees the same sensor noise (see [`sim`]).

mod analysis;
mod cost;
mod figures;
mod report;
pub mod scenario;
pub mod sim;
mod subset;

use fathom_sensors::integrated::DvlDrParams;
use fathom_traj::FusionMission;
use rand_chacha::ChaCha8Rng;

pub use self::analysis::{RunResult, run_once};
use self::analysis::{SWEEP_METHODS, SWEEPS};
use self::scenario::{FusionScenario, FusionSetup};
use self::sim::{Method, RunConfig};
use fathom_sim::SimError;
use fathom_sim::cost::CostTerm;
use fathom_sim::experiment::{Analysis, Batch, Environment, Experiment};

/// One value of a sensitivity sweep and the run configuration it gives.
#[derive(Debug, Clone)]
pub struct SweepPoint {
    /// 0: the scenario's reading, 1: the other reading.
    reading: usize,
    /// Index into the sweeps (`analysis::SWEEPS`).
    sweep: usize,
    /// The swept value.
    value: f64,
    /// The configuration of its runs.
    cfg: RunConfig,
}

/// The checked scenario, the mission and the sweep configurations.
#[derive(Debug, Clone)]
pub struct Prepared {
    setup: FusionSetup,
    mission: FusionMission,
    /// The run configuration under the other reading of the tuning (same sensors).
    other: RunConfig,
    sweep_points: Vec<SweepPoint>,
}

/// Index of the other reading's main batch.
const OTHER: usize = 1;
/// Index of the first sweep batch.
const FIRST_SWEEP: usize = 2;

/// The `fusion` experiment.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fusion;

impl Experiment for Fusion {
    type Scenario = FusionScenario;
    type Checked = FusionSetup;
    type Prepared = Prepared;
    type Record = RunResult;
    type Kept = Self::Record;
    type Fold = ();

    const NAME: &'static str = "fusion";
    const SEED_DOC: &'static str = "000_777a2c84247a6c44.txt";
    const DEFAULT_SCENARIO: &'static str = "scenarios/fusion.toml";
    const PRESET: &'static str = include_str!("../../../../scenarios/fusion.toml");
    const METHODS: &'static [&'static str] = &[
        "MF",
        "T2T",
        "EFF",
        "EFF-no-feedback",
        "EFF-no-equalization",
        "T2T-BC",
        "T2T-CI",
        "INS-only",
        "DVL-DR",
    ];
    const CONSOLE_METRICS: &'static [&'static str] = &["mean_3d", "std_3d"];
    const ABOUT: &'static str = "INS+DVL fusion: measurement fusion, track-to-track and the equalize-fuse-feedback filter on one UUV mission (seed 000, Tables 2-3)";

    fn check(&self, scenario: &FusionScenario, file: &str) -> Result<FusionSetup, SimError> {
        scenario.check(file)
    }

    fn cost(&self, scenario: &FusionScenario) -> Vec<CostTerm> {
        cost::terms(scenario)
    }

    fn prepare(&self, setup: FusionSetup, _env: &Environment) -> Result<Prepared, SimError> {
        let mission = setup.mission()?;
        let mut other = setup.run.clone();
        other.tuning.reading = setup.run.tuning.reading.other();
        let mut sweep_points = Vec::new();
        for (reading, base) in [&setup.run, &other].into_iter().enumerate() {
            for &v in &setup.sweep_dvl_noise {
                let dvl = DvlDrParams {
                    vel_noise_sigma: v,
                    ..setup.dvl_params
                }
                .check()
                .map_err(|e| SimError::model("sensitivity DVL parameters", e))?;
                sweep_points.push(SweepPoint {
                    reading,
                    sweep: 0,
                    value: v,
                    cfg: RunConfig {
                        dvl,
                        ..base.clone()
                    },
                });
            }
            for &v in &setup.sweep_v_dvl {
                let mut cfg = base.clone();
                cfg.tuning.v_dvl = v;
                sweep_points.push(SweepPoint {
                    reading,
                    sweep: 1,
                    value: v,
                    cfg,
                });
            }
        }
        Ok(Prepared {
            setup,
            mission,
            other,
            sweep_points,
        })
    }

    fn batches(&self, p: &Prepared) -> Vec<Batch> {
        if !p.setup.all_methods() {
            // A subset: the main batch only (module docs of `methods`).
            return vec![Batch::new(Self::NAME, p.setup.runs)];
        }
        let mut b = vec![
            Batch::new(Self::NAME, p.setup.runs),
            Batch::new(
                format!("fusion: reading {}", p.other.tuning.reading.name()),
                p.setup.runs,
            ),
        ];
        for point in &p.sweep_points {
            let cfg = &point.cfg;
            b.push(Batch::new(
                format!(
                    "fusion: sensitivity {} = {} ({})",
                    SWEEPS[point.sweep].0,
                    point.value,
                    cfg.tuning.reading.name()
                ),
                p.setup.sensitivity_runs,
            ));
        }
        b
    }

    fn run(
        &self,
        p: &Prepared,
        batch: usize,
        index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<RunResult, SimError> {
        match batch {
            // Run 0 of the main batch is the detail run: it keeps the paths the
            // figures draw (the numbers do not depend on it).
            0 => run_once(
                &p.setup,
                &p.setup.run,
                &p.mission,
                &p.setup.methods,
                index == 0,
                rng,
            ),
            OTHER => run_once(&p.setup, &p.other, &p.mission, &Method::ALL, false, rng),
            _ => run_once(
                &p.setup,
                &p.sweep_points[batch - FIRST_SWEEP].cfg,
                &p.mission,
                &SWEEP_METHODS,
                false,
                rng,
            ),
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
        records: Vec<Vec<RunResult>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        if p.setup.all_methods() {
            // One direction: analysis (rows, claims), then figures, then report.
            let a = analysis::analyse(p, records, out)?;
            let sweeps: Vec<&analysis::SweepResult> = a.sweeps.iter().collect();
            let detail = a
                .results
                .first()
                .ok_or_else(|| SimError::invalid_argument("fusion", "the main batch has no run"))?;
            figures::write_all(out, &p.setup, &p.mission, &a.results, detail, &sweeps)?;
            let section = report::section(&p.setup, &p.mission, &a.readings(p))?;
            out.report(&section);
            Ok(())
        } else {
            subset::analyse(p, records, out)
        }
    }
}

#[cfg(test)]
mod method_tests {
    use super::*;

    #[test]
    fn the_accepted_methods_are_the_method_names() {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(names, Fusion::METHODS);
    }
}
