//! The run a PILS session flies, behind two small traits so the sides do not care
//! where the data comes from: [`SensorSource`] (the simulator: truth and the sensor
//! epochs) and [`Navigator`] (the navigation: epochs in, solutions out). The `urban`
//! flight (`crate::urban_flight`) implements both.

use fathom_ins::local_level::LocalTruthSample;

use crate::PilsError;
use crate::epoch::{Epoch, InitialEstimate, Solution};

/// IMU step, s (100 Hz).
pub const IMU_DT: f64 = 0.01;

/// The simulator side: truth and sensor epochs, step by step.
pub trait SensorSource {
    /// Steps of the run (the last step's index + 1).
    fn steps(&self) -> u64;
    /// The truth at step `k`.
    fn truth(&self, k: u64) -> &LocalTruthSample;
    /// The sensor epoch of step `k >= 1`.
    fn epoch(&self, k: u64) -> &Epoch;
    /// The initial estimate (sent at its step).
    fn initial(&self) -> &InitialEstimate;
}

/// The navigation side: epochs in time order, a solution per epoch once started.
pub trait Navigator {
    /// Processes one epoch (`init` at the start step); returns the solution after it.
    ///
    /// # Errors
    /// [`PilsError::Model`] when the mechanization diverges.
    fn step(
        &mut self,
        e: &Epoch,
        init: Option<&InitialEstimate>,
    ) -> Result<Option<Solution>, PilsError>;
}
