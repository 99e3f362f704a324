//! The `fusion` experiment: INS + DVL fusion architectures of Lee & Yoon 2011
//! (seed 000, spec A) — measurement fusion (MF), track-to-track fusion (T2T) and
//! the proposed equalize-fuse-feedback filter (EFF) — with the ablations
//! `EFF-no-feedback` and `EFF-no-equalization`, two further track-to-track rules
//! (`T2T-BC`, `T2T-CI`), the raw sensors as references, the course-change analysis
//! and a sensitivity sweep over the DVL noise and the filters' `v_DVL`.
//!
//! One mission (fixed trajectory seed), many noise realizations: run `i` draws the
//! INS and DVL seeds from ChaCha stream `i` of the base seed, and every method of a
//! run sees the same sensor noise (see [`sim`]).

pub mod sim;

mod figures;
mod report;

use fathom_sensors::integrated::{DvlDrParams, InsParams};
use fathom_stats::mean_ci;
use fathom_traj::{
    CheckedFusionMissionParams, FusionMission, FusionMissionParams, generate_fusion_mission,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::SimError;
use crate::experiment::{Experiment, ExperimentContext, ExperimentOutput};
use crate::output::{Claim, Row, Summary};
use crate::scenario::{require_non_negative, require_positive};
use fathom_core::units::{deg_to_rad, knots_to_mps};
use sim::{FilterTuning, Method, MethodMetrics, RunConfig, RunOutput, method_metrics};

/// Registry entry of the `fusion` experiment.
pub const EXPERIMENT: Experiment = Experiment {
    name: "fusion",
    seed_doc: "000_777a2c84247a6c44.txt",
    default_scenario: "scenarios/fusion.toml",
    run,
};

// ---------------------------------------------------------------------------
// Scenario schema
// ---------------------------------------------------------------------------

/// The `fusion` scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FusionScenario {
    /// The experiment this scenario is for: must be `"fusion"` (lets `fathom run`
    /// pick the experiment from the file).
    pub experiment: String,
    /// Monte Carlo runs (noise realizations of the one mission).
    pub runs: usize,
    /// Base seed; run `i` uses ChaCha stream `i`.
    pub base_seed: u64,
    /// Seed of the mission's knot perturbations (fixed across runs). The generated
    /// mission must pass its self-checks (speeds, depth, course changes); that is
    /// only checked when running, not by `fathom check`.
    pub trajectory_seed: u64,
    /// The mission.
    pub mission: MissionToml,
    /// The INS.
    pub ins: InsToml,
    /// The DVL.
    pub dvl: DvlToml,
    /// Filter tuning.
    pub filters: FiltersToml,
    /// Analysis settings.
    pub analysis: AnalysisToml,
    /// Sensitivity sweep.
    pub sensitivity: SensitivityToml,
}

/// `[mission]`: the cubic-spline UUV mission (paper §4.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionToml {
    /// Mission length, s.
    pub duration_s: f64,
    /// Sensor and filter step, s (paper: T = 1).
    pub step_s: f64,
    /// Course changes during the search (paper: 10; knots = 2 n + 5).
    pub n_course_changes: usize,
    /// Search depth, m.
    pub search_depth_m: f64,
    /// Allowed depth deviation during the search, m.
    pub depth_tolerance_m: f64,
    /// Slowest allowed speed during the search, kt.
    pub min_speed_kt: f64,
    /// Fastest allowed speed during the search, kt.
    pub max_speed_kt: f64,
    /// Nominal leg speeds, kt (`n_course_changes + 1` values).
    pub leg_speeds_kt: Vec<f64>,
    /// Eastward offset of each U-turn, m.
    pub turn_width_m: f64,
    /// Std of the random horizontal knot offsets, m.
    pub perturbation_sigma_m: f64,
    /// Smallest heading change counted as a course change, deg.
    pub min_course_change_deg: f64,
}

/// `[ins]`: accelerometer errors of the INS integrator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InsToml {
    /// Per-axis constant bias std, m/s^2.
    pub accel_bias_sigma_mps2: f64,
    /// Per-axis white noise std per sample, m/s^2.
    pub accel_noise_sigma_mps2: f64,
}

