//! Strapdown mechanization in the local-level NED frame on WGS-84 (100 Hz class):
//! quaternion attitude update with coning correction, velocity update with rotation
//! and sculling compensation plus gravity and Coriolis, trapezoidal position update.
//!
//! # Algorithm (one step from `t_{k-1}` to `t_k = t_{k-1} + dt`)
//!
//! Inputs: the IMU increment `(dtheta_k, dv_k)` over the interval and the previous
//! one `(dtheta_{k-1}, dv_{k-1})` (zero on the first step). References: Savage,
//! *Strapdown Analytics* (2000) and "Strapdown inertial navigation integration
//! algorithm design, parts 1-2", JGCD 21(1-2), 1998 (hereafter S98-1, S98-2);
//! Titterton & Weston (2004) ch. 11 (T&W); Groves (2013) ch. 5.
//!
//! 1. **Mid-interval navigation quantities.** Latitude, height and velocity at
//!    `t_{k-1/2}` are *extrapolated* from the last two states (S98-2 §"Velocity
//!    update", T&W §11.2.5):
//!    `x_mid = x_{k-1} + (dt_k / (2 dt_{k-1})) (x_{k-1} - x_{k-2})`
//!    (`x_mid = x_{k-1}` on the first step or after [`Strapdown::set_state`]).
//!    From them: `omega_ie^n`, `omega_en^n` ([`crate::earth`]) and normal gravity
//!    `g^n = [0, 0, gamma(L, h)]`.
//! 2. **Attitude update** (S98-1 eq. 9, 17; T&W eq. 11.27-11.32):
//!    - coning-corrected body rotation vector, two-sample (previous-sample) form
//!      `phi_k = dtheta_k + (1/12) dtheta_{k-1} x dtheta_k`;
//!    - nav-frame rotation vector `zeta_k = (omega_ie^n + omega_en^n)_mid dt`;
//!    - `q_k = q(-zeta_k) (x) q_{k-1} (x) q(phi_k)`, with `q(.)` the exact quaternion of
//!      a rotation vector ([`crate::rotation::quat_from_rotation_vector`]);
//!      `q_k` is renormalised.
//! 3. **Velocity update** (S98-2 eq. 3, 23, 25; T&W eq. 11.38-11.44):
//!    - rotation compensation `dv_rot = 0.5 dtheta_k x dv_k`;
//!    - sculling (previous-sample form)
//!      `dv_scul = (1/12) (dtheta_{k-1} x dv_k + dv_{k-1} x dtheta_k)`;
//!    - `dv_sf^n = q(-zeta_k / 2) C_b^n(k-1) (dv_k + dv_rot + dv_scul)`
//!      (the half nav-frame rotation brings `C_b^n(k-1)` to mid-interval);
//!    - `dv_g/cor = (g^n - (2 omega_ie^n + omega_en^n) x v^n)_mid dt`;
//!    - `v_k = v_{k-1} + dv_sf^n + dv_g/cor`.
//! 4. **Position update**, trapezoidal velocity (Groves eq. 5.54-5.56):
//!    `h_k = h_{k-1} - (dt/2)(v_D,k-1 + v_D,k)`;
//!    `L_k = L_{k-1} + (dt/2)(v_N,k-1 + v_N,k) / (R_N(L_m) + h_m)`;
//!    `lambda_k = lambda_{k-1} + (dt/2)(v_E,k-1 + v_E,k) / ((R_E(L_m) + h_m) cos L_m)`,
//!    with `h_m`, `L_m` the averages over the interval (the latitude mid-point of the
//!    `L` update is predicted once with `R_N(L_{k-1})`; the mid-point radii are the
//!    first-order expansions of those at `L_{k-1}`, exact to far below double
//!    rounding of `L` and `lambda` for steps under 12 m, see `position_update`).
//!
//! The vertical channel is unstable (positive feedback of the `-2 g / R` gravity
//! gradient, time constant about 9.5 min); [`VerticalChannel::Hold`] freezes it at
//! a given height with zero vertical velocity for horizontal-only studies.

use nalgebra::Vector3;

use crate::earth::{self, OMEGA_IE};
use crate::error::InsError;
use crate::rotation::quat_from_rotation_vector;
use crate::state::{ImuIncrement, InsState};

