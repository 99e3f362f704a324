//! Generic extended Kalman filter on the fixed-size core: a pluggable motion model
//! (prediction mean, Jacobian and process noise from an input and a time step) and
//! pluggable scalar measurement models (prediction and Jacobian row), with sequential
//! (diagonal `R`) and stacked (full `R`) group updates and per-measurement gating.
//!
//! The filter is generic over the state dimension `N` (a const generic) so the same
//! code serves the 4-state `(x, y, z, psi)` beacon EKF of paper B ([`crate::beacon_ekf`])
//! and a 3-state wheel-odometry EKF `(x, y, heading)` for real data.
//!
//! # Linearization of a group
//! A *group* is a set of scalar measurements taken at the filter time. Every scalar
//! `i` is linearized **once**, at the state `x0` before the group:
//! `h_i(x) ~ h_i(x0) + H_i (x - x0)`. The stacked update applies all of them at once
//! with a full `R`; the sequential update applies them one after another, the `i`-th
//! with innovation `nu_i = (z_i - h_i(x0)) - H_i (x - x0)` at the partially updated
//! state `x` (scalar Joseph update, `r_i = R_ii`). With a diagonal `R` both are the same
//! linear-Gaussian update, so they agree to rounding error: any difference between the
//! two comes only from the off-diagonal terms of `R` and from gating.
//!
//! # Gating (paper B eq. 10)
//! A scalar with a gate is rejected when `nu_i^2 / S_i > d^2`. Stacked: `S_i` is the
//! diagonal entry of `S = H P H^T + R` at the prior `P`, and the rejected components
//! are removed before the stacked update. Sequential: `S_i = H_i P H_i^T + r_i` with
//! the `P` after the preceding scalars of the group.

use crate::{
    EstimatorError, GateThreshold, KalmanFilter, ScalarMeasurement, ScalarOutcome,
    error::check_finite_entries,
    smoother::{ForwardPass, ModelSpace, SmoothedStep},
};
use fathom_core::{Gaussian, Time, gaussian::SYMMETRY_TOLERANCE};
use nalgebra::{DMatrix, RowSVector, SMatrix, SVector};

/// The discrete motion step computed by a [`MotionModel`].
#[derive(Debug, Clone, PartialEq)]
pub struct Propagation<const N: usize> {
    /// Predicted mean `x^- = f(x, u, dt)`.
    pub x_pred: SVector<f64, N>,
    /// Jacobian `F = df/dx` at the prior mean.
    pub f_jacobian: SMatrix<f64, N, N>,
    /// Discrete process noise `Q` of the step (symmetric, positive semi-definite).
    pub q: SMatrix<f64, N, N>,
}

/// A motion model: how the state moves over `dt` given the current input.
///
/// The input is assembled from samples of possibly several sensors (e.g. the
/// latest DVL velocity and the latest AHRS yaw rate): [`MotionModel::apply_sample`]
/// merges one received sample into the input held by the filter, which then
/// drives every prediction until the next sample arrives (zero-order hold).
pub trait MotionModel<const N: usize> {
    /// The full input used by a prediction.
    type Input: Clone + std::fmt::Debug;
    /// One sample as a sensor delivers it.
    type InputSample: Clone + std::fmt::Debug;

    /// Merges a received sample into the held input.
    fn apply_sample(&self, input: &mut Self::Input, sample: &Self::InputSample);

    /// The first non-finite component of `sample` as `(quantity, index, value)`, or
    /// `None` when the sample is finite. Used by [`Ekf::try_apply_input`] and by the
    /// scheme filter, which drops and counts such samples
    /// ([`crate::schemes::SchemeFilter::non_finite_inputs`]). The default checks
    /// nothing (`None`); then a non-finite sample is caught by the next prediction.
    fn non_finite_in_sample(
        &self,
        _sample: &Self::InputSample,
    ) -> Option<(&'static str, usize, f64)> {
        None
    }

    /// Mean, Jacobian and process noise of a step of length `dt > 0` from `x`.
    ///
    /// # Errors
    /// Model-specific (e.g. a non-finite input), as [`EstimatorError`]; the model
    /// does not know the filter time, [`Ekf::predict_to`] stamps the error with the
    /// prediction's target time.
    fn propagate(
        &self,
        x: &SVector<f64, N>,
        input: &Self::Input,
        dt: f64,
    ) -> Result<Propagation<N>, EstimatorError>;

