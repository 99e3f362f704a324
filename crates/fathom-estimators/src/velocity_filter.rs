//! The velocity Kalman filter (VKF) and the switching box of the velocity-filter-aided
//! navigation (spec C; paper §2.3, eqs. 5-12, rebuilt from the text).
//!
//! # VKF
//!
//! State `x = [V, sf, b]`: forward body speed, RPM scale factor (m/s per rpm) and
//! RPM bias (m/s). With the propeller revolutions `rpm_k`:
//!
//! ```text
//! V_{k+1}  = sf_k rpm_k + b_k + w_V        (eq. 6)
//! sf_{k+1} = sf_k + w_sf,  b_{k+1} = b_k + w_b   (random walks, small noise)
//! z_k      = V_k + v,  z = (C_n^b v_dvl)_x, the DVL forward body speed   (eqs. 5, 7-10)
//! ```
//!
//! so `F = [[0, rpm, 1], [0, 1, 0], [0, 0, 1]]`,
//! `Q = diag(sf^2 sigma_rpm^2 + q_V, q_sf dt, q_b dt)`, `H = [1, 0, 0]`,
//! `R = sigma_dvl^2`. The update is applied only while the DVL is judged valid (the
//! echo sounder's altitude within the DVL range); while invalid only the prediction
//! runs, so `sf` and `b` are **held** at their last estimates (their variances grow
//! by the random-walk noise). `sf` and `b` are separately observable only while the
//! revolutions vary (acceleration phases); at constant speed only `sf rpm + b` is.
//!
//! # Switching box (eqs. 11-12)
//!
//! Altitude `<= range`: the DVL's navigation-frame velocity with its noise
//! covariance. Otherwise the RPM-derived velocity `C_b^n [sf rpm + b, 0, 0]^T` with
//! covariance `C_b^n diag(s_V^2, s_lat^2, s_lat^2) C_n^b`, where
//! `s_V^2 = [rpm, 1] P_(sf,b) [rpm, 1]^T + sf^2 sigma_rpm^2 + q_V` is the VKF's own
//! uncertainty of the RPM speed and `s_lat` a setting for the lateral and vertical
//! body speeds assumed zero (sideslip, heave, current).

use fathom_core::Gaussian;
use nalgebra::{Matrix1, Matrix3, RowVector3, Vector1, Vector3};

use crate::{EstimatorError, KalmanFilter, UpdateInfo};

/// Unchecked VKF parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityFilterParams {
    /// Initial forward speed estimate, m/s.
    pub speed0: f64,
    /// Initial scale-factor estimate, m/s per rpm.
    pub sf0: f64,
    /// Initial bias estimate, m/s.
    pub b0: f64,
    /// Initial sigmas `[V, sf, b]` (> 0).
    pub sigma0: [f64; 3],
    /// Revolution noise sigma, rpm (>= 0).
    pub rpm_sigma: f64,
    /// Extra forward-speed process noise variance per step, (m/s)^2 (>= 0).
    pub speed_process_var: f64,
    /// Scale-factor random-walk intensity, (m/s/rpm)^2 per s (>= 0).
    pub sf_rw_psd: f64,
    /// Bias random-walk intensity, (m/s)^2 per s (>= 0).
    pub bias_rw_psd: f64,
    /// DVL forward-speed noise sigma, m/s (> 0).
    pub dvl_sigma: f64,
}

impl VelocityFilterParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] / [`EstimatorError::Core`] naming the parameter.
    pub fn check(&self) -> Result<VelocityFilterConfig, EstimatorError> {
        use fathom_core::error::{ensure_finite, ensure_non_negative, ensure_positive};
        ensure_finite(
            "vkf speed0, sf0, b0",
            [self.speed0, self.sf0, self.b0].iter(),
        )?;
        for (i, s) in self.sigma0.iter().enumerate() {
            ensure_positive(&format!("vkf sigma0[{i}]"), *s)?;
        }
        ensure_non_negative("vkf rpm_sigma", self.rpm_sigma)?;
        ensure_non_negative("vkf speed_process_var", self.speed_process_var)?;
        ensure_non_negative("vkf sf_rw_psd", self.sf_rw_psd)?;
        ensure_non_negative("vkf bias_rw_psd", self.bias_rw_psd)?;
        ensure_positive("vkf dvl_sigma", self.dvl_sigma)?;
        Ok(VelocityFilterConfig { params: *self })
    }
}