/// `[dvl]`: velocity errors of the DVL dead reckoning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DvlToml {
    /// Half width `h` of the per-axis scale-factor error `U(-h, h)`, drawn per run; a
    /// fraction (0.002 = 0.2 %).
    pub scale_half_width: f64,
    /// Per-axis white velocity noise std, m/s.
    pub vel_noise_sigma_mps: f64,
}

/// `[filters]`: paper tuning `Q = w^2 I6`, `R = v^2 I3`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FiltersToml {
    /// INS track process noise scale, m.
    pub w_ins_m: f64,
    /// DVL track process noise scale, m.
    pub w_dvl_m: f64,
    /// INS position measurement std, m.
    pub v_ins_m: f64,
    /// DVL position measurement std, m.
    pub v_dvl_m: f64,
    /// MF process noise scale, m.
    pub w_mf_m: f64,
    /// Initial position std of every filter, m.
    pub initial_sigma_pos_m: f64,
    /// Initial velocity std of every filter, m/s.
    pub initial_sigma_vel_mps: f64,
}

/// `[analysis]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisToml {
    /// Half width of the window around each course change, s (spec: 7).
    pub turn_half_window_s: f64,
    /// A method "spikes" at turns when its turn ratio exceeds this; EFF is robust
    /// when its ratio is at most this (spec: 1.1).
    pub turn_ratio_limit: f64,
    /// Centre of the zoom window of the path figures, s (paper: 440).
    pub zoom_center_s: f64,
    /// Half width of the zoom window, s (paper: 7).
    pub zoom_half_width_s: f64,
    /// Bins of the error histograms.
    pub histogram_bins: usize,
    /// Smallest improvement, relative to the competitor's value, that makes "X beats
    /// Y" hold: the paired 95 % CI of `X - Y` must lie below `-min * Y` (the paper
    /// claims 25..60 % improvements, not differences of micrometres).
    pub min_relative_improvement: f64,
}

/// `[sensitivity]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensitivityToml {
    /// Monte Carlo runs per sweep value (with `--runs N`: `ceil(N / 4)`, at least 2,
    /// at most this).
    pub runs: usize,
    /// DVL velocity noise values, m/s (filters keep their tuning).
    pub dvl_vel_noise_mps: Vec<f64>,
    /// Filters' `v_DVL` values, m (sensors keep their defaults).
    pub filter_v_dvl_m: Vec<f64>,
}

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct FusionSetup {
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed.
    pub base_seed: u64,
    /// Trajectory seed.
    pub trajectory_seed: u64,
    /// Mission parameters.
    pub mission: CheckedFusionMissionParams,
    /// Per-run configuration.
    pub run: RunConfig,
    /// Unchecked INS parameters (for the report).
    pub ins_params: InsParams,
    /// Unchecked DVL parameters (the sweep varies them).
    pub dvl_params: DvlDrParams,
    /// Course-change window half width, s.
    pub turn_half_window: f64,
    /// Turn-ratio limit.
    pub turn_ratio_limit: f64,
    /// Zoom window `(centre, half width)`, s.
    pub zoom: (f64, f64),
    /// Histogram bins.
    pub histogram_bins: usize,
    /// Smallest relative improvement for a "beats" claim.
    pub min_relative_improvement: f64,
    /// Runs per sensitivity value.
    pub sensitivity_runs: usize,
    /// DVL noise sweep, m/s.
    pub sweep_dvl_noise: Vec<f64>,
    /// `v_DVL` sweep, m.
    pub sweep_v_dvl: Vec<f64>,
}

fn sweep(file: &str, key: &str, values: &[f64]) -> Result<Vec<f64>, SimError> {
    if values.len() < 2 {
        return Err(SimError::invalid(
            file,
            key,
            format!("needs at least 2 values, got {}", values.len()),
        ));
    }
    for (i, &v) in values.iter().enumerate() {
        require_positive(file, &format!("{key}[{i}]"), v)?;
        if i > 0 && v <= values[i - 1] {
            return Err(SimError::invalid(
                file,
                format!("{key}[{i}]"),
                format!("values must increase, {v} follows {}", values[i - 1]),
            ));
        }
    }
    Ok(values.to_vec())
}

