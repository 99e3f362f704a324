//! The recorded forward pass of a Kalman filter: per step the time, the transition
//! Jacobian, and the predicted and filtered mean and covariance (what the
//! Rauch-Tung-Striebel backward pass needs, [`super`] module docs).

use fathom_core::Time;
use nalgebra::{SMatrix, SVector};

use crate::{EstimatorError, KalmanFilter};

/// One step `k` of a forward pass: the prediction from step `k - 1` to `time` and the
/// estimate after the updates at `time`.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardStep<const N: usize> {
    /// Time of the step, s.
    pub time: Time,
    /// Transition Jacobian `F_k = d x_k / d x_{k-1}` of the prediction into this step
    /// (the identity for the first step, which is the prior).
    pub transition: SMatrix<f64, N, N>,
    /// Predicted mean `x_{k|k-1}`.
    pub predicted_mean: SVector<f64, N>,
    /// Predicted covariance `P_{k|k-1}`.
    pub predicted_cov: SMatrix<f64, N, N>,
    /// Filtered mean `x_{k|k}` (equal to the prediction when no update was applied,
    /// e.g. when the gate rejected every measurement of the step).
    pub filtered_mean: SVector<f64, N>,
    /// Filtered covariance `P_{k|k}`.
    pub filtered_cov: SMatrix<f64, N, N>,
}

impl<const N: usize> ForwardStep<N> {
    /// Bytes one step occupies: `8 (1 + 2 N + 3 N^2)` (time, two means, the
    /// transition and two covariances; e.g. 456 B for `N = 4`, 5,648 B for `N = 15`).
    pub const BYTES: usize = std::mem::size_of::<Self>();

    fn at(
        time: Time,
        transition: SMatrix<f64, N, N>,
        x: SVector<f64, N>,
        p: SMatrix<f64, N, N>,
    ) -> Self {
        Self {
            time,
            transition,
            predicted_mean: x,
            predicted_cov: p,
            filtered_mean: x,
            filtered_cov: p,
        }
    }
}

/// A forward pass recorded for smoothing ([`super`] module docs).
///
/// Recording never fails and never changes the filter it watches: a misuse (a
/// prediction stamped before the previous step, an update recorded at a time that is
/// not the last step's) is kept and returned by the backward pass
/// ([`ForwardPass::smooth`]), which also checks every recorded value.
#[derive(Clone, PartialEq)]
pub struct ForwardPass<const N: usize> {
    steps: Vec<ForwardStep<N>>,
    misuse: Option<EstimatorError>,
}

impl<const N: usize> std::fmt::Debug for ForwardPass<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ForwardPass")
            .field("steps", &self.steps.len())
            .field("first", &self.steps.first().map(|s| s.time))
            .field("last", &self.steps.last().map(|s| s.time))
            .field("misuse", &self.misuse)
            .finish()
    }
}

impl<const N: usize> ForwardPass<N> {
    /// A pass whose first step is the prior `(mean, cov)` at `time`.
    pub fn new(time: Time, mean: SVector<f64, N>, cov: SMatrix<f64, N, N>) -> Self {
        Self {
            steps: vec![ForwardStep::at(time, SMatrix::identity(), mean, cov)],
            misuse: None,
        }
    }

    /// A pass starting from the current estimate of `kf`.
    pub fn from_filter(kf: &KalmanFilter<N>) -> Self {
        Self::new(kf.time(), *kf.state(), *kf.covariance())
    }

    /// Records a prediction to `time` with transition Jacobian `transition`: a new
    /// step whose predicted (and, until an update, filtered) estimate is
    /// `(mean, cov)`. A covariance inflation (e.g. the lock-out recovery of
    /// [`crate::robust`]) is recorded the same way, as a step with `F = I` at the
    /// same time.
    pub fn push_prediction(
        &mut self,
        time: Time,
        transition: &SMatrix<f64, N, N>,
        mean: &SVector<f64, N>,
        cov: &SMatrix<f64, N, N>,
    ) {
        let prev = self.last().time;
        // A NaN time is a misuse too.
        if time.is_nan() || time < prev {
            self.note(EstimatorError::TimeBackwards {
                what: format!("smoother record, step {}", self.steps.len()),
                prev,
                next: time,
            });
        }
        self.steps
            .push(ForwardStep::at(time, *transition, *mean, *cov));
    }

    /// [`ForwardPass::push_prediction`] of the estimate `kf` holds after its prediction.
    pub fn record_prediction(&mut self, transition: &SMatrix<f64, N, N>, kf: &KalmanFilter<N>) {
        self.push_prediction(kf.time(), transition, kf.state(), kf.covariance());
    }

    /// Records the estimate after the updates of the last step (call it after every
    /// update, accepted or not; the last call of a step wins).
    pub fn push_update(&mut self, time: Time, mean: &SVector<f64, N>, cov: &SMatrix<f64, N, N>) {
        let index = self.steps.len() - 1;
        let last = self.last_mut();
        if last.time == time {
            last.filtered_mean = *mean;
            last.filtered_cov = *cov;
        } else {
            let step_time = last.time;
            self.note(EstimatorError::Smoother {
                what: format!(
                    "update at t = {time} s recorded on step {index}, whose time is {step_time} s \
                     (a prediction was not recorded)"
                ),
                time,
            });
        }
    }

    /// [`ForwardPass::push_update`] of the current estimate of `kf`.
    pub fn record_update(&mut self, kf: &KalmanFilter<N>) {
        self.push_update(kf.time(), kf.state(), kf.covariance());
    }

    fn note(&mut self, e: EstimatorError) {
        if self.misuse.is_none() {
            self.misuse = Some(e);
        }
    }

    fn last(&self) -> &ForwardStep<N> {
        // `steps` is never empty: the constructor pushes the prior and
        // `drain_before` keeps at least one step.
        &self.steps[self.steps.len() - 1]
    }

    fn last_mut(&mut self) -> &mut ForwardStep<N> {
        let i = self.steps.len() - 1;
        &mut self.steps[i]
    }

    /// The recorded steps, oldest first (never empty).
    pub fn steps(&self) -> &[ForwardStep<N>] {
        &self.steps
    }

    /// Number of steps (at least 1: the prior).
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// Always `false` (a pass holds at least its prior); for API symmetry.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// Index of the newest step (the one the filter's current estimate belongs to).
    pub fn last_index(&self) -> usize {
        self.steps.len() - 1
    }

    /// The first misuse of the recording API, if any ([`ForwardPass`] docs).
    pub fn misuse(&self) -> Option<&EstimatorError> {
        self.misuse.as_ref()
    }

    /// Heap bytes held by the steps (`capacity * ForwardStep::BYTES`).
    pub fn memory_bytes(&self) -> usize {
        self.steps.capacity() * ForwardStep::<N>::BYTES
    }

    /// Drops the steps before index `first` (kept: at least the newest step); used by
    /// the fixed-lag smoother. Returns how many were dropped.
    pub fn drain_before(&mut self, first: usize) -> usize {
        let n = first.min(self.steps.len() - 1);
        self.steps.drain(..n);
        n
    }
}
