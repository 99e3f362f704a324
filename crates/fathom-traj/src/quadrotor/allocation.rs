//! Moments from rotor thrusts, eq. (21), and the thrust allocation that inverts it,
//! eq. (22), with saturation at the rotor limits.
//!
//! Rotor order everywhere: `[FL, FR, BL, BR]` (front-left, front-right, back-left,
//! back-right). Body axes x forward, y right, z down; thrust acts along body -z.
//!
//! ```text
//! Mx = l     (T_FL + T_BL - T_FR - T_BR)                                   (21)
//! My = l     (T_FL - T_BL + T_FR - T_BR)
//! Mz = kappa (T_FL - T_BL - T_FR + T_BR)
//! ```
//!
//! # Checks of the paper's equations (the report prints [`eq22_discrepancies`])
//!
//! - **Eq. (21) against the frame conventions.** A rotor at `r = (x, y, 0)` pushing
//!   `(0, 0, -T)` gives `r x F = (-y T, x T, 0)`: with the left rotors at `y = -l` and
//!   the front ones at `x = +l`, `Mx` and `My` of eq. (21) follow (roll right when the
//!   left rotors push harder, nose up when the front ones do). The yaw row makes FL
//!   and BR (one diagonal) turn the body nose-right by their drag torque, i.e. they
//!   spin counter-clockwise seen from above; FR and BL the other way. Consistent.
//! - **Eq. (22) against eq. (21).** Written out, eq. (22) is
//!   `T_i = F/4 + s_x,i Mx/(4l) + s_y,i My/(4l) + s_z,i Mz/(4 kappa)` with the signs
//!   `FL (+,+,+)`, `FR (-,+,-)`, `BL (+,-,-)`, `BR (-,-,+)` (`F = |F_con|`, the
//!   collective thrust). The 4 x 4 matrix of eq. (21) with the collective
//!   `F = sum T_i` as first row has orthogonal rows of squared norms `4, 4 l^2, 4 l^2,
//!   4 kappa^2`, so its inverse is its transpose with the rows scaled by those norms:
//!   exactly eq. (22). No sign discrepancy: [`eq22_discrepancies`] compares the
//!   coefficients of the printed eq. (22) ([`paper_eq22`]) with the inverse computed
//!   by a general 4 x 4 inversion and finds none; the implementation
//!   ([`thrusts_from_wrench`]) is that exact inverse.
//! - The paper calls `l` the arm length; for eq. (21) to hold it must be the lever arm
//!   about each body axis (`a / sqrt(2)` for an X frame with arm length `a`).

use nalgebra::{Matrix4, Vector3, Vector4};

use super::params::Vehicle;

/// What checking eq. (21)-(22) of seed 004 found (module docs), for the report; the
/// coefficient comparison itself is computed by [`eq22_discrepancies`].
pub const EQ21_EQ22_FINDINGS: &[&str] = &[
    "eq. (22) is the exact inverse of eq. (21) (with the collective thrust |F_con| = sum T_i as fourth equation): no sign discrepancy",
    "eq. (21) matches body axes x forward, y right, z down with thrust along -z; its yaw row implies FL and BR spin counter-clockwise seen from above, FR and BL clockwise",
    "the paper calls l the arm length; eq. (21) needs the lever arm about each body axis (arm length / sqrt(2) for an X frame)",
    "eq. (22) allocates |F_con|, the norm of the commanded thrust vector, as collective thrust",
];

/// Rotor names in the order used by every thrust array.
pub const ROTORS: [&str; 4] = ["FL", "FR", "BL", "BR"];

/// Names of the wrench components, in the order of [`allocation_matrix`]'s rows.
pub const WRENCH: [&str; 4] = ["F", "Mx", "My", "Mz"];

/// Control moments from rotor thrusts, eq. (21), N m.
pub fn moments_from_thrusts(thrusts: &[f64; 4], l: f64, kappa: f64) -> Vector3<f64> {
    let [fl, fr, bl, br] = *thrusts;
    Vector3::new(
        l * (fl + bl - fr - br),
        l * (fl - bl + fr - br),
        kappa * (fl - bl - fr + br),
    )
}

/// Collective thrust `sum T_i`, N.
pub fn collective_thrust(thrusts: &[f64; 4]) -> f64 {
    thrusts.iter().sum()
}

/// The matrix `A` with `[F, Mx, My, Mz]^T = A [T_FL, T_FR, T_BL, T_BR]^T` (eq. 21 plus
/// the collective thrust as first row).
pub fn allocation_matrix(l: f64, kappa: f64) -> Matrix4<f64> {
    Matrix4::new(
        1.0, 1.0, 1.0, 1.0, //
        l, -l, l, -l, //
        l, l, -l, -l, //
        kappa, -kappa, -kappa, kappa,
    )
}

