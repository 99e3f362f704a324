//! Rigid-body dynamics of the quadrotor and their RK4 integration.
//!
//! State `x = (p^n, v^n, q_b^n, omega^b, T_1..4)`, input `u = (T_cmd, w^n)` (rotor
//! thrust commands and the wind, both held over a step):
//!
//! ```text
//! p'     = v
//! v'     = g^n + (1/m) C_b^n ( [0, 0, -sum T_i] - D C_n^b (v - w) )
//! q'     = 0.5 q (x) [0, omega]
//! omega' = J^{-1} ( M(T) - omega x J omega )            M(T): eq. (21)
//! T_i'   = (sat(T_cmd,i) - T_i) / tau_m                  (T_i = sat(T_cmd,i) if tau_m = 0)
//! ```
//!
//! `D` is the linear body drag, `sat` the clamp to `[T_min, T_max]`. The specific
//! force an accelerometer senses is `f^b = (1/m)([0, 0, -sum T_i] - D C_n^b (v - w))
//! = C_n^b (v' - g^n)`. Classical RK4 with the quaternion integrated as four numbers
//! and renormalised at the end of each step (the stages use its normalised rotation).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::allocation::moments_from_thrusts;
use super::params::Vehicle;

/// The true state of the quadrotor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBodyState {
    /// Position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude `C_b^n`.
    pub nav_from_body: UnitQuaternion<f64>,
    /// Body angular rate relative to NED (an inertial frame here), body axes, rad/s.
    pub omega_body: Vector3<f64>,
    /// Actual rotor thrusts `[FL, FR, BL, BR]`, N.
    pub rotor_thrust: [f64; 4],
}

impl RigidBodyState {
    /// At rest at `pos_in_nav`, level, heading `yaw`, rotors at `thrust` each.
    pub fn at_rest(pos_in_nav: Vector3<f64>, yaw: f64, thrust: f64) -> Self {
        Self {
            pos_in_nav,
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            omega_body: Vector3::zeros(),
            rotor_thrust: [thrust; 4],
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.pos_in_nav.iter().all(|x| x.is_finite())
            && self.vel_in_nav.iter().all(|x| x.is_finite())
            && self.nav_from_body.coords.iter().all(|x| x.is_finite())
            && self.omega_body.iter().all(|x| x.is_finite())
            && self.rotor_thrust.iter().all(|x| x.is_finite())
    }
}

/// The input held over one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInput {
    /// Rotor thrust commands `[FL, FR, BL, BR]`, N (clamped to the rotor limits).
    pub thrust_cmd: [f64; 4],
    /// Wind velocity in NED, m/s.
    pub wind_in_nav: Vector3<f64>,
}

/// Time derivative of the state (quaternion as four numbers).
#[derive(Debug, Clone, Copy)]
struct Derivative {
    pos: Vector3<f64>,
    vel: Vector3<f64>,
    quat: Quaternion<f64>,
    omega: Vector3<f64>,
    thrust: [f64; 4],
}

/// Forces in the body frame divided by mass: the specific force `f^b`, m/s^2.
pub fn specific_force_in_body(
    vehicle: &Vehicle,
    state: &RigidBodyState,
    wind_in_nav: &Vector3<f64>,
) -> Vector3<f64> {
    let air_in_body = state.nav_from_body.inverse() * (state.vel_in_nav - wind_in_nav);
    let thrust: f64 = state.rotor_thrust.iter().sum();
    (Vector3::new(0.0, 0.0, -thrust) - vehicle.drag().component_mul(&air_in_body)) / vehicle.mass()
}

/// Acceleration in NED, `g^n + C_b^n f^b`, m/s^2.
pub fn acceleration_in_nav(
    vehicle: &Vehicle,
    state: &RigidBodyState,
    wind_in_nav: &Vector3<f64>,
) -> Vector3<f64> {
    vehicle.gravity_in_nav()
        + state.nav_from_body * specific_force_in_body(vehicle, state, wind_in_nav)
}

/// Angular acceleration in body axes, `J^{-1}(M(T) - omega x J omega)`, rad/s^2.
pub fn angular_acceleration(vehicle: &Vehicle, state: &RigidBodyState) -> Vector3<f64> {
    let m = moments_from_thrusts(&state.rotor_thrust, vehicle.arm_length(), vehicle.kappa());
    let w = &state.omega_body;
    vehicle.inertia_inv() * (m - w.cross(&(vehicle.inertia() * w)))
}

/// Thrust commands clamped to the rotor limits.
pub fn saturate(vehicle: &Vehicle, cmd: &[f64; 4]) -> [f64; 4] {
    std::array::from_fn(|i| cmd[i].clamp(vehicle.thrust_min(), vehicle.thrust_max()))
}

