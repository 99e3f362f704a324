//! The 12-state error-state INS filter (eq. 1-5, 14): prediction with the error
//! dynamics of [`super::error_model`], the closed-loop feedback interface, and the
//! nominal navigation state the measurement models linearize about.
//!
//! Closed loop: after an update the caller takes the estimated error with
//! [`Ins12Filter::take_correction`] (the filter's error mean is reset to zero, `P` is
//! kept), applies it to its nominal INS state with [`Correction::apply`] (or by hand:
//! `p -= dp`, `v -= dv`, `C = exp(-[psi x]) C`, accelerometer-bias estimate `+= db`),
//! and feeds the corrected IMU (specific force minus the bias estimate) to the next
//! predictions. Between updates the error mean is therefore zero.
//!
//! Equation (14) of the paper is the textbook EKF; as printed it has two misprints
//! (see [`super::findings`]): `P_k = P_k^- - K_k H P_k^{-1}` must read
//! `P_k = P_k^- - K_k H P_k^-` (the prior covariance, not an inverse), and
//! `x_k = x_k^- + K_k K_k (z - h)` must read `x_k = x_k^- + K_k (z - h)` (one gain).
//! The filter implements the correct forms, with the Joseph-form covariance update of
//! [`crate::KalmanFilter`].

use fathom_core::{Gaussian, Time};
use nalgebra::{UnitQuaternion, Vector3};

use super::error::{MapAidedError, finite_input};
use super::error_model::transition;
use super::params::ImuNoise;
use super::{ACCEL_BIAS, ATT, ErrorVector12, Matrix12, N_STATES, POS, VEL};
use crate::{EstimatorError, KalmanFilter};

/// The nominal (mechanized) navigation state the error state refers to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NominalNav {
    /// Position in the local NED frame, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude `C_b^n`.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Accelerometer-bias estimate, body axes, m/s^2 (subtracted from the IMU).
    pub accel_bias_in_body: Vector3<f64>,
}

impl NominalNav {
    /// Checks that every field is finite.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] naming the field, stamped with `time`.
    pub fn check(&self, time: Time) -> Result<(), MapAidedError> {
        finite_input("nominal pos_in_nav", self.pos_in_nav.as_slice(), time)?;
        finite_input("nominal vel_in_nav", self.vel_in_nav.as_slice(), time)?;
        finite_input(
            "nominal nav_from_body",
            self.nav_from_body.as_ref().coords.as_slice(),
            time,
        )?;
        finite_input(
            "nominal accel_bias_in_body",
            self.accel_bias_in_body.as_slice(),
            time,
        )
    }

    /// The pose the error `dx` says the truth has: `p = p_hat - dp`,
    /// `C = exp(-[psi x]) C_hat` (velocity and bias likewise); the inverse of the
    /// error definition of [`super`].
    pub fn corrected(&self, dx: &ErrorVector12) -> NominalNav {
        Correction::from_vector(dx).apply(self)
    }
}

/// The estimated error taken from the filter for feedback (estimated minus true,
/// conventions of [`super`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Position error `dp`, NED, m.
    pub dpos_in_nav: Vector3<f64>,
    /// Velocity error `dv`, NED, m/s.
    pub dvel_in_nav: Vector3<f64>,
    /// Attitude error `psi` (rotation vector, NED), rad.
    pub datt_in_nav: Vector3<f64>,
    /// Residual accelerometer error `db_a` (body), m/s^2.
    pub daccel_bias_in_body: Vector3<f64>,
}

impl Correction {
    /// The correction held in an error vector.
    pub fn from_vector(dx: &ErrorVector12) -> Self {
        Self {
            dpos_in_nav: dx.fixed_rows::<3>(POS).into(),
            dvel_in_nav: dx.fixed_rows::<3>(VEL).into(),
            datt_in_nav: dx.fixed_rows::<3>(ATT).into(),
            daccel_bias_in_body: dx.fixed_rows::<3>(ACCEL_BIAS).into(),
        }
    }

