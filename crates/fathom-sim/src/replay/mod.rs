//! Replaying estimators on recorded (real) data sets, shared by the paper experiments
//! and the `fathom replay` command.
//!
//! - [`plaza`]: range-beacon localization on the CMU Plaza logs: settings (TOML
//!   schema and checked form), the prepared event stream, the methods (dead reckoning,
//!   AS / SC / SI, ablations) and the range-error analysis against ground truth. Its
//!   outputs are the `plaza` experiment's ([`crate::experiments::plaza`]).

pub mod plaza;