impl FusionScenario {
    /// Checks every value and converts the scenario into checked parameters;
    /// `runs_override` is `--runs`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the file and key.
    pub fn check(&self, file: &str, runs_override: Option<usize>) -> Result<FusionSetup, SimError> {
        crate::scenario::require_experiment(file, &self.experiment, "fusion")?;
        let runs = runs_override.unwrap_or(self.runs);
        if runs < 2 {
            return Err(SimError::invalid(
                file,
                "runs",
                format!("needs at least 2 Monte Carlo runs for a confidence interval, got {runs}"),
            ));
        }
        let m = &self.mission;
        require_positive(file, "mission.duration_s", m.duration_s)?;
        require_positive(file, "mission.step_s", m.step_s)?;
        let n_steps_f = (m.duration_s / m.step_s).round();
        if (n_steps_f * m.step_s - m.duration_s).abs() > 1e-9 * m.duration_s || n_steps_f < 10.0 {
            return Err(SimError::invalid(
                file,
                "mission.step_s",
                format!(
                    "must divide mission.duration_s ({} s) into at least 10 steps",
                    m.duration_s
                ),
            ));
        }
        require_positive(file, "mission.search_depth_m", m.search_depth_m)?;
        require_positive(file, "mission.depth_tolerance_m", m.depth_tolerance_m)?;
        require_positive(file, "mission.min_speed_kt", m.min_speed_kt)?;
        require_positive(file, "mission.max_speed_kt", m.max_speed_kt)?;
        require_positive(file, "mission.turn_width_m", m.turn_width_m)?;
        require_non_negative(file, "mission.perturbation_sigma_m", m.perturbation_sigma_m)?;
        require_positive(
            file,
            "mission.min_course_change_deg",
            m.min_course_change_deg,
        )?;
        for (i, v) in m.leg_speeds_kt.iter().enumerate() {
            require_positive(file, &format!("mission.leg_speeds_kt[{i}]"), *v)?;
        }
        let mission = FusionMissionParams {
            duration: m.duration_s,
            // Saturating: a count too large for the pattern is refused by `check`.
            n_knots: m.n_course_changes.saturating_mul(2).saturating_add(5),
            n_course_changes: m.n_course_changes,
            search_depth: m.search_depth_m,
            depth_tolerance: m.depth_tolerance_m,
            min_speed: knots_to_mps(m.min_speed_kt),
            max_speed: knots_to_mps(m.max_speed_kt),
            leg_speeds: m.leg_speeds_kt.iter().map(|&v| knots_to_mps(v)).collect(),
            turn_width: m.turn_width_m,
            perturbation_sigma: m.perturbation_sigma_m,
            min_course_change: deg_to_rad(m.min_course_change_deg),
            check_dt: m.step_s,
        }
        .check()
        .map_err(|e| SimError::invalid(file, "mission", e.to_string()))?;

        let ins = InsParams {
            accel_bias_sigma: self.ins.accel_bias_sigma_mps2,
            accel_noise_sigma: self.ins.accel_noise_sigma_mps2,
        };
        require_non_negative(file, "ins.accel_bias_sigma_mps2", ins.accel_bias_sigma)?;
        require_non_negative(file, "ins.accel_noise_sigma_mps2", ins.accel_noise_sigma)?;
        let ins_params = ins;
        let ins = ins
            .check()
            .map_err(|e| SimError::invalid(file, "ins", e.to_string()))?;
        let dvl_params = DvlDrParams {
            scale_half_width: self.dvl.scale_half_width,
            vel_noise_sigma: self.dvl.vel_noise_sigma_mps,
        };
        require_non_negative(file, "dvl.scale_half_width", dvl_params.scale_half_width)?;
        require_non_negative(file, "dvl.vel_noise_sigma_mps", dvl_params.vel_noise_sigma)?;
        let dvl = dvl_params
            .check()
            .map_err(|e| SimError::invalid(file, "dvl", e.to_string()))?;

        let f = &self.filters;
        let tuning = FilterTuning {
            w_ins: require_non_negative(file, "filters.w_ins_m", f.w_ins_m)?,
            w_dvl: require_non_negative(file, "filters.w_dvl_m", f.w_dvl_m)?,
            v_ins: require_positive(file, "filters.v_ins_m", f.v_ins_m)?,
            v_dvl: require_positive(file, "filters.v_dvl_m", f.v_dvl_m)?,
            w_mf: require_non_negative(file, "filters.w_mf_m", f.w_mf_m)?,
            p0_pos: require_positive(file, "filters.initial_sigma_pos_m", f.initial_sigma_pos_m)?,
            p0_vel: require_positive(
                file,
                "filters.initial_sigma_vel_mps",
                f.initial_sigma_vel_mps,
            )?,
        };
        let a = &self.analysis;
        require_positive(file, "analysis.turn_half_window_s", a.turn_half_window_s)?;
        require_positive(file, "analysis.turn_ratio_limit", a.turn_ratio_limit)?;
        require_non_negative(file, "analysis.zoom_center_s", a.zoom_center_s)?;
        require_positive(file, "analysis.zoom_half_width_s", a.zoom_half_width_s)?;
        if a.zoom_center_s > m.duration_s {
            return Err(SimError::invalid(
                file,
                "analysis.zoom_center_s",
                format!("must lie within the mission (0..{} s)", m.duration_s),
            ));
        }
        if a.histogram_bins < 2 {
            return Err(SimError::invalid(
                file,
                "analysis.histogram_bins",
                "needs at least 2 bins",
            ));
        }
        let s = &self.sensitivity;
        if s.runs < 2 {
            return Err(SimError::invalid(
                file,
                "sensitivity.runs",
                format!("needs at least 2 runs, got {}", s.runs),
            ));
        }
        Ok(FusionSetup {
            runs,
            base_seed: self.base_seed,
            trajectory_seed: self.trajectory_seed,
            mission,
            run: RunConfig {
                step: m.step_s,
                n_steps: n_steps_f as usize,
                ins,
                dvl,
                tuning,
            },
            ins_params,
            dvl_params,
            turn_half_window: a.turn_half_window_s,
            turn_ratio_limit: a.turn_ratio_limit,
            zoom: (a.zoom_center_s, a.zoom_half_width_s),
            histogram_bins: a.histogram_bins,
            min_relative_improvement: require_non_negative(
                file,
                "analysis.min_relative_improvement",
                a.min_relative_improvement,
            )?,
            sensitivity_runs: runs_override.map_or(s.runs, |r| r.div_ceil(4).clamp(2, s.runs)),
            sweep_dvl_noise: sweep(file, "sensitivity.dvl_vel_noise_mps", &s.dvl_vel_noise_mps)?,
            sweep_v_dvl: sweep(file, "sensitivity.filter_v_dvl_m", &s.filter_v_dvl_m)?,
        })
    }
}

