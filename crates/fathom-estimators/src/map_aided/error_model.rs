//! The 12-state error dynamics of the reduced INS, eq. (2)-(5): `F` and `G` from the
//! nominal attitude and specific force, and their discretization over one IMU step.
//!
//! # Model (eq. 2-4, conventions of [`super`])
//!
//! ```text
//! d/dt dp  = dv
//! d/dt dv  = -[(C f^b) x] psi + C db_a + C w_acc
//! d/dt psi =                             C w_gyro
//! d/dt db_a =                                        w_ba
//! ```
//!
//! with `C = C_b^n` the nominal (estimated) attitude and `f^b` the corrected specific
//! force. The first two noise blocks are the paper's `G` (eq. 4); the third, the
//! accelerometer-bias random walk `w_ba`, is an addition (zero PSD gives the paper's
//! constant bias). There is no gyro bias state (calibrated at rest) and no Earth
//! rate, transport rate or gravity gradient (the reduced mechanization).
//!
//! # Discretization (stated method)
//!
//! `F` and `G` are held at their values at the start of the step (zero-order hold).
//! This `F` is nilpotent, `F^3 = 0` (position depends on velocity, velocity on
//! attitude and bias, which depend on nothing), so
//!
//! - `Phi = exp(F dt) = I + F dt + F^2 dt^2 / 2` exactly (the second-order series
//!   is not an approximation here), and
//! - `Q_d = int_0^dt Phi(s) G Q_c G^T Phi(s)^T ds` is a polynomial in `dt`, evaluated
//!   in closed form: the exact Van Loan integral for the held `F` ([`discretize`] for
//!   any nilpotent `F` of order 3, tested against the Van Loan matrix exponential;
//!   [`transition`], what the filter uses, writes the same numbers block by block).

use nalgebra::{Matrix3, SMatrix, UnitQuaternion, Vector3};

use fathom_core::frames::skew;

use super::params::ImuNoise;
use super::{ACCEL_BIAS, ATT, Matrix12, N_NOISE, POS, VEL};

/// The 12 x 9 noise input matrix `G` (columns: `w_acc`, `w_gyro`, `w_ba`).
pub type NoiseInput = SMatrix<f64, 12, N_NOISE>;
/// The 9 x 9 continuous noise PSD `Q_c`.
pub type NoisePsd = SMatrix<f64, N_NOISE, N_NOISE>;

/// `F` (eq. 3) and `G` (eq. 4, plus the bias random walk) at the nominal attitude
/// `nav_from_body` and the corrected specific force `specific_force_in_body` (m/s^2).
pub fn error_dynamics(
    nav_from_body: &UnitQuaternion<f64>,
    specific_force_in_body: &Vector3<f64>,
) -> (Matrix12, NoiseInput) {
    let c = nav_from_body.to_rotation_matrix().into_inner();
    let f_nav = c * specific_force_in_body;
    let mut f = Matrix12::zeros();
    f.fixed_view_mut::<3, 3>(POS, VEL)
        .copy_from(&Matrix3::identity());
    f.fixed_view_mut::<3, 3>(VEL, ATT)
        .copy_from(&(-skew(&f_nav)));
    f.fixed_view_mut::<3, 3>(VEL, ACCEL_BIAS).copy_from(&c);
    let mut g = NoiseInput::zeros();
    g.fixed_view_mut::<3, 3>(VEL, 0).copy_from(&c);
    g.fixed_view_mut::<3, 3>(ATT, 3).copy_from(&c);
    g.fixed_view_mut::<3, 3>(ACCEL_BIAS, 6)
        .copy_from(&Matrix3::identity());
    (f, g)
}

/// The diagonal `Q_c = diag(accel_psd I3, gyro_psd I3, accel_bias_psd I3)`.
pub fn noise_psd(noise: &ImuNoise) -> NoisePsd {
    let mut q = NoisePsd::zeros();
    for i in 0..3 {
        q[(i, i)] = noise.accel_psd;
        q[(3 + i, 3 + i)] = noise.gyro_psd;
        q[(6 + i, 6 + i)] = noise.accel_bias_psd;
    }
    q
}

