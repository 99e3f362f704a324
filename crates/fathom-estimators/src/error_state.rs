//! The 15-state error-state (indirect, feedback) INS filter for DVL / RPM velocity
//! and depth aiding (spec C, "ESKF", beyond the paper).
//!
//! Error state `dx = [dr (0..3), dv (3..6), psi (6..9), b_a (9..12), b_g (12..15)]`,
//! **estimated minus true**, in the layout and conventions of
//! `fathom_ins::error_model` (position error in NED metres, `psi` the phi-angle
//! attitude error, body-frame sensor errors). This crate does not depend on the
//! INS crate: the caller computes the transition matrix `Phi` and the discrete
//! process noise `Q_d` from the INS state (e.g. with `fathom_ins::error_model`) and
//! passes them to [`ErrorStateFilter::predict`].
//!
//! Feedback: after each update the caller takes the estimated error with
//! [`ErrorStateFilter::take_correction`] (which resets it to zero, keeping `P`),
//! removes it from the INS state and adds the sensor-error estimates to the IMU
//! correction. Between updates the error state is therefore zero and the prediction
//! propagates `P` only.
//!
//! Measurements (with `y = INS - sensor`, so `y = H dx + noise`):
//! - NED velocity: `y = v_ins - v_aid`, `H = [0 I 0 0 0]`;
//! - depth: `y = depth_ins - depth_meas = dr_D`, `H = e_2`.

use fathom_core::Gaussian;
use nalgebra::{Matrix1, Matrix3, SMatrix, SVector, Vector1, Vector3};

use crate::smoother::{ForwardPass, SmoothedStep};
use crate::{EstimatorError, Gate, GateThreshold, KalmanFilter, UpdateInfo};

/// Number of error states.
pub const N_ERROR_STATES: usize = 15;
/// Index of the first position-error state.
pub const POS: usize = 0;
/// Index of the first velocity-error state.
pub const VEL: usize = 3;
/// Index of the first attitude-error state.
pub const ATT: usize = 6;
/// Index of the first accelerometer-bias state.
pub const ACCEL_BIAS: usize = 9;
/// Index of the first gyro-bias state.
pub const GYRO_BIAS: usize = 12;

/// A 15-vector of the error state.
pub type ErrorVector = SVector<f64, N_ERROR_STATES>;
/// A 15x15 matrix (`Phi`, `Q_d`, `P`).
pub type ErrorCovariance = SMatrix<f64, N_ERROR_STATES, N_ERROR_STATES>;

/// The feedback error-state filter (see the module docs).
///
/// Bad input: a non-finite INS value, aid, depth, `Phi` or `Q_d` is an error naming
/// the quantity and index with the time stamp; a covariance that stops being
/// positive definite (e.g. an indefinite `Q_d`, a variance `<= 0`) is an error with
/// the time; the filter is unchanged on error.
///
/// Smoothing ([`crate::smoother`], "Error-state filters"): after
/// [`ErrorStateFilter::start_recording`] each prediction is a step with the predicted
/// error (zero after a feedback) and each update records the error estimate before
/// [`ErrorStateFilter::take_correction`] resets it; the smoothed error of a step
/// refers to the nominal state *before* that step's feedback.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorStateFilter {
    kf: KalmanFilter<N_ERROR_STATES>,
    recording: Option<ForwardPass<N_ERROR_STATES>>,
}

impl ErrorStateFilter {
    /// A filter at `t0` with zero error and covariance `p0`.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`] (e.g. `p0` not positive definite).
    pub fn new(p0: &ErrorCovariance, t0: f64) -> Result<Self, EstimatorError> {
        Ok(Self {
            kf: KalmanFilter::new(Gaussian::new_unchecked(ErrorVector::zeros(), *p0), t0)?,
            recording: None,
        })
    }

    /// Starts recording the forward pass for smoothing from the current estimate
    /// (type docs); recording does not change any estimate.
    pub fn start_recording(&mut self) {
        self.recording = Some(ForwardPass::from_filter(&self.kf));
    }

