//! 2D wheel-odometry motion model and calibrated range measurements for the generic
//! [`crate::ekf`] core: state `(x, y, heading, c_1, ..., c_k)` with `k = N - 3`
//! calibration states (random walks) used by the range model, e.g. a range offset and
//! a range scale error.
//!
//! # Motion ([`WheelOdometry`])
//! Odometry delivers distance and heading increments `(dd, dth)` per step. The filter
//! holds them as rates ([`OdometryRate`]: `v = dd / T`, `w = dth / T` over the step's
//! interval `T`), so a prediction over any `dt` integrates `dd = v dt`, `dth = w dt` at
//! the mid heading `th_m = th + dth / 2`:
//!
//! ```text
//! x' = x + dd cos th_m      y' = y + dd sin th_m      th' = wrap(th + dth)      c' = c
//! ```
//!
//! Predicting over a whole step gives exactly the data set's integration rule.
//! `F = I` plus `dx'/dth = -dd sin th_m`, `dy'/dth = dd cos th_m`. Process noise grows
//! with the increments: `var(dd) = s_d^2 |dd|`, `var(dth) = s_hm^2 |dd| + s_hr^2 |dth|`
//! (variances proportional to distance driven and angle turned, so splitting a step
//! into parts adds up to the same noise), mapped by `G = d(x', y', th')/d(dd, dth)`;
//! calibration state `i` gets `q_i dt` (random walk).
//!
//! # Ranges ([`CalibratedRange`])
//! `h = (1 + s) |p - b| + o` with an optional offset state `o` and scale state `s`
//! (absent: 0), `H = [(1 + s) u^T, 0, ..., 1 (o), |p - b| (s), ...]`, `u` the unit
//! vector from the beacon to the robot. Real radio ranges are often longer than the
//! true distance by an amount that grows with distance; estimating `o` and `s` from a
//! zero prior lets the filter learn that from the data.

use crate::{
    EstimatorError,
    ekf::{MotionModel, Propagation, ScalarModel},
};
use fathom_core::units::wrap_pi;
use nalgebra::{Matrix2, Matrix3x2, RowSVector, SMatrix, SVector, Vector2};

/// Unchecked parameters of [`WheelOdometry`].
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WheelOdometryParams {
    /// Distance error sigma per square root of distance driven, m/sqrt(m) (>= 0).
    pub distance_sigma_per_sqrt_m: f64,
    /// Heading error sigma per square root of distance driven, rad/sqrt(m) (>= 0).
    pub heading_sigma_per_sqrt_m: f64,
    /// Heading error sigma per square root of angle turned, rad/sqrt(rad) (>= 0).
    pub heading_sigma_per_sqrt_rad: f64,
    /// Random-walk sigma of each calibration state per square root of time, unit/sqrt(s)
    /// (>= 0; one entry per state after the pose, in state order).
    pub calibration_random_walk: Vec<f64>,
}

