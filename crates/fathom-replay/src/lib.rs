//! Replaying estimators on recorded (real) data sets, shared by the paper experiments
//! and the `fathom replay` command.
//!
//! - [`plaza`]: range-beacon localization on the CMU Plaza logs: settings (TOML
//!   schema and checked form), the prepared event stream, the methods (dead reckoning,
//!   AS / SC / SI, ablations) and the range-error analysis against ground truth. Its
//!   outputs are the `plaza` experiment's (`fathom_experiments::plaza`);
//! - [`range_beacon`]: range-beacon localization on one's own log in fathom's CSV
//!   layout (odometry through the Plaza engine, or DVL + heading), with or without
//!   ground truth;
//! - [`ins_dvl`]: INS / DVL navigation on one's own log (PINS, INS-DVL, gated
//!   INS-DVL, the RPM velocity filter, the 15-state ESKF);
//! - [`consistency`]: the tested measurements and the NIS summaries a replay reports;
//! - [`own_log`]: the front end of `fathom replay range-beacon|ins-dvl <dir>`
//!   (settings, log, replay, the output texts);
//! - [`figures`]: the figures every replay draws (estimate vs truth, error with 3σ,
//!   innovations with ±3√S, NIS against a consistent filter's interval);
//! - [`data_dir`]: where a replay's data folder is.

pub mod consistency;
pub mod data_dir;
pub mod figures;
pub mod ins_dvl;
pub mod own_log;
pub mod plaza;
pub mod range_beacon;