impl FusionSetup {
    /// The mission (generated from the trajectory seed).
    ///
    /// # Errors
    /// [`SimError::Model`] when the perturbed mission fails its own checks.
    pub fn mission(&self) -> Result<FusionMission, SimError> {
        generate_fusion_mission(
            &self.mission,
            &mut ChaCha8Rng::seed_from_u64(self.trajectory_seed),
        )
        .map_err(|e| SimError::model("fusion mission (trajectory_seed)", e))
    }
}

// ---------------------------------------------------------------------------
// Paper values (reference column only)
// ---------------------------------------------------------------------------

/// Table 2 (3D) and Table 3 (2D): `(mean_3d, std_3d, mean_2d, std_2d)`.
fn paper_values(m: Method) -> Option<[f64; 4]> {
    match m {
        Method::Mf => Some([3.67, 1.01, 3.57, 1.23]),
        Method::T2t => Some([1.83, 1.53, 2.70, 1.48]),
        Method::Eff => Some([1.38, 0.32, 1.07, 0.29]),
        _ => None,
    }
}

/// The metrics of `summary.json` (per method).
pub const METRICS: [&str; 5] = ["mean_3d", "std_3d", "mean_2d", "std_2d", "turn_ratio_3d"];

fn metric_of(m: &MethodMetrics, name: &str) -> f64 {
    match name {
        "mean_3d" => m.mean_3d,
        "std_3d" => m.std_3d,
        "mean_2d" => m.mean_2d,
        "std_2d" => m.std_2d,
        "turn_ratio_3d" => m.turn_ratio_3d,
        "max_3d" => m.max_3d,
        _ => m.final_3d,
    }
}

