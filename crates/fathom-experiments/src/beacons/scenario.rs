//! The `beacons` scenario file: schema and check.

use fathom_core::echo::echo;
use fathom_estimators::schemes::UpdateScheme;
use fathom_sensors::{
    BeaconSuiteConfig, BeaconSuiteParams, NoiseSwitches, Timing, noise::OutlierParams,
};
use fathom_traj::velocity_command::VelocityCommandParams;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::MAIN_CASE;
use super::filter::{EkfSettings, FilterSetup};
use crate::common::{BeaconsToml, MotionToml, check_case_name};
use fathom_sim::SimError;
use fathom_sim::method_list::select;
use fathom_sim::scenario::{require_in_range, require_non_negative, require_positive};

/// EKF range-beacon localization.
///
/// Paper B (Han et al. 2016, seed 003) §5, Tables 12-14: a 4-state `(x, y, z, ψ)` EKF
/// dead-reckons on DVL velocity and AHRS yaw rate and is corrected by four ranges and
/// depth, under the update schemes AS (asynchronous), SC (synchronous collective) and
/// SI (synchronous individual), with chi-square gating of every range. Preset:
/// `scenarios/beacons.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeaconsScenario {
    /// The experiment this file is for.
    ///
    /// Range: `"beacons"`.
    pub experiment: String,
    /// Monte Carlo runs (spec: ≥ 100); `--runs` overrides.
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// Run `i` uses ChaCha stream `i` of this seed.
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub base_seed: u64,
    /// Robot motion (Tables 1 and 9).
    pub motion: MotionToml,
    /// Sensor clocks (Tables 2-3).
    pub timing: TimingToml,
    /// Beacon positions.
    pub beacons: BeaconsToml,
    /// Sensor noise (Tables 4-8, 10).
    pub noise: NoiseToml,
    /// The localization filter (Table 12).
    pub ekf: EkfToml,
    /// Figure settings.
    pub figures: FiguresToml,
    /// Further beacon layouts, each run on the main case with the same random numbers
    /// (the geometry sensitivity: the paper gives no layout).
    #[serde(default)]
    pub geometry: Vec<GeometryToml>,
    /// Sensor configurations (Table 13 is `high`).
    pub cases: Vec<CaseToml>,
    /// Post-processing: also run the fixed-interval RTS smoother over each scheme's
    /// forward pass and report `<scheme>+RTS/<case>` rows (the same statistics and CIs)
    /// beside the filtered ones.
    ///
    /// Range: `true` or `false`. Default: `false`.
    #[serde(default)]
    pub smooth: bool,
    /// The update schemes to run, report and plot (the paper's comparisons of the
    /// schemes and its Tables 13-14 need all three and are left out otherwise, with a
    /// note).
    ///
    /// Range: a list of `"AS"`, `"SC"`, `"SI"`. Default: all three.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
    /// `[statistics]`: how the runs of each row are summarized (bootstrap resamples,
    /// divergence factor); defaults when absent.
    #[serde(default)]
    pub statistics: fathom_sim::statistics::StatisticsParams,
}

/// `[timing]`: synchronous and asynchronous clocks (Tables 2-3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimingToml {
    /// Sample-time jitter σ_t of every clock (not given by the paper).
    ///
    /// Unit: s. Range: ≥ 0 and < 1/4 of every period in use.
    pub jitter_sigma_s: f64,
    /// The one clock of all sensors in cases with `timing = "sync"` (paper: 0.1).
    ///
    /// Unit: s. Range: > 0.
    pub sync_period_s: f64,
    /// Asynchronous DVL period (Table 3: 0.20); also how long the filter holds a
    /// velocity sample.
    ///
    /// Unit: s. Range: > 0.
    pub dvl_period_s: f64,
    /// Asynchronous AHRS period (Table 3: 0.01).
    ///
    /// Unit: s. Range: > 0.
    pub ahrs_period_s: f64,
    /// Asynchronous period of each range sensor, one clock per beacon (Table 3: 0.10).
    ///
    /// Unit: s. Range: > 0.
    pub range_period_s: f64,
    /// Asynchronous depth period (Table 3: 0.02).
    ///
    /// Unit: s. Range: > 0.
    pub depth_period_s: f64,
}