    /// The error vector.
    pub fn to_vector(&self) -> ErrorVector12 {
        let mut dx = ErrorVector12::zeros();
        dx.fixed_rows_mut::<3>(POS).copy_from(&self.dpos_in_nav);
        dx.fixed_rows_mut::<3>(VEL).copy_from(&self.dvel_in_nav);
        dx.fixed_rows_mut::<3>(ATT).copy_from(&self.datt_in_nav);
        dx.fixed_rows_mut::<3>(ACCEL_BIAS)
            .copy_from(&self.daccel_bias_in_body);
        dx
    }

    /// The corrected nominal state: `p - dp`, `v - dv`, `exp(-[psi x]) C`, bias
    /// estimate `+ db`.
    pub fn apply(&self, nav: &NominalNav) -> NominalNav {
        NominalNav {
            pos_in_nav: nav.pos_in_nav - self.dpos_in_nav,
            vel_in_nav: nav.vel_in_nav - self.dvel_in_nav,
            nav_from_body: UnitQuaternion::from_scaled_axis(-self.datt_in_nav) * nav.nav_from_body,
            accel_bias_in_body: nav.accel_bias_in_body + self.daccel_bias_in_body,
        }
    }
}

/// The 12-state error-state filter (module docs). Every failing step leaves it
/// unchanged.
#[derive(Debug, Clone, PartialEq)]
pub struct Ins12Filter {
    kf: KalmanFilter<N_STATES>,
    noise: ImuNoise,
}

impl Ins12Filter {
    /// A filter at `t0` with zero error mean, covariance `p0` and the IMU noise.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`] (`p0` not symmetric positive definite, `t0` not finite).
    pub fn new(p0: &Matrix12, t0: Time, noise: ImuNoise) -> Result<Self, MapAidedError> {
        Ok(Self {
            kf: KalmanFilter::new(Gaussian::new_unchecked(ErrorVector12::zeros(), *p0), t0)?,
            noise,
        })
    }

    /// A diagonal covariance from per-block sigmas
    /// `[position m, velocity m/s, attitude rad, accelerometer bias m/s^2]`.
    pub fn diagonal_covariance(sigmas: [f64; 4]) -> Matrix12 {
        let mut d = ErrorVector12::zeros();
        for (block, s) in sigmas.iter().enumerate() {
            for i in 0..3 {
                d[3 * block + i] = s * s;
            }
        }
        Matrix12::from_diagonal(&d)
    }

    /// Predicts to `t` over one IMU step from the nominal attitude at the start of the
    /// step and the corrected specific force of the step (body, m/s^2), with the
    /// discretization of [`super::error_model`]: `x = Phi x`, `P = Phi P Phi^T + Q_d`.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a non-finite attitude or specific force (at
    /// the target time) or a non-finite `t` (at the filter time);
    /// [`EstimatorError::TimeBackwards`] for `t` before the filter time; as
    /// [`KalmanFilter::predict`].
    pub fn predict(
        &mut self,
        nav_from_body: &UnitQuaternion<f64>,
        specific_force_in_body: &Vector3<f64>,
        t: Time,
    ) -> Result<(), MapAidedError> {
        finite_input("nav_from_body", nav_from_body.as_ref().coords.as_slice(), t)?;
        finite_input(
            "specific_force_in_body",
            specific_force_in_body.as_slice(),
            t,
        )?;
        finite_input("prediction time", &[t], self.kf.time())?;
        let dt = t - self.kf.time();
        if dt < 0.0 {
            return Err(EstimatorError::TimeBackwards {
                what: "12-state prediction".into(),
                prev: self.kf.time(),
                next: t,
            }
            .into());
        }
        let (phi, qd) = transition(nav_from_body, specific_force_in_body, &self.noise, dt);
        self.predict_with(&phi, &qd, t)
    }

