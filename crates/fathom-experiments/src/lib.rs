//! The paper experiments of fathom: one folder each (scenario, one run, analysis,
//! figures, report), the registry that every front end reads, and the simulated
//! example logs of `fathom log example` ([`example_log`]).
//!
//! Each experiment implements [`fathom_sim::Experiment`]; the runner (`fathom-sim`)
//! owns the pipeline, the plaza experiment replays through `fathom-replay`, and the
//! outputs are `fathom-report`'s.

pub mod beacons;
pub mod common;
#[cfg(test)]
mod cost_tests;
pub mod example_log;
#[cfg(test)]
mod example_log_tests;
pub mod fusion;
pub mod noise;
pub mod plaza;
#[cfg(test)]
mod runner_tests;
pub mod urban;
pub mod vkf;

use fathom_sim::experiment::DynExperiment;

/// Every registered experiment, in report order. Adding an experiment means a new
/// folder and one line here; `fathom list / run / check`, `cargo xtask paper`, the
/// benchmarks and the fuzz targets all read this list.
pub fn registry() -> Vec<&'static dyn DynExperiment> {
    vec![
        &fusion::Fusion,
        &noise::Noise,
        &beacons::Beacons,
        &vkf::Vkf,
        &plaza::Plaza,
        &urban::Urban,
    ]
}

/// Every job a scenario file may name, what `fathom run` / `fathom check` and
/// `fathom.run` / `fathom.check` accept: the registered experiments, then the replays of
/// one's own log (whose output folders hold a `scenario.toml` that runs again).
pub fn jobs() -> Vec<&'static dyn DynExperiment> {
    let mut all = registry();
    all.extend(fathom_replay::own_log_replays());
    all
}