/// How the (unstable) vertical channel is treated.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum VerticalChannel {
    /// Integrated freely like the horizontal channels.
    #[default]
    Free,
    /// After every step, height is reset to `h` and the down velocity to zero
    /// (a perfect external height reference, e.g. a depth gauge at constant depth).
    Hold {
        /// Height above the ellipsoid to hold, m.
        h: f64,
    },
}

/// The navigation state at the start of the last interval and that interval's length,
/// used to extrapolate mid-interval quantities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NavHistory {
    pub(crate) lat: f64,
    pub(crate) h: f64,
    pub(crate) vel: Vector3<f64>,
    pub(crate) dt: f64,
}

/// Mid-interval nav-frame rotation vector and gravity/Coriolis velocity increment.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MidTerms {
    /// `zeta = (omega_ie^n + omega_en^n)_mid dt`, rad.
    pub(crate) zeta: Vector3<f64>,
    /// `(g^n - (2 omega_ie^n + omega_en^n) x v^n)_mid dt`, m/s.
    pub(crate) dv_grav_cor: Vector3<f64>,
    /// `(sin, cos)` of the latitude at the start of the interval (the one `sin_cos`
    /// call of a step: the mid-interval values and those of the position update are
    /// offsets of it, [`sin_cos_offset`]).
    pub(crate) sin_cos_lat: (f64, f64),
}

/// Step 1 of the algorithm: extrapolated mid-interval quantities.
pub(crate) fn mid_terms(
    lat: f64,
    h: f64,
    vel: &Vector3<f64>,
    history: Option<&NavHistory>,
    dt: f64,
) -> MidTerms {
    let (lat_m, h_m, vel_m) = match history {
        Some(p) => {
            let c = 0.5 * dt / p.dt;
            (
                lat + c * (lat - p.lat),
                h + c * (h - p.h),
                vel + (vel - p.vel) * c,
            )
        }
        None => (lat, h, *vel),
    };
    // One sin/cos of the latitude per step; the mid latitude's is an offset of it,
    // used by every Earth-model term (the same formulas as
    // earth::{earth_rate_in_nav, transport_rate_in_nav, gravity_in_nav}).
    let sin_cos_lat = lat.sin_cos();
    let (s, c) = sin_cos_offset(sin_cos_lat, lat, lat_m - lat);
    let w_ie = Vector3::new(OMEGA_IE * c, 0.0, -OMEGA_IE * s);
    // (the three share one square root, see earth::ellipsoid_factor)
    let re = earth::transverse_radius_from_sin(s) + h_m;
    let rn = earth::meridian_radius_from_sin(s) + h_m;
    let w_en = Vector3::new(vel_m.y / re, -vel_m.x / rn, -vel_m.y * (s / c) / re);
    let g = Vector3::new(0.0, 0.0, earth::normal_gravity_from_sin(s, h_m));
    MidTerms {
        zeta: (w_ie + w_en) * dt,
        dv_grav_cor: (g - (w_ie * 2.0 + w_en).cross(&vel_m)) * dt,
        sin_cos_lat,
    }
}

/// `(sin, cos)` of `lat + d` from `(sin, cos)` of `lat`: the angle-sum formula with
/// `cos d = 1 - d^2/2` and `sin d = d - d^3/6`, whose truncation errors (`d^4/24`,
/// `d^5/120`) are below double rounding for `|d| < 1e-4` rad (640 m of latitude: a
/// strapdown step moves ~1e-8 rad); exact `sin_cos` otherwise.
fn sin_cos_offset((s, c): (f64, f64), lat: f64, d: f64) -> (f64, f64) {
    if d.abs() < 1e-4 {
        let d2 = d * d;
        let (cd, sd) = (1.0 - 0.5 * d2, d * (1.0 - d2 / 6.0));
        (s * cd + c * sd, c * cd - s * sd)
    } else {
        (lat + d).sin_cos()
    }
}

/// Coning correction `(1/12) dtheta_{k-1} x dtheta_k` (S98-1 eq. 17, two-sample form).
pub(crate) fn coning(dtheta_prev: &Vector3<f64>, dtheta: &Vector3<f64>) -> Vector3<f64> {
    dtheta_prev.cross(dtheta) / 12.0
}

/// Sculling correction `(1/12)(dtheta_{k-1} x dv_k + dv_{k-1} x dtheta_k)`
/// (S98-2 eq. 25, previous-sample form).
pub(crate) fn sculling(
    dtheta_prev: &Vector3<f64>,
    dv_prev: &Vector3<f64>,
    dtheta: &Vector3<f64>,
    dv: &Vector3<f64>,
) -> Vector3<f64> {
    (dtheta_prev.cross(dv) + dv_prev.cross(dtheta)) / 12.0
}

