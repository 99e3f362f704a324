//! The `fusion` scenario file: schema, check, and the checked setup.

use fathom_core::echo::echo;
use fathom_core::units::{deg_to_rad, knots_to_mps};
use fathom_sensors::integrated::{DvlDrParams, InsParams};
use fathom_traj::{
    CheckedFusionMissionParams, FusionMission, FusionMissionParams, generate_fusion_mission,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::sim::{FilterTuning, Method, Reading, RunConfig};
use fathom_sim::SimError;
use fathom_sim::method_list::select;
use fathom_sim::parameter_key::parameter_invalid;
use fathom_sim::scenario::{require_non_negative, require_positive};

/// INS + DVL fusion architectures.
///
/// Paper A (Lee & Yoon 2011, seed 000): measurement fusion (MF), track-to-track fusion
/// (T2T, eq. 10) and the equalize-fuse-feedback filter (EFF, eqs. 9-10 plus feedback)
/// on one cubic-spline UUV mission; many noise realizations of the same mission.
/// Preset: `scenarios/fusion.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FusionScenario {
    /// The experiment this file is for.
    ///
    /// Range: `"fusion"`.
    pub experiment: String,
    /// Monte Carlo runs (noise realizations; spec: ≥ 200); `--runs` overrides.
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// Run `i` draws its INS and DVL seeds from ChaCha stream `i` of this seed.
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub base_seed: u64,
    /// Seed of the mission's knot perturbations: one mission for all runs (the
    /// generated mission must pass its self-checks: speeds, depth, course changes;
    /// checked when running).
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub trajectory_seed: u64,
    /// The mission (paper §4.1).
    pub mission: MissionToml,
    /// The INS (main sensor, large error).
    pub ins: InsToml,
    /// The DVL (assistance sensor, small error).
    pub dvl: DvlToml,
    /// Filter tuning (`Q = w² I6`, `R = v² I3`, eqs. 5-6).
    pub filters: FiltersToml,
    /// Analysis settings (course changes, zoom, histogram, claims).
    pub analysis: AnalysisToml,
    /// Sweeps (not in the paper).
    pub sensitivity: SensitivityToml,
    /// The methods to run, report and plot. With a subset only the main batch runs:
    /// the paper's claims, the other `v_DVL` reading and the sensitivity sweeps
    /// compare the methods and are left out (the report says so).
    ///
    /// Range: a list of `"MF"`, `"T2T"`, `"EFF"`, `"EFF-no-feedback"`,
    /// `"EFF-no-equalization"`, `"T2T-BC"`, `"T2T-CI"`, `"INS-only"`, `"DVL-DR"`.
    /// Default: all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
    /// `[statistics]`: how the runs of each row are summarized (bootstrap resamples,
    /// divergence factor); defaults when absent.
    #[serde(default)]
    pub statistics: fathom_sim::statistics::StatisticsParams,
}

/// `[mission]`: the cubic-spline UUV mission (paper §4.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MissionToml {
    /// Mission length (paper: 1000).
    ///
    /// Unit: s. Range: > 0.
    pub duration_s: f64,
    /// Sensor and filter step T (paper: 1); also the step of the course-change
    /// detection.
    ///
    /// Unit: s. Range: > 0, divides `duration_s` into ≥ 10 steps.
    pub step_s: f64,
    /// Course changes of the search pattern (paper: 10); the spline has `2 n + 5` knots
    /// evenly spaced over the mission.
    ///
    /// Range: ≥ 1.
    pub n_course_changes: usize,
    /// Depth of the search phase (paper: 100).
    ///
    /// Unit: m. Range: > 0.
    pub search_depth_m: f64,
    /// Allowed depth deviation during the search.
    ///
    /// Unit: m. Range: > 0.
    pub depth_tolerance_m: f64,
    /// Slowest allowed speed during the search (paper: 1).
    ///
    /// Unit: kt. Range: > 0 and < `max_speed_kt`.
    pub min_speed_kt: f64,
    /// Fastest allowed speed during the search (paper: 6).
    ///
    /// Unit: kt. Range: > 0.
    pub max_speed_kt: f64,
    /// Nominal speed of each leg (leg 0 is flown while diving, the last while
    /// surfacing).
    ///
    /// Unit: kt. Range: `n_course_changes + 1` values in [`min_speed_kt`,
    /// `max_speed_kt`].
    pub leg_speeds_kt: Vec<f64>,
    /// Eastward offset of each U-turn of the lawnmower pattern.
    ///
    /// Unit: m. Range: > 0.
    pub turn_width_m: f64,
    /// σ of the random horizontal knot offsets ("random values" in the knots).
    ///
    /// Unit: m. Range: ≥ 0.
    pub perturbation_sigma_m: f64,
    /// Smallest heading change counted as a course change.
    ///
    /// Unit: deg. Range: (0, 180).
    pub min_course_change_deg: f64,
}

