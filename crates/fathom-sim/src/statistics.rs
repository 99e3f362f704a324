//! The `[statistics]` settings of a Monte Carlo scenario: how the rows of its
//! `summary.json` summarize the runs (see `fathom_stats::metric_summary` and
//! docs/reading-the-numbers.md).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::SimError;
use fathom_stats::SummarySettings;

/// Bootstrap resamples per interval when the scenario does not say.
pub const DEFAULT_RESAMPLES: usize = 2000;
/// A run diverged when its value exceeds this many times the metric's median, when
/// the scenario does not say.
pub const DEFAULT_DIVERGENCE_FACTOR: f64 = 10.0;

/// `[statistics]`: how the runs of every row are summarized.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StatisticsParams {
    /// Bootstrap resamples behind the interval of a non-negative metric's mean
    /// (100 to 1,000,000); the resampling is seeded from `base_seed`.
    #[serde(default = "default_resamples")]
    pub bootstrap_resamples: usize,
    /// A run counts as diverged for a metric when its value exceeds this factor times
    /// the metric's median over the runs (> 1).
    #[serde(default = "default_divergence_factor")]
    pub divergence_factor: f64,
}

fn default_resamples() -> usize {
    DEFAULT_RESAMPLES
}

fn default_divergence_factor() -> f64 {
    DEFAULT_DIVERGENCE_FACTOR
}

impl Default for StatisticsParams {
    fn default() -> Self {
        Self {
            bootstrap_resamples: DEFAULT_RESAMPLES,
            divergence_factor: DEFAULT_DIVERGENCE_FACTOR,
        }
    }
}

impl StatisticsParams {
    /// The checked settings for runs seeded from `base_seed` (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming `statistics.bootstrap_resamples` or
    /// `statistics.divergence_factor`.
    pub fn check(&self, base_seed: u64, file: &str) -> Result<SummarySettings, SimError> {
        if !(fathom_stats::bootstrap::MIN_RESAMPLES..=fathom_stats::bootstrap::MAX_RESAMPLES)
            .contains(&self.bootstrap_resamples)
        {
            return Err(SimError::invalid(
                file,
                "statistics.bootstrap_resamples",
                format!(
                    "must be between 100 and 1000000, got {}",
                    self.bootstrap_resamples
                ),
            ));
        }
        if !(self.divergence_factor.is_finite() && self.divergence_factor > 1.0) {
            return Err(SimError::invalid(
                file,
                "statistics.divergence_factor",
                format!(
                    "must be a finite number above 1, got {}",
                    self.divergence_factor
                ),
            ));
        }
        Ok(SummarySettings::new(
            self.bootstrap_resamples,
            self.divergence_factor,
            base_seed,
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_and_bad_values_name_their_key() {
        let ok = StatisticsParams::default().check(7, "f.toml").unwrap();
        assert_eq!((ok.resamples(), ok.base_seed()), (2000, 7));
        let few = StatisticsParams {
            bootstrap_resamples: 3,
            ..Default::default()
        };
        let e = few.check(0, "f.toml").unwrap_err().to_string();
        assert!(e.contains("statistics.bootstrap_resamples"), "{e}");
        let bad = StatisticsParams {
            divergence_factor: 0.5,
            ..Default::default()
        };
        let e = bad.check(0, "f.toml").unwrap_err().to_string();
        assert!(e.contains("statistics.divergence_factor"), "{e}");
        let parsed: StatisticsParams = toml::from_str("bootstrap_resamples = 500").unwrap();
        assert_eq!(parsed.divergence_factor, DEFAULT_DIVERGENCE_FACTOR);
        assert!(toml::from_str::<StatisticsParams>("resamples = 500").is_err());
    }
}