/// Step 4: trapezoidal position update; returns `(lat, lon, h)` at `t_k`. `sc` is
/// `(sin, cos)` of `lat`.
///
/// The radii at the mid-point latitudes `L + delta` come from their values at `L`
/// (one square root) by the first-order expansion
///
/// ```text
/// R_N(L + delta) = R_N(L) (1 + 3 kappa delta),  R_E(L + delta) = R_E(L) (1 + kappa delta),
/// kappa = e^2 sin L cos L / (1 - e^2 sin^2 L)
/// ```
///
/// (`dR_N/dL = 3 kappa R_N`, `dR_E/dL = kappa R_E`), whose relative error `O(e^2
/// delta^2)` (about `0.01 delta^2`) is at most ~`1e-14` for `|delta| < 1e-6` rad (a
/// half step of 6 m; at 100 Hz that is 1200 m/s): the latitude and longitude steps
/// are then exact to far below double rounding of `L` and `lambda`. Larger steps
/// take the exact radii at the mid-point latitudes.
pub(crate) fn position_update(
    lat: f64,
    sc: (f64, f64),
    lon: f64,
    h: f64,
    vel_prev: &Vector3<f64>,
    vel: &Vector3<f64>,
    dt: f64,
) -> (f64, f64, f64) {
    position_update_with(lat, sc, lon, h, (vel_prev, vel), dt, 1e-6)
}

/// [`position_update`] with the radii linearized below the half-step offset
/// `max_linear_offset` (rad) and exact above it (`0` = always exact).
fn position_update_with(
    lat: f64,
    sc: (f64, f64),
    lon: f64,
    h: f64,
    (vel_prev, vel): (&Vector3<f64>, &Vector3<f64>),
    dt: f64,
    max_linear_offset: f64,
) -> (f64, f64, f64) {
    let dr = (vel_prev + vel) * (0.5 * dt);
    let h_new = h - dr.z;
    let h_m = 0.5 * (h + h_new);
    let (s, c) = sc;
    let rn = earth::meridian_radius_from_sin(s);
    let re = earth::transverse_radius_from_sin(s);
    let kappa = earth::radius_log_derivative_from_sin_cos(s, c);
    // half the latitude step, predicted with R_N(L)
    let delta_pred = 0.5 * dr.x / (rn + h_m);
    // (false for a NaN offset too: the exact path then carries the NaN to the checks)
    let (lat_new, lon_new) = if delta_pred.abs() < max_linear_offset {
        let lat_new = lat + dr.x / (rn * (1.0 + 3.0 * kappa * delta_pred) + h_m);
        let delta = 0.5 * (lat_new - lat);
        let (_, c_m) = sin_cos_offset(sc, lat, delta);
        let lon_new = lon + dr.y / ((re * (1.0 + kappa * delta) + h_m) * c_m);
        (lat_new, lon_new)
    } else {
        // the mid-point latitudes' sin/cos are offsets of `lat`'s
        let (s_p, _) = sin_cos_offset(sc, lat, delta_pred);
        let lat_new = lat + dr.x / (earth::meridian_radius_from_sin(s_p) + h_m);
        let (s_m, c_m) = sin_cos_offset(sc, lat, 0.5 * (lat_new - lat));
        let lon_new = lon + dr.y / ((earth::transverse_radius_from_sin(s_m) + h_m) * c_m);
        (lat_new, lon_new)
    };
    (lat_new, lon_new, h_new)
}

/// A strapdown INS integrating IMU increments in local-level NED (see module docs).
///
/// `step` performs no heap allocation.
///
/// Bad input: a non-finite increment (NaN IMU `delta_theta` / `delta_v`, `dt`) or a
/// step that would leave a non-finite state is an [`InsError`] naming the field and
/// component, and the state is unchanged (no clock here: the caller adds the time).
#[derive(Debug, Clone, PartialEq)]
pub struct Strapdown {
    state: InsState,
    history: Option<NavHistory>,
    prev_increment: Option<ImuIncrement>,
    vertical: VerticalChannel,
}

