//! Range-beacon localization EKF of paper B (seed 003, Table 12): state
//! `x = (x, y, z, psi)` in NED (roll and pitch zero), dead reckoning from the measured
//! body velocity (DVL) and yaw rate (AHRS), corrected by ranges to known beacons and
//! depth. Built on the generic [`crate::ekf`] core; run it under an AS / SC / SI
//! policy with [`crate::schemes::SchemeFilter`].
//!
//! # Motion model ([`DvlAhrsMotion`])
//! With the held input `(u, v, w)` (body velocity) and `r` (yaw rate), over `dt` and
//! the midpoint heading `psi_m = psi + r dt / 2`:
//!
//! ```text
//! x' = x + dt (cos psi_m u - sin psi_m v)      y' = y + dt (sin psi_m u + cos psi_m v)
//! z' = z + dt w                                psi' = wrap(psi + dt r)
//! ```
//!
//! `F = I` plus `dx'/dpsi = -dt (sin psi_m u + cos psi_m v)`,
//! `dy'/dpsi = dt (cos psi_m u - sin psi_m v)`.
//!
//! Process noise: a held input sample is wrong by `e ~ N(0, sigma^2)` for the whole
//! time `tau` it is held (its sensor period), so the integrated error over one hold
//! has variance `tau^2 sigma^2`. The model uses the white-noise equivalent with power
//! spectral density `q = sigma^2 tau`, which gives the same variance at the end of each
//! hold whatever the prediction step: `Q = dt diag(R(psi_m) diag(q_u, q_v) R^T, q_w, q_r)`.
//!
//! # Measurements ([`BeaconMeasurement`])
//! Range to beacon `b`: `h = |p - b|`, `H = [(p - b)^T / h, 0]`; depth: `h = z`,
//! `H = [0, 0, 1, 0]`.

use crate::{
    EstimatorError,
    ekf::{MotionModel, Propagation, ScalarModel},
};
use fathom_core::units::wrap_pi;
use nalgebra::{Matrix2, Matrix4, RowVector4, Vector3, Vector4};

/// State dimension of the beacon EKF: `(x, y, z, psi)`.
pub const BEACON_STATE_DIM: usize = 4;

/// Unchecked parameters of [`DvlAhrsMotion`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlAhrsMotionParams {
    /// Error sigma of the held body velocity `(u, v, w)`, m/s (>= 0).
    pub vel_sigma: [f64; 3],
    /// Hold time (DVL period) of a velocity sample, s (> 0).
    pub vel_hold: f64,
    /// Error sigma of the held yaw rate, rad/s (>= 0).
    pub yaw_rate_sigma: f64,
    /// Hold time (AHRS period) of a yaw-rate sample, s (> 0).
    pub yaw_rate_hold: f64,
}

