//! The cascaded flight controller (seed 004, Fig. 7): position / velocity loop ->
//! desired thrust vector; thrust direction and yaw -> desired attitude; attitude loop
//! -> body-rate command -> rate loop -> moments; moments and collective thrust ->
//! rotor thrusts by the exact allocation (eq. 22) with saturation.
//!
//! The controller reads the vehicle's state through [`ControlState`] only, so it flies
//! on the truth (`ControlState::from_truth`) or on any estimate the caller supplies.
//!
//! ```text
//! v_cmd = v_sp + K_p (p_sp - p)                     (no p_sp on a leg: v_cmd = v_sp)
//!         clipped to the horizontal / vertical speed limits
//! a_cmd = K_v (v_cmd - v) + I,   I' = K_i (v_cmd - v), |I_j| <= I_max
//! f     = m (a_cmd - g^n)       thrust force wanted in NED; f_z <= -0.2 m g, tilt of f
//!                               from vertical <= max_tilt, |f| <= 4 T_max
//! z_b,d = -f / |f|,  y_c = (-sin psi_d, cos psi_d, 0),  x_b,d = y_c x z_b,d / |.|,
//! y_b,d = z_b,d x x_b,d,   C_d = [x_b,d y_b,d z_b,d]     desired attitude
//!                               (x_b,d is orthogonal to y_c: its ZYX yaw is psi_d)
//! F     = |f|                                           collective thrust (eq. 22's |F_con|)
//! e     = rotation vector of C^T C_d (body axes),  omega_cmd = K_att e (clipped)
//! M     = J K_rate (omega_cmd - omega) + omega x J omega
//! ```
//!
//! With the default gains each attitude axis is critically damped
//! (`K_rate = 4 K_att`: a double pole at `2 K_att`) and the translational loops, with
//! the integral, have their poles well inside the attitude bandwidth.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use super::allocation::allocate_saturated;
use super::dynamics::RigidBodyState;
use super::params::{ControllerGains, ControllerParams, Vehicle};
use crate::TrajError;

/// The state the controller (and the guidance) act on: the truth or an estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlState {
    /// Position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude `C_b^n`.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Body angular rate, rad/s (e.g. the bias-corrected gyro for an estimate).
    pub omega_body: Vector3<f64>,
}

impl ControlState {
    /// The truth as the controller's state.
    pub fn from_truth(x: &RigidBodyState) -> Self {
        Self {
            pos_in_nav: x.pos_in_nav,
            vel_in_nav: x.vel_in_nav,
            nav_from_body: x.nav_from_body,
            omega_body: x.omega_body,
        }
    }

    /// Yaw (ZYX) of the attitude, rad.
    pub fn yaw(&self) -> f64 {
        self.nav_from_body.euler_angles().2
    }

    /// Checks that every component is finite.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field of `control_state`.
    pub fn check(&self) -> Result<(), TrajError> {
        let fields: [(&str, &[f64]); 4] = [
            ("control_state.pos_in_nav", self.pos_in_nav.as_slice()),
            ("control_state.vel_in_nav", self.vel_in_nav.as_slice()),
            (
                "control_state.nav_from_body",
                self.nav_from_body.coords.as_slice(),
            ),
            ("control_state.omega_body", self.omega_body.as_slice()),
        ];
        for (field, v) in fields {
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(TrajError::InvalidParameter {
                    field: field.into(),
                    reason: format!("must be finite, got {x}"),
                });
            }
        }
        Ok(())
    }
}

/// What the guidance asks of the controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// Position to hold, NED m (`None` on a leg: velocity only).
    pub pos_in_nav: Option<Vector3<f64>>,
    /// Velocity command (feed-forward when a position is held), NED m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Yaw command, rad.
    pub yaw: f64,
}

impl Setpoint {
    /// Hold `pos` with yaw `yaw`.
    pub fn hold(pos: Vector3<f64>, yaw: f64) -> Self {
        Self {
            pos_in_nav: Some(pos),
            vel_in_nav: Vector3::zeros(),
            yaw,
        }
    }
}

/// Everything one controller update decided.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlOutput {
    /// Rotor thrust commands `[FL, FR, BL, BR]` after saturation, N.
    pub thrust_cmd: [f64; 4],
    /// Collective thrust wanted, N.
    pub collective: f64,
    /// Moments wanted (before saturation), N m.
    pub moments: Vector3<f64>,
    /// Desired attitude.
    pub nav_from_body_des: UnitQuaternion<f64>,
    /// Velocity command, NED m/s.
    pub vel_cmd: Vector3<f64>,
    /// Acceleration command, NED m/s^2.
    pub accel_cmd: Vector3<f64>,
}