/// Rotor thrusts that produce the collective thrust `collective` and the moments
/// `moments`: the exact inverse of eq. (21) (equal to eq. 22, module docs), N.
pub fn thrusts_from_wrench(
    collective: f64,
    moments: &Vector3<f64>,
    l: f64,
    kappa: f64,
) -> [f64; 4] {
    let f = collective / 4.0;
    let (x, y, z) = (
        moments.x / (4.0 * l),
        moments.y / (4.0 * l),
        moments.z / (4.0 * kappa),
    );
    [f + x + y + z, f - x + y - z, f + x - y - z, f - x - y + z]
}

/// Eq. (22) exactly as printed in the paper (rotor order `[FL, FR, BL, BR]`), N.
pub fn paper_eq22(collective: f64, moments: &Vector3<f64>, l: f64, kappa: f64) -> [f64; 4] {
    let (mx, my, mz, f) = (moments.x, moments.y, moments.z, collective);
    let t_fr = -mx / (4.0 * l) + my / (4.0 * l) - mz / (4.0 * kappa) + f / 4.0;
    let t_br = -mx / (4.0 * l) - my / (4.0 * l) + mz / (4.0 * kappa) + f / 4.0;
    let t_fl = mx / (4.0 * l) + my / (4.0 * l) + mz / (4.0 * kappa) + f / 4.0;
    let t_bl = mx / (4.0 * l) - my / (4.0 * l) - mz / (4.0 * kappa) + f / 4.0;
    [t_fl, t_fr, t_bl, t_br]
}

/// One coefficient where the printed eq. (22) differs from the inverse of eq. (21).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoefficientMismatch {
    /// Rotor (row of the allocation).
    pub rotor: &'static str,
    /// Wrench component (column).
    pub input: &'static str,
    /// Coefficient of eq. (22) as printed.
    pub paper: f64,
    /// Coefficient of the exact inverse.
    pub exact: f64,
}

/// Compares the coefficients of the printed eq. (22) with the inverse of eq. (21)
/// computed by a general 4 x 4 inversion, for lever arm `l` and `kappa`; returns the
/// mismatches (relative tolerance 1e-12). Empty for every `l, kappa > 0`: eq. (22)
/// inverts eq. (21). `None` if the matrix is singular (`l` or `kappa` zero).
pub fn eq22_discrepancies(l: f64, kappa: f64) -> Option<Vec<CoefficientMismatch>> {
    let exact = allocation_matrix(l, kappa).try_inverse()?;
    let mut out = Vec::new();
    for (j, input) in WRENCH.iter().enumerate() {
        let mut unit = Vector4::zeros();
        unit[j] = 1.0;
        let paper = paper_eq22(unit[0], &Vector3::new(unit[1], unit[2], unit[3]), l, kappa);
        for (i, rotor) in ROTORS.iter().enumerate() {
            let e = exact[(i, j)];
            if (paper[i] - e).abs() > 1e-12 * e.abs().max(1e-300) {
                out.push(CoefficientMismatch {
                    rotor,
                    input,
                    paper: paper[i],
                    exact: e,
                });
            }
        }
    }
    Some(out)
}

