//! The cost of a `vkf` scenario ([`fathom_sim::cost`]): the shared truth at the IMU rate,
//! the strapdown integrations of every method of every run, the 1 Hz error series
//! the analysis keeps per run. The byte and time constants are measured on the preset
//! (one core).

use super::scenario::VkfScenario;
use fathom_sim::cost::{CostTerm, Held};

/// Bytes per IMU sample of the shared truth (truth sample, increments, series).
const TRUTH_SAMPLE_BYTES: f64 = 300.0;
/// Single-core time per IMU sample of one run (five methods), s.
const IMU_SAMPLE_S: f64 = 1.5e-6;
/// Bytes per second of route a run holds (1 Hz series of every method, filters).
const RUN_BYTES_PER_S: f64 = 400.0;
/// Bytes per second of route of the figure run's detailed series.
const DETAIL_BYTES_PER_S: f64 = 2_000.0;

/// The terms of `s` (checked).
pub(super) fn terms(s: &VkfScenario) -> Vec<CostTerm> {
    let runs = s.runs as f64;
    let all_runs = runs + s.literal_bias_runs as f64;
    let d = s.route.duration_s;
    let rate = s.route.imu_rate_hz;
    let imu = d * rate;
    vec![
        CostTerm::new(
            "IMU samples of the shared truth",
            imu,
            IMU_SAMPLE_S,
            imu * TRUTH_SAMPLE_BYTES,
            Held::Once,
        )
        .up("route.imu_rate_hz", rate, 100.0)
        .up("route.duration_s", d, 1620.0),
        CostTerm::new(
            "strapdown steps of every run",
            all_runs * imu,
            IMU_SAMPLE_S,
            d * RUN_BYTES_PER_S,
            Held::PerThread,
        )
        .up("route.imu_rate_hz", rate, 100.0)
        .up("route.duration_s", d, 1620.0)
        .up("runs", runs, 50.0)
        .up("literal_bias_runs", s.literal_bias_runs as f64, 10.0),
        CostTerm::new(
            "1 Hz error series kept per run and the figure run's series",
            0.0,
            0.0,
            all_runs * d * 10.0 * 8.0 + d * DETAIL_BYTES_PER_S,
            Held::Once,
        )
        .up("runs", runs, 50.0)
        .up("route.duration_s", d, 1620.0),
    ]
}
