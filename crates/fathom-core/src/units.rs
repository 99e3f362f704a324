//! Named unit conversions used at the configuration boundary (knots, degrees, ...).

/// One international knot in m/s (1852 m per hour).
pub const KNOT_IN_MPS: f64 = 1852.0 / 3600.0;

/// Standard gravity, m/s^2 (used to convert `mg` and `g` figures of data sheets).
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Knots to m/s.
pub fn knots_to_mps(knots: f64) -> f64 {
    knots * KNOT_IN_MPS
}

/// m/s to knots.
pub fn mps_to_knots(mps: f64) -> f64 {
    mps / KNOT_IN_MPS
}

/// Degrees to radians.
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

/// Radians to degrees.
pub fn rad_to_deg(rad: f64) -> f64 {
    rad.to_degrees()
}

/// Degrees per hour to rad/s (gyro bias figures).
pub fn deg_per_hour_to_rad_per_s(v: f64) -> f64 {
    v.to_radians() / 3600.0
}

/// Degrees per square-root hour to rad/sqrt(s) (angle random walk figures).
pub fn deg_per_sqrt_hour_to_rad_per_sqrt_s(v: f64) -> f64 {
    v.to_radians() / 60.0
}

/// Units per square-root hour to units per square-root second (`/ 60`): velocity
/// random walk quoted in m/s/sqrt(h) becomes m/s/sqrt(s).
pub fn per_sqrt_hour_to_per_sqrt_s(v: f64) -> f64 {
    v / 60.0
}

/// Milli-g to m/s^2 (accelerometer bias figures).
pub fn milli_g_to_mps2(v: f64) -> f64 {
    v * 1e-3 * STANDARD_GRAVITY
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_pi(angle: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut a = angle.rem_euclid(two_pi);
    if a > std::f64::consts::PI {
        a -= two_pi;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn conversions() {
        assert_relative_eq!(knots_to_mps(1.0), 0.514_444_444, epsilon = 1e-9);
        assert_relative_eq!(mps_to_knots(knots_to_mps(6.0)), 6.0, epsilon = 1e-12);
        assert_relative_eq!(
            deg_per_hour_to_rad_per_s(15.041_067),
            7.292_115e-5,
            epsilon = 1e-10
        );
        assert_relative_eq!(milli_g_to_mps2(1.0), 0.009_806_65, epsilon = 1e-12);
        // 0.14 m/s/sqrt(h) = 0.14 m/s / 60 sqrt(s)
        assert_relative_eq!(
            per_sqrt_hour_to_per_sqrt_s(0.14),
            0.14 / 60.0,
            epsilon = 1e-15
        );
    }

    #[test]
    fn wrap() {
        use std::f64::consts::PI;
        assert_relative_eq!(wrap_pi(3.0 * PI / 2.0), -PI / 2.0, epsilon = 1e-12);
        assert_relative_eq!(wrap_pi(-PI), PI, epsilon = 1e-12);
        assert_relative_eq!(wrap_pi(0.1), 0.1, epsilon = 1e-15);
    }
}
