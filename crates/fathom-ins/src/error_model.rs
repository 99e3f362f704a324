//! The 15-state INS error-state model in NED: continuous-time dynamics matrix `F`,
//! noise input matrix `G`, noise power spectral densities, discretisation, and the
//! mapping between a pair of navigation states and their error.
//!
//! # State and conventions
//!
//! `dx = [dr^n (0..3), dv^n (3..6), psi (6..9), b_a (9..12), b_g (12..15)]`, all
//! **estimated minus true**:
//!
//! - `dr^n = [(R_N + h) dL, (R_E + h) cos L dlambda, -dh]`, position error in metres
//!   (north, east, down) derived from the curvilinear errors;
//! - `dv^n = v_est - v_true` (NED);
//! - `psi`: attitude error as a small rotation of the **estimated nav frame about the
//!   true nav frame**, resolved in NED ("phi-angle" form, Groves §14.2.1, Titterton &
//!   Weston §12.2): `C_b^n(est) = (I + [psi x]) C_b^n(true)`, i.e.
//!   `psi = log(C_est C_true^T)`. A positive `psi_D` means the estimated heading is
//!   too large (rotated clockwise seen from above);
//! - `b_a`, `b_g`: accelerometer and gyro errors in the body frame, measured minus true
//!   (`f_meas = f + b_a + w_a`, `omega_meas = omega + b_g + w_g`); a filter corrects
//!   the IMU by subtracting them.
//!
//! # Dynamics (derived by perturbing the NED mechanization equations; cf. Groves
//! eq. 14.64-14.71 and Titterton & Weston eq. 12.8-12.28)
//!
//! With `R_N' = R_N + h`, `R_E' = R_E + h`, `omega_in = omega_ie + omega_en`,
//! `f^n = C_b^n f^b`, `W_ie = d omega_ie^n / d dr`, `W_en,r = d omega_en^n / d dr`,
//! `W_en,v = d omega_en^n / d dv` (the Jacobians of [`crate::earth`]'s rates, with the
//! derivatives of the radii with respect to latitude neglected):
//!
//! ```text
//! dr_dot  = F_rr dr + dv
//! dv_dot  = ([v x](2 W_ie + W_en,r) + G_r) dr - ([(2 omega_ie + omega_en) x] - [v x] W_en,v) dv
//!           - [f^n x] psi + C_b^n b_a + C_b^n w_a
//! psi_dot = -(W_ie + W_en,r) dr - W_en,v dv - [omega_in x] psi + C_b^n b_g + C_b^n w_g
//! b_a_dot = -b_a / tau_a + w_ba          (tau = infinity for a random walk)
//! b_g_dot = -b_g / tau_g + w_bg
//! ```
//!
//! where
//!
//! ```text
//! F_rr = [ -v_D/R_N'           0                           v_N/R_N' ]
//!        [ v_E tan L/R_N'   -(v_D/R_E' + v_N tan L/R_N')   v_E/R_E' ]
//!        [ 0                   0                           0        ]
//! W_ie   = omega_ie / R_N' * [-sin L, 0, -cos L]^T  in the north column
//! W_en,r : (N,D) = v_E/R_E'^2, (E,D) = -v_N/R_N'^2,
//!          (D,N) = -v_E / (cos^2 L R_E' R_N'), (D,D) = -v_E tan L / R_E'^2
//! W_en,v : (N,E) = 1/R_E', (E,N) = -1/R_N', (D,E) = -tan L / R_E'
//! G_r    : (D,D) = -d gamma / d h  (about +2 g / R: the vertical-channel instability)
//! ```
//!
//! `F_rr` is the exact linearisation of `dr` as defined above (it differs from the
//! `-[omega_en x]` form of a geometric position error by terms of order `v / R`).

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::earth::{self, Geodetic};
use crate::error::InsError;
use crate::rotation::{quat_from_rotation_vector, rotation_vector_from_quat};
use crate::state::InsState;

/// Number of error states.
pub const N_STATES: usize = 15;
/// Number of continuous white-noise inputs (`w_a`, `w_g`, `w_ba`, `w_bg`).
pub const N_NOISE: usize = 12;
/// Index of the first position-error state (north).
pub const POS: usize = 0;
/// Index of the first velocity-error state.
pub const VEL: usize = 3;
/// Index of the first attitude-error state `psi`.
pub const ATT: usize = 6;
/// Index of the first accelerometer-bias state.
pub const ACCEL_BIAS: usize = 9;
/// Index of the first gyro-bias state.
pub const GYRO_BIAS: usize = 12;

