//! Accurate conversions between rotation vectors and unit quaternions for the tiny
//! rotations of a 100 Hz strapdown (1e-7 rad and below), where `acos`-based angle
//! extraction would lose half the significant digits.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Unit quaternion of the rotation vector `phi` (axis times angle, rad):
///
/// ```text
/// q = [cos(|phi|/2), sin(|phi|/2) phi / |phi|]          (Savage 2000, eq. 7.1.1-4)
/// ```
///
/// For `|phi| < 1e-2` (a 100 Hz step below 1 rad/s) the Taylor series of
/// `cos(x/2)` and `sin(x/2)/x` to `x^8` are used (truncation error below 1e-29, far
/// under double rounding; no `sin`/`cos` call on the strapdown's hot path).
pub fn quat_from_rotation_vector(phi: &Vector3<f64>) -> UnitQuaternion<f64> {
    let a2 = phi.norm_squared();
    let (w, s) = if a2 < 1e-4 {
        // cos(x/2) = sum (-1)^k x^2k / (2^2k (2k)!), sin(x/2)/x = sum (-1)^k x^2k / (2^(2k+1) (2k+1)!)
        (
            1.0 + a2
                * (-1.0 / 8.0 + a2 * (1.0 / 384.0 + a2 * (-1.0 / 46_080.0 + a2 / 10_321_920.0))),
            0.5 + a2
                * (-1.0 / 48.0
                    + a2 * (1.0 / 3840.0 + a2 * (-1.0 / 645_120.0 + a2 / 185_794_560.0))),
        )
    } else {
        let a = a2.sqrt();
        let (sh, ch) = (0.5 * a).sin_cos();
        (ch, sh / a)
    };
    UnitQuaternion::new_unchecked(Quaternion::new(w, s * phi.x, s * phi.y, s * phi.z))
}

/// Rotation vector of a unit quaternion (inverse of [`quat_from_rotation_vector`]),
/// angle in `[0, pi]`:
///
/// ```text
/// phi = 2 atan2(|q_v|, q_w) q_v / |q_v|     (with q_w >= 0 chosen by sign flip)
/// ```
///
/// Uses `atan2`, accurate to full relative precision for tiny angles.
pub fn rotation_vector_from_quat(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = q.as_ref();
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let n = v.norm();
    if n < 1e-12 {
        // atan2(n, w) / n = (1/w) (1 - n^2/(3 w^2) + ...), n <= 1e-12.
        v * (2.0 / w)
    } else {
        v * (2.0 * n.atan2(w) / n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn roundtrip_small_and_large() {
        for scale in [0.0, 1e-13, 1e-9, 7e-7, 1e-4, 1e-2, 0.5, 3.0] {
            let phi = Vector3::new(0.3, -0.5, 0.8).normalize() * scale;
            let q = quat_from_rotation_vector(&phi);
            assert_relative_eq!(q.as_ref().norm(), 1.0, epsilon = 1e-15);
            let back = rotation_vector_from_quat(&q);
            assert_relative_eq!(back, phi, max_relative = 1e-14, epsilon = 1e-300);
            let nq = UnitQuaternion::from_scaled_axis(phi);
            assert_relative_eq!(q, nq, epsilon = 1e-15);
        }
    }

    #[test]
    fn tiny_angle_keeps_relative_precision() {
        // nalgebra's acos-based angle would be wrong by ~1e-8 rad here.
        let phi = Vector3::new(3.6e-7, 0.0, -1.1e-7);
        let back = rotation_vector_from_quat(&quat_from_rotation_vector(&phi));
        assert_relative_eq!(back, phi, max_relative = 1e-14);
    }
}