    /// Brings a state into its canonical range (e.g. wraps headings to `(-pi, pi]`).
    fn normalize(&self, _x: &mut SVector<f64, N>) {}

    /// The difference `a - b` of two states, angles wrapped (used for NEES).
    fn difference(&self, a: &SVector<f64, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
        a - b
    }
}

/// A scalar measurement model `z = h(x) + v`.
pub trait ScalarModel<const N: usize> {
    /// The predicted measurement `h(x)` and its Jacobian row `H = dh/dx` at `x`.
    ///
    /// # Errors
    /// Where `h` is not differentiable (e.g. a range at zero distance).
    fn evaluate(&self, x: &SVector<f64, N>) -> Result<(f64, RowSVector<f64, N>), EstimatorError>;

    /// The residual `z - h` (override to wrap angles).
    fn residual(&self, z: f64, predicted: f64) -> f64 {
        z - predicted
    }
}

/// One scalar measurement of a group update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupItem<'a, S> {
    /// Measured value `z`.
    pub value: f64,
    /// Its model.
    pub model: &'a S,
    /// Noise variance `r` (used by the sequential update; the stacked update takes
    /// the full `R`).
    pub variance: f64,
    /// Gate, or `None` to always accept.
    pub gate: Option<GateThreshold>,
}

/// An EKF: a [`KalmanFilter`] plus a motion model and the input it currently holds.
///
/// Bad input (crate docs, "Bad input"): a non-finite measurement, input sample or
/// time is an error naming the quantity, the item index and the filter time; a
/// covariance that stops being positive definite is an error with the time; the
/// filter is unchanged on every error.
///
/// Smoothing: after [`Ekf::start_recording`] every prediction, group update and
/// covariance inflation is recorded ([`crate::smoother`]), and [`Ekf::smooth`] runs
/// the RTS backward pass over the record.
#[derive(Debug, Clone, PartialEq)]
pub struct Ekf<const N: usize, M: MotionModel<N>> {
    kf: KalmanFilter<N>,
    model: M,
    input: M::Input,
    recording: Option<ForwardPass<N>>,
}

impl<const N: usize, M: MotionModel<N>> Ekf<N, M> {
    /// An EKF starting from `prior` at `time`, holding `input` until the first sample.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`].
    pub fn new(
        prior: Gaussian<N>,
        time: Time,
        model: M,
        input: M::Input,
    ) -> Result<Self, EstimatorError> {
        Ok(Self {
            kf: KalmanFilter::new(prior, time)?,
            model,
            input,
            recording: None,
        })
    }

    /// Starts recording the forward pass for smoothing from the current estimate
    /// (replacing an earlier record). Recording does not change any estimate.
    pub fn start_recording(&mut self) {
        self.recording = Some(ForwardPass::from_filter(&self.kf));
    }

    /// The forward pass recorded so far (`None` unless [`Ekf::start_recording`] was
    /// called); its [`ForwardPass::last_index`] is the step of the current estimate.
    pub fn forward_pass(&self) -> Option<&ForwardPass<N>> {
        self.recording.as_ref()
    }

    /// Takes the recorded forward pass out (recording stops).
    pub fn take_forward_pass(&mut self) -> Option<ForwardPass<N>> {
        self.recording.take()
    }

    /// The fixed-interval RTS smoother over the recorded pass, in the model's state
    /// space ([`ModelSpace`]: its `difference` and `normalize`).
    ///
    /// # Errors
    /// [`EstimatorError::Smoother`] when recording is off, else as
    /// [`ForwardPass::smooth_with`].
    pub fn smooth(&self) -> Result<Vec<SmoothedStep<N>>, EstimatorError> {
        match &self.recording {
            Some(pass) => pass.smooth_with(&ModelSpace(&self.model)),
            None => Err(EstimatorError::Smoother {
                what: "EKF smoother: the forward pass was not recorded (start_recording)".into(),
                time: self.kf.time(),
            }),
        }
    }

    fn record_update(&mut self) {
        if let Some(pass) = &mut self.recording {
            pass.record_update(&self.kf);
        }
    }

