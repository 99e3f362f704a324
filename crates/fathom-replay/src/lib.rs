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
//! - [`gnss_ins`]: GNSS / INS navigation of a drone flight (a PX4 ULog or a
//!   `gnss-ins` log): INS alone, the 12- and 15-state GPS/INS filters, against PX4's
//!   EKF2 and, in simulation, the ground truth;
//! - [`consistency`]: the tested measurements and the NIS summaries a replay reports;
//! - [`own_log`]: what the two replays of one's own log share as jobs of the runner
//!   (`fathom replay range-beacon|ins-dvl <dir>`): built-in settings, the log folder,
//!   the rows and checks, the report's notes;
//! - [`figures`]: the figures every replay draws (estimate vs truth, error with 3σ,
//!   innovations with ±3√S, NIS against a consistent filter's interval);
//! - [`data_dir`]: where a replay's data folder is;
//! - [`method_keys`]: the values each `[[methods]]` key of a replay accepts;
//! - [`scene_mesh`]: a world mesh as the scene page draws it;
//! - [`world_file`]: a user's OBJ / STL world read with its checks (the `urban`
//!   experiment's world files and the `gnss-ins` replay's `--world`).
//!
//! [`own_log_replays`] lists the own-log replays as jobs ([`range_beacon::RangeBeacon`],
//! [`ins_dvl::InsDvl`], [`gnss_ins::GnssIns`]) for the front ends, beside the paper experiments' registry.

pub mod consistency;
pub mod data_dir;
pub mod figures;
pub mod gnss_ins;
pub mod ins_dvl;
pub mod method_keys;
pub mod own_log;
pub mod plaza;
pub mod range_beacon;
pub mod scene_mesh;
pub mod world_file;

use fathom_sim::experiment::DynExperiment;

/// The replays of one's own log as jobs of the runner, in the order `fathom replay`
/// lists them: `range-beacon`, `ins-dvl`, `gnss-ins`.
pub fn own_log_replays() -> Vec<&'static dyn DynExperiment> {
    vec![
        &range_beacon::RangeBeacon,
        &ins_dvl::InsDvl,
        &gnss_ins::GnssIns,
    ]
}
