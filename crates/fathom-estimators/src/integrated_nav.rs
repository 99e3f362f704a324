//! The 9-state integrated navigation filter of the velocity-filter paper (spec C,
//! paper §2.4): state `x = [p (3), v (3), b_a (3)]`, position and velocity in a local
//! level NED frame (north and east as distances travelled, down as depth), `b_a` the
//! acceleration bias, modelled in the body frame (an accelerometer bias) or in the
//! navigation frame ([`AccelBiasFrame`]; with `Nav`, `C_k` below is `I`).
//!
//! # Model
//!
//! The input is the INS's navigation-frame velocity increment over each IMU interval,
//! `dv^n_k = C_b^n (dv_k + rotation/sculling terms) + (g^n - (2 omega_ie + omega_en) x v) dt`
//! (the accelerometer output rotated by the INS attitude, gravity and Coriolis
//! compensated), and the INS attitude `C_k = C_b^n`:
//!
//! ```text
//! v_{k+1} = v_k + dv^n_k - C_k b_a dt
//! p_{k+1} = p_k + (v_k + v_{k+1}) dt / 2
//! b_a,{k+1} = b_a,k + w_b
//! ```
//!
//! The state is propagated at the IMU rate by [`IntegratedNavFilter::propagate`]. The
//! covariance is propagated less often, over the accumulated interval `T` since the
//! last covariance step ([`IntegratedNavFilter::propagate_covariance`], called by the
//! user at e.g. 10 Hz and automatically before every update), with the exact
//! Jacobian of the sum of the steps above:
//!
//! ```text
//! Phi = [ I   T I   B ]     A = -sum C_k dt,  B = sum (A_k + A_{k+1}) dt / 2
//!       [ 0    I    A ]     (A_k: the partial sum up to step k)
//!       [ 0    0    I ]
//! Q   : white acceleration PSD q_a on v (Q_pp = q_a T^3/3, Q_pv = q_a T^2/2,
//!       Q_vv = q_a T), bias random walk q_b (Q_bb = q_b T); the bias noise's
//!       second-order cross terms are neglected.
//! ```
//!
//! This decimation changes nothing in the state and is exact in `Phi`; it only
//! lumps the process noise of `T` into one step (see the experiment report for the
//! rate used). Measurements: NED velocity (`H = [0 I 0]`, from the switching box),
//! optionally chi-square gated, and depth (`H = e_3`).

use fathom_core::Gaussian;
use nalgebra::{Matrix1, Matrix3, SMatrix, SVector, Vector1, Vector3};

use crate::smoother::{ForwardPass, SmoothedStep};
use crate::{EstimatorError, Gate, GateThreshold, KalmanFilter, UpdateInfo};

/// A 9-vector / 9x9 matrix of this filter.
pub type Vector9 = SVector<f64, 9>;
/// A 9x9 matrix of this filter.
pub type Matrix9 = SMatrix<f64, 9, 9>;

/// The frame in which the 9-state filter models its acceleration bias.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AccelBiasFrame {
    /// An accelerometer bias (body frame): enters as `C_b^n b_a`.
    #[default]
    Body,
    /// A bias of the navigation-frame acceleration input (e.g. from an uncorrected INS
    /// tilt): enters as `b_a` directly (`C_k` replaced by `I` in the model).
    Nav,
}

/// Unchecked parameters of the 9-state filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegratedNavParams {
    /// White acceleration noise PSD on the velocity, (m/s^2)^2/Hz = m^2/s^3 (> 0).
    pub accel_psd: f64,
    /// Accelerometer-bias random-walk PSD, (m/s^2)^2/s (>= 0).
    pub accel_bias_rw_psd: f64,
    /// Initial sigmas: position (m), velocity (m/s), accelerometer bias (m/s^2), all > 0.
    pub sigma0: [f64; 3],
    /// Frame of the bias state.
    pub bias_frame: AccelBiasFrame,
}