/// A 15 x 15 error-state matrix (`F`, `Phi`, `Q_d`, `P`).
pub type ErrorMatrix = SMatrix<f64, N_STATES, N_STATES>;
/// The 15 x 12 noise input matrix `G`.
pub type NoiseInputMatrix = SMatrix<f64, N_STATES, N_NOISE>;
/// The 12 x 12 continuous noise PSD matrix `Q_c`.
pub type NoisePsdMatrix = SMatrix<f64, N_NOISE, N_NOISE>;

/// Stochastic model of one sensor triad's bias (same on the three axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BiasModel {
    /// Constant (turn-on) bias: `b_dot = 0`, no driving noise.
    Constant,
    /// Random walk `b_dot = w`, `w` white with PSD `sigma_rate^2`.
    RandomWalk {
        /// Random-walk intensity (units of the bias per sqrt(s)).
        sigma_rate: f64,
    },
    /// First-order Gauss-Markov `b_dot = -b / tau + w`, stationary std `sigma`,
    /// driving PSD `2 sigma^2 / tau`.
    GaussMarkov {
        /// Stationary standard deviation (units of the bias).
        sigma: f64,
        /// Correlation time, s (> 0).
        tau: f64,
    },
}

impl BiasModel {
    /// The diagonal dynamics coefficient (`0` or `-1/tau`).
    pub fn drift(&self) -> f64 {
        match *self {
            Self::GaussMarkov { tau, .. } => -1.0 / tau,
            _ => 0.0,
        }
    }

    /// PSD of the driving white noise.
    pub fn driving_psd(&self) -> f64 {
        match *self {
            Self::Constant => 0.0,
            Self::RandomWalk { sigma_rate } => sigma_rate * sigma_rate,
            Self::GaussMarkov { sigma, tau } => 2.0 * sigma * sigma / tau,
        }
    }

    fn check(&self, what: &str) -> Result<(), InsError> {
        use fathom_core::error::{ensure_non_negative, ensure_positive};
        match *self {
            Self::Constant => {}
            Self::RandomWalk { sigma_rate } => {
                ensure_non_negative(&format!("{what} random-walk sigma_rate"), sigma_rate)?;
            }
            Self::GaussMarkov { sigma, tau } => {
                ensure_non_negative(&format!("{what} Gauss-Markov sigma"), sigma)?;
                ensure_positive(&format!("{what} Gauss-Markov tau"), tau)?;
            }
        }
        Ok(())
    }
}

/// Unchecked IMU error parameters for the error-state model; validate with
/// [`ImuErrorParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuErrorParams {
    /// Accelerometer white noise (velocity random walk), m/s/sqrt(s) (= m/s^2/sqrt(Hz)).
    pub accel_vrw: f64,
    /// Gyro white noise (angle random walk), rad/sqrt(s).
    pub gyro_arw: f64,
    /// Accelerometer bias model.
    pub accel_bias: BiasModel,
    /// Gyro bias model.
    pub gyro_bias: BiasModel,
}

impl ImuErrorParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`InsError::Core`] naming the negative / non-finite parameter.
    pub fn check(&self) -> Result<ImuErrorModel, InsError> {
        use fathom_core::error::ensure_non_negative;
        ensure_non_negative("accel_vrw", self.accel_vrw)?;
        ensure_non_negative("gyro_arw", self.gyro_arw)?;
        self.accel_bias.check("accel_bias")?;
        self.gyro_bias.check("gyro_bias")?;
        Ok(ImuErrorModel { params: *self })
    }
}

/// Validated IMU error parameters (from [`ImuErrorParams::check`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuErrorModel {
    params: ImuErrorParams,
}

impl ImuErrorModel {
    /// The validated parameters.
    pub fn params(&self) -> &ImuErrorParams {
        &self.params
    }