/// Rotation vector of a unit quaternion, angle in `[0, pi]` (accurate for tiny angles).
fn rotation_vector(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let n = v.norm();
    if n < 1e-12 {
        v * (2.0 / w)
    } else {
        v * (2.0 * n.atan2(w) / n)
    }
}

/// Desired attitude from the wanted thrust force in NED (body -z along it) and the
/// yaw command (module docs).
pub fn desired_attitude(thrust_force_in_nav: &Vector3<f64>, yaw: f64) -> UnitQuaternion<f64> {
    let z_b = -thrust_force_in_nav.normalize();
    let y_c = Vector3::new(-yaw.sin(), yaw.cos(), 0.0);
    let x_b = y_c.cross(&z_b).normalize();
    let y_b = z_b.cross(&x_b);
    let m = Matrix3::from_columns(&[x_b, y_b, z_b]);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m))
}

/// The cascaded controller with its one piece of memory, the velocity integral.
#[derive(Debug, Clone, PartialEq)]
pub struct CascadedController {
    vehicle: Vehicle,
    gains: ControllerParams,
    vel_integral: Vector3<f64>,
}

impl CascadedController {
    /// A controller for `vehicle` with `gains`, integral at zero.
    pub fn new(vehicle: &Vehicle, gains: &ControllerGains) -> Self {
        Self {
            vehicle: *vehicle,
            gains: *gains.params(),
            vel_integral: Vector3::zeros(),
        }
    }

    /// Clears the velocity integral.
    pub fn reset(&mut self) {
        self.vel_integral = Vector3::zeros();
    }

    /// The velocity-error integral term, m/s^2.
    pub fn velocity_integral(&self) -> &Vector3<f64> {
        &self.vel_integral
    }

    /// The velocity command of a setpoint (module docs), clipped to the speed limits.
    pub fn velocity_command(&self, state: &ControlState, sp: &Setpoint) -> Vector3<f64> {
        let g = &self.gains;
        let mut v = sp.vel_in_nav;
        if let Some(p) = sp.pos_in_nav {
            v += g.position_gain.component_mul(&(p - state.pos_in_nav));
        }
        let h = v.xy().norm();
        if h > g.max_horizontal_speed_mps {
            let s = g.max_horizontal_speed_mps / h;
            v.x *= s;
            v.y *= s;
        }
        v.z =
            v.z.clamp(-g.max_vertical_speed_mps, g.max_vertical_speed_mps);
        v
    }

    /// The thrust force wanted in NED for an acceleration command, with the limits of
    /// the module docs.
    pub fn thrust_force(&self, accel_cmd: &Vector3<f64>) -> Vector3<f64> {
        let v = &self.vehicle;
        let mg = v.mass() * v.gravity();
        let mut f = (accel_cmd - v.gravity_in_nav()) * v.mass();
        f.z = f.z.min(-0.2 * mg);
        let f_max = 4.0 * v.thrust_max();
        f.z = f.z.max(-f_max);
        let h_max = (f.z.abs() * self.gains.max_tilt_rad.tan())
            .min((f_max * f_max - f.z * f.z).max(0.0).sqrt());
        let h = f.xy().norm();
        if h > h_max {
            let s = h_max / h;
            f.x *= s;
            f.y *= s;
        }
        f
    }

    /// Moments of the attitude and rate loops toward `nav_from_body_des` (module docs).
    pub fn attitude_moments(
        &self,
        state: &ControlState,
        nav_from_body_des: &UnitQuaternion<f64>,
    ) -> Vector3<f64> {
        let g = &self.gains;
        let e = rotation_vector(&(state.nav_from_body.inverse() * nav_from_body_des));
        let mut w_cmd = g.attitude_gain.component_mul(&e);
        for i in 0..3 {
            w_cmd[i] = w_cmd[i].clamp(-g.max_rate_rad_s[i], g.max_rate_rad_s[i]);
        }
        let w = &state.omega_body;
        let j = self.vehicle.inertia();
        j * g.rate_gain.component_mul(&(w_cmd - w)) + w.cross(&(j * w))
    }