/// `[ins]`: accelerometer errors of the INS integrator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InsToml {
    /// σ of the per-axis accelerometer bias `b_a`, constant per run, in `a_m = a + b_a
    /// + n_a` (not given by the paper; spec A: 2e-4).
    ///
    /// Unit: m/s². Range: ≥ 0.
    pub accel_bias_sigma_mps2: f64,
    /// σ of the per-axis white accelerometer noise `n_a` per sample (spec A: 1e-3); the
    /// INS integrates `a_m` twice.
    ///
    /// Unit: m/s². Range: ≥ 0.
    pub accel_noise_sigma_mps2: f64,
}

/// `[dvl]`: velocity errors of the DVL dead reckoning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DvlToml {
    /// Half width h of the per-axis scale-factor error `s ~ U(-h, h)`, drawn per run,
    /// in `v_m = (1 + s) v + n_v` (0.002 = 0.2 %).
    ///
    /// Unit: - (fraction). Range: ≥ 0.
    pub scale_half_width: f64,
    /// σ of the per-axis white velocity noise `n_v` per sample (spec A: 0.02); the DVL
    /// position is its velocity integrated once.
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub vel_noise_sigma_mps: f64,
}

/// `[filters]`: paper tuning `Q = w^2 I6`, `R = v^2 I3`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FiltersToml {
    /// How the paper's printed `w` and `v` are read: `"bar_shalom"` (the notation of
    /// its references: `v` is the white-acceleration process noise, `w` the position
    /// measurement noise; every printed unit consistent) or `"as_printed"` (`Q = w² I6`,
    /// `R = v² I3`, with two unit repairs). The other reading runs too, with the same
    /// seeds, and the report shows both.
    ///
    /// Range: `"bar_shalom"` or `"as_printed"`.
    pub reading: String,
    /// The paper's `w_INS` (10): the INS position σ (`bar_shalom`) or the INS track's
    /// process-noise scale (`as_printed`).
    ///
    /// Unit: m. Range: > 0 (`bar_shalom`), ≥ 0 (`as_printed`).
    pub w_ins_m: f64,
    /// The paper's `w_DVL` (1), read like `w_ins_m`.
    ///
    /// Unit: m. Range: as `w_ins_m`.
    pub w_dvl_m: f64,
    /// The paper's `v_INS` ("1 g ≈ 9.8 m/s²"): the INS filter's white-acceleration σ,
    /// m/s² (`bar_shalom`), or the INS position σ read as metres (`as_printed`).
    ///
    /// Unit: m/s² or m (see the reading). Range: > 0.
    pub v_ins: f64,
    /// The paper's `v_DVL` ("0.02 m/s²"), read like `v_ins`.
    ///
    /// Unit: m/s² or m (see the reading). Range: > 0.
    pub v_dvl: f64,
    /// Process-noise scale of the single MF filter under `as_printed` (not given by the
    /// paper).
    ///
    /// Unit: m. Range: ≥ 0.
    pub w_mf_m: f64,
    /// White-acceleration σ of the single MF filter under `bar_shalom` (not given by the
    /// paper; the preset uses the DVL filter's, the precise sensor's).
    ///
    /// Unit: m/s². Range: > 0.
    pub mf_accel_sigma_mps2: f64,
    /// Initial position σ of every filter (not given by the paper).
    ///
    /// Unit: m. Range: > 0.
    pub initial_sigma_pos_m: f64,
    /// Initial velocity σ of every filter (not given by the paper).
    ///
    /// Unit: m/s. Range: > 0.
    pub initial_sigma_vel_mps: f64,
}