// ---------------------------------------------------------------------------
// Monte Carlo
// ---------------------------------------------------------------------------

/// One run's metrics per method (index of [`Method::ALL`]) and its error series.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Per-method metrics (`None` for methods not computed).
    pub metrics: Vec<Option<MethodMetrics>>,
    /// The run's error series.
    pub output: RunOutput,
}

/// Simulates one run and computes the metrics of `methods`.
///
/// # Errors
/// As [`sim::simulate_run`] and [`sim::method_metrics`].
pub fn run_once(
    setup: &FusionSetup,
    cfg: &RunConfig,
    mission: &FusionMission,
    methods: &[Method],
    keep_paths: bool,
    rng: &mut ChaCha8Rng,
) -> Result<RunResult, SimError> {
    let output = sim::simulate_run(cfg, mission.trajectory(), methods, keep_paths, rng)?;
    let mut metrics = vec![None; Method::ALL.len()];
    for &m in methods {
        let i = m.index();
        metrics[i] = Some(method_metrics(
            &output.times,
            &output.err_3d[i],
            &output.err_2d[i],
            mission.course_changes(),
            setup.turn_half_window,
        )?);
    }
    Ok(RunResult { metrics, output })
}

/// Values of `metric` of `method` over runs.
pub fn values(results: &[RunResult], method: Method, metric: &str) -> Vec<f64> {
    results
        .iter()
        .filter_map(|r| r.metrics[method.index()].as_ref())
        .map(|m| metric_of(m, metric))
        .collect()
}

/// Mean and 95 % CI of a list of run values.
fn ci(values: &[f64]) -> Result<(f64, [f64; 2]), SimError> {
    let c = mean_ci(values).map_err(|e| SimError::model("Monte Carlo mean", e))?;
    Ok((c.mean, c.ci95.unwrap_or([c.mean, c.mean])))
}

/// Paired difference `a - b` of a metric over runs: mean and 95 % CI.
fn paired(
    results: &[RunResult],
    a: Method,
    b: Method,
    metric: &str,
) -> Result<(f64, [f64; 2]), SimError> {
    let va = values(results, a, metric);
    let vb = values(results, b, metric);
    let d: Vec<f64> = va.iter().zip(&vb).map(|(x, y)| x - y).collect();
    ci(&d)
}

/// Methods computed in the sensitivity sweep (the paper's three, the ablations and
/// the DVL reference; the extra fusion rules are left out to keep the run short).
const SWEEP_METHODS: [Method; 6] = [
    Method::Mf,
    Method::T2t,
    Method::Eff,
    Method::EffNoFeedback,
    Method::EffNoEqualization,
    Method::DvlDr,
];

/// One sweep: per value, per method, mean 3D error and its CI.
struct SweepResult {
    key: &'static str,
    label: &'static str,
    values: Vec<f64>,
    /// `[value][method in SWEEP_METHODS] -> (mean, ci)`.
    means: Vec<Vec<(f64, [f64; 2])>>,
}

