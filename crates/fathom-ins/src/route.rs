//! A simple analytic route generator for tests and experiments: constant depth,
//! a smooth speed ramp to cruise, and coordinated turns with cosine-ramped turn rate.
//!
//! Heading and speed are closed-form functions of time; latitude and longitude are
//! integrated from the NED velocity with fixed-step RK4 at `dt / substeps`
//! (position rates of [`crate::earth::position_rates`]). The attitude is that of a
//! coordinated turn without sideslip: yaw = heading, pitch = 0,
//! `roll = atan(V r / g)` (`r` the turn rate; right turns bank right).

use nalgebra::{UnitQuaternion, Vector3};

use crate::earth::{self, Geodetic};
use crate::error::InsError;
use crate::imu_from_truth::TruthSample;

/// One coordinated turn: the turn rate rises from 0 to `rate` with a half-cosine ramp of
/// `ramp` s, holds, and falls back over `ramp` s; total length `duration`.
/// Heading change = `rate * (duration - ramp)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turn {
    /// Start time, s.
    pub start: f64,
    /// Total duration including both ramps, s (>= 2 ramp).
    pub duration: f64,
    /// Ramp length, s (> 0).
    pub ramp: f64,
    /// Peak turn rate, rad/s (positive = clockwise seen from above = to starboard).
    pub rate: f64,
}

impl Turn {
    /// Normalised rate profile `s(t)` in [0, 1] and its integral `S(t)`.
    fn profile(&self, t: f64) -> (f64, f64) {
        use std::f64::consts::PI;
        let (d, tau) = (self.duration, self.ramp);
        let u = t - self.start;
        if u <= 0.0 {
            (0.0, 0.0)
        } else if u < tau {
            let x = PI * u / tau;
            (0.5 * (1.0 - x.cos()), 0.5 * u - tau / (2.0 * PI) * x.sin())
        } else if u < d - tau {
            (1.0, 0.5 * tau + (u - tau))
        } else if u < d {
            let w = d - u;
            let x = PI * w / tau;
            (
                0.5 * (1.0 - x.cos()),
                (d - tau) - (0.5 * w - tau / (2.0 * PI) * x.sin()),
            )
        } else {
            (0.0, d - tau)
        }
    }
}

/// Analytic constant-depth route with a speed ramp and coordinated turns.
#[derive(Debug, Clone, PartialEq)]
pub struct TurningRoute {
    /// Start position (height = minus depth).
    pub start: Geodetic,
    /// Initial heading, rad (clockwise from north).
    pub initial_heading: f64,
    /// Speed at t = 0, m/s.
    pub initial_speed: f64,
    /// Cruise speed, m/s.
    pub cruise_speed: f64,
    /// Duration of the half-cosine speed ramp from initial to cruise speed, s (> 0).
    pub accel_duration: f64,
    /// The turns (may overlap; their rates add).
    pub turns: Vec<Turn>,
}

impl TurningRoute {
    /// The `vkf` experiment's default route (spec C §3.2): 35 N 129 E, 50 m depth,
    /// heading 030, 2 m/s accelerating to 10 kt (5.144 m/s) over the first 120 s, then
    /// five coordinated turns of 2-4 deg/s (+90, -90, +90, +180, -90 deg).
    pub fn vkf_default() -> Self {
        let d = f64::to_radians;
        Self {
            start: Geodetic::new(d(35.0), d(129.0), -50.0),
            initial_heading: d(30.0),
            initial_speed: 2.0,
            cruise_speed: fathom_core::units::knots_to_mps(10.0),
            accel_duration: 120.0,
            turns: vec![
                Turn {
                    start: 180.0,
                    duration: 35.0,
                    ramp: 5.0,
                    rate: d(3.0),
                },
                Turn {
                    start: 420.0,
                    duration: 35.0,
                    ramp: 5.0,
                    rate: d(-3.0),
                },
                Turn {
                    start: 700.0,
                    duration: 50.0,
                    ramp: 5.0,
                    rate: d(2.0),
                },
                Turn {
                    start: 1000.0,
                    duration: 65.0,
                    ramp: 5.0,
                    rate: d(3.0),
                },
                Turn {
                    start: 1300.0,
                    duration: 27.5,
                    ramp: 5.0,
                    rate: d(-4.0),
                },
            ],
        }
    }

    /// Checks the definition.
    ///
    /// # Errors
    /// [`InsError::InvalidRoute`] naming the problem.
    pub fn check(&self) -> Result<(), InsError> {
        let bad = |what: String| Err(InsError::InvalidRoute { what });
        let vals = [
            self.start.lat,
            self.start.lon,
            self.start.h,
            self.initial_heading,
            self.initial_speed,
            self.cruise_speed,
            self.accel_duration,
        ];
        if vals.iter().any(|v| !v.is_finite()) {
            return bad("non-finite start, heading, speed or ramp".into());
        }
        if self.start.lat.abs() >= 1.5 {
            return bad(format!(
                "start latitude {} rad too close to a pole",
                self.start.lat
            ));
        }
        if self.accel_duration <= 0.0 {
            return bad(format!(
                "accel_duration {} must be > 0",
                self.accel_duration
            ));
        }
        for (i, t) in self.turns.iter().enumerate() {
            let ok = [t.start, t.duration, t.ramp, t.rate]
                .iter()
                .all(|v| v.is_finite())
                && t.ramp > 0.0
                && t.duration >= 2.0 * t.ramp;
            if !ok {
                return bad(format!(
                    "turn {i}: need finite values, ramp > 0 and duration >= 2 ramp"
                ));
            }
        }
        Ok(())
    }

