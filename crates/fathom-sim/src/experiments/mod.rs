//! The registered experiments: one folder each (scenario, one run, analysis,
//! figures, report), and the registry that every front end reads.

pub mod beacons;
pub mod common;
#[cfg(test)]
mod cost_tests;
pub mod fusion;
pub mod noise;
pub mod plaza;
pub mod urban;
pub mod vkf;

use crate::experiment::DynExperiment;

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
