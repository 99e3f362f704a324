//! Motion-model builders: constant-velocity transition matrices and process noise
//! (one axis, and the 6-state `[x, vx, y, vy, z, vz]` layout of paper A).

use crate::EstimatorError;
use fathom_core::error::{ensure_finite, ensure_non_negative};
use nalgebra::{Matrix2, SMatrix};

/// 6x6 matrix type of the paper-A state `[x, vx, y, vy, z, vz]`.
pub type Matrix6 = SMatrix<f64, 6, 6>;

/// Constant-velocity transition for one axis, state `[p, v]`: `F = [1 dt; 0 1]`.
///
/// # Errors
/// [`EstimatorError::Core`] if `dt` is not finite or negative.
pub fn cv_transition_1d(dt: f64) -> Result<Matrix2<f64>, EstimatorError> {
    ensure_non_negative("time step dt", dt)?;
    Ok(Matrix2::new(1.0, dt, 0.0, 1.0))
}

/// Process noise of the continuous white-noise-acceleration model discretized over
/// `dt`, for one axis with acceleration PSD `q_psd` (m^2/s^3):
/// `Q = q_psd [dt^3/3, dt^2/2; dt^2/2, dt]` (Bar-Shalom, Li & Kirubarajan §6.2.2).
///
/// # Errors
/// [`EstimatorError::Core`] if `dt` or `q_psd` is not finite or negative.
pub fn cv_white_accel_q_1d(dt: f64, q_psd: f64) -> Result<Matrix2<f64>, EstimatorError> {
    ensure_non_negative("time step dt", dt)?;
    ensure_non_negative("acceleration noise PSD q", q_psd)?;
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    Ok(Matrix2::new(dt3 / 3.0, dt2 / 2.0, dt2 / 2.0, dt) * q_psd)
}

/// Process noise of the discrete white-noise-acceleration model (Bar-Shalom, Li &
/// Kirubarajan §6.3.2): the acceleration is constant over each step and white between
/// steps with standard deviation `accel_sigma` (m/s^2), entering through
/// `Gamma = [dt^2/2, dt]`: `Q = accel_sigma^2 [dt^4/4, dt^3/2; dt^3/2, dt^2]`.
///
/// # Errors
/// [`EstimatorError::Core`] if `dt` or `accel_sigma` is not finite or negative.
pub fn cv_discrete_white_accel_q_1d(
    dt: f64,
    accel_sigma: f64,
) -> Result<Matrix2<f64>, EstimatorError> {
    ensure_non_negative("time step dt", dt)?;
    ensure_non_negative("acceleration noise std", accel_sigma)?;
    let g = nalgebra::Vector2::new(0.5 * dt * dt, dt);
    Ok(g * g.transpose() * (accel_sigma * accel_sigma))
}

/// [`cv_discrete_white_accel_q_1d`] on each axis of the paper-A layout, one
/// acceleration standard deviation for all three axes.
///
/// # Errors
/// As [`cv_discrete_white_accel_q_1d`].
pub fn cv_discrete_white_accel_q_3d(dt: f64, accel_sigma: f64) -> Result<Matrix6, EstimatorError> {
    Ok(block_diag3(&cv_discrete_white_accel_q_1d(dt, accel_sigma)?))
}

/// Constant-velocity transition for three axes in the paper-A layout
/// `[x, vx, y, vy, z, vz]` (block diagonal of [`cv_transition_1d`]; the paper's `A`
/// with `T = dt`).
///
/// # Errors
/// [`EstimatorError::Core`] if `dt` is not finite or negative.
pub fn cv_transition_3d(dt: f64) -> Result<Matrix6, EstimatorError> {
    let f1 = cv_transition_1d(dt)?;
    Ok(block_diag3(&f1))
}

/// The paper-A tuning `Q = w^2 I6` (`w` in the state's units, e.g. `w_INS = 10`).
///
/// # Errors
/// [`EstimatorError::Core`] if `w` is not finite or negative.
pub fn cv_scaled_identity_q_3d(w: f64) -> Result<Matrix6, EstimatorError> {
    ensure_non_negative("process noise scale w", w)?;
    Ok(Matrix6::identity() * (w * w))
}

