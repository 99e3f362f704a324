//! One Monte Carlo run of a registered experiment, prepared once (scenario loaded and
//! checked, shared truth built) and then callable with any run RNG: what the
//! benchmarks (`crates/fathom-experiments/benches/montecarlo.rs`, `cargo xtask bench`) time
//! as "one run", and the unit of the thread-scaling measurement.
//!
//! ```no_run
//! use fathom_sim::driver::SingleRun;
//! use fathom_sim::montecarlo::run_rng;
//! # fn demo(registry: &[&'static dyn fathom_sim::DynExperiment]) {
//! // `registry` is `fathom_experiments::registry()` in the benchmarks.
//! let beacons = *registry.iter().find(|e| e.name() == "beacons").unwrap();
//! let run = SingleRun::prepare(beacons, std::path::Path::new(".")).unwrap();
//! run.run(3, &mut run_rng(3, 3)).unwrap();
//! # }
//! ```

use std::path::Path;

use rand_chacha::ChaCha8Rng;

use crate::SimError;
use crate::experiment::{DynExperiment, Environment, SingleRunFn};

/// One experiment's single Monte Carlo run (of its main batch), ready to call.
pub struct SingleRun {
    name: &'static str,
    run: SingleRunFn,
}

impl std::fmt::Debug for SingleRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SingleRun")
            .field("name", &self.name)
            .finish()
    }
}

impl SingleRun {
    /// Prepares `exp` from its preset scenario under `workspace_root`.
    ///
    /// # Errors
    /// Scenario, preparation or model errors, as the experiment's own run; an
    /// experiment without a Monte Carlo batch (e.g. `plaza` without its data).
    pub fn prepare(exp: &dyn DynExperiment, workspace_root: &Path) -> Result<Self, SimError> {
        let label = exp.default_scenario();
        let path = workspace_root.join(label);
        let text = std::fs::read_to_string(&path).map_err(|e| SimError::io("read", &path, e))?;
        let env = Environment::new(workspace_root);
        Ok(Self {
            name: exp.name(),
            run: exp.single_run(&text, label, &env)?,
        })
    }

    /// The experiment's name.
    pub fn name(&self) -> &str {
        self.name
    }

    /// Runs run `index` of the main batch once with `rng` (results are discarded; an
    /// experiment may record extra detail for its figure run, usually run 0).
    ///
    /// # Errors
    /// As the experiment's run.
    pub fn run(&self, index: usize, rng: &mut ChaCha8Rng) -> Result<(), SimError> {
        (self.run)(index, rng)
    }
}