fn run_sweep(
    ctx: &ExperimentContext,
    setup: &FusionSetup,
    mission: &FusionMission,
    key: &'static str,
    label: &'static str,
    values: &[f64],
    configure: impl Fn(&RunConfig, f64) -> Result<RunConfig, SimError> + Sync,
) -> Result<SweepResult, SimError> {
    let mut means = Vec::with_capacity(values.len());
    for &v in values {
        let cfg = configure(&setup.run, v)?;
        let results: Vec<RunResult> = ctx.try_monte_carlo_labeled(
            &format!("fusion: sensitivity {key} = {v}"),
            setup.sensitivity_runs,
            setup.base_seed,
            |_, rng| run_once(setup, &cfg, mission, &SWEEP_METHODS, false, rng),
        )?;
        let row = SWEEP_METHODS
            .iter()
            .map(|&m| ci(&values_of_mean(&results, m)))
            .collect::<Result<Vec<_>, _>>()?;
        means.push(row);
    }
    Ok(SweepResult {
        key,
        label,
        values: values.to_vec(),
        means,
    })
}

fn values_of_mean(results: &[RunResult], m: Method) -> Vec<f64> {
    values(results, m, "mean_3d")
}

// ---------------------------------------------------------------------------
// The experiment
// ---------------------------------------------------------------------------

fn run(ctx: &ExperimentContext) -> Result<ExperimentOutput, SimError> {
    let scenario: FusionScenario = ctx.load_scenario()?;
    let mut setup = scenario.check(&ctx.scenario_label, ctx.runs)?;
    // `fathom run --seed`: every batch and the figure run below use this seed.
    setup.base_seed = ctx.seed_or(setup.base_seed);
    let mission = setup.mission()?;

    let results: Vec<RunResult> = ctx.try_monte_carlo(setup.runs, setup.base_seed, |_, rng| {
        run_once(&setup, &setup.run, &mission, &Method::ALL, false, rng)
    })?;
    // Run 0 again, keeping the paths for the figures (same stream: same numbers).
    let run0 = run_once(
        &setup,
        &setup.run,
        &mission,
        &Method::ALL,
        true,
        &mut crate::montecarlo::run_rng(setup.base_seed, 0),
    )?;

    let sweep_noise = run_sweep(
        ctx,
        &setup,
        &mission,
        "dvl_vel_noise_mps",
        "DVL velocity noise std (m/s)",
        &setup.sweep_dvl_noise,
        |base, v| {
            let dvl = DvlDrParams {
                vel_noise_sigma: v,
                ..setup.dvl_params
            }
            .check()
            .map_err(|e| SimError::model("sensitivity DVL parameters", e))?;
            Ok(RunConfig {
                dvl,
                ..base.clone()
            })
        },
    )?;
    let sweep_v = run_sweep(
        ctx,
        &setup,
        &mission,
        "filter_v_dvl_m",
        "filters' v_DVL (m)",
        &setup.sweep_v_dvl,
        |base, v| {
            let mut cfg = base.clone();
            cfg.tuning.v_dvl = v;
            Ok(cfg)
        },
    )?;

    let mut summary = Summary::new(
        EXPERIMENT.name,
        EXPERIMENT.seed_doc,
        setup.runs,
        setup.base_seed,
    );
    for m in Method::ALL {
        let paper = paper_values(m);
        for (k, metric) in METRICS.iter().enumerate() {
            let (mean, [lo, hi]) = ci(&values(&results, m, metric))?;
            summary.push_row(
                Row::new(m.name(), *metric, mean)
                    .with_paper(paper.and_then(|p| p.get(k).copied()))
                    .with_ci95(lo, hi),
            );
        }
    }
    // The INS integrator under EFF feedback (what the acceptance test bounds).
    let ins_fb_mean: Vec<f64> = results
        .iter()
        .map(|r| {
            let s = &r.output.ins_err_with_feedback;
            s.iter().sum::<f64>() / s.len().max(1) as f64
        })
        .collect();
    let ins_fb_max: Vec<f64> = results
        .iter()
        .map(|r| {
            r.output
                .ins_err_with_feedback
                .iter()
                .copied()
                .fold(0.0, f64::max)
        })
        .collect();
    let (m_fb, [lo, hi]) = ci(&ins_fb_mean)?;
    summary.push_row(Row::new("EFF", "ins_integrator_mean_err", m_fb).with_ci95(lo, hi));
    let (m_fbx, [lo, hi]) = ci(&ins_fb_max)?;
    summary.push_row(Row::new("EFF", "ins_integrator_max_err", m_fbx).with_ci95(lo, hi));

    let claims = claims(&setup, &results)?;
    for c in claims {
        summary.push_claim(c);
    }
    summary.extra.insert(
        "course_changes_s".into(),
        serde_json::json!(mission.course_changes()),
    );
    summary.extra.insert(
        "sensitivity".into(),
        report::sweeps_json(&[&sweep_noise, &sweep_v]),
    );

    figures::write_all(
        ctx,
        &setup,
        &mission,
        &results,
        &run0,
        &[&sweep_noise, &sweep_v],
    )?;
    let report_section = report::section(&setup, &mission, &results, &[&sweep_noise, &sweep_v])?;
    Ok(ExperimentOutput {
        summary,
        report_section,
    })
}

