//! WGS-84 geodesy for the GNSS models: geodetic <-> ECEF, and the local NED frame of
//! the scenario origin (a tangent plane at a reference latitude, longitude, height).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::check_finite;

/// WGS-84 semi-major axis, m.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 Earth rotation rate, rad/s.
pub const WGS84_OMEGA_E: f64 = 7.292_115_146_7e-5;
/// WGS-84 gravitational parameter (GPS value), m^3/s^2.
pub const WGS84_GM: f64 = 3.986_005e14;

/// ECEF position of a geodetic point (latitude, longitude in rad, height in m).
pub fn ecef_from_geodetic(lat: f64, lon: f64, h: f64) -> Vector3<f64> {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let (sl, cl) = lat.sin_cos();
    let n = WGS84_A / (1.0 - e2 * sl * sl).sqrt();
    Vector3::new(
        (n + h) * cl * lon.cos(),
        (n + h) * cl * lon.sin(),
        (n * (1.0 - e2) + h) * sl,
    )
}

/// Rotation taking ECEF vectors to the local NED frame at `(lat, lon)` (rad):
/// rows north, east, down.
pub fn ned_from_ecef(lat: f64, lon: f64) -> Matrix3<f64> {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    Matrix3::new(
        -sl * co,
        -sl * so,
        cl, //
        -so,
        co,
        0.0, //
        -cl * co,
        -cl * so,
        -sl,
    )
}

/// The scenario origin: a reference point whose local NED frame is the navigation
/// frame of the map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalFrameParams {
    /// Latitude, deg. Default 37.5 (Seoul, where the paper flew).
    pub lat_deg: f64,
    /// Longitude, deg. Default 127.0.
    pub lon_deg: f64,
    /// Height above the ellipsoid, m. Default 50.
    pub height_m: f64,
}

impl Default for LocalFrameParams {
    fn default() -> Self {
        Self {
            lat_deg: 37.5,
            lon_deg: 127.0,
            height_m: 50.0,
        }
    }
}

impl LocalFrameParams {
    /// Checks the numbers (finite, latitude within +-90 deg).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<LocalFrame, SensorError> {
        check_finite("frame.lon_deg", self.lon_deg)?;
        check_finite("frame.height_m", self.height_m)?;
        let lat = check_finite("frame.lat_deg", self.lat_deg)?;
        if lat.abs() > 90.0 || self.height_m.abs() > 1e6 {
            return Err(SensorError::InvalidParameter {
                field: "frame.lat_deg / height_m".into(),
                value: lat,
                reason: "latitude must be within +-90 deg and |height| <= 1e6 m",
            });
        }
        let (lat, lon) = (lat.to_radians(), self.lon_deg.to_radians());
        Ok(LocalFrame {
            origin_ecef: ecef_from_geodetic(lat, lon, self.height_m),
            ned_from_ecef: ned_from_ecef(lat, lon),
        })
    }
}

/// The local NED frame of the scenario origin (flat: a tangent plane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    origin_ecef: Vector3<f64>,
    ned_from_ecef: Matrix3<f64>,
}

impl LocalFrame {
    /// ECEF of the origin, m.
    pub fn origin_ecef(&self) -> Vector3<f64> {
        self.origin_ecef
    }

    /// Rotation ECEF -> NED.
    pub fn ned_from_ecef(&self) -> Matrix3<f64> {
        self.ned_from_ecef
    }

    /// A local NED point in ECEF.
    pub fn ecef_from_ned(&self, pos_in_nav: &Vector3<f64>) -> Vector3<f64> {
        self.origin_ecef + self.ned_from_ecef.transpose() * pos_in_nav
    }

    /// An ECEF point in local NED.
    pub fn ned_from_ecef_point(&self, ecef: &Vector3<f64>) -> Vector3<f64> {
        self.ned_from_ecef * (ecef - self.origin_ecef)
    }

    /// A local NED vector (velocity, direction) in ECEF.
    pub fn ecef_vector(&self, v_in_nav: &Vector3<f64>) -> Vector3<f64> {
        self.ned_from_ecef.transpose() * v_in_nav
    }
}

