//! The paper experiments run by `cargo xtask paper`, and their registry.
//!
//! Each experiment module owns its scenario schema (serde structs with
//! `deny_unknown_fields`), converts it into the checked parameter types of the
//! library crates, runs the Monte Carlo batch and writes figures and CSV files;
//! [`crate::run_paper`] writes `summary.json` and `report.md` from what it returns.

pub mod beacons;
pub mod common;
pub mod fusion;
pub mod noise;
pub mod plaza;
pub mod single_run;
pub mod vkf;

use crate::experiment::Experiment;

/// All registered paper experiments, in report order.
pub fn registry() -> Vec<Experiment> {
    vec![
        fusion::EXPERIMENT,
        noise::EXPERIMENT,
        beacons::EXPERIMENT,
        vkf::EXPERIMENT,
        plaza::EXPERIMENT,
    ]
}