fn derivative(vehicle: &Vehicle, x: &RigidBodyState, u: &StepInput) -> Derivative {
    let cmd = saturate(vehicle, &u.thrust_cmd);
    let tau = vehicle.motor_time_constant();
    let thrust = if tau > 0.0 {
        std::array::from_fn(|i| (cmd[i] - x.rotor_thrust[i]) / tau)
    } else {
        [0.0; 4]
    };
    let w = &x.omega_body;
    Derivative {
        pos: x.vel_in_nav,
        vel: acceleration_in_nav(vehicle, x, &u.wind_in_nav),
        quat: x.nav_from_body.quaternion() * Quaternion::new(0.0, w.x, w.y, w.z) * 0.5,
        omega: angular_acceleration(vehicle, x),
        thrust,
    }
}

/// `x + h k` with the quaternion added as four numbers and normalised (the stage
/// states of RK4 and the step's result).
fn advance(x: &RigidBodyState, k: &Derivative, h: f64) -> RigidBodyState {
    let q = x.nav_from_body.quaternion() + k.quat * h;
    RigidBodyState {
        pos_in_nav: x.pos_in_nav + k.pos * h,
        vel_in_nav: x.vel_in_nav + k.vel * h,
        nav_from_body: UnitQuaternion::from_quaternion(q),
        omega_body: x.omega_body + k.omega * h,
        rotor_thrust: std::array::from_fn(|i| x.rotor_thrust[i] + k.thrust[i] * h),
    }
}

/// One classical RK4 step of length `h` with the input held.
pub fn rk4_step(vehicle: &Vehicle, x: &RigidBodyState, u: &StepInput, h: f64) -> RigidBodyState {
    let mut x0 = *x;
    if vehicle.motor_time_constant() <= 0.0 {
        x0.rotor_thrust = saturate(vehicle, &u.thrust_cmd);
    }
    let k1 = derivative(vehicle, &x0, u);
    let k2 = derivative(vehicle, &advance(&x0, &k1, 0.5 * h), u);
    let k3 = derivative(vehicle, &advance(&x0, &k2, 0.5 * h), u);
    let k4 = derivative(vehicle, &advance(&x0, &k3, h), u);
    let sum = Derivative {
        pos: (k1.pos + (k2.pos + k3.pos) * 2.0 + k4.pos) / 6.0,
        vel: (k1.vel + (k2.vel + k3.vel) * 2.0 + k4.vel) / 6.0,
        quat: (k1.quat + (k2.quat + k3.quat) * 2.0 + k4.quat) / 6.0,
        omega: (k1.omega + (k2.omega + k3.omega) * 2.0 + k4.omega) / 6.0,
        thrust: std::array::from_fn(|i| {
            (k1.thrust[i] + 2.0 * (k2.thrust[i] + k3.thrust[i]) + k4.thrust[i]) / 6.0
        }),
    };
    advance(&x0, &sum, h)
}