/// Geodetic latitude, longitude (rad) and height (m) of an ECEF point (WGS-84), by
/// Bowring's iteration on the reduced latitude (three rounds: below 1e-9 m anywhere
/// between the Earth's surface and 1e6 m; tested against [`ecef_from_geodetic`]).
/// The poles' longitude is 0.
pub fn geodetic_from_ecef(ecef: &Vector3<f64>) -> (f64, f64, f64) {
    let a = WGS84_A;
    let b = a * (1.0 - WGS84_F);
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let ep2 = e2 / (1.0 - e2);
    let p = ecef.x.hypot(ecef.y);
    let lon = if p > 0.0 { ecef.y.atan2(ecef.x) } else { 0.0 };
    let mut beta = (ecef.z * a).atan2(p * b);
    let mut lat = 0.0;
    for _ in 0..3 {
        let (sb, cb) = beta.sin_cos();
        lat = (ecef.z + ep2 * b * sb.powi(3)).atan2(p - e2 * a * cb.powi(3));
        beta = ((1.0 - WGS84_F) * lat.sin()).atan2(lat.cos());
    }
    let (sl, cl) = lat.sin_cos();
    let n = a / (1.0 - e2 * sl * sl).sqrt();
    let h = if cl.abs() > 1e-10 {
        p / cl - n
    } else {
        ecef.z.abs() - b
    };
    (lat, lon, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn ecef_of_known_points_and_frame_round_trip() {
        assert_relative_eq!(
            ecef_from_geodetic(0.0, 0.0, 0.0),
            Vector3::new(WGS84_A, 0.0, 0.0)
        );
        let pole = ecef_from_geodetic(std::f64::consts::FRAC_PI_2, 0.0, 0.0);
        assert_relative_eq!(pole.z, WGS84_A * (1.0 - WGS84_F), epsilon = 1e-6);
        let f = LocalFrameParams::default().check().unwrap();
        let p = Vector3::new(120.0, -35.0, -20.0);
        assert_relative_eq!(
            f.ned_from_ecef_point(&f.ecef_from_ned(&p)),
            p,
            epsilon = 1e-8
        );
        // "down" points to the Earth's centre (within the geodetic-geocentric angle)
        let down = f.ecef_vector(&Vector3::z());
        assert!(down.dot(&(-f.origin_ecef().normalize())) > 0.99999);
        // a point 100 m up has a larger geodetic height by 100 m
        let up = f.ecef_from_ned(&Vector3::new(0.0, 0.0, -100.0));
        assert_relative_eq!(up.norm() - f.origin_ecef().norm(), 100.0, epsilon = 1e-3);
        assert!(
            LocalFrameParams {
                lat_deg: 91.0,
                ..LocalFrameParams::default()
            }
            .check()
            .is_err()
        );
        assert!(
            LocalFrameParams {
                lon_deg: f64::NAN,
                ..LocalFrameParams::default()
            }
            .check()
            .is_err()
        );
    }

    #[test]
    fn geodetic_from_ecef_inverts_ecef_from_geodetic() {
        for &(lat, lon, h) in &[
            (37.5f64, 127.0f64, 50.0),
            (-33.9, 18.4, -20.0),
            (0.0, 0.0, 0.0),
            (89.9, -170.0, 1e6),
            (-60.0, 200.0 - 360.0, 3000.0),
        ] {
            let (la, lo) = (lat.to_radians(), lon.to_radians());
            let e = ecef_from_geodetic(la, lo, h);
            let (la2, lo2, h2) = geodetic_from_ecef(&e);
            assert!(
                (ecef_from_geodetic(la2, lo2, h2) - e).norm() < 1e-8,
                "{lat} {lon} {h}"
            );
            assert!((la2 - la).abs() < 1e-12 && (h2 - h).abs() < 1e-6);
        }
        // Negative control: a perturbed latitude is detected.
        let e = ecef_from_geodetic(0.5, 0.5, 10.0);
        let (la, lo, h) = geodetic_from_ecef(&e);
        assert!((ecef_from_geodetic(la + 1e-9, lo, h) - e).norm() > 1e-3);
    }
}
