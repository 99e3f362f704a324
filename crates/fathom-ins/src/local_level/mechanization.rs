//! Propagation of the reduced nominal state with IMU increments (seed 004's 12-state
//! INS: local NED, constant gravity `g^n = [0, 0, g]`, no Earth or transport rate).
//!
//! # Algorithm (one step from `t_{k-1}` to `t_k = t_{k-1} + dt`)
//!
//! The WGS-84 [`crate::strapdown`] with the frame-rate terms set to zero (same
//! references: Savage 1998, Titterton & Weston ch. 11):
//!
//! 1. attitude, coning-corrected (two-sample form):
//!    `phi_k = dtheta_k + (1/12) dtheta_{k-1} x dtheta_k`, `q_k = q_{k-1} (x) q(phi_k)`,
//!    renormalised;
//! 2. velocity, rotation and sculling compensated:
//!    `v_k = v_{k-1} + C_b^n(k-1) (dv_k + 0.5 dtheta_k x dv_k + dv_scul) + g^n dt`,
//!    `dv_scul = (1/12)(dtheta_{k-1} x dv_k + dv_{k-1} x dtheta_k)`;
//! 3. position, trapezoidal: `p_k = p_{k-1} + (dt/2)(v_{k-1} + v_k)`.
//!
//! The increments of [`super::imu_from_truth`] invert steps 1-2 exactly, so attitude
//! and velocity follow the truth to rounding; the position then differs from the
//! truth by the trapezoidal error of the true velocity, `-(dt^3/12) a'` per step,
//! which telescopes to `-(dt^2/12)(a(t) - a(0))` (about 1e-5 m at 100 Hz).

use nalgebra::Vector3;

use crate::error::{InsError, check_finite};
use crate::rotation::quat_from_rotation_vector;
use crate::state::ImuIncrement;
use crate::strapdown::{coning, sculling};

use super::LocalLevelState;

/// The reduced strapdown: nominal state plus the previous increment (for coning
/// and sculling). `step` performs no heap allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalLevelMechanization {
    state: LocalLevelState,
    gravity: f64,
    prev_increment: Option<ImuIncrement>,
}

impl LocalLevelMechanization {
    /// A mechanization started at `initial` with gravity `g` (m/s^2, down positive;
    /// use the same value as the truth, e.g. [`fathom_core::units::STANDARD_GRAVITY`]).
    ///
    /// # Errors
    /// [`InsError::NonFinite`] for a non-finite state or gravity.
    pub fn new(initial: LocalLevelState, gravity: f64) -> Result<Self, InsError> {
        initial.check()?;
        check_finite("gravity", &[gravity])?;
        Ok(Self {
            state: initial,
            gravity,
            prev_increment: None,
        })
    }

    /// The current nominal state.
    pub fn state(&self) -> &LocalLevelState {
        &self.state
    }

    /// The gravity magnitude used, m/s^2.
    pub fn gravity(&self) -> f64 {
        self.gravity
    }

    /// Replaces the nominal state (e.g. an error-state filter's feedback). The
    /// previous increment (coning / sculling memory) is kept.
    ///
    /// # Errors
    /// [`InsError::NonFinite`]; the mechanization is then unchanged.
    pub fn set_state(&mut self, state: LocalLevelState) -> Result<(), InsError> {
        state.check()?;
        self.state = state;
        Ok(())
    }

    /// Forgets the previous increment (as after `new`).
    pub fn reset_history(&mut self) {
        self.prev_increment = None;
    }

    /// The last increment processed.
    pub fn previous_increment(&self) -> Option<&ImuIncrement> {
        self.prev_increment.as_ref()
    }