impl Strapdown {
    /// A strapdown initialised at `initial` with a free vertical channel.
    ///
    /// # Errors
    /// If `initial` is not finite or its latitude is at a pole ([`InsState::check`]).
    pub fn new(initial: InsState) -> Result<Self, InsError> {
        initial.check()?;
        Ok(Self {
            state: initial,
            history: None,
            prev_increment: None,
            vertical: VerticalChannel::Free,
        })
    }

    /// Sets the vertical-channel treatment (builder style).
    ///
    /// # Errors
    /// [`InsError::NonFinite`] if the held height is not finite.
    pub fn with_vertical_channel(mut self, vertical: VerticalChannel) -> Result<Self, InsError> {
        self.set_vertical_channel(vertical)?;
        Ok(self)
    }

    /// Sets the vertical-channel treatment; with [`VerticalChannel::Hold`] the current
    /// state is immediately set to the held height with zero down velocity.
    ///
    /// # Errors
    /// [`InsError::NonFinite`] if the held height is not finite.
    pub fn set_vertical_channel(&mut self, vertical: VerticalChannel) -> Result<(), InsError> {
        if let VerticalChannel::Hold { h } = vertical {
            crate::error::check_finite("held height", &[h])?;
            self.state.h = h;
            self.state.vel_in_nav.z = 0.0;
            self.history = None;
        }
        self.vertical = vertical;
        Ok(())
    }

    /// The vertical-channel treatment.
    pub fn vertical_channel(&self) -> VerticalChannel {
        self.vertical
    }

    /// The current navigation state.
    pub fn state(&self) -> &InsState {
        &self.state
    }

    /// Replaces the navigation state (e.g. an error-state filter's feedback
    /// correction). The IMU-increment memory (for coning/sculling) is kept; the
    /// navigation history used for mid-interval extrapolation is cleared, so the next
    /// step evaluates gravity, Coriolis and frame rates at the new state.
    ///
    /// # Errors
    /// If `state` is not finite or at a pole; the strapdown is then unchanged.
    pub fn set_state(&mut self, state: InsState) -> Result<(), InsError> {
        state.check()?;
        self.state = state;
        self.history = None;
        Ok(())
    }

    /// Forgets the previous increment and navigation history (as after `new`).
    pub fn reset_history(&mut self) {
        self.history = None;
        self.prev_increment = None;
    }

    /// The last increment processed (used for coning/sculling at the next step).
    pub fn previous_increment(&self) -> Option<&ImuIncrement> {
        self.prev_increment.as_ref()
    }

    /// Integrates one IMU increment (see the module docs for the equations).
    ///
    /// # Errors
    /// [`InsError::NonPositiveDt`] / [`InsError::NonFinite`] for a bad increment or a
    /// step whose new state would not be finite (overflow),
    /// [`InsError::LatitudeOutOfRange`] if the step would reach a pole. On error the
    /// strapdown is unchanged. The strapdown has no clock: the caller adds the time
    /// stamp to the error.
    pub fn step(&mut self, inc: &ImuIncrement) -> Result<(), InsError> {
        inc.check()?;
        let s = &self.state;
        let dt = inc.dt;
        let mid = mid_terms(s.lat, s.h, &s.vel_in_nav, self.history.as_ref(), dt);
        let (dth_prev, dv_prev) = match &self.prev_increment {
            Some(p) => (p.delta_theta, p.delta_v),
            None => (Vector3::zeros(), Vector3::zeros()),
        };
        let dth = &inc.delta_theta;
        let dv = &inc.delta_v;

        // Attitude.
        let phi = dth + coning(&dth_prev, dth);
        let mut q_new = quat_from_rotation_vector(&-mid.zeta)
            * s.nav_from_body
            * quat_from_rotation_vector(&phi);
        q_new.renormalize();

        // Velocity.
        let dv_sf_body = dv + dth.cross(dv) * 0.5 + sculling(&dth_prev, &dv_prev, dth, dv);
        let dv_sf_nav =
            quat_from_rotation_vector(&(mid.zeta * -0.5)) * (s.nav_from_body * dv_sf_body);
        let mut vel_new = s.vel_in_nav + dv_sf_nav + mid.dv_grav_cor;

        // Position.
        let (lat_new, lon_new, mut h_new) = position_update(
            s.lat,
            mid.sin_cos_lat,
            s.lon,
            s.h,
            &s.vel_in_nav,
            &vel_new,
            dt,
        );
        if let VerticalChannel::Hold { h } = self.vertical {
            h_new = h;
            vel_new.z = 0.0;
        }
        if !lat_new.is_finite() || lat_new.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(InsError::LatitudeOutOfRange { lat: lat_new });
        }
        let new_state = InsState {
            lat: lat_new,
            lon: lon_new,
            h: h_new,
            vel_in_nav: vel_new,
            nav_from_body: q_new,
        };
        crate::error::check_finite("propagated vel_in_nav", new_state.vel_in_nav.as_slice())?;
        // A finite velocity can still overflow the position (absurd dt or increment).
        crate::error::check_finite(
            "propagated position (lat, lon, h)",
            &[lat_new, lon_new, h_new],
        )?;
        crate::error::check_finite("propagated attitude quaternion", q_new.coords.as_slice())?;
        self.history = Some(NavHistory {
            lat: s.lat,
            h: s.h,
            vel: s.vel_in_nav,
            dt,
        });
        self.state = new_state;
        self.prev_increment = Some(*inc);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::earth::{Geodetic, curvilinear_offset, meridian_radius, normal_gravity};
    use crate::imu_from_truth::{imu_from_truth, stationary_truth};
    use approx::assert_abs_diff_eq;
    use nalgebra::UnitQuaternion;

