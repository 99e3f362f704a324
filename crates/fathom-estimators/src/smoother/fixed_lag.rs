//! The fixed-lag smoother: the RTS backward pass of [`super::rts`] over a sliding
//! window of the forward pass, for near-real-time use ([`super`] module docs).

use fathom_core::Time;
use nalgebra::SMatrix;

use super::forward::ForwardPass;
use super::rts::{SmoothedStep, StateSpace, backward_pass};
use crate::{EstimatorError, KalmanFilter};

/// A fixed-lag smoother with lag `L` (s): after each recorded step at time `t`, the
/// estimate of the newest step stamped at or before `t - L`, given every measurement
/// up to `t` (`x_{j|k}`). It equals the fixed-interval smoother run on the pass
/// recorded so far, at that step (tested), and costs one backward pass over the
/// window, `O(L / step) N^3` per call; the window keeps only the steps from that step
/// on, so memory is bounded by the lag.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedLagSmoother<const N: usize> {
    lag: f64,
    pass: ForwardPass<N>,
}

impl<const N: usize> FixedLagSmoother<N> {
    /// A smoother with lag `lag` (s, finite and >= 0) starting from the estimate of `kf`.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for a negative or non-finite lag.
    pub fn new(lag: f64, kf: &KalmanFilter<N>) -> Result<Self, EstimatorError> {
        if !(lag.is_finite() && lag >= 0.0) {
            return Err(EstimatorError::OutOfRange {
                what: "fixed-lag smoother lag".into(),
                value: lag,
                expected: "finite and >= 0 s",
            });
        }
        Ok(Self {
            lag,
            pass: ForwardPass::from_filter(kf),
        })
    }

    /// The lag, s.
    pub fn lag(&self) -> f64 {
        self.lag
    }

    /// The window of the forward pass (oldest step first).
    pub fn window(&self) -> &ForwardPass<N> {
        &self.pass
    }

    /// Records a prediction ([`ForwardPass::record_prediction`]).
    pub fn record_prediction(&mut self, transition: &SMatrix<f64, N, N>, kf: &KalmanFilter<N>) {
        self.pass.record_prediction(transition, kf);
    }

    /// Records the estimate after an update ([`ForwardPass::record_update`]).
    pub fn record_update(&mut self, kf: &KalmanFilter<N>) {
        self.pass.record_update(kf);
    }

    /// The lagged estimate: the smoothed estimate of the newest step stamped at or
    /// before `t - lag` (`t` = the newest step's time), or `None` while no step is that
    /// old yet. Drops the steps before it.
    ///
    /// # Errors
    /// As [`ForwardPass::smooth_with`].
    pub fn lagged(
        &mut self,
        space: &impl StateSpace<N>,
    ) -> Result<Option<SmoothedStep<N>>, EstimatorError> {
        if let Some(e) = self.pass.misuse() {
            return Err(e.clone());
        }
        let steps = self.pass.steps();
        let now: Time = steps[steps.len() - 1].time;
        let horizon = now - self.lag;
        let Some(j) = steps.iter().rposition(|s| s.time <= horizon) else {
            return Ok(None);
        };
        let mut smoothed = backward_pass(steps, j, space)?;
        self.pass.drain_before(j);
        Ok(Some(smoothed.swap_remove(0)))
    }
}
