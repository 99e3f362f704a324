//! The cost of a `noise` scenario ([`fathom_sim::cost`]): the motion steps and sensor
//! samples of the Monte Carlo runs and of the long run. The byte and time constants
//! are measured on the preset (one core).

use super::scenario::NoiseScenario;
use fathom_sim::cost::{CostTerm, Held};

/// Bytes of one stored motion step.
const MOTION_STEP_BYTES: f64 = 120.0;
/// Bytes per long-run motion step with its sensor samples (measured: the preset's
/// 360 000 steps peak at about 230 MB).
const LONG_STEP_BYTES: f64 = 700.0;
/// Bytes of one stored sample of the five channels.
const EPOCH_BYTES: f64 = 96.0;
/// Single-core time per motion step, s.
const MOTION_STEP_S: f64 = 2e-7;
/// Single-core time per sampled epoch (five channels), s.
const EPOCH_S: f64 = 4e-7;
/// Single-core time per long-run motion step with its sampling, s.
const LONG_STEP_S: f64 = 7e-6;

/// The terms of `s` (checked).
pub(super) fn terms(s: &NoiseScenario) -> Vec<CostTerm> {
    let runs = s.runs as f64;
    let d = s.motion.duration_s;
    let steps = d / s.motion.step_s;
    let cases = s.cases.len() as f64;
    let epochs = d / s.timing.period_s;
    let long_steps = s.long_run.duration_s / s.long_run.step_s;
    vec![
        CostTerm::new(
            "motion steps",
            runs * steps,
            MOTION_STEP_S,
            steps * MOTION_STEP_BYTES,
            Held::PerThread,
        )
        .up("motion.duration_s", d, 180.0)
        .down("motion.step_s", s.motion.step_s, 0.01)
        .up("runs", runs, 200.0),
        CostTerm::new(
            "sensor epochs (four ranges and depth) per case",
            runs * cases * epochs,
            EPOCH_S,
            cases * epochs * EPOCH_BYTES,
            Held::PerThread,
        )
        .up("motion.duration_s", d, 180.0)
        .down("timing.period_s", s.timing.period_s, 0.1)
        .up("runs", runs, 200.0)
        .up("cases", cases, 5.0),
        CostTerm::new(
            "the long run",
            long_steps,
            LONG_STEP_S,
            long_steps * LONG_STEP_BYTES,
            Held::Once,
        )
        .up("long_run.duration_s", s.long_run.duration_s, 36_000.0)
        .down("long_run.step_s", s.long_run.step_s, 0.1),
        CostTerm::new(
            "per-run covariances kept for the intervals",
            0.0,
            0.0,
            runs * cases * 25.0 * 8.0,
            Held::Once,
        )
        .up("runs", runs, 200.0),
    ]
}