/// `[noise]`: sensor noise (Tables 4-8, 10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NoiseToml {
    /// DVL `(u, v, w)` and AHRS `(p, q, r)` noise σ (Table 10: 0.1, 0, 0.1, 0, 0, 0.1);
    /// the filter uses u, v, w and r (p and q only enter the simulated AHRS data).
    ///
    /// Unit: m/s (u, v, w), rad/s (p, q, r). Range: each ≥ 0.
    pub velocity_sigma: [f64; 6],
    /// White range noise σ_r (paper: 0.1).
    ///
    /// Unit: m. Range: > 0.
    pub range_sigma_m: f64,
    /// White depth noise σ_d (paper: 0.2).
    ///
    /// Unit: m. Range: > 0.
    pub depth_sigma_m: f64,
    /// Hold time t_gap of the common-mode range noise (Table 7: 1).
    ///
    /// Unit: s. Range: > 0.
    pub corr_gap_s: f64,
    /// Number N of range samples (of all beacons) shifted by ±`outlier_magnitude_m`
    /// (Table 8; Table 14 counts 276); 0 = no outliers.
    ///
    /// Range: ≥ 0, at most the run's range samples (checked when running).
    pub outlier_count: usize,
    /// Outlier magnitude σ_o, random sign (Table 8: 1).
    ///
    /// Unit: m. Range: ≥ 0.
    pub outlier_magnitude_m: f64,
}

/// `[ekf]`: the localization filter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EkfToml {
    /// Sync epoch of SC and SI (paper: 0.1); also the period at which every scheme's
    /// error is evaluated.
    ///
    /// Unit: s. Range: > 0.
    pub epoch_period_s: f64,
    /// Gate distance d of eq. (10): a range is rejected when `ν²/S > d²` (paper: 2.5,
    /// two-sided 98.76 %); depth is never gated.
    ///
    /// Unit: innovation σ. Range: > 0.
    pub gate_sigma: f64,
    /// AS only: a measurement stamped up to this much before the filter time is still
    /// applied (at the filter time); older ones are dropped.
    ///
    /// Unit: s. Range: ≥ 0.
    pub stale_tolerance_s: f64,
    /// Initial position σ per axis; each run's initial estimate is drawn from N(truth,
    /// P0).
    ///
    /// Unit: m. Range: > 0.
    pub init_pos_sigma_m: f64,
    /// Initial heading σ.
    ///
    /// Unit: rad. Range: > 0.
    pub init_yaw_sigma_rad: f64,
    /// Whether the filter's input error adds the vehicle's per-step motion noise to the
    /// sensor noise: σ = √(σ_sensor² + σ_motion²) (the held sample misses the velocity
    /// changes within a sensor period).
    pub include_motion_noise: bool,
    /// Factor on every process-noise σ (1 = as designed).
    ///
    /// Range: > 0.
    pub process_noise_scale: f64,
}

/// `[figures]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FiguresToml {
    /// The Monte Carlo run shown in the single-run figures.
    ///
    /// Range: < `runs` (and < `--runs` when given).
    pub run: usize,
}

/// Sensor timing of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum TimingKind {
    /// Every sensor on its own clock (Table 3).
    Async,
    /// One common clock.
    Sync,
}

/// One beacon layout of the geometry sensitivity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GeometryToml {
    /// Layout name (in the method names of its rows, `AS/high@name`).
    ///
    /// Range: non-empty, `[A-Za-z0-9_-]`, unique.
    pub name: String,
    /// Beacon positions `[north, east, down]` of the layout.
    ///
    /// Unit: m (NED). Range: finite, at least one beacon.
    pub positions: Vec<[f64; 3]>,
}

/// `[[cases]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CaseToml {
    /// Case name; `high` is the main case (Tables 13-14, paper numbers); with a `low`
    /// case the claim `sc_advantage_shrinks_low_corr` is evaluated.
    ///
    /// Range: `[A-Za-z0-9_-]`, unique; one case must be `high`.
    pub name: String,
    /// Every sensor on its own clock (Table 3) or one common clock
    /// (`timing.sync_period_s`).
    ///
    /// Range: `"async"` or `"sync"`.
    pub timing: TimingKind,
    /// Common-mode range noise σ_c (0 = none; paper: 0.2 high, 0.05 low); SC's stacked
    /// update uses it in R.
    ///
    /// Unit: m. Range: ≥ 0.
    pub corr_sigma_m: f64,
}

fathom_sim::monte_carlo_scenario!(BeaconsScenario);

/// One checked case.
#[derive(Debug, Clone)]
pub struct Case {
    pub(super) name: String,
    pub(super) config: BeaconSuiteConfig,
    pub(super) setup: FilterSetup,
}