/// `[analysis]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnalysisToml {
    /// Half width of the window around each detected course change (spec: 7); the turn
    /// ratio is the mean error inside the windows over the mean error outside.
    ///
    /// Unit: s. Range: > 0.
    pub turn_half_window_s: f64,
    /// A method "spikes" at turns when its turn ratio exceeds this; EFF is robust when
    /// its ratio is at most this (spec: 1.1; claim `eff_robust_at_turns`).
    ///
    /// Range: > 0.
    pub turn_ratio_limit: f64,
    /// Centre of the zoom window of the path figures (paper: 440).
    ///
    /// Unit: s. Range: [0, `mission.duration_s`].
    pub zoom_center_s: f64,
    /// Half width of the zoom window (paper: 7).
    ///
    /// Unit: s. Range: > 0.
    pub zoom_half_width_s: f64,
    /// Bins of the error histograms.
    ///
    /// Range: ≥ 2.
    pub histogram_bins: usize,
    /// A claim "X beats Y" holds only when the paired 95 % CI of `X - Y` lies below
    /// `-min × Y` (0.01 = 1 %).
    ///
    /// Unit: - (fraction). Range: ≥ 0.
    pub min_relative_improvement: f64,
}

/// `[sensitivity]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensitivityToml {
    /// At most this many Monte Carlo runs per sweep value: each sweep value runs
    /// `ceil(runs / 4)` runs (`runs` after `--runs`), clamped to [2, this].
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// DVL velocity-noise values of the first sweep (the filters keep their tuning).
    ///
    /// Unit: m/s. Range: ≥ 2 values, each > 0, strictly increasing.
    pub dvl_vel_noise_mps: Vec<f64>,
    /// The filters' `v_DVL` values of the second sweep (the sensors keep the scenario's
    /// values), in the unit of each reading (m/s² for `bar_shalom`, m for `as_printed`).
    ///
    /// Unit: see `filters.v_dvl`. Range: ≥ 2 values, each > 0, strictly increasing.
    pub filter_v_dvl: Vec<f64>,
}

fathom_sim::monte_carlo_scenario!(FusionScenario);

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
    /// `v_DVL` sweep (unit of the reading).
    pub sweep_v_dvl: Vec<f64>,
    /// `methods`: the methods run, in [`Method::ALL`] order.
    pub methods: Vec<Method>,
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
    /// Checks every value and converts the scenario into checked parameters.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the file and key.
    pub fn check(&self, file: &str) -> Result<FusionSetup, SimError> {
        let runs = self.runs;
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
        let mission_params = FusionMissionParams {
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
        };
        if m.max_speed_kt <= m.min_speed_kt {
            return Err(SimError::invalid(
                file,
                "mission.max_speed_kt",
                format!(
                    "must be above mission.min_speed_kt = {} kt, got {} kt",
                    m.min_speed_kt, m.max_speed_kt
                ),
            ));
        }
        let mission = mission_params
            .check()
            .map_err(|e| parameter_invalid(file, "mission", m, &e))?;

        let ins = InsParams {
            accel_bias_sigma: self.ins.accel_bias_sigma_mps2,
            accel_noise_sigma: self.ins.accel_noise_sigma_mps2,
        };
        require_non_negative(file, "ins.accel_bias_sigma_mps2", ins.accel_bias_sigma)?;
        require_non_negative(file, "ins.accel_noise_sigma_mps2", ins.accel_noise_sigma)?;
        let ins_params = ins;
        let ins = ins
            .check()
            .map_err(|e| parameter_invalid(file, "ins", &self.ins, &e))?;
        let dvl_params = DvlDrParams {
            scale_half_width: self.dvl.scale_half_width,
            vel_noise_sigma: self.dvl.vel_noise_sigma_mps,
        };
        require_non_negative(file, "dvl.scale_half_width", dvl_params.scale_half_width)?;
        require_non_negative(file, "dvl.vel_noise_sigma_mps", dvl_params.vel_noise_sigma)?;
        let dvl = dvl_params
            .check()
            .map_err(|e| parameter_invalid(file, "dvl", &self.dvl, &e))?;

        let f = &self.filters;
        let reading = match f.reading.as_str() {
            "bar_shalom" => Reading::BarShalom,
            "as_printed" => Reading::AsPrinted,
            other => {
                return Err(SimError::invalid(
                    file,
                    "filters.reading",
                    format!(
                        "must be \"bar_shalom\" or \"as_printed\", got \"{}\"",
                        echo(other)
                    ),
                ));
            }
        };
        let w_check = |key: &str, v: f64| match reading {
            Reading::BarShalom => require_positive(file, key, v),
            Reading::AsPrinted => require_non_negative(file, key, v),
        };
        let tuning = FilterTuning {
            reading,
            w_ins: w_check("filters.w_ins_m", f.w_ins_m)?,
            w_dvl: w_check("filters.w_dvl_m", f.w_dvl_m)?,
            v_ins: require_positive(file, "filters.v_ins", f.v_ins)?,
            v_dvl: require_positive(file, "filters.v_dvl", f.v_dvl)?,
            w_mf: require_non_negative(file, "filters.w_mf_m", f.w_mf_m)?,
            mf_accel_sigma: require_positive(
                file,
                "filters.mf_accel_sigma_mps2",
                f.mf_accel_sigma_mps2,
            )?,
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
            // A quarter of the main batch, at most the scenario's `sensitivity.runs`.
            sensitivity_runs: runs.div_ceil(4).clamp(2, s.runs),
            sweep_dvl_noise: sweep(file, "sensitivity.dvl_vel_noise_mps", &s.dvl_vel_noise_mps)?,
            sweep_v_dvl: sweep(file, "sensitivity.filter_v_dvl", &s.filter_v_dvl)?,
            methods: select(
                file,
                "fusion",
                self.methods.as_deref(),
                &Method::ALL,
                Method::name,
            )?,
        })
    }
}