    /// One controller update over `dt` (the integral advances by `dt`).
    pub fn update(&mut self, state: &ControlState, sp: &Setpoint, dt: f64) -> ControlOutput {
        let g = self.gains;
        let vel_cmd = self.velocity_command(state, sp);
        let e = vel_cmd - state.vel_in_nav;
        let lim = g.velocity_integral_limit_mps2;
        self.vel_integral += g.velocity_integral_gain.component_mul(&e) * dt;
        for i in 0..3 {
            self.vel_integral[i] = self.vel_integral[i].clamp(-lim, lim);
        }
        let accel_cmd = g.velocity_gain.component_mul(&e) + self.vel_integral;
        let f = self.thrust_force(&accel_cmd);
        let nav_from_body_des = desired_attitude(&f, sp.yaw);
        let collective = f.norm();
        let moments = self.attitude_moments(state, &nav_from_body_des);
        ControlOutput {
            thrust_cmd: allocate_saturated(collective, &moments, &self.vehicle),
            collective,
            moments,
            nav_from_body_des,
            vel_cmd,
            accel_cmd,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrotor::params::{ControllerParams, VehicleParams};

    fn setup() -> (Vehicle, CascadedController) {
        let v = VehicleParams::default().check().unwrap();
        let g = ControllerParams::default().check().unwrap();
        (v, CascadedController::new(&v, &g))
    }

    /// Acceptance (part): in equilibrium (at the setpoint, level, at rest) every rotor
    /// is commanded exactly `m g / 4`.
    #[test]
    fn equilibrium_commands_hover_thrust() {
        let (v, mut c) = setup();
        let x = RigidBodyState::at_rest(Vector3::new(5.0, -3.0, -20.0), 0.7, 0.0);
        let s = ControlState::from_truth(&x);
        let out = c.update(&s, &Setpoint::hold(x.pos_in_nav, 0.7), 0.005);
        for t in out.thrust_cmd {
            assert!((t - v.hover_thrust_per_rotor()).abs() < 1e-12, "{t}");
        }
        assert!(out.moments.norm() < 1e-12);
    }

    #[test]
    fn desired_attitude_points_body_down_along_minus_thrust() {
        for (f, yaw) in [
            (Vector3::new(0.0, 0.0, -15.0), 0.0),
            (Vector3::new(3.0, -2.0, -15.0), 1.2),
            (Vector3::new(-4.0, 1.0, -10.0), -2.5),
        ] {
            let q = desired_attitude(&f, yaw);
            let z_b = q * Vector3::z();
            assert!((z_b + f.normalize()).norm() < 1e-12);
            // heading: body x projected on the horizontal points along yaw
            let x_b = q * Vector3::x();
            let heading = x_b.y.atan2(x_b.x);
            assert!((heading - yaw).abs() < 1e-12, "{heading} vs {yaw}");
        }
        let level = desired_attitude(&Vector3::new(0.0, 0.0, -1.0), 0.3);
        let (r, p, y) = level.euler_angles();
        assert!(r.abs() < 1e-15 && p.abs() < 1e-15 && (y - 0.3).abs() < 1e-15);
    }

    #[test]
    fn limits_are_respected() {
        let (v, c) = setup();
        let g = ControllerParams::default();
        let x = RigidBodyState::at_rest(Vector3::zeros(), 0.0, 0.0);
        let s = ControlState::from_truth(&x);
        let far = Setpoint::hold(Vector3::new(1000.0, 1000.0, -500.0), 0.0);
        let vc = c.velocity_command(&s, &far);
        assert!((vc.xy().norm() - g.max_horizontal_speed_mps).abs() < 1e-12);
        assert_eq!(vc.z, -g.max_vertical_speed_mps);
        let f = c.thrust_force(&Vector3::new(50.0, 0.0, 0.0));
        let tilt = f.xy().norm().atan2(-f.z);
        assert!((tilt - g.max_tilt_rad).abs() < 1e-12);
        let f = c.thrust_force(&Vector3::new(0.0, 0.0, 30.0));
        assert!((f.z + 0.2 * v.mass() * v.gravity()).abs() < 1e-12);
        let f = c.thrust_force(&Vector3::new(0.0, 0.0, -100.0));
        assert!((f.norm() - 4.0 * v.thrust_max()).abs() < 1e-12);
    }

    #[test]
    fn bad_estimate_is_reported() {
        let x = RigidBodyState::at_rest(Vector3::zeros(), 0.0, 0.0);
        let mut s = ControlState::from_truth(&x);
        assert!(s.check().is_ok());
        s.vel_in_nav.y = f64::NAN;
        let e = s.check().unwrap_err();
        assert!(e.to_string().contains("control_state.vel_in_nav"), "{e}");
    }

    #[test]
    fn rotation_vector_is_accurate() {
        for phi in [
            Vector3::new(1e-9, -2e-9, 3e-10),
            Vector3::new(0.3, -0.2, 1.0),
            Vector3::new(0.0, 0.0, 3.0),
        ] {
            let q = UnitQuaternion::from_scaled_axis(phi);
            assert!((rotation_vector(&q) - phi).norm() < 1e-14 * phi.norm().max(1.0));
            // the sign of the quaternion does not matter
            let neg = UnitQuaternion::new_unchecked(-q.into_inner());
            assert!((rotation_vector(&neg) - phi).norm() < 1e-12);
        }
    }
}