    /// Continuous noise PSD `Q_c = diag(vrw^2 I3, arw^2 I3, q_ba I3, q_bg I3)`, matching
    /// the columns of [`noise_input`].
    pub fn noise_psd(&self) -> NoisePsdMatrix {
        let p = &self.params;
        let d = [
            p.accel_vrw * p.accel_vrw,
            p.gyro_arw * p.gyro_arw,
            p.accel_bias.driving_psd(),
            p.gyro_bias.driving_psd(),
        ];
        let mut q = NoisePsdMatrix::zeros();
        for (block, v) in d.iter().enumerate() {
            for i in 0..3 {
                q[(3 * block + i, 3 * block + i)] = *v;
            }
        }
        q
    }
}

/// Continuous-time error dynamics `F` (see the module docs) at the navigation state
/// `state` with the specific force `specific_force_in_body` (e.g.
/// `delta_v / dt` of the current increment).
pub fn error_dynamics(
    state: &InsState,
    specific_force_in_body: &Vector3<f64>,
    model: &ImuErrorModel,
) -> ErrorMatrix {
    let (lat, h, v) = (state.lat, state.h, &state.vel_in_nav);
    let rn = earth::meridian_radius(lat) + h;
    let re = earth::transverse_radius(lat) + h;
    let (sl, cl) = lat.sin_cos();
    let tl = sl / cl;
    let (vn, ve, vd) = (v.x, v.y, v.z);
    let w_ie = earth::earth_rate_in_nav(lat);
    let w_en = earth::transport_rate_in_nav(lat, h, v);
    let c = state.nav_from_body.to_rotation_matrix().into_inner();
    let f_nav = c * specific_force_in_body;
    let skew = fathom_core::frames::skew;

    let f_rr = Matrix3::new(
        -vd / rn,
        0.0,
        vn / rn,
        ve * tl / rn,
        -(vd / re + vn * tl / rn),
        ve / re,
        0.0,
        0.0,
        0.0,
    );
    let mut w_ie_r = Matrix3::zeros();
    w_ie_r[(0, 0)] = -earth::OMEGA_IE * sl / rn;
    w_ie_r[(2, 0)] = -earth::OMEGA_IE * cl / rn;
    let mut w_en_r = Matrix3::zeros();
    w_en_r[(0, 2)] = ve / (re * re);
    w_en_r[(1, 2)] = -vn / (rn * rn);
    w_en_r[(2, 0)] = -ve / (cl * cl * re * rn);
    w_en_r[(2, 2)] = -ve * tl / (re * re);
    let mut w_en_v = Matrix3::zeros();
    w_en_v[(0, 1)] = 1.0 / re;
    w_en_v[(1, 0)] = -1.0 / rn;
    w_en_v[(2, 1)] = -tl / re;
    let mut g_r = Matrix3::zeros();
    g_r[(2, 2)] = -earth::normal_gravity_height_gradient(lat, h);

    let sv = skew(v);
    let mut f = ErrorMatrix::zeros();
    f.fixed_view_mut::<3, 3>(POS, POS).copy_from(&f_rr);
    f.fixed_view_mut::<3, 3>(POS, VEL)
        .copy_from(&Matrix3::identity());
    f.fixed_view_mut::<3, 3>(VEL, POS)
        .copy_from(&(sv * (w_ie_r * 2.0 + w_en_r) + g_r));
    f.fixed_view_mut::<3, 3>(VEL, VEL)
        .copy_from(&(-skew(&(w_ie * 2.0 + w_en)) + sv * w_en_v));
    f.fixed_view_mut::<3, 3>(VEL, ATT)
        .copy_from(&(-skew(&f_nav)));
    f.fixed_view_mut::<3, 3>(VEL, ACCEL_BIAS).copy_from(&c);
    f.fixed_view_mut::<3, 3>(ATT, POS)
        .copy_from(&(-(w_ie_r + w_en_r)));
    f.fixed_view_mut::<3, 3>(ATT, VEL).copy_from(&(-w_en_v));
    f.fixed_view_mut::<3, 3>(ATT, ATT)
        .copy_from(&(-skew(&(w_ie + w_en))));
    f.fixed_view_mut::<3, 3>(ATT, GYRO_BIAS).copy_from(&c);
    let (ba, bg) = (
        model.params.accel_bias.drift(),
        model.params.gyro_bias.drift(),
    );
    for i in 0..3 {
        f[(ACCEL_BIAS + i, ACCEL_BIAS + i)] = ba;
        f[(GYRO_BIAS + i, GYRO_BIAS + i)] = bg;
    }
    f
}