    /// The forward pass recorded so far (`None` unless recording).
    pub fn forward_pass(&self) -> Option<&ForwardPass<N_ERROR_STATES>> {
        self.recording.as_ref()
    }

    /// Takes the recorded forward pass out (recording stops).
    pub fn take_forward_pass(&mut self) -> Option<ForwardPass<N_ERROR_STATES>> {
        self.recording.take()
    }

    /// The fixed-interval RTS smoother over the recorded pass: per step the smoothed
    /// error relative to the nominal before that step's feedback (type docs).
    ///
    /// # Errors
    /// [`EstimatorError::Smoother`] when recording is off, else as
    /// [`ForwardPass::smooth`].
    pub fn smooth(&self) -> Result<Vec<SmoothedStep<N_ERROR_STATES>>, EstimatorError> {
        match &self.recording {
            Some(pass) => pass.smooth(),
            None => Err(not_recorded("error-state", self.kf.time())),
        }
    }

    fn record_update(&mut self) {
        if let Some(pass) = &mut self.recording {
            pass.record_update(&self.kf);
        }
    }

    /// A diagonal initial covariance from per-block sigmas
    /// `[position m, velocity m/s, attitude rad, accel bias m/s^2, gyro bias rad/s]`.
    pub fn diagonal_covariance(sigmas: [f64; 5]) -> ErrorCovariance {
        let mut d = ErrorVector::zeros();
        for (block, s) in sigmas.iter().enumerate() {
            for i in 0..3 {
                d[3 * block + i] = s * s;
            }
        }
        ErrorCovariance::from_diagonal(&d)
    }

