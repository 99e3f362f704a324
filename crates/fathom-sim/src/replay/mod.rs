//! Replaying estimators on recorded (real) data sets, shared by the paper experiments
//! and the `fathom replay` command.
//!
//! - [`plaza`]: range-beacon localization on the CMU Plaza logs: settings (TOML
//!   schema and checked form), the run (dead reckoning, AS / SC / SI, ablations) and
//!   the range-error analysis against ground truth;
//! - [`plaza_output`]: its CSV series, SVG figures, `summary.json` rows and claims,
//!   and the report text.

pub mod plaza;
pub mod plaza_output;
