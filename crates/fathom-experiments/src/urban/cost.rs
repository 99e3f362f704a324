//! The cost of an `urban` scenario ([`fathom_sim::cost`]): per flight, the strapdown and
//! filter steps of the six methods at the IMU rate and the ray casts of the grid and
//! particle filters (grid points x beams at their update rate), which dominate; what
//! a run holds (its traces at the evaluation rate) and what the analysis keeps. The
//! constants are set from the preset's measured cost (50 runs + 3 x 20 ablation runs
//! on the 41 x 41 x 9 grid at 5 Hz: ~560 s of CPU in a release build,
//! `docs/performance.md`); the estimate is good to a factor of a few.

use super::scenario::{PresetWorld, Ranging, SceneToml, UrbanScenario};
use fathom_sim::cost::{CostTerm, Held};

/// Methods run on every flight.
const METHODS: f64 = 6.0;
/// Single-core time per IMU sample of one flight, all methods, s.
const IMU_SAMPLE_S: f64 = 1e-6;
/// Single-core time per ray the grid and particle filters would cast over the whole
/// flight, s: ~70 ns per ray cast and evaluated inside an update, times the share of
/// the flight they run (the GNSS shadow, about a fifth).
const RAY_S: f64 = 1.3e-8;
/// Bytes a flight holds per evaluation instant (truth and every method's estimate,
/// covariance diagonal, mode).
const EVAL_BYTES: f64 = 6.0 * 240.0;
/// Range finders of the `rangefinders` ranging (6 around + 1 down).
const RANGEFINDERS: f64 = 7.0;
/// The preset's values, the reference for which key a refusal names.
const PRESET_RUNS: f64 = 50.0;
const PRESET_ABLATION_RUNS: f64 = 20.0;
const PRESET_IMU_HZ: f64 = 100.0;
const PRESET_GRID_POINTS: f64 = 41.0 * 41.0 * 9.0;
const PRESET_GRID_HZ: f64 = 5.0;
const PRESET_EVAL_HZ: f64 = 5.0;
const PRESET_FLIGHT_S: f64 = 155.0;

/// Estimated flight time of a scene: rest, the path at cruise speed, the hovers.
fn flight_s(s: &UrbanScenario, scene: &SceneToml) -> f64 {
    let v = &s.vehicle;
    let (length_m, waypoints) = match &scene.path.waypoints {
        Some(w) => (
            w.windows(2)
                .map(|p| {
                    let d = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                })
                .sum::<f64>(),
            w.len() as f64,
        ),
        None => match scene.world.preset {
            Some(PresetWorld::Bridge) => (
                2.0 * scene
                    .world
                    .bridge
                    .as_ref()
                    .map_or(200.0, |b| b.deck_length_m),
                4.0,
            ),
            _ => (
                4.0 * scene
                    .world
                    .buildings
                    .as_ref()
                    .map_or(100.0, |b| b.path_side_m),
                5.0,
            ),
        },
    };
    v.rest_s + length_m / v.cruise_speed_mps + waypoints * v.hover_s
}

/// Ray casts per second of flight of the grid and particle filters in `scene`.
fn rays_per_s(s: &UrbanScenario, scene: &SceneToml) -> f64 {
    let g = s.mgpmf.grid_points;
    let points = g[0] as f64 * g[1] as f64 * g[2] as f64;
    let beams = match scene.ranging {
        Ranging::Lidar => {
            let n = ((s.lidar.last_deg - s.lidar.first_deg) / s.lidar.step_deg).floor() + 1.0;
            (n / s.mgpmf.lidar_beam_stride.max(1) as f64).ceil()
        }
        Ranging::Rangefinders => RANGEFINDERS,
    };
    // MGPMF and the particle filter (as many particles as grid points).
    2.0 * s.mgpmf.rate_hz * points * beams
}

/// The terms of `s` (checked).
pub(super) fn terms(s: &UrbanScenario) -> Vec<CostTerm> {
    let runs = s.runs as f64;
    let ablations = [
        s.ablations.gaussian_ranges.is_some(),
        s.ablations.glass_incidence.is_some(),
        s.ablations.lidar_step.is_some(),
        s.ablations.control_on_estimate.is_some(),
        s.ablations.mgpmf_posterior.is_some(),
    ]
    .iter()
    .filter(|&&a| a)
    .count() as f64;
    let ablation_runs = ablations * s.ablations.runs as f64;
    let scenes = s.scenarios.len().max(1) as f64;
    let flights: f64 = s.scenarios.iter().map(|c| flight_s(s, c)).sum();
    let longest = s
        .scenarios
        .iter()
        .map(|c| flight_s(s, c))
        .fold(0.0, f64::max);
    let rays: f64 = s
        .scenarios
        .iter()
        .map(|c| flight_s(s, c) * rays_per_s(s, c))
        .sum();
    // An ablation flies one scene: the mean scene stands for it.
    let per_scene_runs = runs + ablation_runs / scenes;
    let g = s.mgpmf.grid_points;
    let points = g[0] as f64 * g[1] as f64 * g[2] as f64;
    vec![
        CostTerm::new(
            "strapdown and filter steps of every flight (six methods)",
            per_scene_runs * flights * s.imu.rate_hz,
            IMU_SAMPLE_S,
            longest * s.evaluation.rate_hz * EVAL_BYTES,
            Held::PerThread,
        )
        .up("runs", runs, PRESET_RUNS)
        .up(
            "ablations.runs",
            s.ablations.runs as f64,
            PRESET_ABLATION_RUNS,
        )
        .up("imu.rate_hz", s.imu.rate_hz, PRESET_IMU_HZ)
        .up("evaluation.rate_hz", s.evaluation.rate_hz, PRESET_EVAL_HZ)
        .up(
            "flight time (path length / vehicle.cruise_speed_mps)",
            longest,
            PRESET_FLIGHT_S,
        ),
        CostTerm::new(
            "ray casts of the grid and particle filters",
            per_scene_runs * rays,
            RAY_S,
            // the grid (or particle set) of both filters, a few values a point
            2.0 * points * 64.0,
            Held::PerThread,
        )
        .up("runs", runs, PRESET_RUNS)
        .up("mgpmf.grid_points", points, PRESET_GRID_POINTS)
        .up("mgpmf.rate_hz", s.mgpmf.rate_hz, PRESET_GRID_HZ),
        CostTerm::new(
            "per-run rows and the error histograms the analysis keeps",
            0.0,
            0.0,
            (runs + ablation_runs) * scenes * METHODS * 16.0 * 8.0
                + scenes * METHODS * s.evaluation.histogram_bins as f64 * 8.0,
            Held::Once,
        )
        .up("runs", runs, PRESET_RUNS)
        .up(
            "evaluation.histogram_bins",
            s.evaluation.histogram_bins as f64,
            60.0,
        ),
    ]
}