impl DvlAhrsMotionParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::Core`] naming the field for a negative / non-finite sigma or a
    /// non-positive hold time.
    pub fn check(&self) -> Result<DvlAhrsMotion, EstimatorError> {
        use fathom_core::error::{ensure_non_negative, ensure_positive};
        for (name, s) in ["vel_sigma.u", "vel_sigma.v", "vel_sigma.w"]
            .iter()
            .zip(self.vel_sigma)
        {
            ensure_non_negative(name, s)?;
        }
        ensure_non_negative("yaw_rate_sigma", self.yaw_rate_sigma)?;
        ensure_positive("vel_hold", self.vel_hold)?;
        ensure_positive("yaw_rate_hold", self.yaw_rate_hold)?;
        Ok(DvlAhrsMotion {
            vel_psd: Vector3::from_iterator(self.vel_sigma.iter().map(|s| s * s * self.vel_hold)),
            yaw_rate_psd: self.yaw_rate_sigma.powi(2) * self.yaw_rate_hold,
        })
    }
}

/// The quantity named in errors about the held input.
const INPUT_NAME: &str = "DVL/AHRS input (u, v, w, r)";

/// Dead reckoning from DVL velocity and AHRS yaw rate (module docs).
///
/// Bad input: a non-finite held input is an error of the next prediction naming the
/// component (index 0..3 = `u, v, w`, 3 = `r`) at its target time; under a
/// [`crate::schemes::SchemeFilter`] such samples are dropped and counted instead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlAhrsMotion {
    vel_psd: Vector3<f64>,
    yaw_rate_psd: f64,
}

impl DvlAhrsMotion {
    /// Velocity process-noise PSD `(q_u, q_v, q_w)`, m^2/s.
    pub fn vel_psd(&self) -> Vector3<f64> {
        self.vel_psd
    }

    /// Yaw-rate process-noise PSD `q_r`, rad^2/s.
    pub fn yaw_rate_psd(&self) -> f64 {
        self.yaw_rate_psd
    }
}

/// The input held by the beacon EKF.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DvlAhrsInput {
    /// Latest measured body velocity `(u, v, w)`, m/s.
    pub vel_in_body: Vector3<f64>,
    /// Latest measured yaw rate `r`, rad/s.
    pub yaw_rate: f64,
}

/// One received input sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DvlAhrsSample {
    /// DVL body velocity, m/s.
    Velocity(Vector3<f64>),
    /// AHRS yaw rate, rad/s.
    YawRate(f64),
}

impl MotionModel<4> for DvlAhrsMotion {
    type Input = DvlAhrsInput;
    type InputSample = DvlAhrsSample;

    fn apply_sample(&self, input: &mut DvlAhrsInput, sample: &DvlAhrsSample) {
        match sample {
            DvlAhrsSample::Velocity(v) => input.vel_in_body = *v,
            DvlAhrsSample::YawRate(r) => input.yaw_rate = *r,
        }
    }

    /// Index `0..3` = DVL `(u, v, w)`, `3` = AHRS yaw rate `r` (as in [`Self::propagate`]).
    fn non_finite_in_sample(&self, sample: &DvlAhrsSample) -> Option<(&'static str, usize, f64)> {
        let (offset, values): (usize, &[f64]) = match sample {
            DvlAhrsSample::Velocity(v) => (0, v.as_slice()),
            DvlAhrsSample::YawRate(r) => (3, std::slice::from_ref(r)),
        };
        values
            .iter()
            .position(|v| !v.is_finite())
            .map(|i| (INPUT_NAME, offset + i, values[i]))
    }

    fn propagate(
        &self,
        x: &Vector4<f64>,
        input: &DvlAhrsInput,
        dt: f64,
    ) -> Result<Propagation<4>, EstimatorError> {
        let (vb, r) = (input.vel_in_body, input.yaw_rate);
        // The time stamp is set by `Ekf::predict_to` (the model does not know it).
        if let Some(index) = (0..4).find(|&i| ![vb.x, vb.y, vb.z, r][i].is_finite()) {
            return Err(EstimatorError::NonFinite {
                what: INPUT_NAME.into(),
                index,
                value: [vb.x, vb.y, vb.z, r][index],
                time: f64::NAN,
            });
        }
        if !dt.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "DVL/AHRS prediction step dt".into(),
                index: 0,
                value: dt,
                time: f64::NAN,
            });
        }
        let psi_m = x[3] + 0.5 * r * dt;
        let (s, c) = psi_m.sin_cos();
        let (u, v, w) = (vb.x, vb.y, vb.z);
        let x_pred = Vector4::new(
            x[0] + dt * (c * u - s * v),
            x[1] + dt * (s * u + c * v),
            x[2] + dt * w,
            wrap_pi(x[3] + dt * r),
        );
        let mut f = Matrix4::identity();
        f[(0, 3)] = -dt * (s * u + c * v);
        f[(1, 3)] = dt * (c * u - s * v);
        let rot = Matrix2::new(c, -s, s, c);
        let q_xy =
            rot * Matrix2::new(self.vel_psd.x, 0.0, 0.0, self.vel_psd.y) * rot.transpose() * dt;
        let mut q = Matrix4::zeros();
        q.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&(0.5 * (q_xy + q_xy.transpose())));
        q[(2, 2)] = self.vel_psd.z * dt;
        q[(3, 3)] = self.yaw_rate_psd * dt;
        Ok(Propagation {
            x_pred,
            f_jacobian: f,
            q,
        })
    }

    fn normalize(&self, x: &mut Vector4<f64>) {
        x[3] = wrap_pi(x[3]);
    }

    fn difference(&self, a: &Vector4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
        let mut d = a - b;
        d[3] = wrap_pi(d[3]);
        d
    }
}

/// A scalar measurement of the beacon EKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BeaconMeasurement {
    /// Range to a beacon at this NED position, m.
    Range {
        /// Beacon position in NED, m.
        beacon_in_nav: Vector3<f64>,
    },
    /// Depth (NED z), m.
    Depth,
    /// Absolute heading `psi` (a compass or AHRS heading), rad; the residual is
    /// wrapped to (-pi, pi].
    Heading,
}

/// Below this distance (m) to a beacon the range Jacobian is refused.
pub const MIN_RANGE: f64 = 1e-6;

impl ScalarModel<4> for BeaconMeasurement {
    fn evaluate(&self, x: &Vector4<f64>) -> Result<(f64, RowVector4<f64>), EstimatorError> {
        match self {
            BeaconMeasurement::Range { beacon_in_nav } => {
                let d = Vector3::new(x[0], x[1], x[2]) - beacon_in_nav;
                let h = d.norm();
                if h.is_nan() || h < MIN_RANGE {
                    return Err(EstimatorError::OutOfRange {
                        what: "predicted range to beacon (Jacobian undefined)".into(),
                        value: h,
                        expected: ">= 1e-6 m",
                    });
                }
                Ok((h, RowVector4::new(d.x / h, d.y / h, d.z / h, 0.0)))
            }
            BeaconMeasurement::Depth => Ok((x[2], RowVector4::new(0.0, 0.0, 1.0, 0.0))),
            BeaconMeasurement::Heading => Ok((x[3], RowVector4::new(0.0, 0.0, 0.0, 1.0))),
        }
    }

    fn residual(&self, z: f64, predicted: f64) -> f64 {
        match self {
            BeaconMeasurement::Heading => wrap_pi(z - predicted),
            _ => z - predicted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        EstimatorError, GateThreshold,
        ekf::{Ekf, GroupItem},
        schemes::{Disposition, Event, Observation, SchemeFilter, SchemeParams, UpdateScheme},
    };
    use approx::assert_relative_eq;
    use fathom_core::Gaussian;
    use nalgebra::DMatrix;

    /// The heading measurement: Jacobian by finite differences, and a heading across
    /// +-pi corrects the short way round (negative control: the unwrapped residual
    /// would pull the estimate through zero).
    #[test]
    fn heading_update_wraps_its_residual() {
        let m = BeaconMeasurement::Heading;
        let x = Vector4::new(1.0, 2.0, 3.0, 3.1);
        let (h, jac) = m.evaluate(&x).unwrap();
        let eps = 1e-6;
        for i in 0..4 {
            let mut xp = x;
            xp[i] += eps;
            let fd = (m.evaluate(&xp).unwrap().0 - h) / eps;
            assert_relative_eq!(jac[i], fd, epsilon = 1e-6);
        }
        let z = -3.1; // 0.083 rad past +pi
        let nu = m.residual(z, h);
        assert_relative_eq!(nu, 2.0 * std::f64::consts::PI - 6.2, epsilon = 1e-12);
        assert!(
            (z - h).abs() > 6.0,
            "the unwrapped residual is the long way round"
        );
        let prior = Gaussian::new(x, Matrix4::identity() * 0.01).unwrap();
        let mut ekf = Ekf::new(prior, 0.0, motion(), DvlAhrsInput::default()).unwrap();
        let item = GroupItem {
            value: z,
            model: &m,
            variance: 0.01,
            gate: None,
        };
        ekf.update_sequential(&[item]).unwrap();
        let psi = ekf.state()[3];
        assert!(psi.abs() > 3.1, "heading moved towards +-pi, got {psi}");
    }

    const BEACONS: [[f64; 3]; 4] = [
        [15.0, 15.0, 0.0],
        [-15.0, 15.0, 40.0],
        [-15.0, -15.0, 0.0],
        [15.0, -15.0, 40.0],
    ];

    fn motion() -> DvlAhrsMotion {
        DvlAhrsMotionParams {
            vel_sigma: [0.14, 0.0, 0.18],
            vel_hold: 0.1,
            yaw_rate_sigma: 0.14,
            yaw_rate_hold: 0.1,
        }
        .check()
        .unwrap()
    }

    fn ekf() -> Ekf<4, DvlAhrsMotion> {
        let prior = Gaussian::new(
            Vector4::new(1.0, -0.5, 3.0, 0.3),
            Matrix4::from_diagonal(&Vector4::new(0.04, 0.05, 0.03, 0.01)),
        )
        .unwrap();
        let input = DvlAhrsInput {
            vel_in_body: Vector3::new(0.5, 0.0, 0.2),
            yaw_rate: 0.5,
        };
        Ekf::new(prior, 0.0, motion(), input).unwrap()
    }

    fn range(k: usize) -> BeaconMeasurement {
        BeaconMeasurement::Range {
            beacon_in_nav: Vector3::from(BEACONS[k]),
        }
    }

    /// `[range1..4, depth]` at the prior mean of [`ekf`] predicted to `t`, plus
    /// offsets of about one sigma (all pass the 2.5-sigma gate).
    fn z_at(t: f64, offsets: [f64; 5]) -> [f64; 5] {
        let mut f = ekf();
        f.predict_to(t).unwrap();
        std::array::from_fn(|c| model(c).evaluate(f.state()).unwrap().0 + offsets[c])
    }

    const OFFSETS: [f64; 5] = [0.12, -0.08, 0.1, 0.05, -0.15];

    fn cov(sigma_c: f64) -> DMatrix<f64> {
        DMatrix::from_fn(5, 5, |i, j| match (i, j) {
            (4, 4) => 0.04,
            (4, _) | (_, 4) => 0.0,
            _ if i == j => 0.01 + sigma_c * sigma_c,
            _ => sigma_c * sigma_c,
        })
    }

    fn scheme_filter(
        scheme: UpdateScheme,
        sigma_c: f64,
    ) -> SchemeFilter<4, DvlAhrsMotion, BeaconMeasurement> {
        scheme_filter_tol(scheme, sigma_c, 0.0)
    }

    fn scheme_filter_tol(
        scheme: UpdateScheme,
        sigma_c: f64,
        stale_tolerance: f64,
    ) -> SchemeFilter<4, DvlAhrsMotion, BeaconMeasurement> {
        let gate = Some(GateThreshold::from_sigma_distance(2.5).unwrap());
        let config = SchemeParams {
            scheme,
            epoch_period: 0.1,
            stale_tolerance,
            channel_cov: cov(sigma_c),
            gates: vec![gate, gate, gate, gate, None],
        }
        .check()
        .unwrap();
        SchemeFilter::new(ekf(), config)
    }

    fn model(c: usize) -> BeaconMeasurement {
        if c < 4 {
            range(c)
        } else {
            BeaconMeasurement::Depth
        }
    }

    /// Feeds one synchronous epoch (all channels stamped `stamp`) and advances to `to`.
    fn feed(
        f: &mut SchemeFilter<4, DvlAhrsMotion, BeaconMeasurement>,
        stamp: f64,
        z: &[f64; 5],
        to: f64,
    ) {
        for (c, &value) in z.iter().enumerate() {
            f.process(Event::Measurement(Observation {
                channel: c,
                stamp,
                value,
                model: model(c),
                tag: c,
            }))
            .unwrap();
        }
        f.advance_to(to).unwrap();
    }

    fn bad(
        channel: usize,
        stamp: f64,
        value: f64,
        tag: usize,
    ) -> Event<DvlAhrsSample, BeaconMeasurement> {
        Event::Measurement(Observation {
            channel,
            stamp,
            value,
            model: model(channel),
            tag,
        })
    }

    /// Bad input (crate docs, "Bad input"): in every scheme a non-finite range or
    /// depth value, or a non-finite stamp, is dropped, logged as
    /// [`Disposition::NonFinite`], counted per channel and never applied: the
    /// estimate equals the one without the bad samples, bit for bit.
    #[test]
    fn non_finite_measurements_are_dropped_and_counted() {
        for scheme in UpdateScheme::ALL {
            let z = z_at(0.1, OFFSETS);
            let mut clean = scheme_filter(scheme, 0.2);
            feed(&mut clean, 0.097, &z, 0.1);
            let mut dirty = scheme_filter(scheme, 0.2);
            for (c, &value) in z.iter().enumerate() {
                dirty.process(bad(c, 0.097, value, c)).unwrap();
            }
            dirty.process(bad(0, 0.098, f64::NAN, 10)).unwrap();
            dirty.process(bad(2, 0.099, f64::INFINITY, 12)).unwrap();
            dirty.process(bad(1, f64::NAN, 20.0, 11)).unwrap();
            dirty.process(bad(4, 0.099, f64::NEG_INFINITY, 14)).unwrap();
            dirty.advance_to(0.1).unwrap();
            assert_eq!(dirty.ekf().state(), clean.ekf().state(), "{scheme:?}");
            assert_eq!(dirty.ekf().covariance(), clean.ekf().covariance());
            let non_finite: Vec<usize> = dirty.counts().iter().map(|c| c.non_finite).collect();
            assert_eq!(non_finite, [1, 1, 1, 0, 1], "{scheme:?}");
            let dropped: Vec<usize> = dirty
                .decisions()
                .iter()
                .filter(|d| d.disposition == Disposition::NonFinite)
                .map(|d| d.tag)
                .collect();
            assert_eq!(dropped, [10, 12, 11, 14]);
            assert_eq!(
                dirty.counts()[0].accepted,
                clean.counts()[0].accepted,
                "{scheme:?}"
            );
            // Negative control: the clean filter saw none.
            assert!(clean.counts().iter().all(|c| c.non_finite == 0));
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Whatever samples are replaced by NaN / +-inf, in any scheme, the dropped
        /// count equals the number replaced and the estimate equals the one of a
        /// filter that never received them.
        #[test]
        fn any_injected_non_finite_samples_are_dropped_exactly(
            mask in proptest::collection::vec(0u8..4, 15),
            scheme_index in 0usize..3,
        ) {
            let scheme = UpdateScheme::ALL[scheme_index];
            let mut dirty = scheme_filter(scheme, 0.2);
            let mut clean = scheme_filter(scheme, 0.2);
            let mut injected = 0;
            for k in 0..3 {
                let t = 0.1 * (k + 1) as f64;
                let z = z_at(t, OFFSETS);
                for c in 0..5 {
                    let event = bad(c, t - 0.003, z[c], 5 * k + c);
                    let bad_value = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
                    match mask[5 * k + c] {
                        m @ 1..=3 => {
                            injected += 1;
                            dirty.process(bad(c, t - 0.003, bad_value[m as usize - 1], 5 * k + c)).unwrap();
                        }
                        _ => {
                            dirty.process(event.clone()).unwrap();
                            clean.process(event).unwrap();
                        }
                    }
                }
                dirty.advance_to(t).unwrap();
                clean.advance_to(t).unwrap();
            }
            proptest::prop_assert_eq!(dirty.non_finite_measurements(), injected);
            proptest::prop_assert_eq!(dirty.ekf().state(), clean.ekf().state());
            proptest::prop_assert!(dirty.ekf().state().iter().all(|v| v.is_finite()));
        }
    }

    /// With robust handling, dropped non-finite samples are not rejections: a long
    /// run of them never triggers a lock-out recovery, and the estimate is as if
    /// they never arrived. Negative control: as many real 50-sigma outliers do.
    #[test]
    fn robust_lockout_ignores_non_finite_samples() {
        use crate::robust::{RecoveryParams, RobustParams};
        let policy = RobustParams {
            huber_k: Some(2.0),
            recovery: Some(RecoveryParams {
                after_rejections: 3,
                inflation: 4.0,
            }),
        }
        .check()
        .unwrap();
        let robust = |scheme| scheme_filter(scheme, 0.0).with_robust(policy);
        for scheme in UpdateScheme::ALL {
            let (mut dirty, mut clean, mut outliers) =
                (robust(scheme), robust(scheme), robust(scheme));
            for k in 0..6 {
                let t = 0.1 * (k + 1) as f64;
                let stamp = t - 0.003;
                dirty.process(bad(0, stamp, f64::NAN, k)).unwrap();
                outliers.process(bad(0, stamp, 1e3, k)).unwrap();
                for f in [&mut dirty, &mut clean, &mut outliers] {
                    f.advance_to(t).unwrap();
                }
            }
            assert_eq!(dirty.recoveries(), 0, "{scheme:?}");
            assert_eq!(dirty.counts()[0].non_finite, 6);
            assert_eq!(dirty.counts()[0].rejected, 0);
            assert_eq!(dirty.ekf().covariance(), clean.ekf().covariance());
            assert!(outliers.recoveries() >= 1, "{scheme:?}");
        }
    }

    /// A non-finite input sample or input stamp is dropped and counted; the held
    /// input and the prediction are as if it never arrived.
    #[test]
    fn non_finite_inputs_are_dropped_and_counted() {
        for scheme in UpdateScheme::ALL {
            let mut f = scheme_filter(scheme, 0.0);
            let mut g = f.clone();
            let nan_vel = DvlAhrsSample::Velocity(Vector3::new(0.5, f64::NAN, 0.0));
            for (stamp, sample) in [
                (0.05, nan_vel),
                (f64::NAN, DvlAhrsSample::YawRate(0.1)),
                (0.06, DvlAhrsSample::YawRate(f64::INFINITY)),
            ] {
                f.process(Event::Input { stamp, sample }).unwrap();
            }
            assert_eq!(f.non_finite_inputs(), 3);
            assert_eq!(g.non_finite_inputs(), 0);
            f.advance_to(1.0).unwrap();
            g.advance_to(1.0).unwrap();
            assert_eq!(f.ekf().state(), g.ekf().state(), "{scheme:?}");
            assert_eq!(f.ekf().input(), g.ekf().input());
        }
    }

    /// A covariance that overflows (absurd prior and input) is an error at the time
    /// of the failing prediction (the first epoch for SC/SI, the target for AS); the
    /// filter keeps its last good estimate.
    #[test]
    fn covariance_overflow_is_an_error_with_the_time() {
        for (scheme, t_fail) in [
            (UpdateScheme::Asynchronous, 0.35),
            (UpdateScheme::SynchronousCollective, 0.1),
            (UpdateScheme::SynchronousIndividual, 0.1),
        ] {
            let x0 = Vector4::new(1.0, -0.5, 3.0, 0.3);
            let prior = Gaussian::new(x0, Matrix4::identity() * 1e308).unwrap();
            let input = DvlAhrsInput {
                vel_in_body: Vector3::new(100.0, 0.0, 0.0),
                yaw_rate: 0.0,
            };
            let ekf = Ekf::new(prior, 0.0, motion(), input).unwrap();
            let config = scheme_filter(scheme, 0.0).config().clone();
            let mut f: SchemeFilter<4, _, BeaconMeasurement> = SchemeFilter::new(ekf, config);
            let e = f.advance_to(0.35).unwrap_err();
            assert!(
                e.to_string().contains("predicted covariance P"),
                "{scheme:?}: {e}"
            );
            assert_eq!(e.time(), Some(t_fail), "{scheme:?}: {e}");
            assert_eq!(f.ekf().time(), 0.0);
            assert_eq!(*f.ekf().state(), x0);
        }
    }

    /// The motion model names the non-finite input component; the EKF stamps the
    /// error with the prediction's target time.
    #[test]
    fn motion_model_names_the_non_finite_input() {
        let mut f = ekf();
        let nan_w = DvlAhrsSample::Velocity(Vector3::new(0.5, 0.0, f64::NAN));
        let e = f.try_apply_input(&nan_w).unwrap_err();
        assert!(matches!(&e, EstimatorError::NonFinite { index: 2, time, .. } if *time == 0.0));
        f.apply_input(&DvlAhrsSample::YawRate(f64::INFINITY));
        let e = f.predict_to(0.4).unwrap_err();
        match e {
            EstimatorError::NonFinite {
                what,
                index,
                value,
                time,
            } => {
                assert!(what.contains("DVL/AHRS"), "{what}");
                assert_eq!((index, value, time), (3, f64::INFINITY, 0.4));
            }
            other => panic!("unexpected {other}"),
        }
        assert_eq!(f.time(), 0.0);
    }

    #[test]
    fn range_jacobian_matches_finite_differences() {
        let x = Vector4::new(1.3, -2.1, 7.5, 0.4);
        for k in 0..4 {
            let (h, row) = range(k).evaluate(&x).unwrap();
            assert_relative_eq!(
                h,
                (x.xyz() - Vector3::from(BEACONS[k])).norm(),
                epsilon = 1e-12
            );
            for c in 0..4 {
                let eps = 1e-6;
                let mut xp = x;
                let mut xm = x;
                xp[c] += eps;
                xm[c] -= eps;
                let fd = (range(k).evaluate(&xp).unwrap().0 - range(k).evaluate(&xm).unwrap().0)
                    / (2.0 * eps);
                assert_relative_eq!(row[c], fd, epsilon = 1e-8);
            }
        }
        // Control: a wrong Jacobian (transposed sign) would not match.
        let (_, row) = range(0).evaluate(&x).unwrap();
        assert!((row[0] + (x[0] - BEACONS[0][0]) / row.norm()).abs() > 1e-3);
        // At the beacon itself the Jacobian is undefined: an error, not NaN.
        assert!(
            range(0)
                .evaluate(&Vector4::new(15.0, 15.0, 0.0, 0.0))
                .is_err()
        );
    }

    #[test]
    fn motion_jacobian_matches_finite_differences() {
        let m = motion();
        let x = Vector4::new(1.0, 2.0, 3.0, 3.1);
        let input = DvlAhrsInput {
            vel_in_body: Vector3::new(0.5, 0.1, 0.2),
            yaw_rate: 0.5,
        };
        let dt = 0.2;
        let prop = m.propagate(&x, &input, dt).unwrap();
        for c in 0..4 {
            let eps = 1e-6;
            let mut xp = x;
            let mut xm = x;
            xp[c] += eps;
            xm[c] -= eps;
            let d = m.difference(
                &m.propagate(&xp, &input, dt).unwrap().x_pred,
                &m.propagate(&xm, &input, dt).unwrap().x_pred,
            ) / (2.0 * eps);
            for r in 0..4 {
                assert_relative_eq!(prop.f_jacobian[(r, c)], d[r], epsilon = 1e-7);
            }
        }
        // heading wraps across +-pi
        assert!(prop.x_pred[3] < 0.0);
        assert!(prop.q.cholesky().is_none()); // q_v = 0: only semi-definite
        assert!(prop.q[(0, 0)] > 0.0 && prop.q[(3, 3)] > 0.0);
    }

    /// Acceptance: synchronous sensors and a diagonal R give the same estimate for SC
    /// and SI (to 1e-9).
    #[test]
    fn sc_equals_si_with_diagonal_r() {
        let mut sc = scheme_filter(UpdateScheme::SynchronousCollective, 0.0);
        let mut si = scheme_filter(UpdateScheme::SynchronousIndividual, 0.0);
        for k in 0..2 {
            let t = 0.1 * (k + 1) as f64;
            let z = &z_at(t, OFFSETS.map(|o| o * (1.0 - k as f64)));
            feed(&mut sc, t - 0.003, z, t);
            feed(&mut si, t - 0.003, z, t);
        }
        for i in 0..4 {
            assert_relative_eq!(sc.ekf().state()[i], si.ekf().state()[i], epsilon = 1e-9);
            for j in 0..4 {
                assert_relative_eq!(
                    sc.ekf().covariance()[(i, j)],
                    si.ekf().covariance()[(i, j)],
                    epsilon = 1e-9
                );
            }
        }
        assert_eq!(sc.counts()[0].accepted, 2);
    }

    /// Acceptance: with correlated R, SC and SI differ and SC equals a hand-computed
    /// stacked EKF update `K = P H^T (H P H^T + R)^-1`, `x+ = x + K (z - h(x))`.
    #[test]
    fn sc_with_correlated_r_matches_hand_computed_stacked_update() {
        let sigma_c = 0.2;
        let mut sc = scheme_filter(UpdateScheme::SynchronousCollective, sigma_c);
        let mut si = scheme_filter(UpdateScheme::SynchronousIndividual, sigma_c);
        // hand computation from the prediction to the epoch
        let mut reference = ekf();
        reference.predict_to(0.1).unwrap();
        let x = *reference.state();
        let z = z_at(0.1, OFFSETS);
        let p = *reference.covariance();
        let mut h = DMatrix::zeros(5, 4);
        let mut nu = nalgebra::DVector::zeros(5);
        for c in 0..5 {
            let (hc, row) = model(c).evaluate(&x).unwrap();
            nu[c] = z[c] - hc;
            for j in 0..4 {
                h[(c, j)] = row[j];
            }
        }
        let p_d = DMatrix::from_fn(4, 4, |i, j| p[(i, j)]);
        let s = &h * &p_d * h.transpose() + cov(sigma_c);
        let k = &p_d * h.transpose() * s.try_inverse().unwrap();
        let x_expected = nalgebra::DVector::from_fn(4, |i, _| x[i]) + &k * &nu;
        let p_expected = (DMatrix::identity(4, 4) - &k * &h) * &p_d;
        // all components pass the gate (checked below), so nothing is removed
        feed(&mut sc, 0.097, &z, 0.1);
        feed(&mut si, 0.097, &z, 0.1);
        assert!(
            sc.decisions()
                .iter()
                .all(|d| d.disposition == Disposition::Accepted)
        );
        for i in 0..4 {
            assert_relative_eq!(sc.ekf().state()[i], x_expected[i], epsilon = 1e-9);
            for j in 0..4 {
                assert_relative_eq!(
                    sc.ekf().covariance()[(i, j)],
                    p_expected[(i, j)],
                    epsilon = 1e-9
                );
            }
        }
        let diff = (sc.ekf().state() - si.ekf().state()).norm();
        assert!(
            diff > 1e-4,
            "SC and SI should differ with correlated R, diff {diff}"
        );
    }

    /// Acceptance: the gate rejects a 10-sigma innovation and accepts a 1-sigma one.
    #[test]
    fn gate_rejects_ten_sigma_and_accepts_one_sigma() {
        let f = ekf();
        let gate = Some(GateThreshold::from_sigma_distance(2.5).unwrap());
        let m = range(0);
        let (h, row) = m.evaluate(f.state()).unwrap();
        let r = 0.01;
        let s = (row * f.covariance() * row.transpose())[0] + r;
        for (k, accept) in [(1.0, true), (10.0, false), (-10.0, false), (-1.0, true)] {
            let mut g = f.clone();
            let item = GroupItem {
                value: h + k * s.sqrt(),
                model: &m,
                variance: r,
                gate,
            };
            let out = g.update_sequential(&[item]).unwrap();
            assert_eq!(out[0].accepted, accept, "{k} sigma");
            assert_relative_eq!(out[0].nis, k * k, epsilon = 1e-9);
            assert_eq!(g == f, !accept); // rejected: unchanged
            let mut g = f.clone();
            let out = g
                .update_stacked(&[item], &DMatrix::from_element(1, 1, r))
                .unwrap();
            assert_eq!(out[0].accepted, accept);
        }
    }

    /// Acceptance: AS with identical stamps equals SI (same epoch, same measurements).
    #[test]
    fn as_with_identical_stamps_equals_si() {
        let mut as_f = scheme_filter(UpdateScheme::Asynchronous, 0.2);
        let mut si = scheme_filter(UpdateScheme::SynchronousIndividual, 0.2);
        let z = z_at(0.1, OFFSETS);
        feed(&mut as_f, 0.1, &z, 0.1);
        feed(&mut si, 0.1, &z, 0.1);
        assert_eq!(as_f.ekf().time(), si.ekf().time());
        for i in 0..4 {
            assert_relative_eq!(as_f.ekf().state()[i], si.ekf().state()[i], epsilon = 1e-12);
            for j in 0..4 {
                assert_relative_eq!(
                    as_f.ekf().covariance()[(i, j)],
                    si.ekf().covariance()[(i, j)],
                    epsilon = 1e-12
                );
            }
        }
        assert_eq!(as_f.decisions().len(), 5);
    }

    #[test]
    fn as_drops_stale_measurements_and_counts_them() {
        let mut f = scheme_filter(UpdateScheme::Asynchronous, 0.0);
        let obs = |stamp: f64, tag: usize| {
            Event::Measurement(Observation {
                channel: 4,
                stamp,
                value: 3.1,
                model: BeaconMeasurement::Depth,
                tag,
            })
        };
        f.process(obs(0.2, 0)).unwrap();
        f.process(obs(0.1, 1)).unwrap(); // older than the filter time: stale
        f.advance_to(0.2).unwrap();
        f.process(obs(0.2, 2)).unwrap(); // exactly current: processed at t = 0.2
        f.advance_to(0.3).unwrap();
        let d = f.decisions();
        assert_eq!(d.len(), 3);
        // tag 1 closes the group of tag 0 (applied first), then is dropped
        assert_eq!((d[0].tag, d[0].disposition), (0, Disposition::Accepted));
        assert_eq!((d[1].tag, d[1].disposition), (1, Disposition::Stale));
        assert_eq!((d[2].tag, d[2].applied_at), (2, 0.2));
        assert_eq!(f.counts()[4].stale, 1);
        assert_eq!(f.ekf().time(), 0.3);
        // with a tolerance, the late one is applied at the current time
        let mut g = scheme_filter_tol(UpdateScheme::Asynchronous, 0.0, 0.15);
        g.process(obs(0.2, 0)).unwrap();
        g.process(obs(0.1, 1)).unwrap();
        g.advance_to(0.2).unwrap();
        assert_eq!(g.counts()[4].stale, 0);
        assert_eq!(g.counts()[4].accepted, 2);
        assert_eq!(g.decisions()[1].applied_at, 0.2);
    }

    #[test]
    fn sync_keeps_the_newest_sample_and_drops_fired_windows() {
        let mut f = scheme_filter(UpdateScheme::SynchronousIndividual, 0.0);
        let obs = |stamp: f64, tag: usize| {
            Event::Measurement(Observation {
                channel: 4,
                stamp,
                value: 3.1,
                model: BeaconMeasurement::Depth,
                tag,
            })
        };
        f.process(obs(0.02, 0)).unwrap();
        f.process(obs(0.06, 1)).unwrap();
        f.process(obs(0.04, 2)).unwrap(); // out of order, older than pending: superseded
        f.process(obs(0.1, 3)).unwrap(); // exactly at the epoch: still epoch 1
        f.process(obs(0.13, 4)).unwrap(); // fires epoch 1
        f.process(obs(0.09, 5)).unwrap(); // window of epoch 1 already fired: stale
        f.advance_to(0.2).unwrap();
        let by_tag = |t: usize| {
            f.decisions()
                .iter()
                .find(|d| d.tag == t)
                .unwrap()
                .disposition
        };
        assert_eq!(by_tag(0), Disposition::Superseded);
        assert_eq!(by_tag(1), Disposition::Superseded);
        assert_eq!(by_tag(2), Disposition::Superseded);
        assert_eq!(by_tag(3), Disposition::Accepted);
        assert_eq!(by_tag(4), Disposition::Accepted);
        assert_eq!(by_tag(5), Disposition::Stale);
        let applied: Vec<f64> = f
            .decisions()
            .iter()
            .filter(|d| d.disposition == Disposition::Accepted)
            .map(|d| d.applied_at)
            .collect();
        assert_eq!(applied.len(), 2);
        assert_relative_eq!(applied[0], 0.1);
        assert_relative_eq!(applied[1], 0.2);
        let c = f.counts()[4];
        assert_eq!(
            (c.accepted, c.superseded, c.stale, c.rejected),
            (2, 3, 1, 0)
        );
    }

    #[test]
    fn inputs_drive_the_prediction_and_late_inputs_are_counted() {
        let mut f = scheme_filter(UpdateScheme::Asynchronous, 0.0);
        f.process(Event::Input {
            stamp: 0.5,
            sample: DvlAhrsSample::Velocity(Vector3::new(1.0, 0.0, 0.0)),
        })
        .unwrap();
        f.process(Event::Input {
            stamp: 0.4,
            sample: DvlAhrsSample::YawRate(0.0),
        })
        .unwrap();
        assert_eq!(f.late_inputs(), 1);
        assert_eq!(f.ekf().time(), 0.5);
        let before = *f.ekf().state();
        f.advance_to(1.5).unwrap();
        let d = f.ekf().state() - before;
        assert_relative_eq!(d[3], 0.0, epsilon = 1e-15);
        assert_relative_eq!(d.xy().norm(), 1.0, epsilon = 1e-12);
        assert!(f.advance_to(1.0).is_err());
        let bad = f.process(Event::Measurement(Observation {
            channel: 9,
            stamp: 2.0,
            value: 1.0,
            model: BeaconMeasurement::Depth,
            tag: 0,
        }));
        assert!(bad.is_err());
    }
}