impl WheelOdometryParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::Core`] naming the field for a negative or non-finite sigma.
    pub fn check(&self) -> Result<WheelOdometry, EstimatorError> {
        use fathom_core::error::ensure_non_negative;
        ensure_non_negative("distance_sigma_per_sqrt_m", self.distance_sigma_per_sqrt_m)?;
        ensure_non_negative("heading_sigma_per_sqrt_m", self.heading_sigma_per_sqrt_m)?;
        ensure_non_negative(
            "heading_sigma_per_sqrt_rad",
            self.heading_sigma_per_sqrt_rad,
        )?;
        for s in &self.calibration_random_walk {
            ensure_non_negative("calibration_random_walk", *s)?;
        }
        Ok(WheelOdometry {
            var_d_per_m: self.distance_sigma_per_sqrt_m.powi(2),
            var_h_per_m: self.heading_sigma_per_sqrt_m.powi(2),
            var_h_per_rad: self.heading_sigma_per_sqrt_rad.powi(2),
            calibration_psd: self.calibration_random_walk.iter().map(|s| s * s).collect(),
        })
    }
}

/// Wheel-odometry motion in 2D with random-walk calibration states (module docs).
///
/// Bad input: a non-finite odometry rate is an error of the next prediction naming
/// the component (0 = speed, 1 = turn rate) at its target time
/// ([`OdometryRate::from_increments`] refuses non-finite increments up front); under
/// a [`crate::schemes::SchemeFilter`] such samples are dropped and counted.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelOdometry {
    var_d_per_m: f64,
    var_h_per_m: f64,
    var_h_per_rad: f64,
    calibration_psd: Vec<f64>,
}

impl WheelOdometry {
    /// Number of calibration states the model was configured for.
    pub fn calibration_states(&self) -> usize {
        self.calibration_psd.len()
    }
}

/// The odometry input held by the filter: speed and turn rate over the current step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OdometryRate {
    /// Speed along the heading, m/s.
    pub speed: f64,
    /// Heading rate, rad/s.
    pub turn_rate: f64,
}

impl OdometryRate {
    /// The rates of a step with increments `(delta_distance, delta_heading)` over
    /// `interval` seconds.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for a non-positive or non-finite interval,
    /// [`EstimatorError::NonFinite`] for non-finite increments.
    pub fn from_increments(
        delta_distance: f64,
        delta_heading: f64,
        interval: f64,
    ) -> Result<Self, EstimatorError> {
        if !(interval.is_finite() && interval > 0.0) {
            return Err(EstimatorError::OutOfRange {
                what: "odometry step interval".into(),
                value: interval,
                expected: "> 0",
            });
        }
        for (index, value) in [delta_distance, delta_heading].into_iter().enumerate() {
            if !value.is_finite() {
                // No filter time here: a time-free check (the caller knows the row).
                return Err(EstimatorError::Core(fathom_core::CoreError::NonFinite {
                    what: "odometry increment (distance, heading)".into(),
                    index,
                    value,
                }));
            }
        }
        Ok(OdometryRate {
            speed: delta_distance / interval,
            turn_rate: delta_heading / interval,
        })
    }
}

/// One mid-heading integration step of a pose `(x, y, heading)` (module docs; heading
/// not wrapped).
pub fn mid_heading_step(pose: [f64; 3], delta_distance: f64, delta_heading: f64) -> [f64; 3] {
    let th_m = pose[2] + 0.5 * delta_heading;
    [
        pose[0] + delta_distance * th_m.cos(),
        pose[1] + delta_distance * th_m.sin(),
        pose[2] + delta_heading,
    ]
}

/// Pure dead reckoning: the poses after each increment `(dd, dth)` from `start`.
pub fn dead_reckon(start: [f64; 3], increments: &[(f64, f64)]) -> Vec<[f64; 3]> {
    let mut pose = start;
    increments
        .iter()
        .map(|&(dd, dth)| {
            pose = mid_heading_step(pose, dd, dth);
            pose
        })
        .collect()
}

impl<const N: usize> MotionModel<N> for WheelOdometry {
    type Input = OdometryRate;
    type InputSample = OdometryRate;

    fn apply_sample(&self, input: &mut OdometryRate, sample: &OdometryRate) {
        *input = *sample;
    }

    /// Index 0 = speed, 1 = turn rate.
    fn non_finite_in_sample(&self, sample: &OdometryRate) -> Option<(&'static str, usize, f64)> {
        [sample.speed, sample.turn_rate]
            .into_iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
            .map(|(i, v)| ("odometry rate (speed, turn rate)", i, v))
    }

    fn propagate(
        &self,
        x: &SVector<f64, N>,
        input: &OdometryRate,
        dt: f64,
    ) -> Result<Propagation<N>, EstimatorError> {
        if N != 3 + self.calibration_psd.len() {
            return Err(EstimatorError::DimensionMismatch {
                what: "wheel-odometry state (3 pose + calibration states)".into(),
                expected: 3 + self.calibration_psd.len(),
                got: N,
            });
        }
        // The time stamp is set by `Ekf::predict_to` (the model does not know it).
        if let Some((what, index, value)) =
            <Self as MotionModel<N>>::non_finite_in_sample(self, input)
        {
            return Err(EstimatorError::NonFinite {
                what: what.into(),
                index,
                value,
                time: f64::NAN,
            });
        }
        if !dt.is_finite() {
            return Err(EstimatorError::NonFinite {
                what: "odometry prediction step dt".into(),
                index: 0,
                value: dt,
                time: f64::NAN,
            });
        }
        let dd = input.speed * dt;
        let dth = input.turn_rate * dt;
        let th_m = x[2] + 0.5 * dth;
        let (s, c) = th_m.sin_cos();
        let mut x_pred = *x;
        x_pred[0] += dd * c;
        x_pred[1] += dd * s;
        x_pred[2] = wrap_pi(x[2] + dth);
        let mut f = SMatrix::<f64, N, N>::identity();
        f[(0, 2)] = -dd * s;
        f[(1, 2)] = dd * c;
        let g = Matrix3x2::new(c, -0.5 * dd * s, s, 0.5 * dd * c, 0.0, 1.0);
        let var = Matrix2::new(
            self.var_d_per_m * dd.abs(),
            0.0,
            0.0,
            self.var_h_per_m * dd.abs() + self.var_h_per_rad * dth.abs(),
        );
        let q_pose = g * var * g.transpose();
        let mut q = SMatrix::<f64, N, N>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                q[(i, j)] = 0.5 * (q_pose[(i, j)] + q_pose[(j, i)]);
            }
        }
        for (k, psd) in self.calibration_psd.iter().enumerate() {
            q[(3 + k, 3 + k)] = psd * dt;
        }
        Ok(Propagation {
            x_pred,
            f_jacobian: f,
            q,
        })
    }

    fn normalize(&self, x: &mut SVector<f64, N>) {
        x[2] = wrap_pi(x[2]);
    }

    fn difference(&self, a: &SVector<f64, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut d = a - b;
        d[2] = wrap_pi(d[2]);
        d
    }
}

/// Below this distance (m) to a beacon the range Jacobian is refused.
pub const MIN_RANGE: f64 = 1e-6;

/// A 2D range to a surveyed beacon with optional offset and scale calibration states
/// (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedRange {
    /// Beacon position `(x, y)`, m.
    pub beacon: Vector2<f64>,
    /// State index of the range offset `o` (m), if estimated.
    pub offset_state: Option<usize>,
    /// State index of the range scale error `s` (dimensionless), if estimated.
    pub scale_state: Option<usize>,
}

impl<const N: usize> ScalarModel<N> for CalibratedRange {
    fn evaluate(&self, x: &SVector<f64, N>) -> Result<(f64, RowSVector<f64, N>), EstimatorError> {
        for idx in [self.offset_state, self.scale_state].into_iter().flatten() {
            if idx < 3 || idx >= N {
                return Err(EstimatorError::OutOfRange {
                    what: "calibration state index of a range model".into(),
                    value: idx as f64,
                    expected: "3 <= index < state dimension",
                });
            }
        }
        let d = Vector2::new(x[0], x[1]) - self.beacon;
        let dist = d.norm();
        if dist.is_nan() || dist < MIN_RANGE {
            return Err(EstimatorError::OutOfRange {
                what: "distance to beacon (range Jacobian undefined)".into(),
                value: dist,
                expected: ">= 1e-6 m",
            });
        }
        let offset = self.offset_state.map_or(0.0, |i| x[i]);
        let scale = self.scale_state.map_or(0.0, |i| x[i]);
        let mut h = RowSVector::<f64, N>::zeros();
        h[0] = (1.0 + scale) * d.x / dist;
        h[1] = (1.0 + scale) * d.y / dist;
        if let Some(i) = self.offset_state {
            h[i] = 1.0;
        }
        if let Some(i) = self.scale_state {
            h[i] = dist;
        }
        Ok(((1.0 + scale) * dist + offset, h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Vector3, Vector5};

    fn model(cal: usize) -> WheelOdometry {
        WheelOdometryParams {
            distance_sigma_per_sqrt_m: 0.05,
            heading_sigma_per_sqrt_m: 0.01,
            heading_sigma_per_sqrt_rad: 0.05,
            calibration_random_walk: vec![0.01; cal],
        }
        .check()
        .unwrap()
    }

    #[test]
    fn a_whole_step_is_the_mid_heading_rule_and_splitting_adds_up() {
        let m = model(0);
        let x = Vector3::new(1.0, 2.0, 0.3);
        let rate = OdometryRate::from_increments(0.5, 0.2, 0.25).unwrap();
        let whole = MotionModel::<3>::propagate(&m, &x, &rate, 0.25).unwrap();
        let want = mid_heading_step([1.0, 2.0, 0.3], 0.5, 0.2);
        for i in 0..3 {
            assert_relative_eq!(whole.x_pred[i], want[i], epsilon = 1e-14);
        }
        // Two halves: same end pose to second order, same distance/turn noise budget.
        let a = MotionModel::<3>::propagate(&m, &x, &rate, 0.125).unwrap();
        let b = MotionModel::<3>::propagate(&m, &a.x_pred, &rate, 0.125).unwrap();
        assert_relative_eq!(b.x_pred[0], want[0], epsilon = 1e-3);
        assert_relative_eq!(b.x_pred[1], want[1], epsilon = 1e-3);
        let heading_var = a.q[(2, 2)] + b.q[(2, 2)];
        assert_relative_eq!(heading_var, whole.q[(2, 2)], epsilon = 1e-15);
        assert_eq!(dead_reckon([1.0, 2.0, 0.3], &[(0.5, 0.2)])[0], want);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let m = model(2);
        let x = Vector5::new(1.0, -2.0, 2.9, 0.4, 0.05);
        let rate = OdometryRate {
            speed: 1.5,
            turn_rate: 0.4,
        };
        let p = MotionModel::<5>::propagate(&m, &x, &rate, 0.3).unwrap();
        let eps = 1e-7;
        for j in 0..5 {
            let mut xp = x;
            xp[j] += eps;
            let q = MotionModel::<5>::propagate(&m, &xp, &rate, 0.3).unwrap();
            for i in 0..5 {
                let mut diff = q.x_pred[i] - p.x_pred[i];
                if i == 2 {
                    diff = wrap_pi(diff);
                }
                assert_relative_eq!(diff / eps, p.f_jacobian[(i, j)], epsilon = 1e-6);
            }
        }
        assert_relative_eq!(p.q[(3, 3)], 0.01f64.powi(2) * 0.3, epsilon = 1e-18);
        assert_eq!(p.x_pred[3], 0.4);
        // Standing still: no pose noise.
        let still = MotionModel::<5>::propagate(&m, &x, &OdometryRate::default(), 1.0).unwrap();
        assert_eq!(still.q[(0, 0)], 0.0);
        assert_eq!(still.q[(2, 2)], 0.0);
    }

    #[test]
    fn wrong_dimension_and_bad_input_are_errors() {
        let m = model(1);
        let x = Vector3::new(0.0, 0.0, 0.0);
        assert!(MotionModel::<3>::propagate(&m, &x, &OdometryRate::default(), 0.1).is_err());
        assert!(OdometryRate::from_increments(0.1, 0.0, 0.0).is_err());
        assert!(OdometryRate::from_increments(f64::NAN, 0.0, 0.2).is_err());
        assert!(
            WheelOdometryParams {
                distance_sigma_per_sqrt_m: -1.0,
                heading_sigma_per_sqrt_m: 0.0,
                heading_sigma_per_sqrt_rad: 0.0,
                calibration_random_walk: vec![],
            }
            .check()
            .is_err()
        );
    }

    /// Bad input (crate docs): a non-finite increment is a time-free error naming the
    /// component; a non-finite held rate is an error of the EKF's next prediction at
    /// its target time, naming the component; the EKF is unchanged.
    #[test]
    fn non_finite_odometry_is_an_error_with_the_component_and_time() {
        let e = OdometryRate::from_increments(0.1, f64::INFINITY, 0.2).unwrap_err();
        assert!(
            matches!(
                &e,
                EstimatorError::Core(fathom_core::CoreError::NonFinite { index: 1, .. })
            ),
            "{e}"
        );
        let prior =
            fathom_core::Gaussian::new(Vector3::new(0.0, 0.0, 0.1), nalgebra::Matrix3::identity())
                .unwrap();
        let mut ekf =
            crate::ekf::Ekf::<3, _>::new(prior, 2.0, model(0), OdometryRate::default()).unwrap();
        let bad = OdometryRate {
            speed: 1.0,
            turn_rate: f64::NAN,
        };
        let e = ekf.try_apply_input(&bad).unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { index: 1, time, .. } if *time == 2.0),
            "{e}"
        );
        ekf.apply_input(&OdometryRate {
            speed: f64::NEG_INFINITY,
            turn_rate: 0.0,
        });
        let before = ekf.clone();
        let e = ekf.predict_to(2.5).unwrap_err();
        match &e {
            EstimatorError::NonFinite {
                what,
                index,
                value,
                time,
            } => {
                assert!(what.contains("speed"), "{what}");
                assert_eq!((*index, *value, *time), (0, f64::NEG_INFINITY, 2.5));
            }
            other => panic!("unexpected {other}"),
        }
        assert_eq!(ekf, before);
    }

    #[test]
    fn calibrated_range_value_and_jacobian() {
        let r = CalibratedRange {
            beacon: Vector2::new(3.0, -1.0),
            offset_state: Some(3),
            scale_state: Some(4),
        };
        let x = Vector5::new(6.0, 3.0, 0.1, 0.5, 0.1);
        let (h, row) = ScalarModel::<5>::evaluate(&r, &x).unwrap();
        assert_relative_eq!(h, 1.1 * 5.0 + 0.5, epsilon = 1e-12);
        let eps = 1e-7;
        for j in 0..5 {
            let mut xp = x;
            xp[j] += eps;
            let (hp, _) = ScalarModel::<5>::evaluate(&r, &xp).unwrap();
            assert_relative_eq!((hp - h) / eps, row[j], epsilon = 1e-6);
        }
        let plain = CalibratedRange {
            offset_state: None,
            scale_state: None,
            ..r
        };
        let (h3, _) = ScalarModel::<3>::evaluate(&plain, &Vector3::new(6.0, 3.0, 0.0)).unwrap();
        assert_relative_eq!(h3, 5.0, epsilon = 1e-12);
        assert!(ScalarModel::<3>::evaluate(&r, &Vector3::new(6.0, 3.0, 0.0)).is_err());
        assert!(ScalarModel::<5>::evaluate(&r, &Vector5::new(3.0, -1.0, 0.0, 0.0, 0.0)).is_err());
    }
}