    /// Predicts with a caller's `Phi` and `Q_d` (e.g. a multi-step transition).
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`].
    pub fn predict_with(
        &mut self,
        phi: &Matrix12,
        qd: &Matrix12,
        t: Time,
    ) -> Result<(), MapAidedError> {
        Ok(self.kf.predict(phi, qd, t)?)
    }

    /// The estimated error for feedback; resets the error mean to zero (keeps `P`).
    pub fn take_correction(&mut self) -> Correction {
        let c = Correction::from_vector(self.kf.state());
        // zero is finite: cannot fail
        let _ = self.kf.set_state(ErrorVector12::zeros());
        c
    }

    /// The error mean (zero between updates in closed loop).
    pub fn error_mean(&self) -> &ErrorVector12 {
        self.kf.state()
    }

    /// The error covariance `P`.
    pub fn covariance(&self) -> &Matrix12 {
        self.kf.covariance()
    }

    /// The filter time, s.
    pub fn time(&self) -> Time {
        self.kf.time()
    }

    /// The IMU noise of the predictions.
    pub fn noise(&self) -> &ImuNoise {
        &self.noise
    }

    /// Multiplies the covariance of the position, velocity and attitude errors by
    /// `factor` (rows and columns scaled by `sqrt(factor)`: their correlations with
    /// each other and with the bias are kept): a filter that has lost lock widens its
    /// gate.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a `factor` not finite and > 0; as
    /// [`KalmanFilter::set_estimate`] for an overflow. The filter is unchanged on error.
    pub fn inflate_navigation_covariance(&mut self, factor: f64) -> Result<(), MapAidedError> {
        super::error::positive_input("covariance inflation", 0, factor, self.kf.time())?;
        let k = factor.sqrt();
        let mut d = ErrorVector12::repeat(1.0);
        for i in 0..ACCEL_BIAS {
            d[i] = k;
        }
        let p = Matrix12::from_fn(|i, j| self.kf.covariance()[(i, j)] * d[i] * d[j]);
        self.kf
            .set_estimate(Gaussian::new_unchecked(*self.kf.state(), p))?;
        Ok(())
    }

    /// Adds `spread` (symmetric positive semi-definite, m² or (m/s)²) to the
    /// covariance block of the position (`block = POS`) or the velocity
    /// (`block = VEL`) error: the filter admits an error it did not account for.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a non-finite spread,
    /// [`MapAidedError::Filter`] when the result is not a valid covariance; the filter
    /// is unchanged on error.
    pub fn widen_covariance_block(
        &mut self,
        block: usize,
        spread: &nalgebra::Matrix3<f64>,
    ) -> Result<(), MapAidedError> {
        let t = self.kf.time();
        super::error::finite_input("covariance spread", spread.as_slice(), t)?;
        let mut p = *self.kf.covariance();
        let b = block.min(N_STATES - 3);
        let mut v = p.fixed_view_mut::<3, 3>(b, b);
        v += spread;
        self.kf
            .set_estimate(Gaussian::new_unchecked(*self.kf.state(), p))?;
        Ok(())
    }

    /// The underlying Kalman filter, mutable (for the updates of this module; each
    /// keeps the no-change-on-error rule).
    pub(crate) fn kf_mut(&mut self) -> &mut KalmanFilter<N_STATES> {
        &mut self.kf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::params::Ins12Params;

    fn filter() -> Ins12Filter {
        let p0 = Ins12Filter::diagonal_covariance([1.0, 0.1, 0.01, 0.01]);
        Ins12Filter::new(&p0, 2.0, Ins12Params::default().check().unwrap()).unwrap()
    }

    /// Bad input (time backwards, NaN specific force, NaN time) is a typed error with
    /// the time stamp, and the filter is unchanged.
    #[test]
    fn bad_prediction_input_leaves_the_filter_unchanged() {
        let mut f = filter();
        let before = f.clone();
        let q = UnitQuaternion::identity();
        let g = Vector3::new(0.0, 0.0, -9.8);
        let e = f.predict(&q, &g, 1.0).unwrap_err();
        assert!(
            matches!(
                &e,
                MapAidedError::Filter(EstimatorError::TimeBackwards { next, .. }) if *next == 1.0
            ),
            "{e}"
        );
        let e = f
            .predict(&q, &Vector3::new(f64::NAN, 0.0, 0.0), 2.1)
            .unwrap_err();
        assert!(
            matches!(&e, MapAidedError::InvalidInput { index: 0, time, .. } if *time == 2.1),
            "{e}"
        );
        assert!(f.predict(&q, &g, f64::NAN).is_err());
        assert_eq!(f, before);
        f.predict(&q, &g, 2.1).unwrap();
        assert!(f.covariance()[(0, 0)] > 1.0);
        assert_eq!(f.time(), 2.1);
    }

    /// Prediction grows the covariance as the model says: a velocity error becomes a
    /// position error, a bias becomes velocity; `C` enters the bias coupling.
    #[test]
    fn prediction_couples_the_blocks() {
        let p0 = Ins12Filter::diagonal_covariance([1e-6, 1e-6, 1e-9, 1e-2]);
        let noise = Ins12Params {
            velocity_random_walk_mps_per_sqrt_s: 0.0,
            angle_random_walk_rad_per_sqrt_s: 0.0,
            accel_bias_random_walk_mps2_per_sqrt_s: 0.0,
        }
        .check()
        .unwrap();
        let mut f = Ins12Filter::new(&p0, 0.0, noise).unwrap();
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.5);
        for k in 1..=100 {
            f.predict(&q, &Vector3::new(0.0, 0.0, -9.8), k as f64 * 0.01)
                .unwrap();
        }
        // a bias of sigma 0.01 over 1 s: velocity sigma ~0.01 m/s, position ~0.005 m
        let p = f.covariance();
        assert!(
            (p[(VEL, VEL)].sqrt() - 0.01).abs() < 1e-4,
            "{}",
            p[(VEL, VEL)]
        );
        assert!((p[(POS, POS)].sqrt() - 0.005).abs() < 1e-4);
    }

    /// Feedback: the correction is the error mean, applying it moves the nominal
    /// state the right way, and the mean is zero afterwards.
    #[test]
    fn correction_round_trip() {
        let mut f = filter();
        let mut dx = ErrorVector12::zeros();
        dx[POS] = 1.0;
        dx[VEL + 1] = -0.5;
        dx[ATT + 2] = 0.1;
        dx[ACCEL_BIAS] = 0.02;
        f.kf_mut().set_state(dx).unwrap();
        let c = f.take_correction();
        assert_eq!(c.to_vector(), dx);
        assert_eq!(f.error_mean(), &ErrorVector12::zeros());
        let nav = NominalNav {
            pos_in_nav: Vector3::new(10.0, 0.0, -5.0),
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3),
            accel_bias_in_body: Vector3::zeros(),
        };
        let t = c.apply(&nav);
        assert_eq!(t.pos_in_nav, Vector3::new(9.0, 0.0, -5.0));
        assert_eq!(t.vel_in_nav, Vector3::new(0.0, 0.5, 0.0));
        assert!((t.nav_from_body.euler_angles().2 - 0.2).abs() < 1e-12);
        assert_eq!(t.accel_bias_in_body.x, 0.02);
        assert_eq!(nav.corrected(&dx), t);
        // psi is defined by C_hat = exp([psi x]) C_true: recover it
        let psi = (nav.nav_from_body * t.nav_from_body.inverse()).scaled_axis();
        assert!((psi - c.datt_in_nav).norm() < 1e-12);
        let mut bad = nav;
        bad.vel_in_nav.y = f64::INFINITY;
        assert!(matches!(
            bad.check(3.0),
            Err(MapAidedError::InvalidInput { index: 1, .. })
        ));
    }
}