/// Whether `a` beats every method in `others` on `metric` (paired 95 % CI of the
/// difference entirely below zero), with the numbers.
fn beats_all(
    setup: &FusionSetup,
    results: &[RunResult],
    a: Method,
    others: &[Method],
    metric: &str,
) -> Result<(bool, String), SimError> {
    let mut holds = true;
    let mut parts = vec![format!(
        "{} {:.4}",
        a.name(),
        ci(&values(results, a, metric))?.0
    )];
    for &b in others {
        let (mb, _) = ci(&values(results, b, metric))?;
        let (d, [lo, hi]) = paired(results, a, b, metric)?;
        holds &= hi < -setup.min_relative_improvement * mb;
        parts.push(format!(
            "{} {:.4} ({} - {} = {:+.2e} m, paired 95 % CI [{:+.2e}, {:+.2e}])",
            b.name(),
            mb,
            a.name(),
            b.name(),
            d,
            lo,
            hi
        ));
    }
    Ok((holds, parts.join("; ")))
}

fn with_threshold(setup: &FusionSetup, detail: String) -> String {
    format!(
        "{detail}; holds when every paired CI lies below -{} x the competitor's value",
        setup.min_relative_improvement
    )
}

fn claims(setup: &FusionSetup, results: &[RunResult]) -> Result<Vec<Claim>, SimError> {
    let others = [Method::Mf, Method::T2t];
    let mut out = Vec::new();
    for (id, metric, text) in [
        (
            "eff_best_3d_mean",
            "mean_3d",
            "EFF has the lowest 3D mean distance error (Table 2)",
        ),
        (
            "eff_best_3d_std",
            "std_3d",
            "EFF has the lowest 3D error std (Table 2)",
        ),
        (
            "eff_best_2d_mean",
            "mean_2d",
            "EFF has the lowest 2D mean distance error (Table 3)",
        ),
        (
            "eff_best_2d_std",
            "std_2d",
            "EFF has the lowest 2D error std (Table 3)",
        ),
    ] {
        let (holds, detail) = beats_all(setup, results, Method::Eff, &others, metric)?;
        out.push(Claim::new(id, text, holds, with_threshold(setup, detail)));
    }
    let (holds, detail) = beats_all(setup, results, Method::T2t, &[Method::Mf], "mean_3d")?;
    out.push(Claim::new(
        "t2t_beats_mf_3d_mean",
        "T2T has a lower 3D mean distance error than MF (Table 2)",
        holds,
        with_threshold(setup, detail),
    ));
    let lim = setup.turn_ratio_limit;
    let ratio = |m: Method| ci(&values(results, m, "turn_ratio_3d"));
    let (re, re_ci) = ratio(Method::Eff)?;
    let (rm, rm_ci) = ratio(Method::Mf)?;
    let (rt, rt_ci) = ratio(Method::T2t)?;
    let holds = re <= lim && rm > lim && rt > lim;
    out.push(Claim::new(
        "eff_robust_at_turns",
        format!(
            "EFF is robust at course changes (turn ratio <= {lim}) while MF and T2T spike (ratio > {lim})"
        ),
        holds,
        format!(
            "turn_ratio_3d (mean error within +/- {} s of a course change / elsewhere): EFF {:.3} [{:.3}, {:.3}], MF {:.3} [{:.3}, {:.3}], T2T {:.3} [{:.3}, {:.3}]",
            setup.turn_half_window, re, re_ci[0], re_ci[1], rm, rm_ci[0], rm_ci[1], rt, rt_ci[0], rt_ci[1]
        ),
    ));
    Ok(out)
}

