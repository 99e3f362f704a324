//! Post-processing: the fixed-interval Rauch-Tung-Striebel (RTS) smoother over a
//! recorded forward pass of any filter built on the Kalman core, and a fixed-lag
//! variant on the same backward step.
//!
//! # Forward pass
//! The filter runs as usual; a [`ForwardPass`] records, per step `k` (a prediction
//! to a new time and the updates applied there), the transition Jacobian `F_k`, the
//! predicted `x_{k|k-1}, P_{k|k-1}` and the filtered `x_{k|k}, P_{k|k}`. Recording
//! never changes the filter. With the bare [`KalmanFilter`](crate::KalmanFilter) the
//! caller records ([`ForwardPass::record_prediction`] after each prediction,
//! [`ForwardPass::record_update`] after the updates); the filters of this crate
//! record themselves when asked: [`crate::ekf::Ekf::start_recording`] (and through it
//! [`crate::schemes::SchemeFilter::with_recording`]),
//! [`crate::error_state::ErrorStateFilter::start_recording`],
//! [`crate::integrated_nav::IntegratedNavFilter::start_recording`].
//!
//! # Backward pass (Rauch, Tung and Striebel 1965; Särkkä, *Bayesian Filtering and Smoothing*, eq. 8.2)
//! From the last step (`x_{n|n}`, `P_{n|n}`) down to the first:
//!
//! ```text
//! (S1)  C_k     = P_{k|k} F_{k+1}^T P_{k+1|k}^-1
//! (S2)  x_{k|n} = x_{k|k} + C_k (x_{k+1|n} - x_{k+1|k})
//! (S3)  P_{k|n} = P_{k|k} + C_k (P_{k+1|n} - P_{k+1|k}) C_k^T
//! ```
//!
//! For a linear-Gaussian model this is the exact posterior of every state given all
//! measurements of the interval, i.e. the batch least-squares solution and its
//! covariance (tested to 1e-9). For an EKF it is the extended RTS smoother: the
//! Jacobians of the forward pass, no relinearization; `-` in (S2) is the state
//! space's difference ([`StateSpace`], e.g. a wrapped heading with [`ModelSpace`]).
//!
//! # What counts as a step
//! - A rejected or gated-out update changes nothing: the step's filtered estimate is
//!   its prediction, and the smoother ignores that measurement exactly as the filter
//!   did. Several updates at one time (sequential scalars, SC stacks, velocity then
//!   depth) make one step.
//! - A covariance inflation (the lock-out recovery of [`crate::robust`]) is a step at
//!   the same time with `F = I` and `P_{k+1|k} = c P_{k|k}`, i.e. extra process noise.
//! - Consecutive predictions without an update are separate steps, so every instant
//!   at which the caller read the filter (its [`ForwardPass::last_index`]) has its
//!   smoothed estimate.
//!
//! # Error-state (feedback) filters
//! The error state is reset to zero after each feedback into the nominal trajectory,
//! so each step's error is relative to the nominal *before* that step's feedback
//! (the predicted nominal): the record holds `x_{k|k-1} = 0` and `x_{k|k}` = the
//! correction fed back. In these coordinates the model is linear with a known input
//! (the feedback), which cancels in (S2), so the smoother runs unchanged; the smoothed
//! error `x_{k|n}` is applied to the predicted nominal of step `k` (equivalently,
//! `x_{k|n} - x_{k|k}` to the corrected one). [`crate::error_state::ErrorStateFilter`]
//! records this way; an exact equivalence test against the total-state smoother is in
//! the tests.
//!
//! # Memory and time
//! A step holds `8 (1 + 2 N + 3 N^2)` bytes ([`ForwardStep::BYTES`]), the smoothed
//! output `8 (1 + N + N^2)` ([`SmoothedStep::BYTES`]):
//!
//! | N | forward step | smoothed step | example |
//! | --- | --- | --- | --- |
//! | 4 | 456 B | 168 B | beacon EKF `(x, y, z, psi)` |
//! | 5 | 688 B | 248 B | Plaza EKF with range offset and scale |
//! | 9 | 2,096 B | 728 B | 9-state INS/velocity filter |
//! | 15 | 5,648 B | 1,928 B | 15-state error-state INS |
//!
//! The backward step costs one `N x N` Cholesky factorization and a few `N^3`
//! products (`docs/performance.md` has the step counts and memory of the longest runs).
//!
//! # Fixed lag
//! [`FixedLagSmoother`] keeps the steps of the last `L` seconds and runs the same
//! backward pass over them: after each step at `t` it gives the estimate of the step
//! at `t - L` given the data up to `t`.

mod fixed_lag;
mod forward;
mod rts;
#[cfg(test)]
mod tests;

pub use fixed_lag::FixedLagSmoother;
pub use forward::{ForwardPass, ForwardStep};
pub use rts::{Euclidean, ModelSpace, SmoothedStep, StateSpace};