/// Noise input matrix `G` mapping `w = [w_a, w_g, w_ba, w_bg]` (body frame) into the
/// error-state derivative: `C_b^n` in the (vel, w_a) and (att, w_g) blocks, identity
/// in the two bias blocks.
pub fn noise_input(state: &InsState) -> NoiseInputMatrix {
    let c = state.nav_from_body.to_rotation_matrix().into_inner();
    let mut g = NoiseInputMatrix::zeros();
    g.fixed_view_mut::<3, 3>(VEL, 0).copy_from(&c);
    g.fixed_view_mut::<3, 3>(ATT, 3).copy_from(&c);
    g.fixed_view_mut::<3, 3>(ACCEL_BIAS, 6)
        .copy_from(&Matrix3::identity());
    g.fixed_view_mut::<3, 3>(GYRO_BIAS, 9)
        .copy_from(&Matrix3::identity());
    g
}

/// Order of the truncated matrix-exponential discretisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Discretization {
    /// `Phi = I + F dt`.
    #[default]
    FirstOrder,
    /// `Phi = I + F dt + F^2 dt^2 / 2`.
    SecondOrder,
}

/// State transition matrix over `dt` from the truncated series of `exp(F dt)`
/// (Groves eq. 3.34).
pub fn transition_matrix(f: &ErrorMatrix, dt: f64, order: Discretization) -> ErrorMatrix {
    let fdt = f * dt;
    match order {
        Discretization::FirstOrder => ErrorMatrix::identity() + fdt,
        Discretization::SecondOrder => ErrorMatrix::identity() + fdt + fdt * fdt * 0.5,
    }
}

/// Discrete process noise by the trapezoidal approximation
/// `Q_d = (Phi G Q_c G^T Phi^T + G Q_c G^T) dt / 2` (Brown & Hwang, 4th ed., eq. 7.2.5
/// first-order form; Groves eq. 3.46 is its `Phi = I` special case), symmetrised.
pub fn discrete_process_noise(
    phi: &ErrorMatrix,
    g: &NoiseInputMatrix,
    q_c: &NoisePsdMatrix,
    dt: f64,
) -> ErrorMatrix {
    let gqg = g * q_c * g.transpose();
    let q = (phi * gqg * phi.transpose() + gqg) * (0.5 * dt);
    (q + q.transpose()) * 0.5
}

/// Navigation error of an estimated state with respect to a true one (estimated minus
/// true, conventions of the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavError {
    /// `dr^n`, NED metres (curvilinear, radii at the mid-point).
    pub pos_in_nav: Vector3<f64>,
    /// `dv^n`, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// `psi = log(C_est C_true^T)`, rad, resolved in NED.
    pub attitude: Vector3<f64>,
}

/// Error of `est` with respect to `truth` (see [`NavError`]).
pub fn nav_error(est: &InsState, truth: &InsState) -> NavError {
    NavError {
        pos_in_nav: earth::curvilinear_offset(&truth.position(), &est.position()),
        vel_in_nav: est.vel_in_nav - truth.vel_in_nav,
        attitude: rotation_vector_from_quat(&(est.nav_from_body * truth.nav_from_body.inverse())),
    }
}

/// Removes an (estimated) error from a state: the inverse of [`nav_error`], so
/// `correct_state(est, &nav_error(est, truth)) == truth` up to rounding (exact in
/// attitude and velocity; position to second order in the error over `R`).
pub fn correct_state(est: &InsState, err: &NavError) -> InsState {
    let h = est.h + err.pos_in_nav.z;
    let lat = est.lat - err.pos_in_nav.x / (earth::meridian_radius(est.lat) + h);
    let lat_m = 0.5 * (lat + est.lat);
    let h_m = 0.5 * (h + est.h);
    let lat = est.lat - err.pos_in_nav.x / (earth::meridian_radius(lat_m) + h_m);
    let lat_m = 0.5 * (lat + est.lat);
    let lon = est.lon - err.pos_in_nav.y / ((earth::transverse_radius(lat_m) + h_m) * lat_m.cos());
    let mut q = quat_from_rotation_vector(&-err.attitude) * est.nav_from_body;
    q.renormalize();
    InsState::new(
        Geodetic::new(lat, lon, h),
        est.vel_in_nav - err.vel_in_nav,
        q,
    )
}

#[cfg(test)]
mod tests;