    /// `P = Phi P Phi^T + Q_d` to time `t` (the error state is zero between updates).
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`].
    pub fn predict(
        &mut self,
        phi: &ErrorCovariance,
        qd: &ErrorCovariance,
        t: f64,
    ) -> Result<(), EstimatorError> {
        self.kf.predict(phi, qd, t)?;
        if let Some(pass) = &mut self.recording {
            pass.record_prediction(phi, &self.kf);
        }
        Ok(())
    }

    /// Velocity update with the INS velocity `ins_vel_in_nav` and the aid
    /// `aid_vel_in_nav` of covariance `r`; gated when `gate` is given.
    ///
    /// # Errors
    /// As [`KalmanFilter::update_with_innovation_gated`].
    pub fn update_velocity(
        &mut self,
        ins_vel_in_nav: &Vector3<f64>,
        aid_vel_in_nav: &Vector3<f64>,
        r: &Matrix3<f64>,
        gate: Option<GateThreshold>,
    ) -> Result<Gate<3>, EstimatorError> {
        let t = self.kf.time();
        check_finite_at("INS velocity", ins_vel_in_nav.as_slice(), t)?;
        check_finite_at("aid velocity", aid_vel_in_nav.as_slice(), t)?;
        let mut h = SMatrix::<f64, 3, N_ERROR_STATES>::zeros();
        h.fixed_view_mut::<3, 3>(0, VEL)
            .copy_from(&Matrix3::identity());
        let nu = (ins_vel_in_nav - aid_vel_in_nav) - h * self.kf.state();
        let out = match gate {
            Some(g) => self.kf.update_with_innovation_gated(&nu, &h, r, g)?,
            None => Gate::Accepted(self.kf.update_with_innovation(&nu, &h, r)?),
        };
        self.record_update();
        Ok(out)
    }

    /// Position update (a GNSS fix): INS position `ins_pos_in_nav` against the fix
    /// `fix_pos_in_nav` (NED, m) of covariance `r`; gated when `gate` is given.
    ///
    /// # Errors
    /// As [`KalmanFilter::update_with_innovation_gated`].
    pub fn update_position(
        &mut self,
        ins_pos_in_nav: &Vector3<f64>,
        fix_pos_in_nav: &Vector3<f64>,
        r: &Matrix3<f64>,
        gate: Option<GateThreshold>,
    ) -> Result<Gate<3>, EstimatorError> {
        let t = self.kf.time();
        check_finite_at("INS position", ins_pos_in_nav.as_slice(), t)?;
        check_finite_at("fix position", fix_pos_in_nav.as_slice(), t)?;
        let mut h = SMatrix::<f64, 3, N_ERROR_STATES>::zeros();
        h.fixed_view_mut::<3, 3>(0, POS)
            .copy_from(&Matrix3::identity());
        let nu = (ins_pos_in_nav - fix_pos_in_nav) - h * self.kf.state();
        let out = match gate {
            Some(g) => self.kf.update_with_innovation_gated(&nu, &h, r, g)?,
            None => Gate::Accepted(self.kf.update_with_innovation(&nu, &h, r)?),
        };
        self.record_update();
        Ok(out)
    }

    /// Depth update: INS depth `ins_depth` (m, down) against the gauge's `depth`
    /// of variance `r`.
    ///
    /// # Errors
    /// As [`KalmanFilter::update_with_innovation`].
    pub fn update_depth(
        &mut self,
        ins_depth: f64,
        depth: f64,
        r: f64,
    ) -> Result<UpdateInfo<1>, EstimatorError> {
        let t = self.kf.time();
        check_finite_at("INS depth", &[ins_depth], t)?;
        check_finite_at("measured depth", &[depth], t)?;
        let mut h = SMatrix::<f64, 1, N_ERROR_STATES>::zeros();
        h[(0, POS + 2)] = 1.0;
        let nu = Vector1::new(ins_depth - depth) - h * self.kf.state();
        let info = self.kf.update_with_innovation(&nu, &h, &Matrix1::new(r))?;
        self.record_update();
        Ok(info)
    }

    /// The estimated error (for feedback); resets the error state to zero and keeps
    /// the covariance.
    ///
    /// # Errors
    /// Never in practice (zero is finite); kept for the filter's checked setter.
    pub fn take_correction(&mut self) -> Result<ErrorVector, EstimatorError> {
        let dx = *self.kf.state();
        self.kf.set_state(ErrorVector::zeros())?;
        Ok(dx)
    }

    /// The covariance `P`.
    pub fn covariance(&self) -> &ErrorCovariance {
        self.kf.covariance()
    }

    /// Adds `spread` (symmetric, positive semi-definite: e.g. the outer product of
    /// an innovation) to the 3 x 3 covariance block of the states `block..block + 3`
    /// ([`POS`], [`VEL`], ...): the filter admits an error it did not account for (a
    /// re-acquisition after a run of rejected fixes). The error state is unchanged.
    ///
    /// # Errors
    /// [`EstimatorError`] naming the spread for a non-finite entry or a `block`
    /// beyond the last 3 x 3 block, or naming `P` when the result is not a valid
    /// covariance; the filter is unchanged on error.
    pub fn widen_covariance_block(
        &mut self,
        block: usize,
        spread: &Matrix3<f64>,
    ) -> Result<(), EstimatorError> {
        let t = self.kf.time();
        check_finite_at("covariance spread", spread.as_slice(), t)?;
        if block > N_ERROR_STATES - 3 {
            return Err(EstimatorError::OutOfRange {
                what: "covariance block".into(),
                value: block as f64,
                expected: "0 ..= 12 (a block of 3 of the 15 states)",
            });
        }
        let mut p = *self.kf.covariance();
        let mut v = p.fixed_view_mut::<3, 3>(block, block);
        v += spread;
        self.kf
            .set_estimate(Gaussian::new_unchecked(*self.kf.state(), p))
    }

    /// The filter time, s.
    pub fn time(&self) -> f64 {
        self.kf.time()
    }
}

/// The error of a smoother call without a recorded pass.
pub(crate) fn not_recorded(filter: &str, time: f64) -> EstimatorError {
    EstimatorError::Smoother {
        what: format!("{filter} smoother: the forward pass was not recorded (start_recording)"),
        time,
    }
}

/// The first non-finite entry of `values` as an error naming `what` at time `t`.
fn check_finite_at(what: &str, values: &[f64], t: f64) -> Result<(), EstimatorError> {
    crate::error::check_finite_entries(what, values.len(), 1, |i, _| values[i], t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    /// Bad input (crate docs): non-finite INS or aid values name the quantity and
    /// the component at the filter time; a non-finite `Phi` and a `Q_d` that makes
    /// `P` indefinite are errors at the target time; the filter is unchanged.
    #[test]
    fn bad_input_names_the_quantity_and_the_time() {
        let p0 = ErrorStateFilter::diagonal_covariance([1.0, 1.0, 1e-3, 1e-3, 1e-6]);
        let mut f = ErrorStateFilter::new(&p0, 3.0).unwrap();
        let before = f.clone();
        let r = Matrix3::identity();
        let v = Vector3::new(1.0, 0.0, 0.0);
        let nan = Vector3::new(1.0, 0.0, f64::NAN);
        for (ins, aid, what) in [(&v, &nan, "aid velocity"), (&nan, &v, "INS velocity")] {
            match f.update_velocity(ins, aid, &r, None).unwrap_err() {
                EstimatorError::NonFinite {
                    what: w,
                    index,
                    time,
                    ..
                } => {
                    assert!(w.contains(what), "{w}");
                    assert_eq!((index, time), (2, 3.0));
                }
                other => panic!("unexpected {other}"),
            }
        }
        let e = f.update_depth(10.0, f64::INFINITY, 1.0).unwrap_err();
        assert!(e.to_string().contains("depth"), "{e}");
        assert_eq!(e.time(), Some(3.0));
        let e = f.update_depth(10.0, 10.5, 0.0).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { time, .. } if *time == 3.0),
            "{e}"
        );
        let mut phi = ErrorCovariance::identity();
        phi[(0, 1)] = f64::NAN;
        let e = f.predict(&phi, &ErrorCovariance::zeros(), 3.1).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 3.1),
            "{e}"
        );
        // Q_d with a large negative eigenvalue (diagonal >= 0, off-diagonal 10):
        // P = I + Q_d is indefinite.
        let mut qd = ErrorCovariance::zeros();
        qd[(0, 1)] = 10.0;
        qd[(1, 0)] = 10.0;
        let e = f
            .predict(&ErrorCovariance::identity(), &qd, 3.1)
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { time, .. } if *time == 3.1),
            "{e}"
        );
        assert_eq!(f, before);
    }

    /// A position error seen by a fix goes into the position-error state (the
    /// estimated minus true convention: INS minus fix), and a gate rejects a fix far
    /// beyond the covariance.
    #[test]
    fn position_update_estimates_position_error_and_gates() {
        let p0 = ErrorStateFilter::diagonal_covariance([1.0, 1.0, 1e-3, 1e-3, 1e-6]);
        let mut f = ErrorStateFilter::new(&p0, 0.0).unwrap();
        let r = Matrix3::identity();
        let ins = Vector3::new(10.0, 5.0, -2.0);
        let out = f
            .update_position(&ins, &Vector3::new(9.0, 5.0, -2.0), &r, None)
            .unwrap();
        assert!(out.is_accepted());
        let dx = f.take_correction().unwrap();
        assert_abs_diff_eq!(dx[POS], 0.5, epsilon = 1e-12);
        assert_abs_diff_eq!(dx[POS + 1], 0.0, epsilon = 1e-12);
        let gate = GateThreshold::from_squared_distance(16.0).unwrap();
        let far = f
            .update_position(&ins, &Vector3::new(-90.0, 5.0, -2.0), &r, Some(gate))
            .unwrap();
        assert!(!far.is_accepted());
    }

    /// A velocity error seen by the aid goes into the velocity-error state with the
    /// Kalman gain, and feedback resets it.
    #[test]
    fn velocity_update_estimates_velocity_error_and_resets() {
        let p0 = ErrorStateFilter::diagonal_covariance([1.0, 1.0, 1e-3, 1e-3, 1e-6]);
        let mut f = ErrorStateFilter::new(&p0, 0.0).unwrap();
        let r = Matrix3::identity();
        let out = f
            .update_velocity(
                &Vector3::new(2.0, 0.0, 0.0),
                &Vector3::new(1.0, 0.0, 0.0),
                &r,
                None,
            )
            .unwrap();
        assert!(out.is_accepted());
        let dx = f.take_correction().unwrap();
        // Scalar: gain 1 / (1 + 1) on an innovation of 1 m/s.
        assert_abs_diff_eq!(dx[VEL], 0.5, epsilon = 1e-12);
        assert_abs_diff_eq!(f.covariance()[(VEL, VEL)], 0.5, epsilon = 1e-12);
        assert_eq!(f.take_correction().unwrap(), ErrorVector::zeros());
        f.update_depth(50.3, 50.0, 1.0).unwrap();
        let dx = f.take_correction().unwrap();
        assert_abs_diff_eq!(dx[POS + 2], 0.15, epsilon = 1e-12);
        // Gated: a 100-sigma outlier is rejected.
        let gate = GateThreshold::from_chi_square_probability(0.999, 3).unwrap();
        let out = f
            .update_velocity(
                &Vector3::zeros(),
                &Vector3::new(100.0, 0.0, 0.0),
                &r,
                Some(gate),
            )
            .unwrap();
        assert!(!out.is_accepted());
        let phi = ErrorCovariance::identity();
        let q = ErrorCovariance::identity() * 1e-6;
        f.predict(&phi, &q, 0.1).unwrap();
        assert!(f.predict(&phi, &q, 0.05).is_err());
        assert!(ErrorStateFilter::new(&ErrorCovariance::zeros(), 0.0).is_err());
    }

    /// Widening a block adds the spread there only and keeps the error state; a
    /// fix the gate rejected passes after the position block is widened by the
    /// outer product of its innovation (NIS `a / (1 + a) < 1`); bad spreads and
    /// blocks are refused with the filter unchanged.
    #[test]
    fn widening_a_block_lets_a_rejected_fix_pass() {
        let mut f = ErrorStateFilter::new(
            &ErrorStateFilter::diagonal_covariance([1.0, 0.1, 0.01, 0.01, 0.001]),
            0.0,
        )
        .unwrap();
        let ins = Vector3::new(0.0, 0.0, 0.0);
        let fix = Vector3::new(40.0, -30.0, 0.0);
        let r = Matrix3::identity();
        let gate = GateThreshold::from_chi_square_probability(0.999, 3).unwrap();
        let g = f.update_position(&ins, &fix, &r, Some(gate)).unwrap();
        assert!(!g.is_accepted());
        let before = f.clone();
        let nu = ins - fix;
        f.widen_covariance_block(POS, &(nu * nu.transpose()))
            .unwrap();
        let p = f.covariance();
        assert_abs_diff_eq!(p[(0, 0)], 1.0 + 1600.0, epsilon = 1e-9);
        assert_abs_diff_eq!(p[(0, 1)], -1200.0, epsilon = 1e-9);
        assert_abs_diff_eq!(p[(3, 3)], before.covariance()[(3, 3)], epsilon = 0.0);
        let g = f.update_position(&ins, &fix, &r, Some(gate)).unwrap();
        assert!(g.is_accepted() && g.nis() < 1.0, "{}", g.nis());
        let dx = f.take_correction().unwrap();
        // estimated minus true: the INS is ~(-40, 30) off
        assert!(
            (dx[0] + 40.0).abs() < 1.0 && (dx[1] - 30.0).abs() < 1.0,
            "{dx}"
        );
        let kept = f.clone();
        let nan = Matrix3::from_element(f64::NAN);
        assert!(f.widen_covariance_block(POS, &nan).is_err());
        assert!(f.widen_covariance_block(13, &Matrix3::identity()).is_err());
        assert!(
            f.widen_covariance_block(VEL, &(-Matrix3::identity() * 10.0))
                .is_err()
        );
        assert_eq!(f, kept);
    }
}
