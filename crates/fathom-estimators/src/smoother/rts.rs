//! The Rauch-Tung-Striebel backward pass over a recorded [`ForwardPass`] ([`super`]
//! module docs, equations (S1)-(S3)).

use fathom_core::{Time, gaussian::symmetrize};
use nalgebra::{Cholesky, SMatrix, SVector};

use super::forward::{ForwardPass, ForwardStep};
use crate::{EstimatorError, error::check_finite_entries};

/// How states are compared and kept canonical: the backward pass forms
/// `x_{k+1|n} - x_{k+1|k}` with [`StateSpace::difference`] and normalizes every
/// smoothed mean (e.g. wraps a heading).
pub trait StateSpace<const N: usize> {
    /// `a - b` (override to wrap angles).
    fn difference(&self, a: &SVector<f64, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
        a - b
    }

    /// Brings `x` into its canonical range (default: nothing).
    fn normalize(&self, _x: &mut SVector<f64, N>) {}
}

/// Plain vectors: `a - b`, no normalization (linear Kalman filters, error states).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Euclidean;

impl<const N: usize> StateSpace<N> for Euclidean {}

/// The states of an EKF's motion model ([`crate::ekf::MotionModel::difference`] and
/// [`crate::ekf::MotionModel::normalize`]).
#[derive(Debug, Clone, Copy)]
pub struct ModelSpace<'a, M>(pub &'a M);

impl<const N: usize, M: crate::ekf::MotionModel<N>> StateSpace<N> for ModelSpace<'_, M> {
    fn difference(&self, a: &SVector<f64, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
        self.0.difference(a, b)
    }
    fn normalize(&self, x: &mut SVector<f64, N>) {
        self.0.normalize(x);
    }
}

/// One smoothed step: `x_{k|n}`, `P_{k|n}` given every measurement of the pass.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedStep<const N: usize> {
    /// Time of the step, s.
    pub time: Time,
    /// Smoothed mean `x_{k|n}`.
    pub mean: SVector<f64, N>,
    /// Smoothed covariance `P_{k|n}` (symmetric).
    pub cov: SMatrix<f64, N, N>,
}

impl<const N: usize> SmoothedStep<N> {
    /// Bytes one smoothed step occupies: `8 (1 + N + N^2)`.
    pub const BYTES: usize = std::mem::size_of::<Self>();
}

impl<const N: usize> ForwardPass<N> {
    /// The fixed-interval RTS smoother over the whole pass (linear states,
    /// [`Euclidean`]): one smoothed step per recorded step, oldest first.
    ///
    /// # Errors
    /// As [`ForwardPass::smooth_with`].
    pub fn smooth(&self) -> Result<Vec<SmoothedStep<N>>, EstimatorError> {
        self.smooth_with(&Euclidean)
    }

    /// The fixed-interval RTS smoother over the whole pass in the state space `space`.
    ///
    /// # Errors
    /// The recording's first misuse ([`ForwardPass::misuse`]);
    /// [`EstimatorError::NotPositiveDefinite`] naming the step when a predicted
    /// covariance cannot be factored; [`EstimatorError::NonFinite`] for a non-finite
    /// recorded or smoothed value; each with the step's time.
    pub fn smooth_with(
        &self,
        space: &impl StateSpace<N>,
    ) -> Result<Vec<SmoothedStep<N>>, EstimatorError> {
        if let Some(e) = self.misuse() {
            return Err(e.clone());
        }
        backward_pass(self.steps(), 0, space)
    }
}

/// The backward pass over `steps` (the last one is the end of the interval, its
/// smoothed estimate is its filtered one) down to index `first`; returns the smoothed
/// steps `first..`, oldest first.
pub(crate) fn backward_pass<const N: usize>(
    steps: &[ForwardStep<N>],
    first: usize,
    space: &impl StateSpace<N>,
) -> Result<Vec<SmoothedStep<N>>, EstimatorError> {
    let Some(last) = steps.last() else {
        return Ok(Vec::new());
    };
    let n = steps.len();
    check_step(n - 1, last)?;
    let mut out = Vec::with_capacity(n - first);
    out.push(SmoothedStep {
        time: last.time,
        mean: last.filtered_mean,
        cov: last.filtered_cov,
    });
    for k in (first..n - 1).rev() {
        let next_smoothed = &out[out.len() - 1];
        let s = backward_step(k, &steps[k], &steps[k + 1], next_smoothed, space)?;
        out.push(s);
    }
    out.reverse();
    Ok(out)
}