/// Continuous white-noise-acceleration `Q` for three axes in the paper-A layout,
/// with one PSD per axis (block diagonal of [`cv_white_accel_q_1d`]).
///
/// # Errors
/// [`EstimatorError::Core`] if `dt` or a PSD is not finite or negative.
pub fn cv_white_accel_q_3d(dt: f64, q_psd: [f64; 3]) -> Result<Matrix6, EstimatorError> {
    ensure_finite("acceleration noise PSD q", q_psd.iter())?;
    let mut q = Matrix6::zeros();
    for (axis, &qa) in q_psd.iter().enumerate() {
        let b = cv_white_accel_q_1d(dt, qa)?;
        q.fixed_view_mut::<2, 2>(2 * axis, 2 * axis).copy_from(&b);
    }
    Ok(q)
}

/// Position measurement matrix for the paper-A layout: `H` selects `x, y, z`
/// (3x6; the paper prints `[1 1 0 0 0 0; ...]`, read as a position measurement).
pub fn cv_position_h_3d() -> SMatrix<f64, 3, 6> {
    let mut h = SMatrix::<f64, 3, 6>::zeros();
    for axis in 0..3 {
        h[(axis, 2 * axis)] = 1.0;
    }
    h
}

fn block_diag3(b: &Matrix2<f64>) -> Matrix6 {
    let mut m = Matrix6::zeros();
    for axis in 0..3 {
        m.fixed_view_mut::<2, 2>(2 * axis, 2 * axis).copy_from(b);
    }
    m
}

#[cfg(test)]
mod tests {

    #[test]
    fn discrete_white_accel_q_is_gamma_gamma_t_sigma2() {
        let q = cv_discrete_white_accel_q_1d(2.0, 0.5).unwrap();
        // Gamma = [2, 2], sigma^2 = 0.25.
        assert_eq!(q, Matrix2::new(1.0, 1.0, 1.0, 1.0));
        let q3 = cv_discrete_white_accel_q_3d(1.0, 2.0).unwrap();
        assert_eq!(
            q3.fixed_view::<2, 2>(4, 4).into_owned(),
            Matrix2::new(1.0, 2.0, 2.0, 4.0)
        );
        assert_eq!(q3[(0, 2)], 0.0);
        assert!(cv_discrete_white_accel_q_1d(1.0, -1.0).is_err());
        assert!(cv_discrete_white_accel_q_1d(f64::NAN, 1.0).is_err());
    }

    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Vector2, Vector6};

    #[test]
    fn one_axis_cv() {
        let f = cv_transition_1d(0.5).unwrap();
        assert_relative_eq!(f * Vector2::new(1.0, 2.0), Vector2::new(2.0, 2.0));
        let q = cv_white_accel_q_1d(2.0, 3.0).unwrap();
        assert_relative_eq!(q, Matrix2::new(8.0, 6.0, 6.0, 6.0));
        assert!(q.cholesky().is_some());
        assert!(cv_transition_1d(-1.0).is_err());
        assert!(cv_transition_1d(f64::NAN).is_err());
        assert!(cv_white_accel_q_1d(1.0, -1.0).is_err());
    }

    #[test]
    fn three_axis_layout() {
        let f = cv_transition_3d(1.0).unwrap();
        // [x, vx, y, vy, z, vz] = [0, 1, 10, -2, 100, 0.5]
        let x = Vector6::new(0.0, 1.0, 10.0, -2.0, 100.0, 0.5);
        assert_relative_eq!(f * x, Vector6::new(1.0, 1.0, 8.0, -2.0, 100.5, 0.5));
        let h = cv_position_h_3d();
        assert_relative_eq!(h * x, nalgebra::Vector3::new(0.0, 10.0, 100.0));
        assert_relative_eq!(
            cv_scaled_identity_q_3d(10.0).unwrap(),
            Matrix6::identity() * 100.0
        );
        let q = cv_white_accel_q_3d(1.0, [1.0, 2.0, 3.0]).unwrap();
        assert_relative_eq!(q[(2, 2)], 2.0 / 3.0);
        assert_relative_eq!(q[(5, 4)], 1.5);
        assert_eq!(q[(0, 2)], 0.0);
        assert!(cv_white_accel_q_3d(1.0, [1.0, f64::NAN, 1.0]).is_err());
        assert!(cv_scaled_identity_q_3d(f64::INFINITY).is_err());
    }
}