impl FusionSetup {
    /// Whether `methods` selects every method (the paper's full experiment).
    pub fn all_methods(&self) -> bool {
        self.methods.len() == Method::ALL.len()
    }

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fusion::analysis::run_once;
    use crate::fusion::sim::Method;

    fn scenario_text() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/fusion.toml"),
        )
        .unwrap()
    }

    fn parse(text: &str) -> FusionScenario {
        fathom_sim::scenario::parse_toml(text, "fusion.toml").unwrap()
    }

    #[test]
    fn preset_parses_and_checks() {
        let s = parse(&scenario_text());
        let c = s.check("fusion.toml").unwrap();
        assert!(c.runs >= 200);
        assert_eq!(c.run.n_steps, 1000);
        assert!(c.sweep_dvl_noise.len() >= 5 && c.sweep_v_dvl.len() >= 5);
        let m = c.mission().unwrap();
        assert_eq!(m.course_changes().len(), 10);
        assert!(m.course_changes().iter().any(|t| (t - 440.0).abs() <= 7.0));
    }

    #[test]
    fn bad_values_name_the_key() {
        let text = scenario_text().replace("v_dvl = 0.02", "v_dvl = -0.02");
        let err = parse(&text).check("fusion.toml").unwrap_err().to_string();
        assert!(err.contains("filters.v_dvl"), "{err}");
        let text = scenario_text().replace("step_s = 1.0", "step_s = 0.3");
        let err = parse(&text).check("fusion.toml").unwrap_err().to_string();
        assert!(err.contains("mission.step_s"), "{err}");
        let text = scenario_text().replace("runs = 20\n", "runs = 1\n");
        let err = parse(&text).check("fusion.toml").unwrap_err().to_string();
        assert!(err.contains("sensitivity.runs"), "{err}");
        let text =
            scenario_text().replace("turn_width_m = 40.0", "turn_width_m = 40.0\nturn_widht = 1");
        let err = fathom_sim::scenario::parse_toml::<FusionScenario>(&text, "fusion.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("turn_widht"), "{err}");
    }

    #[test]
    fn short_run_is_finite_and_paired() {
        let s = parse(&scenario_text());
        let mut s = s;
        s.runs = 2;
        let mut setup = s.check("fusion.toml").unwrap();
        setup.run.n_steps = 300;
        let mission = setup.mission().unwrap();
        let mut rng = fathom_sim::montecarlo::run_rng(3, 0);
        let r = run_once(&setup, &setup.run, &mission, &Method::ALL, true, &mut rng).unwrap();
        for m in Method::ALL {
            let mm = r.metrics[m.index()].unwrap();
            assert!(
                mm.mean_3d.is_finite() && mm.turn_ratio_3d.is_finite(),
                "{m:?}"
            );
        }
        // The same stream gives the same numbers.
        let mut rng = fathom_sim::montecarlo::run_rng(3, 0);
        let again = run_once(&setup, &setup.run, &mission, &Method::ALL, false, &mut rng).unwrap();
        assert_eq!(r.metrics, again.metrics);
    }
}
