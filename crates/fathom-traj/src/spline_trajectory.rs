//! A [`Trajectory`] whose NED position is a [`CubicSpline3`]: velocity and
//! acceleration from the spline's analytic derivatives, attitude aligned with the
//! velocity vector (roll 0), body rates from the analytic Euler-angle rates.

use fathom_core::{Time, frames::Euler};
use nalgebra::{Matrix3, Vector3};

use crate::{CubicSpline3, TrajError, Trajectory, TrueState};

/// Below this horizontal speed (m/s) the heading is considered undefined: the yaw
/// rate is reported as 0 (and the yaw is whatever `atan2` gives, finite).
pub const MIN_HORIZONTAL_SPEED: f64 = 1e-9;

/// Inverse of [`fathom_core::frames::euler_rates_from_body_rates_matrix`]: maps Euler angle rates
/// `(phi_dot, theta_dot, psi_dot)` to body angular rates `(p, q, r)`,
///
/// ```text
/// [1   0         -sin(theta)         ]
/// [0   cos(phi)   sin(phi) cos(theta)]
/// [0  -sin(phi)   cos(phi) cos(theta)]
/// ```
///
/// This closed form is defined at every attitude (unlike its inverse, singular at
/// pitch = +/- 90 deg).
pub fn body_rates_from_euler_rates_matrix(att: &Euler) -> Matrix3<f64> {
    let (sp, cp) = att.roll.sin_cos();
    let (st, ct) = att.pitch.sin_cos();
    Matrix3::new(1.0, 0.0, -st, 0.0, cp, sp * ct, 0.0, -sp, cp * ct)
}

/// Attitude and body rates of a vehicle whose x axis follows the velocity
/// `vel_in_nav` (roll 0), given the acceleration `acc_in_nav` for the rates.
///
/// - yaw `psi = atan2(v_y, v_x)`, pitch `theta = atan2(-v_z, |v_h|)` (nose up
///   when rising; z is down), roll `phi = 0`;
/// - `psi_dot = (v_x a_y - v_y a_x) / |v_h|^2` (0 when `|v_h| < MIN_HORIZONTAL_SPEED`);
/// - `theta_dot = (|v_h| (-a_z) + v_z d|v_h|/dt) / |v|^2` with
///   `d|v_h|/dt = (v_x a_x + v_y a_y) / |v_h|` (terms dropped when the speeds vanish);
/// - `omega_body = body_rates_from_euler_rates_matrix(att) * (0, theta_dot, psi_dot)`.
///
/// Never returns NaN for finite inputs.
pub fn velocity_aligned_attitude(
    vel_in_nav: &Vector3<f64>,
    acc_in_nav: &Vector3<f64>,
) -> (Euler, Vector3<f64>) {
    let (vx, vy, vz) = (vel_in_nav.x, vel_in_nav.y, vel_in_nav.z);
    let (ax, ay, az) = (acc_in_nav.x, acc_in_nav.y, acc_in_nav.z);
    let vh2 = vx * vx + vy * vy;
    let vh = vh2.sqrt();
    let yaw = vy.atan2(vx);
    let pitch = (-vz).atan2(vh);
    let (yaw_rate, vh_rate) = if vh >= MIN_HORIZONTAL_SPEED {
        ((vx * ay - vy * ax) / vh2, (vx * ax + vy * ay) / vh)
    } else {
        (0.0, 0.0)
    };
    let v2 = vh2 + vz * vz;
    let pitch_rate = if v2 >= MIN_HORIZONTAL_SPEED * MIN_HORIZONTAL_SPEED {
        (vh * (-az) - (-vz) * vh_rate) / v2
    } else {
        0.0
    };
    let att = Euler::new(0.0, pitch, yaw);
    let omega_body =
        body_rates_from_euler_rates_matrix(&att) * Vector3::new(0.0, pitch_rate, yaw_rate);
    (att, omega_body)
}

/// A trajectory whose NED position is a natural cubic spline per axis; the
/// vehicle's x axis points along the velocity (see [`velocity_aligned_attitude`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SplineTrajectory {
    spline: CubicSpline3,
}

impl SplineTrajectory {
    /// Wraps a position spline (NED, m, knot times in s).
    pub fn new(pos_in_nav: CubicSpline3) -> Self {
        Self { spline: pos_in_nav }
    }

    /// The position spline.
    pub fn spline(&self) -> &CubicSpline3 {
        &self.spline
    }
}

impl Trajectory for SplineTrajectory {
    fn start_time(&self) -> Time {
        self.spline.start_time()
    }

    fn end_time(&self) -> Time {
        self.spline.end_time()
    }

    fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
        let p = self.spline.eval(t)?;
        let (attitude, omega_body) = velocity_aligned_attitude(&p.d1, &p.d2);
        Ok(TrueState {
            time: t,
            pos_in_nav: p.value,
            vel_in_nav: p.d1,
            acc_in_nav: p.d2,
            attitude,
            omega_body,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::{assert_abs_diff_eq, assert_relative_eq};
    use fathom_core::{
        frames::{euler_rates_from_body_rates_matrix, nav_from_body},
        units::wrap_pi,
    };

    fn wiggly() -> SplineTrajectory {
        let t = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0];
        let pts = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(10.0, 3.0, 5.0),
            Vector3::new(18.0, 12.0, 7.0),
            Vector3::new(20.0, 25.0, 6.0),
            Vector3::new(12.0, 33.0, 2.0),
            Vector3::new(5.0, 40.0, 1.0),
        ];
        SplineTrajectory::new(CubicSpline3::new(&t, &pts).unwrap())
    }

    #[test]
    fn inverse_matrix_is_inverse() {
        let att = Euler::new(0.3, -0.7, 2.0);
        let prod =
            body_rates_from_euler_rates_matrix(&att) * euler_rates_from_body_rates_matrix(&att);
        assert_relative_eq!(prod, Matrix3::identity(), epsilon = 1e-12);
    }

    #[test]
    fn forward_axis_follows_velocity() {
        let tr = wiggly();
        for &t in &[0.0, 7.0, 23.5, 50.0] {
            let s = tr.state_at(t).unwrap();
            let fwd = nav_from_body(&s.attitude) * Vector3::x();
            assert_relative_eq!(fwd, s.vel_in_nav.normalize(), epsilon = 1e-12);
            let vb = s.vel_in_body();
            assert_relative_eq!(vb.x, s.vel_in_nav.norm(), epsilon = 1e-12);
            assert_abs_diff_eq!(vb.y, 0.0, epsilon = 1e-12);
            assert_abs_diff_eq!(vb.z, 0.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn pitch_is_nose_up_when_rising() {
        let t = [0.0, 10.0];
        let pts = [Vector3::new(0.0, 0.0, 10.0), Vector3::new(10.0, 0.0, 0.0)];
        let tr = SplineTrajectory::new(CubicSpline3::new(&t, &pts).unwrap());
        let s = tr.state_at(5.0).unwrap();
        assert_relative_eq!(
            s.attitude.pitch,
            std::f64::consts::FRAC_PI_4,
            epsilon = 1e-12
        );
        assert_eq!(s.attitude.roll, 0.0);
    }

    #[test]
    fn body_rates_match_finite_differences_of_attitude() {
        let tr = wiggly();
        let h = 1e-5;
        for &t in &[3.0, 14.0, 27.0, 41.0] {
            let s = tr.state_at(t).unwrap();
            let a = tr.state_at(t - h).unwrap().attitude;
            let b = tr.state_at(t + h).unwrap().attitude;
            let euler_rates = Vector3::new(
                (b.roll - a.roll) / (2.0 * h),
                (b.pitch - a.pitch) / (2.0 * h),
                wrap_pi(b.yaw - a.yaw) / (2.0 * h),
            );
            let fd_omega = body_rates_from_euler_rates_matrix(&s.attitude) * euler_rates;
            assert_relative_eq!(s.omega_body, fd_omega, epsilon = 1e-7, max_relative = 1e-5);
            // Velocity and acceleration are the analytic spline derivatives.
            let pa = tr.state_at(t - h).unwrap();
            let pb = tr.state_at(t + h).unwrap();
            let fd_v = (pb.pos_in_nav - pa.pos_in_nav) / (2.0 * h);
            assert_relative_eq!(s.vel_in_nav, fd_v, epsilon = 1e-6);
            let fd_a = (pb.vel_in_nav - pa.vel_in_nav) / (2.0 * h);
            assert_relative_eq!(s.acc_in_nav, fd_a, epsilon = 1e-6);
        }
    }

    #[test]
    fn vertical_or_resting_motion_gives_no_nan() {
        // Pure vertical dive: horizontal speed 0.
        let (att, w) =
            velocity_aligned_attitude(&Vector3::new(0.0, 0.0, 1.0), &Vector3::new(0.3, 0.2, 0.1));
        assert!(
            att.to_vector()
                .iter()
                .chain(w.iter())
                .all(|x| x.is_finite())
        );
        assert_eq!(w.z, 0.0);
        // At rest.
        let (att, w) = velocity_aligned_attitude(&Vector3::zeros(), &Vector3::new(1.0, 1.0, 1.0));
        assert!(
            att.to_vector()
                .iter()
                .chain(w.iter())
                .all(|x| x.is_finite())
        );
        assert_eq!(w, Vector3::zeros());
    }

    #[test]
    fn out_of_range_is_an_error() {
        let tr = wiggly();
        assert!(matches!(
            tr.state_at(50.5),
            Err(TrajError::OutOfRange { .. })
        ));
        assert!(tr.state_at(-0.1).is_err());
        assert!(tr.state_at(f64::NAN).is_err());
    }
}
