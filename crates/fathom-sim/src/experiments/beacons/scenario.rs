//! The `beacons` scenario file: schema and check.

use fathom_sensors::{
    BeaconSuiteConfig, BeaconSuiteParams, NoiseSwitches, Timing, noise::OutlierParams,
};
use fathom_traj::velocity_command::VelocityCommandParams;
use serde::{Deserialize, Serialize};

use super::MAIN_CASE;
use super::filter::{EkfSettings, FilterSetup};
use crate::SimError;
use crate::experiments::common::{BeaconsToml, MotionToml, check_case_name};
use crate::scenario::{require_non_negative, require_positive};

/// The `beacons` scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeaconsScenario {
    /// The experiment this scenario is for: must be `"beacons"` (lets `fathom run`
    /// pick the experiment from the file).
    pub experiment: String,
    /// Monte Carlo runs.
    pub runs: usize,
    /// Base seed; run `i` uses ChaCha stream `i`.
    pub base_seed: u64,
    /// Robot motion.
    pub motion: MotionToml,
    /// Sensor clocks.
    pub timing: TimingToml,
    /// Beacon positions.
    pub beacons: BeaconsToml,
    /// Sensor noise.
    pub noise: NoiseToml,
    /// Filter settings.
    pub ekf: EkfToml,
    /// Figure settings.
    pub figures: FiguresToml,
    /// The cases.
    pub cases: Vec<CaseToml>,
}

/// `[timing]`: synchronous and asynchronous clocks (Tables 2-3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimingToml {
    /// Sample-time jitter sigma, s.
    pub jitter_sigma_s: f64,
    /// Common period of synchronous sensors, s.
    pub sync_period_s: f64,
    /// Asynchronous DVL period, s.
    pub dvl_period_s: f64,
    /// Asynchronous AHRS period, s.
    pub ahrs_period_s: f64,
    /// Asynchronous period of every range sensor, s.
    pub range_period_s: f64,
    /// Asynchronous depth period, s.
    pub depth_period_s: f64,
}

/// `[noise]`: sensor noise (Tables 4-8, 10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseToml {
    /// DVL `(u, v, w)` (m/s) and AHRS `(p, q, r)` (rad/s) noise sigmas. The 4-state
    /// filter uses `u, v, w` and `r`; `p` and `q` only enter the simulated AHRS data.
    pub velocity_sigma: [f64; 6],
    /// White range noise sigma, m.
    pub range_sigma_m: f64,
    /// White depth noise sigma, m.
    pub depth_sigma_m: f64,
    /// Hold time of the common-mode range noise, s.
    pub corr_gap_s: f64,
    /// Number of injected range outliers (over all beacons; at most the run's range
    /// samples, which is only checked when the data are generated).
    pub outlier_count: usize,
    /// Outlier magnitude, m.
    pub outlier_magnitude_m: f64,
}

/// `[ekf]`: the localization filter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EkfToml {
    /// SC/SI epoch period, s; also the period at which every scheme's error is
    /// evaluated.
    pub epoch_period_s: f64,
    /// Gate distance `d` (reject a range when `nu^2 / S > d^2`, eq. 10); depth is never
    /// gated.
    pub gate_sigma: f64,
    /// AS stale tolerance, s: a measurement stamped up to this much before the filter
    /// time is still applied (at the filter time), older ones are dropped.
    pub stale_tolerance_s: f64,
    /// Initial position sigma, m.
    pub init_pos_sigma_m: f64,
    /// Initial heading sigma, rad.
    pub init_yaw_sigma_rad: f64,
    /// Whether the filter's input error includes the per-step motion noise.
    pub include_motion_noise: bool,
    /// Factor on the process-noise sigmas.
    pub process_noise_scale: f64,
}

/// `[figures]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FiguresToml {
    /// Monte Carlo run shown in the single-run figures; must be below `runs` (or
    /// `--runs` when given).
    pub run: usize,
}

/// Sensor timing of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimingKind {
    /// Every sensor on its own clock (Table 3).
    Async,
    /// One common clock.
    Sync,
}

/// `[[cases]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseToml {
    /// Case name (`high`, `low`, `none`, `sync`). One case must be `high` (Table 13's
    /// main case); a `low` case adds the claim `sc_advantage_shrinks_low_corr`.
    pub name: String,
    /// Sensor timing.
    pub timing: TimingKind,
    /// Common-mode range noise sigma, m (0 = none).
    pub corr_sigma_m: f64,
}

crate::monte_carlo_scenario!(BeaconsScenario);

/// One checked case.
#[derive(Debug, Clone)]
pub struct Case {
    pub(super) name: String,
    pub(super) config: BeaconSuiteConfig,
    pub(super) setup: FilterSetup,
}

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct Checked {
    pub(super) runs: usize,
    pub(super) base_seed: u64,
    pub(super) motion: VelocityCommandParams,
    pub(super) figure_run: usize,
    /// Hold time of the common-mode range noise, s.
    pub(super) corr_gap: f64,
    pub(super) cases: Vec<Case>,
}

impl BeaconsScenario {
    /// Validates the scenario (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<Checked, SimError> {
        let runs = self.runs;
        if runs < 2 {
            return Err(SimError::invalid(
                file,
                "runs",
                format!("needs at least 2 Monte Carlo runs for a confidence interval, got {runs}"),
            ));
        }
        let motion = self.motion.to_params(file, "motion")?;
        let beacons = self.beacons.to_positions(file, "beacons")?;
        let t = &self.timing;
        require_non_negative(file, "timing.jitter_sigma_s", t.jitter_sigma_s)?;
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
        require_positive(file, "ekf.gate_sigma", e.gate_sigma)?;
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
            let range_samples =
                beacons.len() * (self.motion.duration_s / range_period).floor() as usize;
            if n.outlier_count > range_samples {
                return Err(SimError::invalid(
                    file,
                    "noise.outlier_count",
                    format!(
                        "{} outliers do not fit into the {range_samples} range samples of a run \
                         of case `{}` ({} beacons x {} s / {} s); lower it or lengthen \
                         motion.duration_s",
                        n.outlier_count,
                        case.name,
                        beacons.len(),
                        self.motion.duration_s,
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
                .map_err(|e| SimError::invalid(file, "ekf", crate::error_chain(&e)))?;
            cases.push(Case {
                name: case.name.clone(),
                config,
                setup,
            });
        }
        Ok(Checked {
            runs,
            base_seed: self.base_seed,
            motion,
            figure_run: self.figures.run,
            corr_gap: n.corr_gap_s,
            cases,
        })
    }
}