    /// Speed at time `t`, m/s.
    pub fn speed(&self, t: f64) -> f64 {
        if t <= 0.0 {
            self.initial_speed
        } else if t < self.accel_duration {
            let x = std::f64::consts::PI * t / self.accel_duration;
            self.initial_speed + (self.cruise_speed - self.initial_speed) * 0.5 * (1.0 - x.cos())
        } else {
            self.cruise_speed
        }
    }

    /// Heading and turn rate at time `t`, rad and rad/s.
    pub fn heading_and_rate(&self, t: f64) -> (f64, f64) {
        let mut psi = self.initial_heading;
        let mut r = 0.0;
        for turn in &self.turns {
            let (s, int_s) = turn.profile(t);
            r += turn.rate * s;
            psi += turn.rate * int_s;
        }
        (psi, r)
    }

    /// NED velocity at time `t` (horizontal, constant depth).
    pub fn vel_in_nav(&self, t: f64) -> Vector3<f64> {
        let v = self.speed(t);
        let (psi, _) = self.heading_and_rate(t);
        Vector3::new(v * psi.cos(), v * psi.sin(), 0.0)
    }

    /// Coordinated-turn attitude at time `t`: yaw = heading, pitch 0, roll
    /// `atan(V r / g)`.
    pub fn nav_from_body(&self, t: f64) -> UnitQuaternion<f64> {
        let (psi, r) = self.heading_and_rate(t);
        let g = earth::normal_gravity(self.start.lat, self.start.h);
        let roll = (self.speed(t) * r / g).atan();
        UnitQuaternion::from_euler_angles(roll, 0.0, psi)
    }

    /// `n` true samples at `t = 0, dt, ..., (n-1) dt`; positions integrated with RK4
    /// using `substeps` sub-steps per `dt`.
    ///
    /// # Errors
    /// [`InsError::InvalidRoute`] for a bad route, `dt <= 0` or `substeps == 0`.
    pub fn sample(&self, dt: f64, n: usize, substeps: usize) -> Result<Vec<TruthSample>, InsError> {
        self.check()?;
        if dt.is_nan() || dt <= 0.0 || substeps == 0 {
            return Err(InsError::InvalidRoute {
                what: format!("dt = {dt} must be > 0 and substeps = {substeps} >= 1"),
            });
        }
        let h = self.start.h;
        let rate = |t: f64, lat: f64| earth::position_rates(lat, h, &self.vel_in_nav(t));
        let mut out = Vec::with_capacity(n);
        let (mut lat, mut lon) = (self.start.lat, self.start.lon);
        let hs = dt / substeps as f64;
        for k in 0..n {
            let t = k as f64 * dt;
            out.push(TruthSample {
                time: t,
                lat,
                lon,
                h,
                vel_in_nav: self.vel_in_nav(t),
                nav_from_body: self.nav_from_body(t),
            });
            for j in 0..substeps {
                let ts = t + j as f64 * hs;
                let k1 = rate(ts, lat);
                let k2 = rate(ts + 0.5 * hs, lat + 0.5 * hs * k1.x);
                let k3 = rate(ts + 0.5 * hs, lat + 0.5 * hs * k2.x);
                let k4 = rate(ts + hs, lat + hs * k3.x);
                let d = (k1 + (k2 + k3) * 2.0 + k4) * (hs / 6.0);
                lat += d.x;
                lon += d.y;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn turn_profile_is_continuous_and_integrates_to_heading_change() {
        let turn = Turn {
            start: 10.0,
            duration: 35.0,
            ramp: 5.0,
            rate: 0.05,
        };
        let (_, total) = turn.profile(100.0);
        assert_abs_diff_eq!(total, 30.0, epsilon = 1e-12);
        // Continuity at the breakpoints and derivative consistency (S' = s).
        for t in [10.0, 15.0, 40.0, 45.0, 12.3, 42.1, 30.0] {
            let (s, _) = turn.profile(t);
            let (sm, im) = turn.profile(t - 1e-6);
            let (sp, ip) = turn.profile(t + 1e-6);
            assert_abs_diff_eq!(sm, sp, epsilon = 1e-5);
            assert_abs_diff_eq!((ip - im) / 2e-6, s, epsilon = 1e-5);
        }
    }

    #[test]
    fn default_route_matches_scenario() {
        let r = TurningRoute::vkf_default();
        r.check().unwrap();
        assert!(r.turns.len() >= 4);
        assert_abs_diff_eq!(r.speed(1620.0), 5.144, epsilon = 1e-3);
        let (psi_end, _) = r.heading_and_rate(1620.0);
        assert_abs_diff_eq!(
            psi_end.to_degrees(),
            30.0 + 90.0 - 90.0 + 90.0 + 180.0 - 90.0,
            epsilon = 1e-9
        );
        for t in &r.turns {
            assert!(t.rate.abs().to_degrees() >= 2.0 && t.rate.abs().to_degrees() <= 5.0);
        }
        let mut bad = r.clone();
        bad.turns[0].ramp = 0.0;
        assert!(bad.check().is_err());
        assert!(r.sample(0.0, 10, 1).is_err());
    }

    #[test]
    fn sampled_positions_follow_velocity() {
        let r = TurningRoute::vkf_default();
        let s = r.sample(1.0, 101, 10).unwrap();
        // Straight segment at cruise from 0..100 s (ramp included): north distance.
        let dn = (s[100].lat - s[0].lat) * (earth::meridian_radius(s[0].lat) + s[0].h);
        let expected: f64 = (0..100_000)
            .map(|i| r.vel_in_nav((i as f64 + 0.5) * 1e-3).x * 1e-3)
            .sum();
        assert_abs_diff_eq!(dn, expected, epsilon = 1e-3);
    }
}