/// A checked beacon layout: the main case with the layout's beacons.
#[derive(Debug, Clone)]
pub struct Layout {
    pub(super) name: String,
    pub(super) case: Case,
}

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The geometry sensitivity's layouts.
    pub(super) layouts: Vec<Layout>,
    pub(super) runs: usize,
    pub(super) motion: VelocityCommandParams,
    pub(super) figure_run: usize,
    /// Hold time of the common-mode range noise, s.
    pub(super) corr_gap: f64,
    pub(super) cases: Vec<Case>,
    /// `smooth`: RTS-smoothed rows beside the filtered ones.
    pub(super) smooth: bool,
    /// `methods`: the schemes run, in [`UpdateScheme::ALL`] order.
    pub(super) schemes: Vec<UpdateScheme>,
}

impl Checked {
    /// Index of the main case (the check guarantees it exists).
    pub(super) fn main_case(&self) -> usize {
        self.cases
            .iter()
            .position(|c| c.name == super::MAIN_CASE)
            .unwrap_or(0)
    }
}

impl BeaconsScenario {
    /// The layouts of `[[geometry]]`, each the main case with its own beacons.
    fn check_layouts(
        &self,
        file: &str,
        cases: &[Case],
        settings: &EkfSettings,
        motion: &VelocityCommandParams,
    ) -> Result<Vec<Layout>, SimError> {
        let Some(main) = cases.iter().find(|c| c.name == MAIN_CASE) else {
            return Ok(Vec::new());
        };
        let mut out = Vec::with_capacity(self.geometry.len());
        for (k, g) in self.geometry.iter().enumerate() {
            let key = format!("geometry[{k}]");
            check_case_name(
                file,
                k,
                &g.name,
                self.geometry[..k].iter().map(|g| g.name.as_str()),
            )
            .map_err(|_| {
                SimError::invalid(
                    file,
                    format!("{key}.name"),
                    format!(
                        "must be a non-empty, unique name of [A-Za-z0-9_-], got \"{}\"",
                        echo(&g.name)
                    ),
                )
            })?;
            let beacons = BeaconsToml {
                positions: g.positions.clone(),
            }
            .to_positions(file, &key)?;
            let params = BeaconSuiteParams {
                beacons_in_nav: beacons,
                ..main.config.params().clone()
            };
            let config = params
                .check()
                .map_err(|e| SimError::invalid(file, key.clone(), e.to_string()))?;
            let setup = FilterSetup::new(settings, &config, motion)
                .map_err(|e| SimError::invalid(file, key.clone(), fathom_sim::error_chain(&e)))?;
            out.push(Layout {
                name: g.name.clone(),
                case: Case {
                    name: MAIN_CASE.to_string(),
                    config,
                    setup,
                },
            });
        }
        Ok(out)
    }