/// Validated VKF parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityFilterConfig {
    params: VelocityFilterParams,
}

impl VelocityFilterConfig {
    /// The validated parameters.
    pub fn params(&self) -> &VelocityFilterParams {
        &self.params
    }
}

/// The velocity Kalman filter (see the module docs).
///
/// Bad input: a non-finite rpm, DVL speed or time is an error naming it with the
/// time stamp; a covariance that stops being positive definite (e.g. an absurd rpm)
/// is an error at the step's time; the filter is unchanged on error.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityFilter {
    kf: KalmanFilter<3>,
    params: VelocityFilterParams,
    updates: usize,
}

impl VelocityFilter {
    /// A filter at time `t0` with the configured prior.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`].
    pub fn new(config: &VelocityFilterConfig, t0: f64) -> Result<Self, EstimatorError> {
        let p = config.params;
        let s = p.sigma0;
        let prior = Gaussian::new_unchecked(
            Vector3::new(p.speed0, p.sf0, p.b0),
            Matrix3::from_diagonal(&Vector3::new(s[0] * s[0], s[1] * s[1], s[2] * s[2])),
        );
        Ok(Self {
            kf: KalmanFilter::new(prior, t0)?,
            params: p,
            updates: 0,
        })
    }

    /// Predicts to `t` with the revolutions `rpm` measured at the current time:
    /// `V = sf rpm + b` (eq. 6), `sf`, `b` held (random walks).
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`] for a non-finite `rpm`, otherwise as
    /// [`KalmanFilter::predict`].
    pub fn predict(&mut self, rpm: f64, t: f64) -> Result<(), EstimatorError> {
        if !rpm.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "rpm".into(),
                index: 0,
                value: rpm,
                time: t,
            });
        }
        let dt = (t - self.kf.time()).max(0.0);
        let p = &self.params;
        let sf = self.kf.state()[1];
        let f = Matrix3::new(0.0, rpm, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let q = Matrix3::from_diagonal(&Vector3::new(
            sf * sf * p.rpm_sigma * p.rpm_sigma + p.speed_process_var,
            p.sf_rw_psd * dt,
            p.bias_rw_psd * dt,
        ));
        self.kf.predict(&f, &q, t)
    }

    /// Updates with the DVL forward body speed `dvl_forward_speed` (valid DVL only).
    ///
    /// # Errors
    /// As [`KalmanFilter::update`].
    pub fn update(&mut self, dvl_forward_speed: f64) -> Result<UpdateInfo<1>, EstimatorError> {
        let h = RowVector3::new(1.0, 0.0, 0.0);
        let r = Matrix1::new(self.params.dvl_sigma * self.params.dvl_sigma);
        let info = self.kf.update(&Vector1::new(dvl_forward_speed), &h, &r)?;
        self.updates += 1;
        Ok(info)
    }

    /// One VKF cycle at time `t`: predict with `rpm`, then update with the DVL forward
    /// speed if `dvl_forward_speed` is `Some` (the switching box judged the DVL valid);
    /// with `None`, `sf` and `b` are held. All or nothing: on error the filter is
    /// unchanged (no prediction is committed either).
    ///
    /// # Errors
    /// As [`VelocityFilter::predict`] / [`VelocityFilter::update`] (the update's
    /// errors then carry `t`).
    pub fn step(
        &mut self,
        rpm: f64,
        dvl_forward_speed: Option<f64>,
        t: f64,
    ) -> Result<(), EstimatorError> {
        let mut next = self.clone();
        next.predict(rpm, t)?;
        if let Some(z) = dvl_forward_speed {
            next.update(z)?;
        }
        *self = next;
        Ok(())
    }

    /// Forward speed estimate `V`, m/s.
    pub fn speed(&self) -> f64 {
        self.kf.state()[0]
    }

    /// Scale-factor estimate `sf`, m/s per rpm.
    pub fn scale_factor(&self) -> f64 {
        self.kf.state()[1]
    }

    /// Bias estimate `b`, m/s.
    pub fn bias(&self) -> f64 {
        self.kf.state()[2]
    }

    /// Standard deviations `[V, sf, b]` from the covariance diagonal.
    pub fn sigmas(&self) -> [f64; 3] {
        let p = self.kf.covariance();
        [p[(0, 0)].sqrt(), p[(1, 1)].sqrt(), p[(2, 2)].sqrt()]
    }

    /// Number of DVL updates applied so far.
    pub fn num_updates(&self) -> usize {
        self.updates
    }

    /// The underlying filter (state, covariance, time).
    pub fn filter(&self) -> &KalmanFilter<3> {
        &self.kf
    }

    /// RPM-derived forward speed `sf rpm + b` and its variance (a pure function: a
    /// non-finite `rpm` gives non-finite values, which the aided filter's update then
    /// refuses with an error)
    /// `[rpm, 1] P_(sf,b) [rpm, 1]^T + sf^2 sigma_rpm^2 + q_V`.
    pub fn rpm_speed(&self, rpm: f64) -> (f64, f64) {
        let x = self.kf.state();
        let cov = self.kf.covariance();
        let var = rpm * rpm * cov[(1, 1)]
            + 2.0 * rpm * cov[(1, 2)]
            + cov[(2, 2)]
            + x[1] * x[1] * self.params.rpm_sigma * self.params.rpm_sigma
            + self.params.speed_process_var;
        (x[1] * rpm + x[2], var)
    }
}

/// Which sensor the switching box passed on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VelocitySource {
    /// The DVL (altitude within range).
    Dvl,
    /// The RPM-derived velocity of the VKF.
    Rpm,
}

/// A navigation-frame velocity aid with its noise covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityAid {
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Its noise covariance, (m/s)^2.
    pub cov: Matrix3<f64>,
    /// Where it came from.
    pub source: VelocitySource,
}

/// The switching box (eq. 12): chooses DVL or RPM velocity from the echo-sounder
/// altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchingBox {
    range: f64,
    lateral_sigma: f64,
}

impl SwitchingBox {
    /// A switching box for a DVL of range `range` m; `lateral_sigma` (m/s) is the
    /// uncertainty of the zero lateral / vertical body speed assumed with RPM aiding.
    ///
    /// # Errors
    /// [`EstimatorError::Core`] for a non-positive `range` or `lateral_sigma`.
    pub fn new(range: f64, lateral_sigma: f64) -> Result<Self, EstimatorError> {
        fathom_core::error::ensure_positive("switching box range", range)?;
        fathom_core::error::ensure_positive("switching box lateral_sigma", lateral_sigma)?;
        Ok(Self {
            range,
            lateral_sigma,
        })
    }

    /// The DVL range, m.
    pub fn range(&self) -> f64 {
        self.range
    }

    /// Whether the DVL is judged valid at the measured altitude (`<= range`; a NaN
    /// altitude is judged invalid).
    pub fn dvl_valid(&self, measured_altitude: f64) -> bool {
        measured_altitude <= self.range
    }

    /// The velocity aid: the DVL's `dvl_vel_in_nav` with covariance `dvl_cov` when
    /// [`SwitchingBox::dvl_valid`], else `C_b^n [V_rpm, 0, 0]` from the VKF's
    /// `rpm_speed = (mean, variance)` with the attitude `nav_from_body` (`C_b^n`).
    pub fn select(
        &self,
        measured_altitude: f64,
        dvl_vel_in_nav: &Vector3<f64>,
        dvl_cov: &Matrix3<f64>,
        rpm_speed: (f64, f64),
        nav_from_body: &Matrix3<f64>,
    ) -> VelocityAid {
        if self.dvl_valid(measured_altitude) {
            return VelocityAid {
                vel_in_nav: *dvl_vel_in_nav,
                cov: *dvl_cov,
                source: VelocitySource::Dvl,
            };
        }
        let (v, var) = rpm_speed;
        let lat = self.lateral_sigma * self.lateral_sigma;
        let cov_body = Matrix3::from_diagonal(&Vector3::new(var, lat, lat));
        let cov = nav_from_body * cov_body * nav_from_body.transpose();
        VelocityAid {
            vel_in_nav: nav_from_body * Vector3::new(v, 0.0, 0.0),
            cov: (cov + cov.transpose()) * 0.5,
            source: VelocitySource::Rpm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    const K: f64 = 0.01;
    const B: f64 = 0.05;

    fn params() -> VelocityFilterParams {
        VelocityFilterParams {
            speed0: 2.0,
            sf0: 0.008,
            b0: 0.0,
            sigma0: [0.5, 0.003, 0.2],
            rpm_sigma: 1.0,
            speed_process_var: 1e-4,
            sf_rw_psd: 1e-14,
            bias_rw_psd: 1e-10,
            dvl_sigma: 0.02,
        }
    }

    /// Bad input (crate docs): a non-finite rpm, DVL speed or time is an error with the
    /// time stamp, an rpm so large that the covariance overflows is a
    /// positive-definiteness error at the target time, and `step` is all-or-nothing.
    #[test]
    fn bad_input_is_an_error_with_the_time_and_the_filter_is_unchanged() {
        let cfg = params().check().unwrap();
        let mut f = VelocityFilter::new(&cfg, 0.0).unwrap();
        f.step(1000.0, Some(8.0), 1.0).unwrap();
        let before = f.clone();
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = f.predict(bad, 2.0).unwrap_err();
            assert!(
                matches!(&e, EstimatorError::NonFinite { time, .. } if *time == 2.0),
                "{e}"
            );
            let e = f.update(bad).unwrap_err();
            assert!(
                matches!(&e, EstimatorError::NonFinite { time, .. } if *time == 1.0),
                "{e}"
            );
            let e = f.step(1000.0, Some(bad), 2.0).unwrap_err();
            assert!(
                matches!(&e, EstimatorError::NonFinite { time, .. } if *time == 2.0),
                "{e}"
            );
            assert_eq!(f, before);
        }
        let e = f.predict(1000.0, f64::NAN).unwrap_err();
        assert!(matches!(e, EstimatorError::NonFinite { .. }), "{e}");
        let e = f.step(1e200, None, 2.0).unwrap_err();
        assert!(e.to_string().contains("predicted covariance P"), "{e}");
        assert_eq!(e.time(), Some(2.0));
        assert_eq!(f, before);
        assert_eq!(f.num_updates(), 1);
    }

    /// Speed profile of the vkf route: 2 m/s accelerating to 5.144 m/s over 120 s.
    fn speed(t: f64) -> f64 {
        if t < 120.0 {
            2.0 + 3.144 * 0.5 * (1.0 - (std::f64::consts::PI * t / 120.0).cos())
        } else {
            5.144
        }
    }

    /// Runs the VKF at 5 Hz: valid DVL (forward speed + N(0, 0.02^2) + `dvl_bias`)
    /// until `t_invalid`, then no DVL until `t_end`. Returns the filter at
    /// `t_invalid` and at `t_end`.
    fn run(
        seed: u64,
        dvl_bias: f64,
        t_invalid: f64,
        t_end: f64,
    ) -> (VelocityFilter, VelocityFilter) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let cfg = params().check().unwrap();
        let mut vkf = VelocityFilter::new(&cfg, 0.0).unwrap();
        let mut at_invalid = None;
        let n = (t_end / 0.2).round() as usize;
        for k in 1..=n {
            let t = k as f64 * 0.2;
            let v = speed(t);
            let n_rpm: f64 = StandardNormal.sample(&mut rng);
            let rpm = (v - B) / K + n_rpm;
            let n_dvl: f64 = StandardNormal.sample(&mut rng);
            let valid = t <= t_invalid;
            let z = valid.then_some(v + dvl_bias + 0.02 * n_dvl);
            vkf.step(rpm, z, t).unwrap();
            if at_invalid.is_none() && t >= t_invalid {
                at_invalid = Some(vkf.clone());
            }
        }
        (at_invalid.unwrap(), vkf)
    }

    /// Acceptance (spec C): with the DVL valid, `sf` and `b` converge to the true RPM
    /// constants within 3 sigma of their estimated covariance (and their sigmas
    /// shrink well below the prior); during an invalid interval they are held.
    /// Statistical check over 100 seeds: for a consistent filter each of the two
    /// errors is within 3 sigma with probability 0.9973, so the binomial expectation
    /// of misses over 200 checks is 0.54; more than 5 misses has probability < 1e-3.
    #[test]
    fn sf_and_bias_converge_within_3_sigma_and_are_held_when_invalid() {
        let mut misses = 0;
        for seed in 0..100 {
            let (valid_end, end) = run(seed, 0.0, 300.0, 400.0);
            let [_, s_sf, s_b] = valid_end.sigmas();
            assert!(s_sf < 0.003 / 10.0 && s_b < 0.2 / 10.0, "{s_sf} {s_b}");
            if (valid_end.scale_factor() - K).abs() > 3.0 * s_sf {
                misses += 1;
            }
            if (valid_end.bias() - B).abs() > 3.0 * s_b {
                misses += 1;
            }
            // Held while invalid: exactly the values at the start of the interval.
            assert_eq!(end.scale_factor(), valid_end.scale_factor());
            assert_eq!(end.bias(), valid_end.bias());
            assert_eq!(end.num_updates(), valid_end.num_updates());
            // ... and the RPM speed still follows the vehicle.
            assert!((end.speed() - 5.144).abs() < 0.1);
        }
        assert!(misses <= 5, "{misses} of 200 errors outside 3 sigma");
        // Typical sizes for the record.
        let (f, _) = run(0, 0.0, 300.0, 300.0);
        eprintln!(
            "sf = {:.6} (true {K}, sigma {:.2e}), b = {:.4} (true {B}, sigma {:.2e})",
            f.scale_factor(),
            f.sigmas()[1],
            f.bias(),
            f.sigmas()[2]
        );
    }

    /// Negative control: a DVL with a 0.2 m/s bias biases `b` by 0.2 m/s, far outside
    /// the 3-sigma band, so the check above can fail.
    #[test]
    fn biased_dvl_fails_the_3_sigma_check() {
        let (f, _) = run(1, 0.2, 300.0, 300.0);
        assert!((f.bias() - B).abs() > 3.0 * f.sigmas()[2]);
        assert_abs_diff_eq!(f.bias(), B + 0.2, epsilon = 0.05);
    }

    #[test]
    fn switching_box_selects_and_rotates() {
        let sb = SwitchingBox::new(100.0, 0.05).unwrap();
        let c =
            *nalgebra::Rotation3::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2).matrix();
        let dvl = Vector3::new(1.0, 2.0, 3.0);
        let r = Matrix3::identity() * 4e-4;
        let a = sb.select(99.0, &dvl, &r, (5.0, 1e-4), &c);
        assert_eq!(a.source, VelocitySource::Dvl);
        assert_eq!(a.vel_in_nav, dvl);
        let a = sb.select(101.0, &dvl, &r, (5.0, 1e-4), &c);
        assert_eq!(a.source, VelocitySource::Rpm);
        // Heading east: forward speed goes to the east component.
        assert_abs_diff_eq!(a.vel_in_nav, Vector3::new(0.0, 5.0, 0.0), epsilon = 1e-12);
        assert_abs_diff_eq!(a.cov[(1, 1)], 1e-4, epsilon = 1e-15);
        assert_abs_diff_eq!(a.cov[(0, 0)], 0.0025, epsilon = 1e-15);
        assert!(!sb.dvl_valid(f64::NAN));
        assert!(SwitchingBox::new(0.0, 0.1).is_err());
        let bad = VelocityFilterParams {
            dvl_sigma: 0.0,
            ..params()
        };
        assert!(bad.check().is_err());
        let mut vkf = VelocityFilter::new(&params().check().unwrap(), 0.0).unwrap();
        assert!(vkf.predict(f64::NAN, 0.2).is_err());
        let (v, var) = vkf.rpm_speed(500.0);
        assert_abs_diff_eq!(v, 4.0, epsilon = 1e-12);
        assert!(var > 500.0 * 500.0 * 0.003 * 0.003);
    }
}
