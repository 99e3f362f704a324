//! The `noise` scenario file: schema and check.

use fathom_sensors::{
    BeaconSuiteConfig, BeaconSuiteParams, NoiseSwitches, Timing, noise::OutlierParams,
};
use fathom_traj::velocity_command::VelocityCommandParams;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::common::{BeaconsToml, MotionToml, check_case_name};
use fathom_sim::SimError;
use fathom_sim::scenario::{require_non_negative, require_positive};

/// Noise-generator verification.
///
/// Paper B (Han et al. 2016, seed 003) §4.1-4.3, eqs. (5)-(9): the 5×5 covariance of
/// the noise of `[range1..4, depth]`, estimated per case and run, against the design
/// `diag(σ_r² ×4, σ_d²) + σ_c² (ones(4,4) ⊕ 0)`. Preset: `scenarios/noise.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NoiseScenario {
    /// The experiment this file is for.
    ///
    /// Range: `"noise"`.
    pub experiment: String,
    /// Monte Carlo runs of the paper-length generation; `--runs` overrides.
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// Run `i` uses ChaCha stream `i` of this seed.
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub base_seed: u64,
    /// Robot motion (Tables 1 and 9).
    pub motion: MotionToml,
    /// Synchronous sampling (Tables 2-3).
    pub timing: TimingToml,
    /// Beacon positions.
    pub beacons: BeaconsToml,
    /// Noise levels (Table 10, Table 7).
    pub noise: NoiseLevelsToml,
    /// The convergence run.
    pub long_run: LongRunToml,
    /// The noise configurations (eqs. 5-9).
    pub cases: Vec<CaseToml>,
    /// `[statistics]`: how the runs of each row are summarized (bootstrap resamples,
    /// divergence factor); defaults when absent.
    #[serde(default)]
    pub statistics: fathom_sim::statistics::StatisticsParams,
}

/// `[timing]`: synchronous sampling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimingToml {
    /// Common sample period of the four ranges and the depth gauge, so that the five
    /// noises form one vector per epoch (paper: 0.1).
    ///
    /// Unit: s. Range: > 0.
    pub period_s: f64,
    /// Sample-time jitter σ_t: `t_i = t_{i-1} + dt + N(0, σ_t²)` (not given by the
    /// paper).
    ///
    /// Unit: s. Range: ≥ 0 and < `period_s`/4.
    pub jitter_sigma_s: f64,
}

/// `[noise]`: noise levels shared by the cases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NoiseLevelsToml {
    /// White range noise σ_r (paper: 0.1).
    ///
    /// Unit: m. Range: > 0.
    pub range_sigma_m: f64,
    /// White depth noise σ_d (paper: 0.2).
    ///
    /// Unit: m. Range: > 0.
    pub depth_sigma_m: f64,
    /// Hold time t_gap of the common-mode range noise: one value, added to all four
    /// ranges, redrawn every t_gap (Table 7: 1).
    ///
    /// Unit: s. Range: > 0.
    pub corr_gap_s: f64,
}

/// `[long_run]`: the convergence run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LongRunToml {
    /// Length of one long run that shows convergence to the design.
    ///
    /// Unit: s. Range: > 0 and ≥ `motion.duration_s`.
    pub duration_s: f64,
    /// Its motion step (coarser than the paper's: the noise does not depend on the
    /// path).
    ///
    /// Unit: s. Range: > 0.
    pub step_s: f64,
    /// Largest accepted relative deviation of the long run's covariance from the design
    /// (claim `generator_cov_matches_design`; 0.05 = 5 %).
    ///
    /// Range: > 0.
    pub max_rel_dev: f64,
}

/// `[[cases]]`: one noise configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CaseToml {
    /// Case name; `gaussian`, `corr_high`, `corr_low`, `both_high`, `both_low` get the
    /// paper's matrices (eqs. 5-9) as reference, other names none.
    ///
    /// Range: non-empty, `[A-Za-z0-9_-]`, unique.
    pub name: String,
    /// White Gaussian range and depth noise on or off.
    pub gaussian: bool,
    /// Common-mode range noise σ_c (0 = none; paper: 0.2 high, 0.05 low).
    ///
    /// Unit: m. Range: ≥ 0; not 0 when `gaussian = false`.
    pub corr_sigma_m: f64,
}

fathom_sim::monte_carlo_scenario!(NoiseScenario);

/// The checked scenario.
#[derive(Debug, Clone)]
pub struct Checked {
    pub(super) runs: usize,
    pub(super) base_seed: u64,
    pub(super) motion: VelocityCommandParams,
    pub(super) long_motion: VelocityCommandParams,
    pub(super) long_max_rel_dev: f64,
    /// Synchronous sample period, s.
    pub(super) period: f64,
    /// Sample-time jitter sigma, s.
    pub(super) jitter_sigma: f64,
    /// Hold time of the common-mode noise, s.
    pub(super) corr_gap: f64,
    pub(super) cases: Vec<Case>,
}