    /// The underlying Kalman filter (state, covariance, time).
    pub fn filter(&self) -> &KalmanFilter<N> {
        &self.kf
    }

    /// The motion model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The held input.
    pub fn input(&self) -> &M::Input {
        &self.input
    }

    /// The filter time, s.
    pub fn time(&self) -> Time {
        self.kf.time()
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, N> {
        self.kf.state()
    }

    /// The covariance.
    pub fn covariance(&self) -> &SMatrix<f64, N, N> {
        self.kf.covariance()
    }

    /// Multiplies the covariance by `factor` (> 0), keeping the state: covariance
    /// inflation, e.g. to recover from a lock-out ([`crate::robust`]).
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for a non-positive or non-finite factor, or a
    /// covariance error; the filter is unchanged on error.
    pub fn inflate_covariance(&mut self, factor: f64) -> Result<(), EstimatorError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(EstimatorError::OutOfRange {
                what: "covariance inflation factor".into(),
                value: factor,
                expected: "> 0",
            });
        }
        let t = self.kf.time();
        let estimate = Gaussian::new(*self.kf.state(), self.kf.covariance() * factor)
            .map_err(|e| EstimatorError::from_core_at(e, t))?;
        self.kf.set_estimate(estimate)?;
        // Extra process noise: a step with F = I at the same time (smoother docs).
        if let Some(pass) = &mut self.recording {
            pass.record_prediction(&SMatrix::identity(), &self.kf);
        }
        Ok(())
    }

    /// Merges a received input sample (it drives the predictions from now on).
    ///
    /// Unchecked: a non-finite sample is held and makes every later prediction fail
    /// (with an error naming the input, at the prediction's target time) until a
    /// finite sample replaces it. [`Ekf::try_apply_input`] refuses it up front.
    pub fn apply_input(&mut self, sample: &M::InputSample) {
        self.model.apply_sample(&mut self.input, sample);
    }

    /// [`Ekf::apply_input`] after checking the sample
    /// ([`MotionModel::non_finite_in_sample`]).
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`] naming the quantity and component index, at the
    /// filter time; the held input is unchanged.
    pub fn try_apply_input(&mut self, sample: &M::InputSample) -> Result<(), EstimatorError> {
        if let Some((what, index, value)) = self.model.non_finite_in_sample(sample) {
            return Err(EstimatorError::NonFinite {
                what: what.into(),
                index,
                value,
                time: self.kf.time(),
            });
        }
        self.apply_input(sample);
        Ok(())
    }

    /// Predicts to `time` with the held input (nothing to do when `time` equals the
    /// filter time).
    ///
    /// # Errors
    /// [`EstimatorError::TimeBackwards`] for `time` before the filter time, the motion
    /// model's errors, or the core's prediction errors; the filter is unchanged.
    pub fn predict_to(&mut self, time: Time) -> Result<(), EstimatorError> {
        let now = self.kf.time();
        if !time.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "predict: time".into(),
                index: 0,
                value: time,
                time: now,
            });
        }
        if time < now {
            return Err(EstimatorError::TimeBackwards {
                what: "EKF predict".into(),
                prev: now,
                next: time,
            });
        }
        if time == now {
            return Ok(());
        }
        let prop = self
            .model
            .propagate(self.kf.state(), &self.input, time - now)
            .map_err(|e| e.at_time(time))?;
        let mut x = prop.x_pred;
        self.model.normalize(&mut x);
        self.kf
            .predict_nonlinear(&x, &prop.f_jacobian, &prop.q, time)?;
        if let Some(pass) = &mut self.recording {
            pass.record_prediction(&prop.f_jacobian, &self.kf);
        }
        Ok(())
    }

    /// Linearizes item `i` at `x0`: `(h_i(x0), H_i)`.
    fn linearize_at<S: ScalarModel<N>>(
        &self,
        i: usize,
        item: &GroupItem<'_, S>,
        x0: &SVector<f64, N>,
    ) -> Result<(f64, RowSVector<f64, N>), EstimatorError> {
        if !item.value.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "measurement z".into(),
                index: i,
                value: item.value,
                time: self.kf.time(),
            });
        }
        item.model.evaluate(x0)
    }

    /// Sequential scalar updates of a group at the filter time (module docs:
    /// linearized once at the prior state, diagonal `R`, per-item gate). Returns one
    /// outcome per item, in order.
    ///
    /// # Errors
    /// Non-finite values, model errors, non-positive variances or a covariance that
    /// stops being positive definite; the filter is unchanged on error.
    pub fn update_sequential<S: ScalarModel<N>>(
        &mut self,
        items: &[GroupItem<'_, S>],
    ) -> Result<Vec<ScalarOutcome>, EstimatorError> {
        let x0 = *self.kf.state();
        let backup = self.kf.clone();
        let mut outcomes = Vec::with_capacity(items.len());
        let t = self.kf.time();
        for (i, it) in items.iter().enumerate() {
            let res = self.linearize_at(i, it, &x0).and_then(|(h0, h_row)| {
                let base = it.model.residual(it.value, h0);
                check_item(i, base, &h_row, it.variance, t)?;
                self.kf
                    .update_sequential_scalar_with(1, it.gate, |_, x| ScalarMeasurement {
                        innovation: base - (h_row * (x - x0))[0],
                        h_row,
                        variance: it.variance,
                    })
                    .map_err(|e| reindex(e, i))
            });
            match res {
                Ok(rep) => outcomes.extend(rep.outcomes),
                Err(e) => {
                    self.kf = backup;
                    return Err(e);
                }
            }
        }
        self.renormalize(backup)?;
        self.record_update();
        Ok(outcomes)
    }

    /// Stacked update of a group at the filter time with the full covariance `r`
    /// (`items.len()` square): per-component gating at the prior, rejected components
    /// removed, then one stacked update `K = P H^T S^-1` of the rest. The outcomes
    /// report `nu_i`, `S_ii` and `nu_i^2 / S_ii` per item.
    ///
    /// Computation: with `R_kept = L L^T` (Cholesky), the kept stack is whitened,
    /// `nu' = L^-1 nu`, `H' = L^-1 H`, whose components are independent with unit
    /// variance; their sequential scalar Joseph updates equal the stacked update
    /// exactly (linear-Gaussian algebra; tested against `K = P H^T S^-1` to 1e-9)
    /// while staying on the fixed-size, allocation-light path.
    ///
    /// # Errors
    /// Dimension mismatch, non-finite or non-symmetric inputs, model errors, or a
    /// covariance that is not positive definite; the filter is unchanged on error.
    pub fn update_stacked<S: ScalarModel<N>>(
        &mut self,
        items: &[GroupItem<'_, S>],
        r: &DMatrix<f64>,
    ) -> Result<Vec<ScalarOutcome>, EstimatorError> {
        let m = items.len();
        if r.nrows() != m || r.ncols() != m {
            return Err(EstimatorError::DimensionMismatch {
                what: "stacked measurement noise R".into(),
                expected: m,
                got: if r.nrows() != m { r.nrows() } else { r.ncols() },
            });
        }
        let t = self.kf.time();
        check_finite_entries("measurement noise R", m, m, |i, j| r[(i, j)], t)?;
        for i in 0..m {
            for j in (i + 1)..m {
                let scale = r[(i, i)].abs().max(r[(j, j)].abs()).max(f64::MIN_POSITIVE);
                if (r[(i, j)] - r[(j, i)]).abs() > SYMMETRY_TOLERANCE * scale {
                    return Err(EstimatorError::NotSymmetric {
                        what: "measurement noise R".into(),
                        row: i,
                        col: j,
                        diff: (r[(i, j)] - r[(j, i)]).abs(),
                        time: t,
                    });
                }
            }
        }
        let x0 = *self.kf.state();
        let p = *self.kf.covariance();
        let mut lin = Vec::with_capacity(m);
        let mut outcomes = Vec::with_capacity(m);
        for (i, it) in items.iter().enumerate() {
            let (h0, h_row) = self.linearize_at(i, it, &x0)?;
            let nu = it.model.residual(it.value, h0);
            let s = (h_row * p * h_row.transpose())[0] + r[(i, i)];
            if !(s.is_finite() && s > 0.0) {
                return Err(EstimatorError::NotPositiveDefinite {
                    what: format!("innovation covariance S (diagonal entry {i})"),
                    time: t,
                });
            }
            let nis = nu * nu / s;
            let accepted = it.gate.is_none_or(|g| g.accepts(nis));
            outcomes.push(ScalarOutcome {
                innovation: nu,
                innovation_var: s,
                nis,
                accepted,
            });
            lin.push(h_row);
        }
        let keep: Vec<usize> = (0..m).filter(|&i| outcomes[i].accepted).collect();
        if keep.is_empty() {
            return Ok(outcomes);
        }
        let q = keep.len();
        let r_k = DMatrix::from_fn(q, q, |a, b| {
            0.5 * (r[(keep[a], keep[b])] + r[(keep[b], keep[a])])
        });
        let l = r_k
            .cholesky()
            .ok_or_else(|| EstimatorError::NotPositiveDefinite {
                what: "measurement noise R".into(),
                time: t,
            })?
            .unpack();
        // Forward substitution: L nu' = nu, L H' = H.
        let mut nu_w = Vec::with_capacity(q);
        let mut h_w: Vec<RowSVector<f64, N>> = Vec::with_capacity(q);
        for a in 0..q {
            let mut nu_a = outcomes[keep[a]].innovation;
            let mut h_a = lin[keep[a]];
            for b in 0..a {
                nu_a -= l[(a, b)] * nu_w[b];
                h_a -= h_w[b] * l[(a, b)];
            }
            nu_w.push(nu_a / l[(a, a)]);
            h_w.push(h_a / l[(a, a)]);
        }
        let backup = self.kf.clone();
        self.kf
            .update_sequential_scalar_with(q, None, |a, x| ScalarMeasurement {
                innovation: nu_w[a] - (h_w[a] * (x - x0))[0],
                h_row: h_w[a],
                variance: 1.0,
            })?;
        self.renormalize(backup)?;
        self.record_update();
        Ok(outcomes)
    }

    /// Normalizes the state after an update (restoring `backup` on failure).
    fn renormalize(&mut self, backup: KalmanFilter<N>) -> Result<(), EstimatorError> {
        let mut x = *self.kf.state();
        self.model.normalize(&mut x);
        if let Err(e) = self.kf.set_state(x) {
            self.kf = backup;
            return Err(e);
        }
        Ok(())
    }
}

/// Checks item `i` of a sequential group before the core update, so the error names
/// the item index (the core sees one scalar at a time, index 0).
fn check_item<const N: usize>(
    i: usize,
    innovation: f64,
    h_row: &RowSVector<f64, N>,
    variance: f64,
    time: Time,
) -> Result<(), EstimatorError> {
    if !innovation.is_finite() {
        return Err(EstimatorError::NonFinite {
            what: "innovation nu".into(),
            index: i,
            value: innovation,
            time,
        });
    }
    check_finite_entries(
        &format!("measurement row H[{i}]"),
        1,
        N,
        |_, c| h_row[c],
        time,
    )?;
    if !(variance.is_finite() && variance > 0.0) {
        return Err(EstimatorError::NotPositiveDefinite {
            what: format!("measurement variance r[{i}] = {variance}"),
            time,
        });
    }
    Ok(())
}

/// Renames the core's single-scalar index `[0]` to the group index `i`.
fn reindex(e: EstimatorError, i: usize) -> EstimatorError {
    match e {
        EstimatorError::NotPositiveDefinite { what, time } => EstimatorError::NotPositiveDefinite {
            what: what.replace("[0]", &format!("[{i}]")),
            time,
        },
        EstimatorError::NonFinite {
            what,
            index,
            value,
            time,
        } => EstimatorError::NonFinite {
            what: what.replace("[0]", &format!("[{i}]")),
            index,
            value,
            time,
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{DVector, Matrix2, RowVector2, Vector2};

    /// 1-D constant velocity driven by a measured velocity input: `x = [p, b]`,
    /// `p += dt (u - b)` with a velocity bias state `b`.
    #[derive(Debug, Clone, PartialEq)]
    struct BiasedOdometry;

    impl MotionModel<2> for BiasedOdometry {
        type Input = f64;
        type InputSample = f64;
        fn apply_sample(&self, input: &mut f64, sample: &f64) {
            *input = *sample;
        }
        fn non_finite_in_sample(&self, sample: &f64) -> Option<(&'static str, usize, f64)> {
            (!sample.is_finite()).then_some(("velocity input u", 0, *sample))
        }
        fn propagate(
            &self,
            x: &Vector2<f64>,
            u: &f64,
            dt: f64,
        ) -> Result<Propagation<2>, EstimatorError> {
            Ok(Propagation {
                x_pred: Vector2::new(x[0] + dt * (u - x[1]), x[1]),
                f_jacobian: Matrix2::new(1.0, -dt, 0.0, 1.0),
                q: Matrix2::new(0.01 * dt, 0.0, 0.0, 1e-4 * dt),
            })
        }
    }

    /// `z = p^2` (nonlinear) or `z = p` (linear).
    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Obs {
        Square,
        Position,
    }

    impl ScalarModel<2> for Obs {
        fn evaluate(&self, x: &Vector2<f64>) -> Result<(f64, RowVector2<f64>), EstimatorError> {
            Ok(match self {
                Obs::Square => (x[0] * x[0], RowVector2::new(2.0 * x[0], 0.0)),
                Obs::Position => (x[0], RowVector2::new(1.0, 0.0)),
            })
        }
    }

    /// Bad input (crate docs, "Bad input"): per-item errors name the item index and
    /// the filter time, and leave the filter unchanged.
    #[test]
    fn group_errors_name_the_item_index_and_the_time() {
        let mut f = ekf();
        f.predict_to(0.5).unwrap();
        let before = f.clone();
        let ok = GroupItem {
            value: 1.0,
            model: &Obs::Position,
            variance: 0.1,
            gate: None,
        };
        let e = f
            .update_sequential(&[
                ok,
                ok,
                GroupItem {
                    variance: -0.1,
                    ..ok
                },
            ])
            .unwrap_err();
        match &e {
            EstimatorError::NotPositiveDefinite { what, time } => {
                assert!(what.contains("[2]"), "{what}");
                assert_eq!(*time, 0.5);
            }
            other => panic!("unexpected {other}"),
        }
        assert_eq!(f, before);
        let r = DMatrix::identity(2, 2) * 0.1;
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let items = [ok, GroupItem { value: bad, ..ok }];
            for e in [
                f.update_sequential(&items).unwrap_err(),
                f.update_stacked(&items, &r).unwrap_err(),
            ] {
                assert!(
                    matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 0.5),
                    "{e}"
                );
            }
            assert_eq!(f, before);
        }
    }

    /// A non-finite input sample is refused by `try_apply_input`; an unchecked one is
    /// caught by the next prediction, stamped with its target time.
    #[test]
    fn non_finite_inputs_are_errors_with_the_time() {
        let mut f = ekf();
        f.predict_to(0.5).unwrap();
        let before = f.clone();
        let e = f.try_apply_input(&f64::NAN).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 0, time, .. } if *time == 0.5),
            "{e}"
        );
        assert_eq!(f, before);
        f.try_apply_input(&2.0).unwrap();
        assert_eq!(*f.input(), 2.0);
        let e = f.predict_to(f64::NAN).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { time, .. } if *time == 0.5),
            "{e}"
        );
        f.apply_input(&f64::INFINITY);
        let held = f.clone();
        let e = f.predict_to(0.75).unwrap_err();
        assert_eq!(e.time(), Some(0.75), "{e}");
        assert_eq!(f, held);
    }

    /// A covariance that overflows in the prediction (loses positive definiteness) is
    /// reported at the target time and never committed.
    #[test]
    fn covariance_overflow_is_an_error_at_the_target_time() {
        let prior = Gaussian::new(Vector2::new(1.0, 0.0), Matrix2::identity() * 1e308).unwrap();
        let mut f = Ekf::new(prior, 0.0, BiasedOdometry, 1.0).unwrap();
        let before = f.clone();
        let e = f.predict_to(1.0).unwrap_err();
        // Overflow shows as a non-finite (or not positive definite) predicted P.
        assert!(e.to_string().contains("predicted covariance P"), "{e}");
        assert_eq!(e.time(), Some(1.0), "{e}");
        assert!(e.to_string().contains("t = 1 s"), "{e}");
        assert_eq!(f, before);
    }

    fn ekf() -> Ekf<2, BiasedOdometry> {
        let prior =
            Gaussian::new(Vector2::new(1.0, 0.0), Matrix2::new(0.5, 0.1, 0.1, 0.2)).unwrap();
        Ekf::new(prior, 0.0, BiasedOdometry, 1.0).unwrap()
    }

    #[test]
    fn predict_uses_the_held_input_and_refuses_to_go_back() {
        let mut f = ekf();
        f.predict_to(0.5).unwrap();
        assert_relative_eq!(f.state()[0], 1.5, epsilon = 1e-15);
        f.apply_input(&-2.0);
        f.predict_to(1.0).unwrap();
        assert_relative_eq!(f.state()[0], 0.5, epsilon = 1e-15);
        let before = f.clone();
        assert!(matches!(
            f.predict_to(0.9),
            Err(EstimatorError::TimeBackwards { .. })
        ));
        assert_eq!(f, before);
        f.predict_to(1.0).unwrap(); // same time: no-op
        assert_eq!(f, before);
    }

    #[test]
    fn sequential_equals_stacked_with_diagonal_r_for_nonlinear_models() {
        let items = [
            GroupItem {
                value: 1.3,
                model: &Obs::Square,
                variance: 0.2,
                gate: None,
            },
            GroupItem {
                value: 1.1,
                model: &Obs::Position,
                variance: 0.1,
                gate: None,
            },
            GroupItem {
                value: 1.5,
                model: &Obs::Square,
                variance: 0.3,
                gate: None,
            },
        ];
        let r = DMatrix::from_diagonal(&DVector::from_vec(vec![0.2, 0.1, 0.3]));
        let mut a = ekf();
        let mut b = ekf();
        a.update_sequential(&items).unwrap();
        b.update_stacked(&items, &r).unwrap();
        for i in 0..2 {
            assert_relative_eq!(a.state()[i], b.state()[i], epsilon = 1e-12);
            for j in 0..2 {
                assert_relative_eq!(
                    a.covariance()[(i, j)],
                    b.covariance()[(i, j)],
                    epsilon = 1e-12
                );
            }
        }
    }

    #[test]
    fn gated_items_are_reported_and_skipped() {
        let gate = Some(GateThreshold::from_sigma_distance(2.5).unwrap());
        let items = [
            GroupItem {
                value: 1.0,
                model: &Obs::Position,
                variance: 0.1,
                gate,
            },
            GroupItem {
                value: 30.0,
                model: &Obs::Position,
                variance: 0.1,
                gate,
            },
            GroupItem {
                value: 30.0,
                model: &Obs::Position,
                variance: 0.1,
                gate: None,
            },
        ];
        let mut f = ekf();
        let out = f.update_sequential(&items[..2]).unwrap();
        assert!(out[0].accepted && !out[1].accepted);
        let r = DMatrix::from_diagonal(&DVector::from_vec(vec![0.1, 0.1, 0.1]));
        let mut g = ekf();
        let out = g.update_stacked(&items, &r).unwrap();
        assert_eq!(
            out.iter().map(|o| o.accepted).collect::<Vec<_>>(),
            [true, false, true]
        );
    }

    #[test]
    fn errors_leave_the_filter_unchanged() {
        let mut f = ekf();
        let before = f.clone();
        let items = [
            GroupItem {
                value: 1.0,
                model: &Obs::Position,
                variance: 0.1,
                gate: None,
            },
            GroupItem {
                value: 1.0,
                model: &Obs::Position,
                variance: -0.1,
                gate: None,
            },
        ];
        assert!(f.update_sequential(&items).is_err());
        assert_eq!(f, before);
        let nan = [GroupItem {
            value: f64::NAN,
            model: &Obs::Position,
            variance: 0.1,
            gate: None,
        }];
        assert!(f.update_sequential(&nan).is_err());
        let r = DMatrix::from_element(1, 1, 0.1);
        assert!(f.update_stacked(&nan, &r).is_err());
        assert!(f.update_stacked(&items, &r).is_err()); // 2 items, 1x1 R
        assert_eq!(f, before);
    }
}