/// Advances `x` by `duration` with steps of at most `h`: whole steps, then one partial
/// step for the remainder (below `1e-9 h` it is skipped). With `duration` a whole
/// number of steps this is bit-identical to calling [`rk4_step`] that many times.
pub fn integrate(
    vehicle: &Vehicle,
    x: &RigidBodyState,
    u: &StepInput,
    duration: f64,
    h: f64,
) -> RigidBodyState {
    let mut s = *x;
    let whole = ((duration / h) * (1.0 + 1e-12)).floor() as usize;
    for _ in 0..whole {
        s = rk4_step(vehicle, &s, u, h);
    }
    let rest = duration - whole as f64 * h;
    if rest > 1e-9 * h {
        s = rk4_step(vehicle, &s, u, rest);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrotor::allocation::thrusts_from_wrench;
    use crate::quadrotor::params::VehicleParams;

    fn still(v: &Vehicle) -> StepInput {
        StepInput {
            thrust_cmd: [v.hover_thrust_per_rotor(); 4],
            wind_in_nav: Vector3::zeros(),
        }
    }

    /// Acceptance: with the rotors off the body falls at g (no drag: exactly
    /// `0.5 g t^2`; with drag: initial acceleration g, then the terminal speed
    /// `m g / D_z`).
    #[test]
    fn rotors_off_falls_at_g() {
        let no_drag = VehicleParams {
            drag_n_per_mps: Vector3::zeros(),
            ..VehicleParams::default()
        }
        .check()
        .unwrap();
        let mut x = RigidBodyState::at_rest(Vector3::new(0.0, 0.0, -100.0), 0.3, 0.0);
        let off = StepInput {
            thrust_cmd: [0.0; 4],
            wind_in_nav: Vector3::zeros(),
        };
        for _ in 0..400 {
            x = rk4_step(&no_drag, &x, &off, 0.005);
        }
        let g = no_drag.gravity();
        assert!(
            (x.pos_in_nav.z + 100.0 - 0.5 * g * 4.0).abs() < 1e-10,
            "{}",
            x.pos_in_nav.z
        );
        assert!((x.vel_in_nav.z - 2.0 * g).abs() < 1e-12);
        assert!(x.pos_in_nav.xy().norm() < 1e-15 && x.omega_body.norm() == 0.0);
        let v = VehicleParams::default().check().unwrap();
        let x0 = RigidBodyState::at_rest(Vector3::zeros(), 0.0, 0.0);
        let a0 = acceleration_in_nav(&v, &x0, &Vector3::zeros());
        assert!((a0 - v.gravity_in_nav()).norm() < 1e-15);
        let x_long = integrate(&v, &x0, &off, 60.0, 0.005);
        let terminal = v.mass() * v.gravity() / v.drag().z;
        assert!((x_long.vel_in_nav.z / terminal - 1.0).abs() < 1e-6);
    }

    /// Acceptance: a pure yaw moment changes only the yaw rate (diagonal inertia, level
    /// hover thrust), and at `Mz / Jz`.
    #[test]
    fn pure_yaw_moment_changes_only_yaw_rate() {
        let v = VehicleParams {
            motor_time_constant_s: 0.0,
            ..VehicleParams::default()
        }
        .check()
        .unwrap();
        let mz = 0.05;
        let cmd = thrusts_from_wrench(
            4.0 * v.hover_thrust_per_rotor(),
            &Vector3::new(0.0, 0.0, mz),
            v.arm_length(),
            v.kappa(),
        );
        let u = StepInput {
            thrust_cmd: cmd,
            wind_in_nav: Vector3::zeros(),
        };
        let mut x = RigidBodyState::at_rest(Vector3::new(1.0, 2.0, -20.0), 0.4, 0.0);
        for _ in 0..400 {
            x = rk4_step(&v, &x, &u, 0.005);
        }
        let (roll, pitch, yaw) = x.nav_from_body.euler_angles();
        let rate = mz / v.inertia()[(2, 2)];
        assert!(x.omega_body.xy().norm() < 1e-15, "{}", x.omega_body);
        assert!((x.omega_body.z - rate * 2.0).abs() < 1e-12);
        assert!(roll.abs() < 1e-15 && pitch.abs() < 1e-15);
        assert!((yaw - 0.4 - 0.5 * rate * 4.0).abs() < 1e-10, "{yaw}");
        assert!((x.pos_in_nav - Vector3::new(1.0, 2.0, -20.0)).norm() < 1e-9);
    }

    #[test]
    fn hover_is_an_equilibrium_and_specific_force_is_minus_g() {
        let v = VehicleParams::default().check().unwrap();
        let x0 = RigidBodyState::at_rest(
            Vector3::new(0.0, 0.0, -20.0),
            1.0,
            v.hover_thrust_per_rotor(),
        );
        let x = integrate(&v, &x0, &still(&v), 10.0, 0.0025);
        assert!((x.pos_in_nav - x0.pos_in_nav).norm() < 1e-9);
        for t in x.rotor_thrust {
            assert!((t - v.hover_thrust_per_rotor()).abs() < 1e-12);
        }
        let f = specific_force_in_body(&v, &x0, &Vector3::zeros());
        assert!((f - Vector3::new(0.0, 0.0, -v.gravity())).norm() < 1e-14);
    }

    #[test]
    fn motor_lag_is_first_order() {
        let v = VehicleParams::default().check().unwrap();
        let tau = v.motor_time_constant();
        let x0 = RigidBodyState::at_rest(Vector3::zeros(), 0.0, 2.0);
        let u = StepInput {
            thrust_cmd: [6.0; 4],
            wind_in_nav: Vector3::zeros(),
        };
        let x = integrate(&v, &x0, &u, tau, 0.0025);
        let expect = 6.0 - 4.0 * (-1.0f64).exp();
        assert!(
            (x.rotor_thrust[0] - expect).abs() < 1e-6,
            "{}",
            x.rotor_thrust[0]
        );
        // commands beyond the limit saturate
        let u = StepInput {
            thrust_cmd: [100.0; 4],
            wind_in_nav: Vector3::zeros(),
        };
        let x = integrate(&v, &x0, &u, 2.0, 0.0025);
        assert!((x.rotor_thrust[0] - v.thrust_max()).abs() < 1e-9);
    }

    #[test]
    fn integrate_splits_whole_and_partial_steps() {
        let v = VehicleParams::default().check().unwrap();
        let mut x0 = RigidBodyState::at_rest(Vector3::zeros(), 0.0, 3.0);
        x0.omega_body = Vector3::new(0.3, -0.2, 0.1);
        x0.vel_in_nav = Vector3::new(1.0, 0.5, -0.2);
        let u = StepInput {
            thrust_cmd: [4.5, 3.5, 4.0, 4.2],
            wind_in_nav: Vector3::new(2.0, 0.0, 0.0),
        };
        let mut manual = x0;
        for _ in 0..3 {
            manual = rk4_step(&v, &manual, &u, 0.0025);
        }
        assert_eq!(integrate(&v, &x0, &u, 0.0075, 0.0025), manual);
        // a partial step is continuous with the whole steps
        let a = integrate(&v, &x0, &u, 0.0075 - 1e-7, 0.0025);
        assert!((a.pos_in_nav - manual.pos_in_nav).norm() < 1e-6);
    }
}