    fn busan() -> Geodetic {
        Geodetic::new(35f64.to_radians(), 129f64.to_radians(), -50.0)
    }

    /// The first-order mid-point radii give the same position step as the exact
    /// radii to a few ulps of the latitude / longitude, from slow to 1000 m/s at
    /// 100 Hz and over all latitudes; larger steps take the exact path. Negative
    /// control: dropping the first-order term (radii at `L`) misses the bound.
    #[test]
    fn linearized_mid_point_radii_match_the_exact_position_update() {
        let ulps = |x: f64| 4.0 * f64::EPSILON * x.abs().max(1e-3);
        let mut zeroth_order_misses = 0;
        for lat_deg in (-88..=88).step_by(8) {
            let lat = f64::from(lat_deg).to_radians() + 1e-3;
            let sc = lat.sin_cos();
            for &(speed, dt) in &[
                (0.3, 0.01),
                (5.0, 0.01),
                (250.0, 0.01),
                (1000.0, 0.01),
                (40.0, 1.0),
            ] {
                for &h in &[-6000.0, -50.0, 9000.0] {
                    let vel_prev = Vector3::new(0.8 * speed, -0.6 * speed, 0.2);
                    let vel = Vector3::new(0.79 * speed, -0.61 * speed, 0.1);
                    let lon = 2.2;
                    let fast = position_update(lat, sc, lon, h, &vel_prev, &vel, dt);
                    let exact = position_update_with(lat, sc, lon, h, (&vel_prev, &vel), dt, 0.0);
                    let step = (exact.0 - lat).abs().max((exact.1 - lon).abs());
                    let tol = |x: f64| ulps(x) + 1e-12 * step;
                    assert!(
                        (fast.0 - exact.0).abs() <= tol(lat),
                        "lat {lat_deg} {speed} {dt} {h}"
                    );
                    assert!(
                        (fast.1 - exact.1).abs() <= tol(lon),
                        "lon {lat_deg} {speed} {dt} {h}"
                    );
                    assert_eq!(fast.2, exact.2);
                    // zeroth order: R_N at L for the whole step
                    let dr_n = 0.5 * dt * (vel_prev.x + vel.x);
                    let h_m = h - 0.25 * dt * (vel_prev.z + vel.z);
                    let lat_0 = lat + dr_n / (meridian_radius(lat) + h_m);
                    if (lat_0 - exact.0).abs() > tol(lat) {
                        zeroth_order_misses += 1;
                    }
                }
            }
        }
        assert!(zeroth_order_misses > 50, "{zeroth_order_misses}");
    }

