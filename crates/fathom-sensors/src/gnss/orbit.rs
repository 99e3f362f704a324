//! Satellite orbits: Keplerian elements propagated as two-body orbits in ECEF, and
//! the nominal 24-slot GPS constellation.
//!
//! Model: `M(t) = M0 + n t`, `n = sqrt(GM / a^3)`; Kepler's equation by Newton's
//! method; the orbit plane's ascending node is given as a longitude in ECEF at
//! `t = 0` and moves west with the Earth's rotation, `Omega(t) = Omega0 - omega_e t`
//! (no J2 precession, no perturbations: geometry for line-of-sight and DOP studies,
//! not precise orbits). Velocity in ECEF is `R v_orbit - omega_e z x r`.

use nalgebra::{Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::check_finite;
use crate::gnss::geodesy::{WGS84_GM, WGS84_OMEGA_E};

/// Keplerian elements at `t = 0` (angles in degrees).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeplerElements {
    /// A name for the output (e.g. the GPS slot `A1`).
    pub name: String,
    /// Semi-major axis, m.
    pub semi_major_axis_m: f64,
    /// Eccentricity, `[0, 0.9]`.
    pub eccentricity: f64,
    /// Inclination, deg.
    pub inclination_deg: f64,
    /// Longitude of the ascending node in ECEF at `t = 0`, deg.
    pub node_longitude_deg: f64,
    /// Argument of perigee, deg.
    pub arg_perigee_deg: f64,
    /// Mean anomaly at `t = 0`, deg.
    pub mean_anomaly_deg: f64,
}

/// Position and velocity of a satellite, ECEF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatState {
    /// Position, m.
    pub pos_ecef: Vector3<f64>,
    /// Velocity, m/s.
    pub vel_ecef: Vector3<f64>,
}

/// Checked orbit of one satellite.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    name: String,
    a: f64,
    e: f64,
    i: f64,
    node0: f64,
    w: f64,
    m0: f64,
    n: f64,
}

impl KeplerElements {
    /// Checks the elements (finite; `a` between 6.5e6 and 1e8 m; `e` in `[0, 0.9]`).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the satellite and field.
    pub fn check(&self) -> Result<Orbit, SensorError> {
        let f = |field: &str, v: f64| check_finite(&format!("{}.{field}", self.name), v);
        let a = f("semi_major_axis_m", self.semi_major_axis_m)?;
        let e = f("eccentricity", self.eccentricity)?;
        for (field, v) in [
            ("inclination_deg", self.inclination_deg),
            ("node_longitude_deg", self.node_longitude_deg),
            ("arg_perigee_deg", self.arg_perigee_deg),
            ("mean_anomaly_deg", self.mean_anomaly_deg),
        ] {
            f(field, v)?;
        }
        if !(6.5e6..=1e8).contains(&a) {
            return Err(SensorError::InvalidParameter {
                field: format!("{}.semi_major_axis_m", self.name),
                value: a,
                reason: "must be between 6.5e6 and 1e8 m",
            });
        }
        if !(0.0..=0.9).contains(&e) {
            return Err(SensorError::InvalidParameter {
                field: format!("{}.eccentricity", self.name),
                value: e,
                reason: "must be in [0, 0.9]",
            });
        }
        Ok(Orbit {
            name: self.name.clone(),
            a,
            e,
            i: self.inclination_deg.to_radians(),
            node0: self.node_longitude_deg.to_radians(),
            w: self.arg_perigee_deg.to_radians(),
            m0: self.mean_anomaly_deg.to_radians(),
            n: (WGS84_GM / (a * a * a)).sqrt(),
        })
    }
}

impl Orbit {
    /// The satellite's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Position and velocity in ECEF at time `t` (s from `t = 0`); `t` must be finite
    /// (a non-finite `t` gives non-finite values).
    pub fn state_at(&self, t: f64) -> SatState {
        let m = self.m0 + self.n * t;
        // Kepler: E - e sin E = M (Newton, converges in a few steps for e <= 0.9)
        let mut big_e = if self.e > 0.8 {
            std::f64::consts::PI
        } else {
            m
        };
        for _ in 0..30 {
            let f = big_e - self.e * big_e.sin() - m;
            let step = f / (1.0 - self.e * big_e.cos());
            big_e -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        let (se, ce) = big_e.sin_cos();
        let b = self.a * (1.0 - self.e * self.e).sqrt();
        let e_dot = self.n / (1.0 - self.e * ce);
        let p_orb = Vector3::new(self.a * (ce - self.e), b * se, 0.0);
        let v_orb = Vector3::new(-self.a * se * e_dot, b * ce * e_dot, 0.0);
        let node = self.node0 - WGS84_OMEGA_E * t;
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), node)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), self.i)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), self.w);
        let pos_ecef = rot * p_orb;
        let omega = Vector3::new(0.0, 0.0, WGS84_OMEGA_E);
        SatState {
            pos_ecef,
            vel_ecef: rot * v_orb - omega.cross(&pos_ecef),
        }
    }
}