/// Parses and checks a `fusion` scenario text without running it (`fathom check`);
/// returns the resolved scenario re-serialized as TOML.
///
/// # Errors
/// As the experiment's own loading: [`SimError::Toml`] or [`SimError::Invalid`].
pub fn check_scenario_text(text: &str, file: &str) -> Result<String, SimError> {
    crate::scenario::resolve_scenario_text(text, file, |s: &FusionScenario, f| s.check(f, None))
}

/// One Monte Carlo run of every method on the default scenario (for the benchmarks,
/// [`crate::experiments::single_run`]); scenario and mission prepared once.
pub(crate) fn single_run(ctx: &ExperimentContext) -> Result<super::single_run::RunFn, SimError> {
    let scenario: FusionScenario = ctx.load_scenario()?;
    let setup = scenario.check(&ctx.scenario_label, ctx.runs)?;
    let mission = setup.mission()?;
    Ok(Box::new(move |rng| {
        run_once(&setup, &setup.run, &mission, &Method::ALL, false, rng).map(|_| ())
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario_text() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/fusion.toml"),
        )
        .unwrap()
    }

    fn parse(text: &str) -> FusionScenario {
        crate::scenario::parse_toml(text, "fusion.toml").unwrap()
    }

    #[test]
    fn preset_parses_and_checks() {
        let s = parse(&scenario_text());
        let c = s.check("fusion.toml", None).unwrap();
        assert!(c.runs >= 200);
        assert_eq!(c.run.n_steps, 1000);
        assert!(c.sweep_dvl_noise.len() >= 5 && c.sweep_v_dvl.len() >= 5);
        let m = c.mission().unwrap();
        assert_eq!(m.course_changes().len(), 10);
        assert!(m.course_changes().iter().any(|t| (t - 440.0).abs() <= 7.0));
    }

    #[test]
    fn bad_values_name_the_key() {
        let text = scenario_text().replace("v_dvl_m = 0.02", "v_dvl_m = -0.02");
        let err = parse(&text)
            .check("fusion.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("filters.v_dvl_m"), "{err}");
        let text = scenario_text().replace("step_s = 1.0", "step_s = 0.3");
        let err = parse(&text)
            .check("fusion.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("mission.step_s"), "{err}");
        let text = scenario_text().replace("runs = 20\n", "runs = 1\n");
        let err = parse(&text)
            .check("fusion.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("sensitivity.runs"), "{err}");
        let text =
            scenario_text().replace("turn_width_m = 40.0", "turn_width_m = 40.0\nturn_widht = 1");
        let err = crate::scenario::parse_toml::<FusionScenario>(&text, "fusion.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("turn_widht"), "{err}");
    }

    #[test]
    fn short_run_is_finite_and_paired() {
        let s = parse(&scenario_text());
        let mut setup = s.check("fusion.toml", Some(2)).unwrap();
        setup.run.n_steps = 300;
        let mission = setup.mission().unwrap();
        let mut rng = crate::montecarlo::run_rng(3, 0);
        let r = run_once(&setup, &setup.run, &mission, &Method::ALL, true, &mut rng).unwrap();
        for m in Method::ALL {
            let mm = r.metrics[m.index()].unwrap();
            assert!(
                mm.mean_3d.is_finite() && mm.turn_ratio_3d.is_finite(),
                "{m:?}"
            );
        }
        // The same stream gives the same numbers.
        let mut rng = crate::montecarlo::run_rng(3, 0);
        let again = run_once(&setup, &setup.run, &mission, &Method::ALL, false, &mut rng).unwrap();
        assert_eq!(r.metrics, again.metrics);
    }
}
