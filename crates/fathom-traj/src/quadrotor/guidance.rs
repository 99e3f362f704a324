//! Path guidance (seed 004, section 3.3): hover at waypoints and fly straight legs
//! between them. On a leg from `a` to `b` (unit direction `u`, length `L`), with the
//! vehicle at `p`:
//!
//! ```text
//! s      = (p - a) . u                       along-leg distance flown
//! e      = a + s u - p                       perpendicular offset toward the leg
//! V_leg  = min(cruise / |u_h|, vertical / |u_z|)
//! V_a    = min(V_leg, sqrt(2 a_max (L - s)), K_ct (L - s)),  rising at most a_max per s
//! v_cmd  = V_a u + K_ct e                    (|K_ct e| <= V_leg)
//! ```
//!
//! i.e. the along-leg speed plus a correction perpendicular to the leg toward it (the
//! paper's path convergence). A leg ends when the vehicle is within the capture radius
//! of `b` or has passed it (`s >= L`); the vehicle then holds `b` (position loop),
//! turns in place to the waypoint's yaw if it has one, hovers for the hover time, and
//! leaves when both are done (yaw within the tolerance). The yaw command is held on
//! the legs. The first waypoint is the start: the vehicle is there at rest.

use fathom_core::units::wrap_pi;
use nalgebra::Vector3;

use super::controller::{ControlState, Setpoint};
use super::params::Path;

/// Where the guidance is in the path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    /// Holding waypoint `index`; `arrived_at` is the arrival time once within the
    /// capture radius.
    Hover {
        /// Waypoint index.
        index: usize,
        /// Arrival time, s.
        arrived_at: Option<f64>,
    },
    /// Flying the leg from waypoint `from` to `from + 1`.
    Leg {
        /// Index of the leg's first waypoint.
        from: usize,
    },
    /// Done: holding the last waypoint.
    Finished,
}

/// The path follower (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Guidance {
    path: Path,
    phase: Phase,
    yaw_cmd: f64,
    along_speed_cmd: f64,
}

