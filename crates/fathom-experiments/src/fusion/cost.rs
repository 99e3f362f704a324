//! The cost of a `fusion` scenario ([`fathom_sim::cost`]): filter steps of every run of
//! the main batches and the sensitivity sweeps, the error series the analysis keeps
//! per run, and the histograms. The byte and time constants are measured on the
//! preset (one core).

use super::scenario::FusionScenario;
use super::sim::Method;
use fathom_sim::cost::{CostTerm, Held};

/// Single-core time per mission step of one run (INS, DVL and every method), s.
const STEP_S: f64 = 2e-5;
/// Bytes per mission step of a run while it runs (sensor data, every method's state).
const STEP_BYTES: f64 = 2_000.0;
/// Bytes per mission step of the shared mission (truth).
const MISSION_STEP_BYTES: f64 = 200.0;
/// Bytes per histogram bin and method (counts, bar geometry, SVG text).
const BIN_BYTES: f64 = 400.0;

/// The terms of `s` (checked).
pub(super) fn terms(s: &FusionScenario) -> Vec<CostTerm> {
    let runs = s.runs as f64;
    let d = s.mission.duration_s;
    let steps = d / s.mission.step_s;
    let methods = Method::ALL.len() as f64;
    // The main batch and the other reading's, then the sweeps at a quarter of the
    // runs (at most `sensitivity.runs`).
    let sweep_runs = s.runs.div_ceil(4).clamp(2, s.sensitivity.runs.max(2)) as f64;
    let sweeps = (s.sensitivity.dvl_vel_noise_mps.len() + s.sensitivity.filter_v_dvl.len()) as f64;
    let all_runs = 2.0 * runs + sweeps * sweep_runs;
    vec![
        CostTerm::new(
            "mission steps of every run",
            all_runs * steps,
            STEP_S,
            steps * STEP_BYTES,
            Held::PerThread,
        )
        .up("mission.duration_s", d, 1000.0)
        .down("mission.step_s", s.mission.step_s, 1.0)
        .up("runs", runs, 200.0)
        .up("sensitivity.runs", sweep_runs, 20.0),
        CostTerm::new(
            "the mission",
            steps,
            0.0,
            steps * MISSION_STEP_BYTES,
            Held::Once,
        )
        .up("mission.duration_s", d, 1000.0)
        .down("mission.step_s", s.mission.step_s, 1.0),
        CostTerm::new(
            "error series kept per run",
            0.0,
            0.0,
            all_runs * methods * 2.0 * steps * 8.0,
            Held::Once,
        )
        .up("runs", runs, 200.0)
        .up("mission.duration_s", d, 1000.0)
        .down("mission.step_s", s.mission.step_s, 1.0),
        CostTerm::new(
            "histograms",
            s.analysis.histogram_bins as f64 * methods * 2.0,
            1e-7,
            s.analysis.histogram_bins as f64 * methods * 2.0 * BIN_BYTES,
            Held::Once,
        )
        .up(
            "analysis.histogram_bins",
            s.analysis.histogram_bins as f64,
            40.0,
        ),
    ]
}