    /// Validates the scenario (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<Checked, SimError> {
        let runs = self.runs;
        let motion = self.motion.to_params(file, "motion")?;
        let beacons = self.beacons.to_positions(file, "beacons")?;
        let t = &self.timing;
        require_non_negative(file, "timing.jitter_sigma_s", t.jitter_sigma_s)?;
        for (key, period) in [
            ("timing.sync_period_s", t.sync_period_s),
            ("timing.dvl_period_s", t.dvl_period_s),
            ("timing.ahrs_period_s", t.ahrs_period_s),
            ("timing.range_period_s", t.range_period_s),
            ("timing.depth_period_s", t.depth_period_s),
        ] {
            crate::common::require_period_over_jitter(file, key, period, t.jitter_sigma_s)?;
        }
        for (key, v) in [
            ("timing.sync_period_s", t.sync_period_s),
            ("timing.dvl_period_s", t.dvl_period_s),
            ("timing.ahrs_period_s", t.ahrs_period_s),
            ("timing.range_period_s", t.range_period_s),
            ("timing.depth_period_s", t.depth_period_s),
        ] {
            require_positive(file, key, v)?;
        }
        let n = &self.noise;
        for (i, v) in n.velocity_sigma.iter().enumerate() {
            require_non_negative(file, &format!("noise.velocity_sigma[{i}]"), *v)?;
        }
        require_positive(file, "noise.range_sigma_m", n.range_sigma_m)?;
        require_positive(file, "noise.depth_sigma_m", n.depth_sigma_m)?;
        require_positive(file, "noise.corr_gap_s", n.corr_gap_s)?;
        require_non_negative(file, "noise.outlier_magnitude_m", n.outlier_magnitude_m)?;
        let e = &self.ekf;
        require_positive(file, "ekf.epoch_period_s", e.epoch_period_s)?;
        // its square is the gate: at least 1e-3 sigma, so that the square is a number
        require_in_range(file, "ekf.gate_sigma", e.gate_sigma, 1e-3, 1e3)?;
        require_non_negative(file, "ekf.stale_tolerance_s", e.stale_tolerance_s)?;
        require_positive(file, "ekf.init_pos_sigma_m", e.init_pos_sigma_m)?;
        require_positive(file, "ekf.init_yaw_sigma_rad", e.init_yaw_sigma_rad)?;
        require_positive(file, "ekf.process_noise_scale", e.process_noise_scale)?;
        if self.figures.run >= runs {
            return Err(SimError::invalid(
                file,
                "figures.run",
                format!(
                    "must be below the number of runs ({runs}), got {}",
                    self.figures.run
                ),
            ));
        }
        let settings = EkfSettings {
            epoch_period: e.epoch_period_s,
            gate_sigma: e.gate_sigma,
            stale_tolerance: e.stale_tolerance_s,
            init_pos_sigma: e.init_pos_sigma_m,
            init_yaw_sigma: e.init_yaw_sigma_rad,
            include_motion_noise: e.include_motion_noise,
            process_noise_scale: e.process_noise_scale,
            smooth: self.smooth,
        };
        if !self.cases.iter().any(|c| c.name == MAIN_CASE) {
            return Err(SimError::invalid(
                file,
                "cases",
                format!("needs the main case named {MAIN_CASE:?} (Table 13)"),
            ));
        }
        let mut cases = Vec::with_capacity(self.cases.len());
        for (k, case) in self.cases.iter().enumerate() {
            let key = format!("cases[{k}]");
            check_case_name(
                file,
                k,
                &case.name,
                self.cases[..k].iter().map(|c| c.name.as_str()),
            )?;
            require_non_negative(file, &format!("{key}.corr_sigma_m"), case.corr_sigma_m)?;
            // The outliers are drawn among the range samples of a run: K beacons x
            // (duration / range period) samples (fewer with a short mission or few beacons).
            let range_period = match case.timing {
                TimingKind::Sync => t.sync_period_s,
                TimingKind::Async => t.range_period_s,
            };
            let range_samples = beacons
                .len()
                .saturating_mul((self.motion.duration_s / range_period).floor() as usize);
            if n.outlier_count > range_samples {
                return Err(SimError::invalid(
                    file,
                    "noise.outlier_count",
                    format!(
                        "{} outliers do not fit into the {range_samples} range samples of a run \
                         of case `{}` ({} beacons x motion.duration_s = {} s / the range \
                         period timing.{}_period_s = {} s); lower it or lengthen \
                         motion.duration_s",
                        n.outlier_count,
                        case.name,
                        beacons.len(),
                        self.motion.duration_s,
                        match case.timing {
                            TimingKind::Sync => "sync",
                            TimingKind::Async => "range",
                        },
                        range_period
                    ),
                ));
            }
            let timing = match case.timing {
                TimingKind::Sync => Timing::Synchronous {
                    period: t.sync_period_s,
                },
                TimingKind::Async => Timing::Asynchronous {
                    dvl: t.dvl_period_s,
                    ahrs: t.ahrs_period_s,
                    range: t.range_period_s,
                    depth: t.depth_period_s,
                },
            };
            let params = BeaconSuiteParams {
                timing,
                jitter_sigma: t.jitter_sigma_s,
                stamp_offset: 0.0,
                stamp_jitter_sigma: 0.0,
                velocity_sigma: n.velocity_sigma,
                range_sigma: n.range_sigma_m,
                depth_sigma: n.depth_sigma_m,
                corr_sigma: case.corr_sigma_m,
                t_gap: n.corr_gap_s,
                outliers: OutlierParams {
                    count: n.outlier_count,
                    magnitude: n.outlier_magnitude_m,
                },
                switches: NoiseSwitches {
                    gaussian: true,
                    correlation: case.corr_sigma_m > 0.0,
                    outliers: n.outlier_count > 0,
                },
                beacons_in_nav: beacons.clone(),
            };
            let config = params
                .check()
                .map_err(|e| SimError::invalid(file, key.clone(), e.to_string()))?;
            let setup = FilterSetup::new(&settings, &config, &motion)
                .map_err(|e| SimError::invalid(file, "ekf", fathom_sim::error_chain(&e)))?;
            cases.push(Case {
                name: case.name.clone(),
                config,
                setup,
            });
        }
        let layouts = self.check_layouts(file, &cases, &settings, &motion)?;
        let schemes = select(
            file,
            "beacons",
            self.methods.as_deref(),
            &UpdateScheme::ALL,
            UpdateScheme::short_name,
        )?;
        Ok(Checked {
            schemes,
            smooth: self.smooth,
            runs,
            motion,
            figure_run: self.figures.run,
            corr_gap: n.corr_gap_s,
            layouts,
            cases,
        })
    }
}