/// Semi-major axis of the nominal GPS orbit, m.
pub const GPS_SEMI_MAJOR_AXIS_M: f64 = 26_559_700.0;

/// The baseline 24-slot constellation of the GPS SPS Performance Standard (2008,
/// Table 3.2-1: six planes A-F, four slots each; inclination 55 deg, circular,
/// a = 26,559.7 km): `(slot, RAAN deg, argument of latitude deg)` at the table's
/// epoch. Here the RAAN is used as the node's longitude at `t = 0` and the
/// argument of latitude as the mean anomaly (circular orbits, perigee 0): the
/// relative geometry of the constellation, not its absolute timing.
pub const GPS_24_SLOTS: [(&str, f64, f64); 24] = [
    ("A1", 272.847, 268.126),
    ("A2", 272.847, 161.786),
    ("A3", 272.847, 11.676),
    ("A4", 272.847, 41.806),
    ("B1", 332.847, 80.956),
    ("B2", 332.847, 173.336),
    ("B3", 332.847, 309.976),
    ("B4", 332.847, 204.376),
    ("C1", 32.847, 111.876),
    ("C2", 32.847, 11.796),
    ("C3", 32.847, 339.666),
    ("C4", 32.847, 241.556),
    ("D1", 92.847, 135.226),
    ("D2", 92.847, 265.446),
    ("D3", 92.847, 35.156),
    ("D4", 92.847, 167.356),
    ("E1", 152.847, 197.046),
    ("E2", 152.847, 302.596),
    ("E3", 152.847, 66.066),
    ("E4", 152.847, 333.686),
    ("F1", 212.847, 238.886),
    ("F2", 212.847, 345.226),
    ("F3", 212.847, 105.206),
    ("F4", 212.847, 135.346),
];

/// The nominal 24-slot GPS constellation as Keplerian elements ([`GPS_24_SLOTS`]).
pub fn nominal_gps24() -> Vec<KeplerElements> {
    GPS_24_SLOTS
        .iter()
        .map(|&(name, raan, u)| KeplerElements {
            name: name.to_owned(),
            semi_major_axis_m: GPS_SEMI_MAJOR_AXIS_M,
            eccentricity: 0.0,
            inclination_deg: 55.0,
            node_longitude_deg: raan,
            arg_perigee_deg: 0.0,
            mean_anomaly_deg: u,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gnss::geodesy::LocalFrameParams;
    use approx::assert_relative_eq;

    #[test]
    fn velocity_is_the_derivative_of_position() {
        for el in [
            nominal_gps24()[5].clone(),
            KeplerElements {
                name: "ecc".into(),
                eccentricity: 0.3,
                arg_perigee_deg: 40.0,
                ..nominal_gps24()[0].clone()
            },
        ] {
            let orbit = el.check().unwrap();
            for t in [0.0, 1234.5, 40_000.0] {
                let h = 0.01;
                let fd =
                    (orbit.state_at(t + h).pos_ecef - orbit.state_at(t - h).pos_ecef) / (2.0 * h);
                assert_relative_eq!(orbit.state_at(t).vel_ecef, fd, epsilon = 1e-4);
            }
            let s = orbit.state_at(100.0);
            let r = s.pos_ecef.norm();
            assert!(r >= el.semi_major_axis_m * (1.0 - el.eccentricity) - 1.0);
            assert!(r <= el.semi_major_axis_m * (1.0 + el.eccentricity) + 1.0);
        }
    }

    #[test]
    fn the_nominal_constellation_covers_the_sky() {
        let orbits: Vec<Orbit> = nominal_gps24().iter().map(|e| e.check().unwrap()).collect();
        // a GPS orbit's period is half a sidereal day
        let period = std::f64::consts::TAU / orbits[0].n;
        assert_relative_eq!(period, 43_082.0, epsilon = 5.0);
        // anywhere on a coarse grid, at any hour: at least 4 satellites above 5 deg
        for lat in [-60.0, -30.0, 0.0, 37.5, 60.0] {
            for lon in [0.0, 90.0, 127.0, 200.0] {
                let f = LocalFrameParams {
                    lat_deg: lat,
                    lon_deg: lon,
                    height_m: 0.0,
                }
                .check()
                .unwrap();
                for hour in 0..24 {
                    let t = 3600.0 * f64::from(hour);
                    let visible = orbits
                        .iter()
                        .filter(|o| {
                            let los =
                                f.ned_from_ecef() * (o.state_at(t).pos_ecef - f.origin_ecef());
                            -los.z / los.norm() > 5f64.to_radians().sin()
                        })
                        .count();
                    assert!(visible >= 4, "{lat} {lon} {hour}: {visible}");
                }
            }
        }
        let bad = KeplerElements {
            eccentricity: 1.0,
            ..nominal_gps24()[0].clone()
        };
        assert!(bad.check().is_err());
        let bad = KeplerElements {
            semi_major_axis_m: 1.0,
            ..nominal_gps24()[0].clone()
        };
        assert!(bad.check().is_err());
    }
}