/// One checked case.
#[derive(Debug, Clone)]
pub struct Case {
    pub(super) name: String,
    pub(super) config: BeaconSuiteConfig,
    pub(super) long_config: BeaconSuiteConfig,
}

impl NoiseScenario {
    /// Validates the scenario (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<Checked, SimError> {
        let runs = self.runs;
        let motion = self.motion.to_params(file, "motion")?;
        let beacons = self.beacons.to_positions(file, "beacons")?;
        if beacons.len() != 4 {
            return Err(SimError::invalid(
                file,
                "beacons.positions",
                format!(
                    "the noise experiment reproduces the paper's 5x5 matrices and needs exactly 4 beacons, got {}",
                    beacons.len()
                ),
            ));
        }
        require_positive(file, "timing.period_s", self.timing.period_s)?;
        require_non_negative(file, "timing.jitter_sigma_s", self.timing.jitter_sigma_s)?;
        crate::common::require_period_over_jitter(
            file,
            "timing.period_s",
            self.timing.period_s,
            self.timing.jitter_sigma_s,
        )?;
        require_positive(file, "noise.range_sigma_m", self.noise.range_sigma_m)?;
        require_positive(file, "noise.depth_sigma_m", self.noise.depth_sigma_m)?;
        require_positive(file, "noise.corr_gap_s", self.noise.corr_gap_s)?;
        require_positive(file, "long_run.duration_s", self.long_run.duration_s)?;
        require_positive(file, "long_run.step_s", self.long_run.step_s)?;
        require_positive(file, "long_run.max_rel_dev", self.long_run.max_rel_dev)?;
        if self.long_run.duration_s < self.motion.duration_s {
            return Err(SimError::invalid(
                file,
                "long_run.duration_s",
                format!(
                    "must be at least the paper-length run ({} s), got {}",
                    self.motion.duration_s, self.long_run.duration_s
                ),
            ));
        }
        if self.cases.is_empty() {
            return Err(SimError::invalid(file, "cases", "needs at least one case"));
        }
        let long_motion = VelocityCommandParams {
            duration: self.long_run.duration_s,
            dt: self.long_run.step_s,
            ..motion.clone()
        };
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
            if !case.gaussian && case.corr_sigma_m == 0.0 {
                return Err(SimError::invalid(
                    file,
                    format!("{key}.corr_sigma_m"),
                    "is 0 with gaussian = false: the case has no noise at all",
                ));
            }
            let params = BeaconSuiteParams {
                timing: Timing::Synchronous {
                    period: self.timing.period_s,
                },
                jitter_sigma: self.timing.jitter_sigma_s,
                stamp_offset: 0.0,
                stamp_jitter_sigma: 0.0,
                range_sigma: self.noise.range_sigma_m,
                depth_sigma: self.noise.depth_sigma_m,
                corr_sigma: case.corr_sigma_m,
                t_gap: self.noise.corr_gap_s,
                outliers: OutlierParams {
                    count: 0,
                    ..OutlierParams::default()
                },
                switches: NoiseSwitches {
                    gaussian: case.gaussian,
                    correlation: case.corr_sigma_m > 0.0,
                    outliers: false,
                },
                beacons_in_nav: beacons.clone(),
                ..BeaconSuiteParams::default()
            };
            let config = params
                .check()
                .map_err(|e| SimError::invalid(file, key.clone(), e.to_string()))?;
            let long_config = config.clone();
            cases.push(Case {
                name: case.name.clone(),
                config,
                long_config,
            });
        }
        Ok(Checked {
            runs,
            base_seed: self.base_seed,
            motion,
            long_motion,
            long_max_rel_dev: self.long_run.max_rel_dev,
            period: self.timing.period_s,
            jitter_sigma: self.timing.jitter_sigma_s,
            corr_gap: self.noise.corr_gap_s,
            cases,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario_text() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/noise.toml"),
        )
        .unwrap()
    }

    #[test]
    fn preset_parses_and_checks() {
        let s: NoiseScenario =
            fathom_sim::scenario::parse_toml(&scenario_text(), "noise.toml").unwrap();
        let c = s.check("noise.toml").unwrap();
        assert_eq!(c.cases.len(), 5);
        assert!(c.runs >= 100);
    }

    #[test]
    fn negative_sigma_names_the_key() {
        let text = scenario_text().replace("range_sigma_m = 0.1", "range_sigma_m = -0.1");
        let s: NoiseScenario = fathom_sim::scenario::parse_toml(&text, "noise.toml").unwrap();
        let err = s.check("noise.toml").unwrap_err().to_string();
        assert!(err.contains("noise.range_sigma_m"), "{err}");
    }

    #[test]
    fn unknown_key_names_the_key() {
        let text = scenario_text().replace("corr_gap_s = 1.0", "corr_gap_s = 1.0\ncorr_gapp = 2.0");
        let err = fathom_sim::scenario::parse_toml::<NoiseScenario>(&text, "noise.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("corr_gapp"), "{err}");
    }
}