    #[test]
    fn bad_increments_are_rejected_and_leave_state_unchanged() {
        let s0 = InsState::new(busan(), Vector3::zeros(), UnitQuaternion::identity());
        let mut ins = Strapdown::new(s0).unwrap();
        let ok = ImuIncrement::new(0.01, Vector3::zeros(), Vector3::new(0.0, 0.0, -0.098));
        let cases = [
            (ImuIncrement { dt: 0.0, ..ok }, "dt"),
            (ImuIncrement { dt: -0.01, ..ok }, "dt"),
            (ImuIncrement { dt: f64::NAN, ..ok }, "dt"),
            (
                ImuIncrement {
                    delta_theta: Vector3::new(0.0, f64::NAN, 0.0),
                    ..ok
                },
                "delta_theta",
            ),
            (
                ImuIncrement {
                    delta_v: Vector3::new(0.0, 0.0, f64::INFINITY),
                    ..ok
                },
                "delta_v",
            ),
        ];
        for (inc, field) in cases {
            let err = ins.step(&inc).unwrap_err();
            assert!(err.to_string().contains(field), "{err}");
            assert_eq!(ins.state(), &s0);
            assert!(ins.previous_increment().is_none());
        }
        assert!(matches!(
            ins.step(&ImuIncrement { dt: 0.0, ..ok }),
            Err(InsError::NonPositiveDt { .. })
        ));
        let mut bad = s0;
        bad.lat = std::f64::consts::FRAC_PI_2;
        assert!(matches!(
            Strapdown::new(bad),
            Err(InsError::LatitudeOutOfRange { .. })
        ));
        bad.lat = f64::NAN;
        assert!(Strapdown::new(bad).is_err());
        assert!(ins.set_state(bad).is_err());
        assert!(ins.step(&ok).is_ok());
    }

    /// Bad input (`fathom_estimators` crate docs, "Bad input"): finite but absurd
    /// increments whose step would leave a non-finite state (here the height
    /// overflows to -inf while the velocity stays finite) are refused and nothing is
    /// committed.
    #[test]
    fn a_step_to_a_non_finite_state_is_refused() {
        let s0 = InsState::new(busan(), Vector3::zeros(), UnitQuaternion::identity());
        let mut ins = Strapdown::new(s0).unwrap();
        let absurd = ImuIncrement::new(10.0, Vector3::zeros(), Vector3::new(0.0, 0.0, 1e308));
        let err = ins.step(&absurd).unwrap_err();
        assert!(matches!(err, InsError::NonFinite { .. }), "{err}");
        assert_eq!(ins.state(), &s0);
        assert!(ins.previous_increment().is_none());
        // Negative control: a sane increment still steps.
        let ok = ImuIncrement::new(0.01, Vector3::zeros(), Vector3::new(0.0, 0.0, -0.098));
        ins.step(&ok).unwrap();
        assert!(ins.state().h.is_finite());
    }

    #[test]
    fn northward_motion_increases_latitude() {
        // Truth: moving north at 5 m/s along a meridian at constant height, level.
        let v = 5.0;
        let p0 = busan();
        let rn = meridian_radius(p0.lat) + p0.h;
        let truth: Vec<_> = (0..1001)
            .map(|k| {
                let t = k as f64 * 0.01;
                crate::imu_from_truth::TruthSample {
                    time: t,
                    lat: p0.lat + v * t / rn, // R_N variation over 50 m is negligible
                    lon: p0.lon,
                    h: p0.h,
                    vel_in_nav: Vector3::new(v, 0.0, 0.0),
                    nav_from_body: UnitQuaternion::identity(),
                }
            })
            .collect();
        let incs = imu_from_truth(&truth).unwrap();
        let mut ins = Strapdown::new(truth[0].to_ins_state()).unwrap();
        for inc in &incs {
            ins.step(inc).unwrap();
        }
        let s = ins.state();
        assert!(s.lat > p0.lat);
        let d = curvilinear_offset(&p0, &s.position());
        assert_abs_diff_eq!(d.x, 50.0, epsilon = 1e-6);
        assert_abs_diff_eq!(d.y, 0.0, epsilon = 1e-9);
        // Moving north, the level platform must pitch about -east: the gyro sees
        // -v/R_N about body y (plus Earth rate).
        let w_e = incs[10].mean_angular_rate().y;
        assert_abs_diff_eq!(w_e, -v / rn, epsilon = 1e-12);
    }

    #[test]
    fn held_vertical_channel_stays_at_height() {
        let p = busan();
        let truth = stationary_truth(p, UnitQuaternion::identity(), 0.01, 3).unwrap();
        let mut inc = imu_from_truth(&truth).unwrap()[1];
        inc.delta_v.z += 1e-3 * 0.01; // 1 mm/s^2 vertical accelerometer bias
        let mut free = Strapdown::new(truth[0].to_ins_state()).unwrap();
        let mut held = free
            .clone()
            .with_vertical_channel(VerticalChannel::Hold { h: p.h })
            .unwrap();
        for _ in 0..10_000 {
            free.step(&inc).unwrap();
            held.step(&inc).unwrap();
        }
        assert_eq!(held.state().h, p.h);
        assert_eq!(held.state().vel_in_nav.z, 0.0);
        // Free: 0.5 * 1e-3 * 100^2 = 5 m down (h decreases), slightly more from the
        // gravity-gradient instability.
        let dh = free.state().h - p.h;
        assert!(dh < -5.0 && dh > -5.2, "free vertical error {dh} m");
    }

