//! Frame conventions (NED navigation frame, forward-starboard-down body frame) and
//! rotation helpers named after the frames they map between.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// Roll, pitch, yaw (phi, theta, psi) in radians, ZYX order: the body frame is
/// reached from NED by yawing about z, then pitching about the new y, then
/// rolling about the new x.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Euler {
    /// Roll phi, rad.
    pub roll: f64,
    /// Pitch theta, rad.
    pub pitch: f64,
    /// Yaw (heading) psi, rad, clockwise from north seen from above.
    pub yaw: f64,
}

impl Euler {
    /// Creates roll/pitch/yaw in radians.
    pub fn new(roll: f64, pitch: f64, yaw: f64) -> Self {
        Self { roll, pitch, yaw }
    }

    /// As the vector `[roll, pitch, yaw]`.
    pub fn to_vector(self) -> Vector3<f64> {
        Vector3::new(self.roll, self.pitch, self.yaw)
    }

    /// From the vector `[roll, pitch, yaw]`.
    pub fn from_vector(v: &Vector3<f64>) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

/// Rotation taking body-frame vectors to the NED frame, `C_b^n = R_z(psi) R_y(theta) R_x(phi)`.
pub fn nav_from_body(att: &Euler) -> Rotation3<f64> {
    Rotation3::from_euler_angles(att.roll, att.pitch, att.yaw)
}

/// Rotation taking NED vectors to the body frame, `C_n^b = (C_b^n)^T`.
pub fn body_from_nav(att: &Euler) -> Rotation3<f64> {
    nav_from_body(att).inverse()
}

/// Euler angles of a body-to-NED rotation (ZYX), inverse of [`nav_from_body`].
pub fn euler_from_nav_from_body(nav_from_body: &Rotation3<f64>) -> Euler {
    let (roll, pitch, yaw) = nav_from_body.euler_angles();
    Euler::new(roll, pitch, yaw)
}

/// Matrix mapping body angular rates `(p, q, r)` to Euler angle rates
/// `(phi_dot, theta_dot, psi_dot)` (singular at pitch = +/- 90 deg):
///
/// ```text
/// [1  sin(phi) tan(theta)  cos(phi) tan(theta)]
/// [0  cos(phi)            -sin(phi)           ]
/// [0  sin(phi)/cos(theta)  cos(phi)/cos(theta)]
/// ```
pub fn euler_rates_from_body_rates_matrix(att: &Euler) -> Matrix3<f64> {
    let (sp, cp) = att.roll.sin_cos();
    let (st, ct) = att.pitch.sin_cos();
    let tt = st / ct;
    Matrix3::new(1.0, sp * tt, cp * tt, 0.0, cp, -sp, 0.0, sp / ct, cp / ct)
}

/// Euler angle rates from body angular rates `omega_body = (p, q, r)`.
pub fn euler_rates_from_body_rates(att: &Euler, omega_body: &Vector3<f64>) -> Vector3<f64> {
    euler_rates_from_body_rates_matrix(att) * omega_body
}

/// Skew-symmetric cross-product matrix `[v]x`, so that `[v]x w = v x w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn yaw_east_maps_forward_to_east() {
        let r = nav_from_body(&Euler::new(0.0, 0.0, FRAC_PI_2));
        let v = r * Vector3::x();
        assert_relative_eq!(v, Vector3::y(), epsilon = 1e-12);
    }

    #[test]
    fn pitch_up_maps_forward_to_up() {
        // Positive pitch raises the nose: forward points to -z (up) in NED.
        let r = nav_from_body(&Euler::new(0.0, 0.3, 0.0));
        let v = r * Vector3::x();
        assert!(v.z < 0.0);
    }

    #[test]
    fn euler_roundtrip_and_inverse() {
        let e = Euler::new(0.1, -0.2, 2.5);
        let r = nav_from_body(&e);
        let back = euler_from_nav_from_body(&r);
        assert_relative_eq!(back.to_vector(), e.to_vector(), epsilon = 1e-12);
        assert_relative_eq!(
            (body_from_nav(&e) * r).matrix(),
            &Matrix3::identity(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn level_body_rates_equal_euler_rates() {
        let w = Vector3::new(0.1, 0.2, 0.3);
        assert_relative_eq!(
            euler_rates_from_body_rates(&Euler::default(), &w),
            w,
            epsilon = 1e-15
        );
    }

    #[test]
    fn skew_is_cross_product() {
        let a = Vector3::new(1.0, -2.0, 0.5);
        let b = Vector3::new(0.3, 0.7, -1.1);
        assert_relative_eq!(skew(&a) * b, a.cross(&b), epsilon = 1e-15);
    }
}