    /// Integrates one IMU increment (module docs).
    ///
    /// # Errors
    /// [`InsError::NonPositiveDt`] / [`InsError::NonFinite`] for a bad increment or a
    /// step that would leave a non-finite state; the mechanization is then unchanged.
    pub fn step(&mut self, inc: &ImuIncrement) -> Result<(), InsError> {
        inc.check()?;
        let s = &self.state;
        let (dth_prev, dv_prev) = match &self.prev_increment {
            Some(p) => (p.delta_theta, p.delta_v),
            None => (Vector3::zeros(), Vector3::zeros()),
        };
        let (dth, dv, dt) = (&inc.delta_theta, &inc.delta_v, inc.dt);

        let phi = dth + coning(&dth_prev, dth);
        let mut q_new = s.nav_from_body * quat_from_rotation_vector(&phi);
        q_new.renormalize();

        let dv_sf_body = dv + dth.cross(dv) * 0.5 + sculling(&dth_prev, &dv_prev, dth, dv);
        let vel_new =
            s.vel_in_nav + s.nav_from_body * dv_sf_body + Vector3::new(0.0, 0.0, self.gravity * dt);
        let pos_new = s.pos_in_nav + (s.vel_in_nav + vel_new) * (0.5 * dt);

        let new_state = LocalLevelState {
            pos_in_nav: pos_new,
            vel_in_nav: vel_new,
            nav_from_body: q_new,
        };
        check_finite("propagated vel_in_nav", new_state.vel_in_nav.as_slice())?;
        check_finite("propagated pos_in_nav", new_state.pos_in_nav.as_slice())?;
        check_finite("propagated attitude quaternion", q_new.coords.as_slice())?;
        self.state = new_state;
        self.prev_increment = Some(*inc);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn level_at_rest() -> LocalLevelState {
        LocalLevelState {
            pos_in_nav: Vector3::new(1.0, 2.0, -20.0),
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 0.7),
        }
    }

    #[test]
    fn stationary_with_minus_g_specific_force_stays_put() {
        let g = 9.806_65;
        let mut m = LocalLevelMechanization::new(level_at_rest(), g).unwrap();
        let inc = ImuIncrement::new(0.01, Vector3::zeros(), Vector3::new(0.0, 0.0, -g * 0.01));
        for _ in 0..30_000 {
            m.step(&inc).unwrap();
        }
        let s = m.state();
        assert!((s.pos_in_nav - level_at_rest().pos_in_nav).amax() < 1e-9);
        assert!(s.vel_in_nav.amax() < 1e-12);
        // Negative control: 1 mg of accelerometer bias moves it 0.5 * 1e-2 * 300^2 m.
        let mut b = LocalLevelMechanization::new(level_at_rest(), g).unwrap();
        let biased = ImuIncrement::new(
            0.01,
            Vector3::zeros(),
            Vector3::new(1e-2 * 0.01, 0.0, -g * 0.01),
        );
        for _ in 0..30_000 {
            b.step(&biased).unwrap();
        }
        let moved = b.state().pos_in_nav - level_at_rest().pos_in_nav;
        // body x is at yaw 0.7 rad
        assert!((moved.norm() - 450.0).abs() < 1e-6, "{moved}");
    }

    #[test]
    fn free_fall_is_exact() {
        // rotors off: zero specific force, the position follows 0.5 g t^2 exactly
        let g = 9.81;
        let mut m = LocalLevelMechanization::new(level_at_rest(), g).unwrap();
        let inc = ImuIncrement::new(0.01, Vector3::zeros(), Vector3::zeros());
        for _ in 0..100 {
            m.step(&inc).unwrap();
        }
        let dz = m.state().pos_in_nav.z - level_at_rest().pos_in_nav.z;
        assert!((dz - 0.5 * g).abs() < 1e-12, "{dz}");
        assert!((m.state().vel_in_nav.z - g).abs() < 1e-12);
    }

    #[test]
    fn bad_input_leaves_state_unchanged() {
        let mut m = LocalLevelMechanization::new(level_at_rest(), 9.8).unwrap();
        let bad = ImuIncrement::new(0.01, Vector3::new(f64::NAN, 0.0, 0.0), Vector3::zeros());
        let e = m.step(&bad).unwrap_err();
        assert!(e.to_string().contains("delta_theta"), "{e}");
        assert_eq!(m.state(), &level_at_rest());
        assert!(m.previous_increment().is_none());
        let absurd = ImuIncrement::new(1e300, Vector3::zeros(), Vector3::new(0.0, 0.0, 1e300));
        assert!(m.step(&absurd).is_err());
        assert_eq!(m.state(), &level_at_rest());
        assert!(LocalLevelMechanization::new(level_at_rest(), f64::NAN).is_err());
        let mut s = level_at_rest();
        s.pos_in_nav.x = f64::INFINITY;
        assert!(LocalLevelMechanization::new(s, 9.8).is_err());
        assert!(m.set_state(s).is_err());
    }
}
