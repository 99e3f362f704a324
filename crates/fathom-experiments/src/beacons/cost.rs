//! The cost of a `beacons` scenario ([`fathom_sim::cost`]): motion steps, sensor samples
//! and filter updates per run, what a run holds while it runs and what the analysis
//! keeps. The byte and time constants are measured on the preset (one core).

use super::scenario::{BeaconsScenario, TimingKind};
use fathom_sim::cost::{CostTerm, Held};

/// Bytes of one stored motion step (pose, velocity, time).
const MOTION_STEP_BYTES: f64 = 120.0;
/// Bytes of one stored sensor sample (value, stamps, flags) and its filter event.
const SAMPLE_BYTES: f64 = 64.0;
/// Single-core time per motion step, s.
const MOTION_STEP_S: f64 = 2e-7;
/// Single-core time per sensor sample through the simulation and the three schemes, s.
const SAMPLE_S: f64 = 8e-7;
/// Runs per worker thread whose records are held at once (the driver's chunk).
const RECORDS_IN_FLIGHT: f64 = 32.0;
/// The preset's values, the reference for which key a refusal names.
const PRESET_DURATION_S: f64 = 180.0;
const PRESET_STEP_S: f64 = 0.01;
const PRESET_RUNS: f64 = 100.0;
const PRESET_EPOCH_S: f64 = 0.1;

/// The terms of `s` (checked).
pub(super) fn terms(s: &BeaconsScenario) -> Vec<CostTerm> {
    let runs = s.runs as f64;
    let d = s.motion.duration_s;
    let steps = d / s.motion.step_s;
    let t = &s.timing;
    let per_case = |beacons: f64, timing: TimingKind| match timing {
        TimingKind::Sync => d * (beacons + 3.0) / t.sync_period_s,
        TimingKind::Async => {
            d * (1.0 / t.dvl_period_s
                + 1.0 / t.ahrs_period_s
                + beacons / t.range_period_s
                + 1.0 / t.depth_period_s)
        }
    };
    let k = s.beacons.positions.len() as f64;
    let cases: f64 = s.cases.iter().map(|c| per_case(k, c.timing)).sum();
    let main_timing = s
        .cases
        .iter()
        .find(|c| c.name == super::MAIN_CASE)
        .map_or(TimingKind::Async, |c| c.timing);
    let layouts: f64 = s
        .geometry
        .iter()
        .map(|g| per_case(g.positions.len() as f64, main_timing))
        .sum();
    let batches = 1.0 + s.geometry.len() as f64;
    let epochs = d / s.ekf.epoch_period_s;
    let n_cases = s.cases.len() as f64 + s.geometry.len() as f64;
    let mut samples = CostTerm::new(
        "sensor samples and filter updates",
        runs * (cases + layouts),
        SAMPLE_S,
        cases.max(layouts / batches) * SAMPLE_BYTES,
        Held::PerThread,
    )
    .up("motion.duration_s", d, PRESET_DURATION_S)
    .up("runs", runs, PRESET_RUNS)
    .up("beacons.positions", k, 4.0);
    // The clocks in use; the fastest one drives the sample count most.
    if s.cases.iter().any(|c| c.timing == TimingKind::Async) {
        samples = samples
            .down("timing.ahrs_period_s", t.ahrs_period_s, 0.01)
            .down("timing.depth_period_s", t.depth_period_s, 0.02)
            .down("timing.range_period_s", t.range_period_s, 0.1)
            .down("timing.dvl_period_s", t.dvl_period_s, 0.2);
    }
    if s.cases.iter().any(|c| c.timing == TimingKind::Sync) {
        samples = samples.down("timing.sync_period_s", t.sync_period_s, 0.1);
    }
    vec![
        CostTerm::new(
            "motion steps",
            runs * batches * steps,
            MOTION_STEP_S,
            steps * MOTION_STEP_BYTES,
            Held::PerThread,
        )
        .up("motion.duration_s", d, PRESET_DURATION_S)
        .down("motion.step_s", s.motion.step_s, PRESET_STEP_S)
        .up("runs", runs, PRESET_RUNS),
        samples,
        // Each run's record carries its error series until it is folded.
        CostTerm::new(
            "error series of the runs in flight",
            0.0,
            0.0,
            RECORDS_IN_FLIGHT * n_cases * 3.0 * epochs * 8.0,
            Held::PerThread,
        )
        .up("motion.duration_s", d, PRESET_DURATION_S)
        .down("ekf.epoch_period_s", s.ekf.epoch_period_s, PRESET_EPOCH_S),
        // The batch sums, the CSV and the figures: per evaluation epoch.
        CostTerm::new(
            "per-epoch sums, CSV and figures",
            0.0,
            0.0,
            n_cases * 3.0 * epochs * 8.0 * 8.0,
            Held::Once,
        )
        .up("motion.duration_s", d, PRESET_DURATION_S)
        .down("ekf.epoch_period_s", s.ekf.epoch_period_s, PRESET_EPOCH_S),
        CostTerm::new(
            "per-run statistics kept for the intervals",
            0.0,
            0.0,
            runs * batches * s.cases.len().max(1) as f64 * 3.0 * 96.0,
            Held::Once,
        )
        .up("runs", runs, PRESET_RUNS),
    ]
}