impl Guidance {
    /// A follower at the start of `path`; the yaw command starts at the first
    /// waypoint's yaw, or `initial_yaw` if it has none.
    pub fn new(path: &Path, initial_yaw: f64) -> Self {
        Self {
            yaw_cmd: path.waypoints()[0].yaw_rad.unwrap_or(initial_yaw),
            path: path.clone(),
            phase: Phase::Hover {
                index: 0,
                arrived_at: None,
            },
            along_speed_cmd: 0.0,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Whether the last waypoint's hover is done.
    pub fn is_finished(&self) -> bool {
        self.phase == Phase::Finished
    }

    /// The yaw command, rad.
    pub fn yaw_command(&self) -> f64 {
        self.yaw_cmd
    }

    /// The path followed.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The setpoint at time `t` for the state `state` (the update advances the
    /// along-speed ramp by `dt`).
    pub fn update(&mut self, t: f64, state: &ControlState, dt: f64) -> Setpoint {
        let (capture, yaw_tol) = {
            let p = self.path.params();
            (p.capture_radius_m, p.yaw_tolerance_rad)
        };
        let wps = self.path.waypoints();
        let p_now = state.pos_in_nav;
        // every transition moves forward; the bound only guards the loop
        for _ in 0..(3 * wps.len() + 3) {
            match self.phase {
                Phase::Hover { index, arrived_at } => {
                    let wp = wps[index];
                    let arrived = match arrived_at {
                        Some(a) => a,
                        None if (p_now - wp.pos_in_nav).norm() < capture => {
                            if let Some(y) = wp.yaw_rad {
                                self.yaw_cmd = y;
                            }
                            self.phase = Phase::Hover {
                                index,
                                arrived_at: Some(t),
                            };
                            t
                        }
                        None => return Setpoint::hold(wp.pos_in_nav, self.yaw_cmd),
                    };
                    let yaw_done = wrap_pi(state.yaw() - self.yaw_cmd).abs() < yaw_tol;
                    if t - arrived >= wp.hover_time_s && yaw_done {
                        if index + 1 < wps.len() {
                            self.phase = Phase::Leg { from: index };
                            let d = wps[index + 1].pos_in_nav - wp.pos_in_nav;
                            let n = d.norm();
                            self.along_speed_cmd = if n > 0.0 {
                                state.vel_in_nav.dot(&(d / n)).max(0.0)
                            } else {
                                0.0
                            };
                        } else {
                            self.phase = Phase::Finished;
                        }
                        continue;
                    }
                    return Setpoint::hold(wp.pos_in_nav, self.yaw_cmd);
                }
                Phase::Leg { from } => {
                    let a = wps[from].pos_in_nav;
                    let b = wps[from + 1].pos_in_nav;
                    let d = b - a;
                    let len = d.norm();
                    if len < capture {
                        self.phase = Phase::Hover {
                            index: from + 1,
                            arrived_at: None,
                        };
                        continue;
                    }
                    let u = d / len;
                    let s = (p_now - a).dot(&u);
                    if (b - p_now).norm() < capture || s >= len {
                        self.phase = Phase::Hover {
                            index: from + 1,
                            arrived_at: None,
                        };
                        continue;
                    }
                    return Setpoint {
                        pos_in_nav: None,
                        vel_in_nav: self.leg_velocity(&a, &u, len, s, &p_now, dt),
                        yaw: self.yaw_cmd,
                    };
                }
                Phase::Finished => {
                    return Setpoint::hold(wps[wps.len() - 1].pos_in_nav, self.yaw_cmd);
                }
            }
        }
        Setpoint::hold(p_now, self.yaw_cmd)
    }

    /// The leg's velocity command (module docs).
    fn leg_velocity(
        &mut self,
        a: &Vector3<f64>,
        u: &Vector3<f64>,
        len: f64,
        s: f64,
        p_now: &Vector3<f64>,
        dt: f64,
    ) -> Vector3<f64> {
        let p = self.path.params();
        let uh = u.xy().norm();
        let uz = u.z.abs();
        let mut v_leg = f64::INFINITY;
        if uh > 1e-9 {
            v_leg = v_leg.min(p.cruise_speed_mps / uh);
        }
        if uz > 1e-9 {
            v_leg = v_leg.min(p.vertical_speed_mps / uz);
        }
        let rem = len - s;
        let target = v_leg
            .min((2.0 * p.along_acceleration_mps2 * rem).sqrt())
            .min(p.cross_track_gain * rem);
        let along = target.min(self.along_speed_cmd + p.along_acceleration_mps2 * dt);
        self.along_speed_cmd = along;
        let e = a + u * s - p_now;
        let mut v_perp = e * p.cross_track_gain;
        let n = v_perp.norm();
        if n > v_leg {
            v_perp *= v_leg / n;
        }
        u * along + v_perp
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrotor::dynamics::RigidBodyState;
    use crate::quadrotor::params::{PathParams, Waypoint};
    use nalgebra::UnitQuaternion;

    fn state_at(p: Vector3<f64>, yaw: f64) -> ControlState {
        let mut x = RigidBodyState::at_rest(p, yaw, 0.0);
        x.nav_from_body = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        ControlState::from_truth(&x)
    }

    fn two_point() -> Path {
        PathParams::new(vec![
            Waypoint::new(Vector3::zeros(), 1.0),
            Waypoint::new(Vector3::new(100.0, 0.0, 0.0), 0.0).with_yaw(1.0),
        ])
        .check()
        .unwrap()
    }

    #[test]
    fn hover_then_leg_then_turn_then_finish() {
        let mut g = Guidance::new(&two_point(), 0.2);
        assert_eq!(g.yaw_command(), 0.2);
        let s0 = state_at(Vector3::zeros(), 0.2);
        let sp = g.update(0.0, &s0, 0.01);
        assert_eq!(sp.pos_in_nav, Some(Vector3::zeros()));
        assert!(matches!(
            g.phase(),
            Phase::Hover {
                index: 0,
                arrived_at: Some(_)
            }
        ));
        g.update(0.5, &s0, 0.01);
        assert!(matches!(g.phase(), Phase::Hover { .. }));
        // after the hover time: the leg, speed ramping at a_max
        let sp = g.update(1.0, &s0, 0.01);
        assert_eq!(g.phase(), Phase::Leg { from: 0 });
        assert!(sp.pos_in_nav.is_none());
        assert!((sp.vel_in_nav.x - 0.01).abs() < 1e-12);
        // mid-leg, off to the east by 2 m: cross-track correction west, cruise speed
        let mut s = state_at(Vector3::new(50.0, 2.0, 0.0), 0.2);
        for _ in 0..400 {
            g.update(2.0, &s, 0.01);
        }
        let sp = g.update(2.0, &s, 0.01);
        assert!((sp.vel_in_nav.x - 3.0).abs() < 1e-12);
        assert!((sp.vel_in_nav.y + 0.8 * 2.0).abs() < 1e-12);
        // braking near the end: K_ct * remaining
        s.pos_in_nav = Vector3::new(99.0, 0.0, 0.0);
        let sp = g.update(3.0, &s, 0.01);
        assert!((sp.vel_in_nav.x - 0.8).abs() < 1e-12);
        // arrival: hold the end, turn to its yaw, finish when the yaw is reached
        s.pos_in_nav = Vector3::new(99.9, 0.0, 0.0);
        let sp = g.update(4.0, &s, 0.01);
        assert_eq!(sp.pos_in_nav, Some(Vector3::new(100.0, 0.0, 0.0)));
        assert_eq!(sp.yaw, 1.0);
        assert!(!g.is_finished());
        let turned = state_at(Vector3::new(100.0, 0.0, 0.0), 1.0 - 0.001);
        g.update(5.0, &turned, 0.01);
        assert!(g.is_finished());
    }

    #[test]
    fn vertical_legs_use_the_vertical_speed() {
        let path = PathParams::new(vec![
            Waypoint::new(Vector3::zeros(), 0.0),
            Waypoint::new(Vector3::new(0.0, 0.0, -20.0), 0.0),
        ])
        .check()
        .unwrap();
        let mut g = Guidance::new(&path, 0.0);
        g.update(0.0, &state_at(Vector3::zeros(), 0.0), 0.01);
        let s = state_at(Vector3::new(0.0, 0.0, -10.0), 0.0);
        let mut sp = g.update(0.0, &s, 0.01);
        for _ in 0..1000 {
            sp = g.update(0.0, &s, 0.01);
        }
        assert!((sp.vel_in_nav.z + 1.5).abs() < 1e-12, "{}", sp.vel_in_nav);
    }

    #[test]
    fn passing_the_end_also_ends_the_leg_and_zero_legs_are_skipped() {
        let path = PathParams::new(vec![
            Waypoint::new(Vector3::zeros(), 0.0),
            Waypoint::new(Vector3::zeros(), 0.0),
            Waypoint::new(Vector3::new(10.0, 0.0, 0.0), 0.0),
        ])
        .check()
        .unwrap();
        let mut g = Guidance::new(&path, 0.0);
        let s = state_at(Vector3::zeros(), 0.0);
        g.update(0.0, &s, 0.01);
        assert_eq!(g.phase(), Phase::Leg { from: 1 });
        let beyond = state_at(Vector3::new(11.0, 3.0, 0.0), 0.0);
        let sp = g.update(1.0, &beyond, 0.01);
        assert_eq!(sp.pos_in_nav, Some(Vector3::new(10.0, 0.0, 0.0)));
        assert!(matches!(
            g.phase(),
            Phase::Hover {
                index: 2,
                arrived_at: None
            }
        ));
    }
}