/// `Phi` and `Q_d` over `dt` for the held `F`, `G` (module docs): with
/// `M = G Q_c G^T`,
///
/// ```text
/// Phi = I + F dt + F^2 dt^2 / 2
/// Q_d = M dt + (F M + M F^T) dt^2 / 2 + (F M F^T + (F^2 M + M F^2T) / 2) dt^3 / 3
///       + (F M F^2T + F^2 M F^T) dt^4 / 8 + F^2 M F^2T dt^5 / 20
/// ```
///
/// exact when `F^3 = 0` (true for [`error_dynamics`]). `Q_d` is returned exactly
/// symmetric.
pub fn discretize(f: &Matrix12, g: &NoiseInput, qc: &NoisePsd, dt: f64) -> (Matrix12, Matrix12) {
    let f2 = f * f;
    let phi = Matrix12::identity() + f * dt + f2 * (0.5 * dt * dt);
    let m = g * qc * g.transpose();
    let fm = f * m;
    let f2m = f2 * m;
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    let (dt4, dt5) = (dt2 * dt2, dt2 * dt3);
    let fmft = fm * f.transpose();
    let fmf2t = fm * f2.transpose();
    let qd = m * dt
        + (fm + fm.transpose()) * (0.5 * dt2)
        + (fmft + (f2m + f2m.transpose()) * 0.5) * (dt3 / 3.0)
        + (fmf2t + fmf2t.transpose()) * (dt4 / 8.0)
        + f2m * f2.transpose() * (dt5 / 20.0);
    (phi, (qd + qd.transpose()) * 0.5)
}

/// `Phi`, `Q_d` of one step of length `dt` starting at the given nominal attitude and
/// specific force: the numbers of [`error_dynamics`] + [`discretize`] (tested), from
/// their 3 x 3 blocks. With `A = -[(C f) x]`, `C C^T = I` and
/// `S = q_g A A^T + q_b I` (`A A^T = |C f|^2 I - (C f)(C f)^T`):
///
/// ```text
/// Phi: pv = dt I, pa = dt^2/2 A, pb = dt^2/2 C, va = dt A, vb = dt C (I on the diagonal)
/// Q_d: pp = q_a dt^3/3 I + S dt^5/20   pv = q_a dt^2/2 I + S dt^4/8   vv = q_a dt I + S dt^3/3
///      pa = q_g dt^3/6 A   pb = q_b dt^3/6 C   va = q_g dt^2/2 A   vb = q_b dt^2/2 C
///      aa = q_g dt I       bb = q_b dt I
/// ```
pub fn transition(
    nav_from_body: &UnitQuaternion<f64>,
    specific_force_in_body: &Vector3<f64>,
    noise: &ImuNoise,
    dt: f64,
) -> (Matrix12, Matrix12) {
    let c = nav_from_body.to_rotation_matrix().into_inner();
    let f_nav = c * specific_force_in_body;
    let a = -skew(&f_nav);
    let eye = Matrix3::identity();
    let (qa, qg, qb) = (noise.accel_psd, noise.gyro_psd, noise.accel_bias_psd);
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    let (dt4, dt5) = (dt2 * dt2, dt2 * dt3);
    let aat = eye * f_nav.norm_squared() - f_nav * f_nav.transpose();
    let s = aat * qg + eye * qb;

    let mut phi = Matrix12::identity();
    let set = |m: &mut Matrix12, r: usize, col: usize, b: &Matrix3<f64>| {
        m.fixed_view_mut::<3, 3>(r, col).copy_from(b);
    };
    set(&mut phi, POS, VEL, &(eye * dt));
    set(&mut phi, POS, ATT, &(a * (0.5 * dt2)));
    set(&mut phi, POS, ACCEL_BIAS, &(c * (0.5 * dt2)));
    set(&mut phi, VEL, ATT, &(a * dt));
    set(&mut phi, VEL, ACCEL_BIAS, &(c * dt));

    let mut qd = Matrix12::zeros();
    let mut sym = |r: usize, col: usize, b: Matrix3<f64>| {
        qd.fixed_view_mut::<3, 3>(r, col).copy_from(&b);
        if r != col {
            qd.fixed_view_mut::<3, 3>(col, r).copy_from(&b.transpose());
        }
    };
    sym(POS, POS, eye * (qa * dt3 / 3.0) + s * (dt5 / 20.0));
    sym(POS, VEL, eye * (qa * dt2 / 2.0) + s * (dt4 / 8.0));
    sym(VEL, VEL, eye * (qa * dt) + s * (dt3 / 3.0));
    sym(POS, ATT, a * (qg * dt3 / 6.0));
    sym(POS, ACCEL_BIAS, c * (qb * dt3 / 6.0));
    sym(VEL, ATT, a * (qg * dt2 / 2.0));
    sym(VEL, ACCEL_BIAS, c * (qb * dt2 / 2.0));
    sym(ATT, ATT, eye * (qg * dt));
    sym(ACCEL_BIAS, ACCEL_BIAS, eye * (qb * dt));
    (phi, (qd + qd.transpose()) * 0.5)
}

