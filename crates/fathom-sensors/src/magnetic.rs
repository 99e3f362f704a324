//! The Earth's magnetic field as a tilted dipole (the degree-1 terms of the
//! International Geomagnetic Reference Field), for a magnetometer's noise-free
//! reading: the field in the local north-east-down frame at a geodetic position, and
//! its projection into the body frame. A dipole is a rough model (at 37.5 N 127 E it
//! gives 38,700 nT dipping 47 deg where the full model gives about 50,000 nT and
//! 53 deg): it gives a magnetometer stream a ground station or an autopilot can read,
//! not a heading reference for navigation.
//!
//! With the Gauss coefficients `g10, g11, h11` (nT), the reference radius `a`, the
//! geocentric colatitude `θ` and longitude `φ` at radius `r`, the field of the
//! potential `V = a (a/r)^2 (g10 cos θ + (g11 cos φ + h11 sin φ) sin θ)` is
//!
//! ```text
//! B_r = 2 (a/r)^3 (g10 cos θ + (g11 cos φ + h11 sin φ) sin θ)
//! B_θ =   (a/r)^3 (g10 sin θ - (g11 cos φ + h11 sin φ) cos θ)
//! B_φ =   (a/r)^3 (g11 sin φ - h11 cos φ)
//! ```
//!
//! north = `-B_θ`, east = `B_φ`, down = `-B_r`. The geocentric and geodetic
//! latitudes are treated as equal (their difference, at most 0.19 deg, tilts the
//! local frame by as much).

use nalgebra::{UnitQuaternion, Vector3};

/// Reference radius of the IGRF, m.
const IGRF_RADIUS_M: f64 = 6_371_200.0;

/// The degree-1 Gauss coefficients of a dipole field, nT.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dipole {
    /// `g10`, nT.
    pub g10: f64,
    /// `g11`, nT.
    pub g11: f64,
    /// `h11`, nT.
    pub h11: f64,
}

impl Dipole {
    /// IGRF-13 at epoch 2020.0: `g10 = -29404.8`, `g11 = -1450.9`, `h11 = 4652.5` nT.
    pub const IGRF13_2020: Self = Self {
        g10: -29_404.8,
        g11: -1_450.9,
        h11: 4_652.5,
    };

    /// The field in the local north-east-down frame at latitude `lat_rad`, longitude
    /// `lon_rad` and height `height_m` above the reference sphere, nT (module docs).
    pub fn field_ned_nt(&self, lat_rad: f64, lon_rad: f64, height_m: f64) -> Vector3<f64> {
        let r = IGRF_RADIUS_M + height_m;
        let k = (IGRF_RADIUS_M / r).powi(3);
        let (sin_t, cos_t) = (std::f64::consts::FRAC_PI_2 - lat_rad).sin_cos();
        let (sin_p, cos_p) = lon_rad.sin_cos();
        let eq = self.g11 * cos_p + self.h11 * sin_p;
        let b_r = 2.0 * k * (self.g10 * cos_t + eq * sin_t);
        let b_theta = k * (self.g10 * sin_t - eq * cos_t);
        let b_phi = k * (self.g11 * sin_p - self.h11 * cos_p);
        Vector3::new(-b_theta, b_phi, -b_r)
    }
}

/// A field given in the navigation (NED) frame, seen in the body frame of the
/// attitude `nav_from_body`.
pub fn field_in_body(
    nav_from_body: &UnitQuaternion<f64>,
    field_in_nav: &Vector3<f64>,
) -> Vector3<f64> {
    nav_from_body.inverse_transform_vector(field_in_nav)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axial_dipole_points_north_at_the_equator_and_down_at_the_pole() {
        let d = Dipole {
            g10: -30_000.0,
            g11: 0.0,
            h11: 0.0,
        };
        let eq = d.field_ned_nt(0.0, 0.3, 0.0);
        assert!(
            (eq - Vector3::new(30_000.0, 0.0, 0.0)).norm() < 1e-9,
            "{eq}"
        );
        let pole = d.field_ned_nt(std::f64::consts::FRAC_PI_2, 0.0, 0.0);
        assert!(
            (pole - Vector3::new(0.0, 0.0, 60_000.0)).norm() < 1e-6,
            "{pole}"
        );
        // The field falls off with the cube of the radius.
        let high = d.field_ned_nt(0.0, 0.3, IGRF_RADIUS_M);
        assert!((high.x - 30_000.0 / 8.0).abs() < 1e-9, "{high}");
    }

    #[test]
    fn field_at_seoul_matches_the_formulas_by_hand() {
        // 37.5 N 127 E: by hand from the module's formulas, north 26,121.9, east
        // 1,641.2, down 28,519.9 nT (38,709.6 nT, dip 47.46 deg).
        let b = Dipole::IGRF13_2020.field_ned_nt(37.5f64.to_radians(), 127f64.to_radians(), 0.0);
        assert!(
            (b - Vector3::new(26_121.896, 1_641.204, 28_519.897)).norm() < 1e-2,
            "{b}"
        );
        let dip = b.z.atan2(b.xy().norm()).to_degrees();
        assert!((dip - 47.457).abs() < 1e-3, "{dip}");
        assert!(b.x > 0.0 && b.z > 0.0, "{b}");
    }

    #[test]
    fn body_field_is_the_nav_field_rotated_back() {
        let b_nav = Vector3::new(30_000.0, -2_000.0, 40_000.0);
        let yaw_90 = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let b_body = field_in_body(&yaw_90, &b_nav);
        // Heading east: north is on the vehicle's left (-y), east ahead (+x).
        assert!(
            (b_body - Vector3::new(-2_000.0, -30_000.0, 40_000.0)).norm() < 1e-9,
            "{b_body}"
        );
        assert!((yaw_90 * b_body - b_nav).norm() < 1e-9);
    }
}
