//! One Monte Carlo run of a paper experiment, prepared once (scenario loaded and
//! checked, shared truth built) and then callable with any run RNG: what the
//! benchmarks (`crates/fathom-sim/benches/montecarlo.rs`, `cargo xtask bench`) time
//! as "one run", and the unit of the thread-scaling measurement.
//!
//! ```no_run
//! use fathom_sim::experiments::single_run::SingleRun;
//! use fathom_sim::montecarlo::run_rng;
//! let run = SingleRun::prepare("beacons", std::path::Path::new(".")).unwrap();
//! run.run(&mut run_rng(3, 0)).unwrap();
//! ```

use std::path::Path;

use rand_chacha::ChaCha8Rng;

use crate::SimError;
use crate::experiment::ExperimentContext;

/// The prepared run function of one experiment.
pub(crate) type RunFn = Box<dyn Fn(&mut ChaCha8Rng) -> Result<(), SimError> + Send + Sync>;

/// One experiment's single Monte Carlo run, ready to call.
pub struct SingleRun {
    name: String,
    run: RunFn,
}

impl std::fmt::Debug for SingleRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SingleRun")
            .field("name", &self.name)
            .finish()
    }
}

impl SingleRun {
    /// Prepares experiment `name` (`fusion`, `noise`, `beacons` or `vkf`) from its
    /// registered default scenario under `workspace_root`.
    ///
    /// # Errors
    /// [`SimError::UnknownExperiment`] for another name; scenario or model errors as
    /// the experiment's own run.
    pub fn prepare(name: &str, workspace_root: &Path) -> Result<Self, SimError> {
        let registry = super::registry();
        let Some(exp) = registry.iter().find(|e| e.name == name) else {
            return Err(SimError::UnknownExperiment {
                name: name.to_string(),
                known: registry.iter().map(|e| e.name.to_string()).collect(),
            });
        };
        let ctx = ExperimentContext {
            name: exp.name.to_string(),
            workspace_root: workspace_root.to_path_buf(),
            scenario_path: workspace_root.join(exp.default_scenario),
            scenario_label: exp.default_scenario.to_string(),
            out_dir: workspace_root.join("target").join("bench").join(exp.name),
            runs: None,
            threads: None,
            seed: None,
            progress: None,
        };
        let run = match name {
            "fusion" => super::fusion::single_run(&ctx)?,
            "noise" => super::noise::single_run(&ctx)?,
            "beacons" => super::beacons::single_run(&ctx)?,
            "vkf" => super::vkf::single_run(&ctx)?,
            other => {
                return Err(SimError::UnknownExperiment {
                    name: other.to_string(),
                    known: registry.iter().map(|e| e.name.to_string()).collect(),
                });
            }
        };
        Ok(Self {
            name: name.to_string(),
            run,
        })
    }

    /// The experiment's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Runs it once with `rng` (results are discarded).
    ///
    /// # Errors
    /// As the experiment's run.
    pub fn run(&self, rng: &mut ChaCha8Rng) -> Result<(), SimError> {
        (self.run)(rng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_are_errors() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let e = SingleRun::prepare("nope", &root).unwrap_err();
        assert!(matches!(e, SimError::UnknownExperiment { .. }), "{e}");
        let run = SingleRun::prepare("noise", &root).unwrap();
        assert_eq!(run.name(), "noise");
    }
}