/// Every recorded value of step `k` is finite.
fn check_step<const N: usize>(k: usize, s: &ForwardStep<N>) -> Result<(), EstimatorError> {
    let t = s.time;
    let what = |name: &str| format!("smoother: {name} of step {k}");
    check_finite_entries(&what("time"), 1, 1, |_, _| t, t)?;
    check_finite_entries(&what("transition F"), N, N, |r, c| s.transition[(r, c)], t)?;
    check_finite_entries(&what("predicted mean"), N, 1, |r, _| s.predicted_mean[r], t)?;
    check_finite_entries(
        &what("predicted covariance"),
        N,
        N,
        |r, c| s.predicted_cov[(r, c)],
        t,
    )?;
    check_finite_entries(&what("filtered mean"), N, 1, |r, _| s.filtered_mean[r], t)?;
    check_finite_entries(
        &what("filtered covariance"),
        N,
        N,
        |r, c| s.filtered_cov[(r, c)],
        t,
    )
}

/// One backward step (module docs of [`super`], (S1)-(S3)): the smoothed step `k`
/// from the filtered step `k`, the recorded step `k + 1` and its smoothed estimate.
///
/// The gain `C = P_{k|k} F^T P_{k+1|k}^-1` comes from a Cholesky solve with the
/// predicted covariance scaled to unit diagonal (`D P D`, `D = diag(P_ii^-1/2)`), so
/// that states of very different magnitudes (metres and gyro biases of 1e-7 rad/s)
/// do not cost accuracy.
pub(crate) fn backward_step<const N: usize>(
    k: usize,
    step: &ForwardStep<N>,
    next: &ForwardStep<N>,
    next_smoothed: &SmoothedStep<N>,
    space: &impl StateSpace<N>,
) -> Result<SmoothedStep<N>, EstimatorError> {
    check_step(k, step)?;
    let p_pred = &next.predicted_cov;
    let not_pd = || EstimatorError::NotPositiveDefinite {
        what: format!("smoother: predicted covariance of step {}", k + 1),
        time: next.time,
    };
    let mut d = SVector::<f64, N>::zeros();
    for i in 0..N {
        let v = p_pred[(i, i)];
        if !(v.is_finite() && v > 0.0) {
            return Err(not_pd());
        }
        d[i] = 1.0 / v.sqrt();
    }
    let scaled = SMatrix::<f64, N, N>::from_fn(|r, c| d[r] * p_pred[(r, c)] * d[c]);
    let chol = Cholesky::new(symmetrize(&scaled)).ok_or_else(not_pd)?;
    // C^T = P_pred^-1 F P_f = D (D P_pred D)^-1 D F P_f.
    let mut rhs = next.transition * step.filtered_cov;
    for r in 0..N {
        rhs.row_mut(r).scale_mut(d[r]);
    }
    let mut gain_t = chol.solve(&rhs);
    for r in 0..N {
        gain_t.row_mut(r).scale_mut(d[r]);
    }
    let gain = gain_t.transpose();
    let dx = space.difference(&next_smoothed.mean, &next.predicted_mean);
    let mut mean = step.filtered_mean + gain * dx;
    space.normalize(&mut mean);
    let cov = symmetrize(&(step.filtered_cov + gain * (next_smoothed.cov - p_pred) * gain_t));
    let t = step.time;
    check_finite_entries(
        &format!("smoother: smoothed mean of step {k}"),
        N,
        1,
        |r, _| mean[r],
        t,
    )?;
    check_finite_entries(
        &format!("smoother: smoothed covariance of step {k}"),
        N,
        N,
        |r, c| cov[(r, c)],
        t,
    )?;
    Ok(SmoothedStep { time: t, mean, cov })
}