impl IntegratedNavParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::Core`] naming the parameter.
    pub fn check(&self) -> Result<IntegratedNavConfig, EstimatorError> {
        use fathom_core::error::{ensure_non_negative, ensure_positive};
        ensure_positive("nav accel_psd", self.accel_psd)?;
        ensure_non_negative("nav accel_bias_rw_psd", self.accel_bias_rw_psd)?;
        for (i, s) in self.sigma0.iter().enumerate() {
            ensure_positive(&format!("nav sigma0[{i}]"), *s)?;
        }
        Ok(IntegratedNavConfig { params: *self })
    }
}

/// Validated parameters of the 9-state filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegratedNavConfig {
    params: IntegratedNavParams,
}

impl IntegratedNavConfig {
    /// The validated parameters.
    pub fn params(&self) -> &IntegratedNavParams {
        &self.params
    }
}

/// The 9-state integrated navigation filter (see the module docs).
///
/// Bad input: non-finite INS increments, attitude, `dt` or aiding measurements are
/// errors naming the quantity and index with the time stamp; a propagation that
/// overflows and a covariance that stops being positive definite are errors with the
/// time; the state is never committed on error.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegratedNavFilter {
    kf: KalmanFilter<9>,
    x: Vector9,
    time: f64,
    acc_a: Matrix3<f64>,
    acc_b: Matrix3<f64>,
    acc_t: f64,
    params: IntegratedNavParams,
    recording: Option<ForwardPass<9>>,
}

impl IntegratedNavFilter {
    /// A filter at time `t0` with position `pos0`, velocity `vel0` (NED) and zero
    /// accelerometer bias.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`] (non-finite start).
    pub fn new(
        config: &IntegratedNavConfig,
        pos0: &Vector3<f64>,
        vel0: &Vector3<f64>,
        t0: f64,
    ) -> Result<Self, EstimatorError> {
        let p = config.params;
        let mut x = Vector9::zeros();
        x.fixed_rows_mut::<3>(0).copy_from(pos0);
        x.fixed_rows_mut::<3>(3).copy_from(vel0);
        let mut d = Vector9::zeros();
        for i in 0..3 {
            d[i] = p.sigma0[0].powi(2);
            d[3 + i] = p.sigma0[1].powi(2);
            d[6 + i] = p.sigma0[2].powi(2);
        }
        let kf = KalmanFilter::new(Gaussian::new_unchecked(x, Matrix9::from_diagonal(&d)), t0)?;
        Ok(Self {
            kf,
            x,
            time: t0,
            acc_a: Matrix3::zeros(),
            acc_b: Matrix3::zeros(),
            acc_t: 0.0,
            params: p,
            recording: None,
        })
    }

    /// Starts recording the forward pass for smoothing ([`crate::smoother`]) from the
    /// current estimate: each covariance step (the accumulated transition `Phi`) and
    /// the updates at its time. Call it when no propagation is pending (right after
    /// construction or an update); recording does not change any estimate.
    pub fn start_recording(&mut self) {
        self.recording = Some(ForwardPass::from_filter(&self.kf));
    }

    /// The forward pass recorded so far (`None` unless recording).
    pub fn forward_pass(&self) -> Option<&ForwardPass<9>> {
        self.recording.as_ref()
    }

    /// Takes the recorded forward pass out (recording stops).
    pub fn take_forward_pass(&mut self) -> Option<ForwardPass<9>> {
        self.recording.take()
    }

    /// The fixed-interval RTS smoother over the recorded pass (`[p, v, b]` per
    /// covariance step).
    ///
    /// # Errors
    /// [`EstimatorError::Smoother`] when recording is off, else as
    /// [`ForwardPass::smooth`].
    pub fn smooth(&self) -> Result<Vec<SmoothedStep<9>>, EstimatorError> {
        match &self.recording {
            Some(pass) => pass.smooth(),
            None => Err(crate::error_state::not_recorded("9-state", self.time)),
        }
    }

    fn record_update(&mut self) {
        if let Some(pass) = &mut self.recording {
            pass.record_update(&self.kf);
        }
    }

    /// Propagates the state over one IMU interval `dt` with the INS's NED velocity
    /// increment `dv_in_nav` and attitude `nav_from_body` (`C_b^n`); the covariance
    /// step is deferred (see the module docs). No allocation.
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`] for a non-finite input, `dt` or propagated state
    /// (overflow), stamped with the target time (a non-finite `dt`: the current
    /// time), or `dt <= 0` ([`EstimatorError::OutOfRange`]); the filter is then
    /// unchanged.
    pub fn propagate(
        &mut self,
        dv_in_nav: &Vector3<f64>,
        nav_from_body: &Matrix3<f64>,
        dt: f64,
    ) -> Result<(), EstimatorError> {
        if !dt.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "nav propagate dt".into(),
                index: 0,
                value: dt,
                time: self.time,
            });
        }
        if dt <= 0.0 {
            return Err(EstimatorError::OutOfRange {
                what: "nav propagate dt".into(),
                value: dt,
                expected: "finite and > 0",
            });
        }
        let t_new = self.time + dt;
        crate::error::check_finite_entries("velocity increment", 3, 1, |r, _| dv_in_nav[r], t_new)?;
        crate::error::check_finite_entries(
            "attitude C_b^n",
            3,
            3,
            |r, c| nav_from_body[(r, c)],
            t_new,
        )?;
        let c = match self.params.bias_frame {
            AccelBiasFrame::Body => *nav_from_body,
            AccelBiasFrame::Nav => Matrix3::identity(),
        };
        let nav_from_body = &c;
        let b = self.x.fixed_rows::<3>(6).into_owned();
        let v_old = self.x.fixed_rows::<3>(3).into_owned();
        let v_new = v_old + dv_in_nav - nav_from_body * b * dt;
        let p_new = self.x.fixed_rows::<3>(0) + (v_old + v_new) * (0.5 * dt);
        let a_new = self.acc_a - nav_from_body * dt;
        let b_new = self.acc_b + (self.acc_a + a_new) * (0.5 * dt);
        // An overflow (absurd input) is refused before anything is committed.
        crate::error::check_finite_entries("propagated position", 3, 1, |r, _| p_new[r], t_new)?;
        crate::error::check_finite_entries("propagated velocity", 3, 1, |r, _| v_new[r], t_new)?;
        crate::error::check_finite_entries(
            "accumulated transition (bias columns)",
            3,
            6,
            |r, c| {
                if c < 3 {
                    a_new[(r, c)]
                } else {
                    b_new[(r, c - 3)]
                }
            },
            t_new,
        )?;
        self.x.fixed_rows_mut::<3>(0).copy_from(&p_new);
        self.x.fixed_rows_mut::<3>(3).copy_from(&v_new);
        self.acc_b = b_new;
        self.acc_a = a_new;
        self.acc_t += dt;
        self.time = t_new;
        Ok(())
    }

    /// The transition matrix and process noise of the interval accumulated since the
    /// last covariance step (identity / zero when nothing is pending).
    pub fn pending_model(&self) -> (Matrix9, Matrix9) {
        let t = self.acc_t;
        let mut phi = Matrix9::identity();
        let mut q = Matrix9::zeros();
        let (qa, qb) = (self.params.accel_psd, self.params.accel_bias_rw_psd);
        for i in 0..3 {
            phi[(i, 3 + i)] = t;
            q[(i, i)] = qa * t * t * t / 3.0;
            q[(i, 3 + i)] = qa * t * t / 2.0;
            q[(3 + i, i)] = qa * t * t / 2.0;
            q[(3 + i, 3 + i)] = qa * t;
            q[(6 + i, 6 + i)] = qb * t;
        }
        phi.fixed_view_mut::<3, 3>(0, 6).copy_from(&self.acc_b);
        phi.fixed_view_mut::<3, 3>(3, 6).copy_from(&self.acc_a);
        (phi, q)
    }

    /// Propagates the covariance over the accumulated interval and syncs the state
    /// into the Kalman filter (a no-op when nothing is pending).
    ///
    /// # Errors
    /// As [`KalmanFilter::predict_nonlinear`]; the filter is then unchanged.
    pub fn propagate_covariance(&mut self) -> Result<(), EstimatorError> {
        if self.acc_t == 0.0 {
            return Ok(());
        }
        let (phi, q) = self.pending_model();
        self.kf.predict_nonlinear(&self.x, &phi, &q, self.time)?;
        if let Some(pass) = &mut self.recording {
            pass.record_prediction(&phi, &self.kf);
        }
        self.acc_a = Matrix3::zeros();
        self.acc_b = Matrix3::zeros();
        self.acc_t = 0.0;
        Ok(())
    }

    /// Updates with a NED velocity `z` of noise covariance `r`; with a `gate`, the
    /// update is applied only if its NIS passes (chi-square gating).
    ///
    /// # Errors
    /// As [`KalmanFilter::update_gated`].
    pub fn update_velocity(
        &mut self,
        z: &Vector3<f64>,
        r: &Matrix3<f64>,
        gate: Option<GateThreshold>,
    ) -> Result<Gate<3>, EstimatorError> {
        self.propagate_covariance()?;
        let mut h = SMatrix::<f64, 3, 9>::zeros();
        h.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        let out = match gate {
            Some(g) => self.kf.update_gated(z, &h, r, g)?,
            None => Gate::Accepted(self.kf.update(z, &h, r)?),
        };
        self.x = *self.kf.state();
        self.record_update();
        Ok(out)
    }

    /// Updates with a depth measurement `z` (m, NED down) of variance `r`.
    ///
    /// # Errors
    /// As [`KalmanFilter::update`].
    pub fn update_depth(&mut self, z: f64, r: f64) -> Result<UpdateInfo<1>, EstimatorError> {
        self.propagate_covariance()?;
        let mut h = SMatrix::<f64, 1, 9>::zeros();
        h[(0, 2)] = 1.0;
        let info = self.kf.update(&Vector1::new(z), &h, &Matrix1::new(r))?;
        self.x = *self.kf.state();
        self.record_update();
        Ok(info)
    }

    /// Position estimate (NED, m).
    pub fn position(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(0).into_owned()
    }

    /// Velocity estimate (NED, m/s).
    pub fn velocity(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(3).into_owned()
    }

    /// Accelerometer-bias estimate (body, m/s^2).
    pub fn accel_bias(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(6).into_owned()
    }

    /// Current time, s (the state's time; the covariance may lag until the next
    /// covariance step).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The covariance at its last step (see [`IntegratedNavFilter::propagate_covariance`]).
    pub fn covariance(&self) -> &Matrix9 {
        self.kf.covariance()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    fn cfg() -> IntegratedNavConfig {
        IntegratedNavParams {
            accel_psd: 1e-6,
            accel_bias_rw_psd: 1e-12,
            sigma0: [0.1, 0.01, 1e-3],
            bias_frame: AccelBiasFrame::Body,
        }
        .check()
        .unwrap()
    }

    /// Bad input (crate docs): non-finite inputs or step, and a propagation that
    /// overflows the state, are errors stamped with the target time and never
    /// committed; a non-finite aid is an error with the filter time.
    #[test]
    fn bad_input_and_overflow_are_errors_and_never_committed() {
        let mut f =
            IntegratedNavFilter::new(&cfg(), &Vector3::zeros(), &Vector3::zeros(), 0.0).unwrap();
        let c = Matrix3::identity();
        let huge = Vector3::new(1e308, 0.0, 0.0);
        f.propagate(&huge, &c, 0.1).unwrap();
        let before = f.clone();
        let e = f.propagate(&huge, &c, 0.1).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { time, .. } if *time == 0.2),
            "{e}"
        );
        assert_eq!(f, before);
        assert!(
            f.position()
                .iter()
                .chain(f.velocity().iter())
                .all(|v| v.is_finite())
        );
        let e = f.propagate(&Vector3::zeros(), &c, f64::NAN).unwrap_err();
        assert_eq!(e.time(), Some(0.1), "{e}");
        let e = f
            .propagate(&Vector3::new(0.0, f64::NAN, 0.0), &c, 0.1)
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 0.2),
            "{e}"
        );
        assert_eq!(f, before);
        let mut g =
            IntegratedNavFilter::new(&cfg(), &Vector3::zeros(), &Vector3::zeros(), 0.0).unwrap();
        g.propagate(&Vector3::new(0.01, 0.0, 0.0), &c, 0.1).unwrap();
        let (pos, vel) = (g.position(), g.velocity());
        let e = g
            .update_velocity(&Vector3::new(f64::INFINITY, 0.0, 0.0), &(c * 0.01), None)
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 0, time, .. } if *time == 0.1),
            "{e}"
        );
        let e = g.update_depth(f64::NAN, 0.01).unwrap_err();
        assert_eq!(e.time(), Some(0.1));
        let e = g.update_depth(1.0, -0.01).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { time, .. } if *time == 0.1),
            "{e}"
        );
        assert_eq!((g.position(), g.velocity()), (pos, vel));
    }

    /// The accumulated Jacobian equals the finite-difference Jacobian of the
    /// state propagation over many steps with a turning attitude.
    #[test]
    fn accumulated_transition_matches_finite_differences() {
        let run = |x0: &Vector9| {
            let mut f = IntegratedNavFilter::new(
                &cfg(),
                &x0.fixed_rows::<3>(0).into_owned(),
                &x0.fixed_rows::<3>(3).into_owned(),
                0.0,
            )
            .unwrap();
            f.x.fixed_rows_mut::<3>(6).copy_from(&x0.fixed_rows::<3>(6));
            for k in 0..10 {
                let c = *nalgebra::Rotation3::from_euler_angles(0.1, 0.0, 0.3 * k as f64).matrix();
                f.propagate(&Vector3::new(0.01, -0.02, 0.0), &c, 0.01)
                    .unwrap();
            }
            f
        };
        let x0 = Vector9::from_iterator((0..9).map(|i| 0.1 * i as f64));
        let base = run(&x0);
        let (phi, _) = base.pending_model();
        for j in 0..9 {
            let mut xp = x0;
            xp[j] += 1e-3;
            let d = (run(&xp).x - base.x) / 1e-3;
            for i in 0..9 {
                assert_abs_diff_eq!(phi[(i, j)], d[i], epsilon = 1e-9);
            }
        }
        let mut f = base.clone();
        f.propagate_covariance().unwrap();
        assert_eq!(f.kf.state(), &base.x);
        assert_abs_diff_eq!(f.kf.time(), 0.1, epsilon = 1e-12);
    }

    /// With a constant accelerometer bias, velocity updates let the filter learn it.
    #[test]
    fn learns_a_constant_bias_from_velocity_updates() {
        let mut f =
            IntegratedNavFilter::new(&cfg(), &Vector3::zeros(), &Vector3::zeros(), 0.0).unwrap();
        let bias = Vector3::new(1e-3, -5e-4, 0.0);
        let c = Matrix3::identity();
        let r = Matrix3::identity() * 1e-6;
        let mut v_true = Vector3::zeros();
        for k in 1..=6000 {
            // True acceleration zero; measured increment carries the bias.
            f.propagate(&(bias * 0.01), &c, 0.01).unwrap();
            if k % 20 == 0 {
                let out = f.update_velocity(&v_true, &r, None).unwrap();
                assert!(out.is_accepted());
                f.update_depth(0.0, 0.01).unwrap();
            }
            v_true = Vector3::zeros();
        }
        assert_abs_diff_eq!(f.accel_bias().x, 1e-3, epsilon = 5e-5);
        assert_abs_diff_eq!(f.accel_bias().y, -5e-4, epsilon = 5e-5);
        // A gross outlier is rejected by a chi-square gate and leaves the state alone.
        let before = f.clone();
        let gate = GateThreshold::from_chi_square_probability(0.999, 3).unwrap();
        let out = f
            .update_velocity(&Vector3::new(5.0, 0.0, 0.0), &r, Some(gate))
            .unwrap();
        assert!(!out.is_accepted());
        assert_eq!(f.position(), before.position());
        assert!(f.propagate(&Vector3::zeros(), &c, 0.0).is_err());
        assert!(
            f.propagate(&Vector3::new(f64::NAN, 0.0, 0.0), &c, 0.01)
                .is_err()
        );
    }
}