    /// Acceptance (spec C): a north accelerometer bias on a stationary INS gives the
    /// Schuler oscillation, period 84.4 min, amplitude b / omega_s^2.
    ///
    /// Vertical channel held at the true height (it is unstable). What is measured: the
    /// north position error `e(t) ~ (b/omega_s^2)(1 - cos(Omega sin L t) cos(omega_s t))`
    /// (starts at 0, oscillates between ~0 and ~2 b/omega_s^2; the slow Foucault factor
    /// `cos(Omega sin L t)` rotates the oscillation plane by ~12 deg per period). Period =
    /// time between the two maxima (and, separately, the two minima) of `e`, refined by a
    /// parabola through the 1 s samples; amplitude = (first maximum - first minimum) / 2,
    /// compared with `b / omega_s^2`, `omega_s^2 = gamma(L, h) / (R_N + h)`.
    #[test]
    fn accelerometer_bias_gives_schuler_oscillation() {
        let p = busan();
        let truth = stationary_truth(p, UnitQuaternion::identity(), 0.01, 3).unwrap();
        let mut inc = imu_from_truth(&truth).unwrap()[1];
        let b = 1e-4 * 9.806_65; // 0.1 mg, north (body x = north here)
        inc.delta_v.x += b * inc.dt;
        let mut ins = Strapdown::new(truth[0].to_ins_state())
            .unwrap()
            .with_vertical_channel(VerticalChannel::Hold { h: p.h })
            .unwrap();
        // ~2.05 Schuler periods, north error sampled every 1 s.
        let n_sec = 10_400;
        let mut north = Vec::with_capacity(n_sec + 1);
        north.push(0.0);
        for _ in 0..n_sec {
            for _ in 0..100 {
                ins.step(&inc).unwrap();
            }
            north.push(curvilinear_offset(&p, &ins.state().position()).x);
        }
        // Local extrema with parabolic refinement: (time, value).
        let refine = |i: usize| {
            let (a, c, e) = (north[i - 1], north[i], north[i + 1]);
            let den = a - 2.0 * c + e;
            let off = 0.5 * (a - e) / den;
            (i as f64 + off, c - 0.25 * (a - e) * off)
        };
        let maxima: Vec<_> = (1..n_sec)
            .filter(|&i| north[i] > north[i - 1] && north[i] >= north[i + 1])
            .map(refine)
            .collect();
        let minima: Vec<_> = (1..n_sec)
            .filter(|&i| north[i] < north[i - 1] && north[i] <= north[i + 1])
            .map(refine)
            .collect();
        assert_eq!(maxima.len(), 2, "maxima {maxima:?}");
        assert_eq!(minima.len(), 2, "minima {minima:?}");
        let period = maxima[1].0 - maxima[0].0;
        let period_from_minima = minima[1].0 - minima[0].0;
        let amplitude = (maxima[0].1 - minima[0].1) / 2.0;
        let omega_s2 = normal_gravity(p.lat, p.h) / (meridian_radius(p.lat) + p.h);
        let expected_period = 2.0 * std::f64::consts::PI / omega_s2.sqrt();
        let expected_amplitude = b / omega_s2;
        eprintln!(
            "Schuler: period {:.2} s = {:.3} min (2 pi/omega_s = {:.3} min; minima at {:.1} s, {:.1} s: {:.3} min), \
             amplitude {:.3} m (b/omega_s^2 = {:.3} m), first max {:.3} m, min {:.3} m",
            period,
            period / 60.0,
            expected_period / 60.0,
            minima[0].0,
            minima[1].0,
            period_from_minima / 60.0,
            amplitude,
            expected_amplitude,
            maxima[0].1,
            minima[0].1
        );
        assert!((period / 60.0 / 84.4 - 1.0).abs() < 0.01);
        assert!((period / expected_period - 1.0).abs() < 0.01);
        assert!((period_from_minima / 60.0 / 84.4 - 1.0).abs() < 0.01);
        assert!((amplitude / expected_amplitude - 1.0).abs() < 0.05);
    }
}