/// Allocation with the rotor limits `[T_min, T_max]`: the exact inverse, and when a
/// rotor would leave its range, the yaw moment is scaled down first (yaw matters least
/// for flight; largest factor in [0, 1] that keeps every rotor in range); what still
/// does not fit is clipped per rotor (roll / pitch / collective then suffer).
pub fn allocate_saturated(collective: f64, moments: &Vector3<f64>, vehicle: &Vehicle) -> [f64; 4] {
    let (l, kappa) = (vehicle.arm_length(), vehicle.kappa());
    let (lo, hi) = (vehicle.thrust_min(), vehicle.thrust_max());
    let base = thrusts_from_wrench(
        collective,
        &Vector3::new(moments.x, moments.y, 0.0),
        l,
        kappa,
    );
    let yaw = thrusts_from_wrench(0.0, &Vector3::new(0.0, 0.0, moments.z), l, kappa);
    let mut s: f64 = 1.0;
    for i in 0..4 {
        let b = base[i];
        if b < lo || b > hi {
            continue; // roll / pitch already saturate this rotor: clipped below
        }
        if yaw[i] > 0.0 {
            s = s.min((hi - b) / yaw[i]);
        } else if yaw[i] < 0.0 {
            s = s.min((lo - b) / yaw[i]);
        }
    }
    let s = s.clamp(0.0, 1.0);
    std::array::from_fn(|i| (base[i] + s * yaw[i]).clamp(lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrotor::params::VehicleParams;

    /// Acceptance: allocation then moments returns the commanded moments and collective
    /// thrust (exact inverse), for random wrenches and geometries.
    #[test]
    fn allocation_then_moments_round_trips() {
        let mut worst: f64 = 0.0;
        for k in 0..200 {
            let t = k as f64;
            let (l, kappa) = (
                0.1 + 0.2 * (0.37 * t).sin().abs(),
                0.005 + 0.03 * (0.11 * t).cos().abs(),
            );
            let m = Vector3::new((1.3 * t).sin(), (0.7 * t).cos(), 0.2 * (2.1 * t).sin());
            let f = 10.0 + 5.0 * (0.3 * t).sin();
            let thr = thrusts_from_wrench(f, &m, l, kappa);
            let back = moments_from_thrusts(&thr, l, kappa);
            worst = worst
                .max((back - m).amax())
                .max((collective_thrust(&thr) - f).abs());
        }
        assert!(worst < 1e-13, "{worst:e}");
    }

    /// The printed eq. (22) is the exact inverse: no coefficient differs, and it equals
    /// [`thrusts_from_wrench`] for any input. Negative control: flipping one sign of
    /// eq. (21)'s yaw row makes mismatches appear.
    #[test]
    fn paper_eq22_inverts_eq21() {
        for (l, kappa) in [(0.16, 0.016), (0.3, 0.05), (1.0, 1.0)] {
            assert_eq!(eq22_discrepancies(l, kappa).unwrap(), vec![]);
            let m = Vector3::new(0.3, -0.2, 0.05);
            let a = paper_eq22(12.0, &m, l, kappa);
            let b = thrusts_from_wrench(12.0, &m, l, kappa);
            for i in 0..4 {
                assert!((a[i] - b[i]).abs() < 1e-14);
            }
        }
        let mut flipped = allocation_matrix(0.16, 0.016);
        flipped[(3, 0)] = -flipped[(3, 0)];
        let inv = flipped.try_inverse().unwrap();
        let paper = paper_eq22(0.0, &Vector3::new(0.0, 0.0, 1.0), 0.16, 0.016);
        assert!((0..4).any(|i| (paper[i] - inv[(i, 3)]).abs() > 1e-6));
        assert!(eq22_discrepancies(0.0, 0.016).is_none());
    }

    #[test]
    fn moments_follow_the_lever_arms() {
        // a rotor at (x, y) pushing up (-z) gives r x F = (-y T, x T, 0)
        let l = 0.2;
        let pos = [(l, -l), (l, l), (-l, -l), (-l, l)]; // FL, FR, BL, BR
        for i in 0..4 {
            let mut t = [0.0; 4];
            t[i] = 3.0;
            let m = moments_from_thrusts(&t, l, 0.01);
            let (x, y) = pos[i];
            let r = Vector3::new(x, y, 0.0);
            let rxf = r.cross(&Vector3::new(0.0, 0.0, -3.0));
            assert!((m.xy() - rxf.xy()).amax() < 1e-15, "{}", ROTORS[i]);
        }
    }

    #[test]
    fn saturation_gives_up_yaw_first() {
        let v = VehicleParams::default().check().unwrap();
        let hover = 4.0 * v.hover_thrust_per_rotor();
        // within limits: exact
        let m = Vector3::new(0.1, -0.05, 0.02);
        let t = allocate_saturated(hover, &m, &v);
        assert!((moments_from_thrusts(&t, v.arm_length(), v.kappa()) - m).amax() < 1e-12);
        // a yaw demand beyond the limits is scaled down, roll and pitch kept
        let big = Vector3::new(0.2, 0.1, 5.0);
        let t = allocate_saturated(hover, &big, &v);
        assert!(
            t.iter()
                .all(|&x| (v.thrust_min()..=v.thrust_max()).contains(&x))
        );
        let got = moments_from_thrusts(&t, v.arm_length(), v.kappa());
        assert!((got.xy() - big.xy()).amax() < 1e-12, "{got}");
        assert!(got.z > 0.0 && got.z < big.z);
        assert!((collective_thrust(&t) - hover).abs() < 1e-12);
        // an impossible collective is clipped
        let t = allocate_saturated(100.0, &Vector3::zeros(), &v);
        assert!(t.iter().all(|&x| x == v.thrust_max()));
    }
}