/// `Phi`, `Q_d` of one step of the 15-state extension with a gyro-bias error
/// `db_g` (true minus estimated, body axes, like the accelerometer bias), in the
/// layout of [`crate::error_state`] (`[dp, dv, psi, db_a, db_g]`): the 12-state
/// numbers of [`transition`] plus `d/dt psi = C db_g` and the gyro-bias random walk of
/// PSD `gyro_bias_psd` ((rad/s)^2 / s). `F` stays nilpotent (`F^4 = 0`), so
///
/// ```text
/// Phi: ag = dt C, vg = dt^2/2 A C, pg = dt^3/6 A C
/// Q_d: gg = q_bg dt I, ag = q_bg dt^2/2 C, aa += q_bg dt^3/3 I
/// ```
///
/// with `A = -[(C f) x]`; the bias walk's terms through velocity and position (of
/// order `q_bg dt^4` and smaller) are left out, which keeps `Q_d` positive
/// semi-definite (the added block is that of an integrated random walk).
pub fn transition_with_gyro_bias(
    nav_from_body: &UnitQuaternion<f64>,
    specific_force_in_body: &Vector3<f64>,
    noise: &ImuNoise,
    gyro_bias_psd: f64,
    dt: f64,
) -> (
    crate::error_state::ErrorCovariance,
    crate::error_state::ErrorCovariance,
) {
    use crate::error_state::{ErrorCovariance, GYRO_BIAS};
    let (phi12, qd12) = transition(nav_from_body, specific_force_in_body, noise, dt);
    let c = nav_from_body.to_rotation_matrix().into_inner();
    let a = -skew(&(c * specific_force_in_body));
    let mut phi = ErrorCovariance::identity();
    phi.fixed_view_mut::<12, 12>(0, 0).copy_from(&phi12);
    phi.fixed_view_mut::<3, 3>(ATT, GYRO_BIAS)
        .copy_from(&(c * dt));
    phi.fixed_view_mut::<3, 3>(VEL, GYRO_BIAS)
        .copy_from(&(a * c * (0.5 * dt * dt)));
    phi.fixed_view_mut::<3, 3>(POS, GYRO_BIAS)
        .copy_from(&(a * c * (dt * dt * dt / 6.0)));
    let mut qd = ErrorCovariance::zeros();
    qd.fixed_view_mut::<12, 12>(0, 0).copy_from(&qd12);
    let q = gyro_bias_psd;
    let eye = Matrix3::<f64>::identity();
    qd.fixed_view_mut::<3, 3>(GYRO_BIAS, GYRO_BIAS)
        .copy_from(&(eye * (q * dt)));
    let ag = c * (q * dt * dt / 2.0);
    qd.fixed_view_mut::<3, 3>(ATT, GYRO_BIAS).copy_from(&ag);
    qd.fixed_view_mut::<3, 3>(GYRO_BIAS, ATT)
        .copy_from(&ag.transpose());
    let aa = qd.fixed_view::<3, 3>(ATT, ATT) + eye * (q * dt * dt * dt / 3.0);
    qd.fixed_view_mut::<3, 3>(ATT, ATT).copy_from(&aa);
    (phi, (qd + qd.transpose()) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::ErrorVector12;
    use nalgebra::{SMatrix, SVector};
    use proptest::prelude::*;

    /// The nonlinear error dynamics of the reduced mechanization (no noise), exact for
    /// any error `dx`: the estimate `x_hat = x (+) dx` runs the mechanization with the
    /// corrected IMU (specific force `f + db`), the truth with `f`; then
    /// `d/dt dv = C_hat (f + db) - C f` with `C_hat = exp([psi x]) C`, and
    /// `d/dt psi = 0` (both attitudes turn with the same body rate, so
    /// `C_hat C^T` is constant).
    fn nonlinear_error_rate(
        c_true: &Matrix3<f64>,
        f_body: &Vector3<f64>,
        dx: &ErrorVector12,
    ) -> ErrorVector12 {
        let psi: Vector3<f64> = dx.fixed_rows::<3>(ATT).into();
        let db: Vector3<f64> = dx.fixed_rows::<3>(ACCEL_BIAS).into();
        let c_hat = nalgebra::Rotation3::from_scaled_axis(psi).into_inner() * c_true;
        let mut out = ErrorVector12::zeros();
        out.fixed_rows_mut::<3>(POS)
            .copy_from(&dx.fixed_rows::<3>(VEL));
        out.fixed_rows_mut::<3>(VEL)
            .copy_from(&(c_hat * (f_body + db) - c_true * f_body));
        out
    }

    /// The same with the noise `w = [w_acc, w_gyro, w_ba]` at `dx = 0`: the noise
    /// enters the estimate's IMU; `d/dt psi = C_hat w_gyro` from
    /// `d/dt (C_hat C^T) = C_hat [w x] C^T = [(C_hat w) x] C_hat C^T`.
    fn nonlinear_noise_rate(c: &Matrix3<f64>, w: &SVector<f64, 9>) -> ErrorVector12 {
        let mut out = ErrorVector12::zeros();
        out.fixed_rows_mut::<3>(VEL)
            .copy_from(&(c * w.fixed_rows::<3>(0)));
        out.fixed_rows_mut::<3>(ATT)
            .copy_from(&(c * w.fixed_rows::<3>(3)));
        out.fixed_rows_mut::<3>(ACCEL_BIAS)
            .copy_from(&w.fixed_rows::<3>(6));
        out
    }

    fn unit_quat(a: [f64; 3]) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(a[0], a[1], a[2])
    }

    proptest! {
        /// Acceptance (Jacobians): `F` and `G` equal the central finite differences of
        /// the nonlinear error dynamics at random attitudes and specific forces.
        /// Step 1e-6; tolerance 1e-7 absolute on entries of size <= ~20 (central
        /// differences of a smooth function: truncation ~1e-12 |f''' |, rounding
        /// ~1e-10).
        #[test]
        fn f_and_g_match_finite_differences(
            att in prop::array::uniform3(-3.0f64..3.0),
            fb in prop::array::uniform3(-20.0f64..20.0),
        ) {
            let q = unit_quat(att);
            let c = q.to_rotation_matrix().into_inner();
            let f_body = Vector3::from(fb);
            let (f, g) = error_dynamics(&q, &f_body);
            let h = 1e-6;
            let mut fd = Matrix12::zeros();
            for j in 0..12 {
                let mut e = ErrorVector12::zeros();
                e[j] = h;
                let col = (nonlinear_error_rate(&c, &f_body, &e)
                    - nonlinear_error_rate(&c, &f_body, &(-e)))
                    / (2.0 * h);
                fd.set_column(j, &col);
            }
            prop_assert!((fd - f).amax() < 1e-7, "F {}", (fd - f).amax());
            let mut gd = NoiseInput::zeros();
            for j in 0..9 {
                let mut w = SVector::<f64, 9>::zeros();
                w[j] = h;
                let col = (nonlinear_noise_rate(&c, &w) - nonlinear_noise_rate(&c, &(-w))) / (2.0 * h);
                gd.set_column(j, &col);
            }
            prop_assert!((gd - g).amax() < 1e-7, "G {}", (gd - g).amax());
            // F^3 = 0: the second-order Phi is exact
            prop_assert!((f * f * f).amax() == 0.0);
        }
    }

    /// `exp` of a square matrix by its Taylor series (enough terms for the nilpotent
    /// Van Loan matrix here: exact after 6).
    fn expm<const N: usize>(a: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
        let mut term = SMatrix::<f64, N, N>::identity();
        let mut sum = term;
        for k in 1..30 {
            term = term * a / k as f64;
            sum += term;
        }
        sum
    }

    /// The closed-form `Phi` and `Q_d` equal the Van Loan construction
    /// `exp([[-F, G Q G^T], [0, F^T]] dt) = [[., Phi^-1 Q_d], [0, Phi^T]]`.
    #[test]
    fn discretization_matches_van_loan() {
        let q = unit_quat([0.3, -0.2, 2.0]);
        let f_body = Vector3::new(1.5, -0.7, -9.5);
        let noise = ImuNoise {
            accel_psd: 2e-3,
            gyro_psd: 5e-6,
            accel_bias_psd: 1e-7,
        };
        let (f, g) = error_dynamics(&q, &f_body);
        let m = g * noise_psd(&noise) * g.transpose();
        for dt in [0.01, 0.2, 1.0] {
            let (phi, qd) = discretize(&f, &g, &noise_psd(&noise), dt);
            // the block form of `transition` gives the same numbers
            let (phi_b, qd_b) = transition(&q, &f_body, &noise, dt);
            assert!((phi - phi_b).amax() < 1e-14, "Phi blocks at {dt}");
            assert!((qd - qd_b).amax() < 1e-14 * qd.amax(), "Q_d blocks at {dt}");
            let mut vl = SMatrix::<f64, 24, 24>::zeros();
            vl.fixed_view_mut::<12, 12>(0, 0).copy_from(&(-f * dt));
            vl.fixed_view_mut::<12, 12>(0, 12).copy_from(&(m * dt));
            vl.fixed_view_mut::<12, 12>(12, 12)
                .copy_from(&(f.transpose() * dt));
            let e = expm(&vl);
            let phi_vl: Matrix12 = e.fixed_view::<12, 12>(12, 12).transpose();
            let qd_vl = phi_vl * e.fixed_view::<12, 12>(0, 12);
            assert!((phi - phi_vl).amax() < 1e-12, "Phi at {dt}");
            let scale = qd_vl.amax();
            assert!(
                (qd - qd_vl).amax() < 1e-10 * scale,
                "Q_d at {dt}: {}",
                (qd - qd_vl).amax() / scale
            );
            assert_eq!(qd, qd.transpose());
            assert!(qd.cholesky().is_some());
        }
    }

    #[test]
    fn gyro_bias_extension_is_exp_of_its_f_and_keeps_the_12_state_block() {
        let q = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7);
        let f = Vector3::new(0.3, -0.1, -9.7);
        let noise = ImuNoise {
            accel_psd: 1e-4,
            gyro_psd: 1e-6,
            accel_bias_psd: 1e-8,
        };
        let dt = 0.01;
        let (phi, qd) = transition_with_gyro_bias(&q, &f, &noise, 1e-9, dt);
        let (phi12, qd12) = transition(&q, &f, &noise, dt);
        assert_eq!(phi.fixed_view::<12, 12>(0, 0), phi12);
        assert!(
            (qd.fixed_view::<9, 9>(0, 0) - qd12.fixed_view::<9, 9>(0, 0))
                .abs()
                .max()
                < 1e-12
        );
        // Phi = exp(F dt) with F the 12-state F plus C in (psi, b_g): F^4 = 0
        let (f12, _) = error_dynamics(&q, &f);
        let mut big = SMatrix::<f64, 15, 15>::zeros();
        big.fixed_view_mut::<12, 12>(0, 0).copy_from(&f12);
        big.fixed_view_mut::<3, 3>(ATT, 12)
            .copy_from(&q.to_rotation_matrix().into_inner());
        let f2 = big * big;
        let f3 = f2 * big;
        assert!((f3 * big).abs().max() < 1e-12);
        let expected = SMatrix::<f64, 15, 15>::identity()
            + big * dt
            + f2 * (dt * dt / 2.0)
            + f3 * (dt * dt * dt / 6.0);
        assert!((phi - expected).abs().max() < 1e-12);
        // Q_d symmetric, positive semi-definite
        assert_eq!(qd, qd.transpose());
        let eig = qd.symmetric_eigen().eigenvalues;
        assert!(eig.min() > -1e-18, "{eig}");
    }
}
