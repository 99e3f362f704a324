//! Measurement fusion: one centralized Kalman filter whose update stacks the
//! measurements of several sensors (paper A, "MF", the MARPOS structure):
//! `z = [z_1; ...; z_S]`, `H = [H_1; ...; H_S]`, `R = blockdiag(R_1, ..., R_S)`.

use super::ArchitectureError;
use crate::KalmanFilter;
use fathom_core::{Gaussian, Time, error::ensure_finite, gaussian::check_covariance};
use nalgebra::{DMatrix, SMatrix, SVector};

/// One sensor of a [`MeasurementFusion`]: its measurement matrix `H_i` (`m_i x N`)
/// and noise covariance `R_i` (`m_i x m_i`).
#[derive(Debug, Clone, PartialEq)]
pub struct SensorBlock {
    /// Sensor name (for error messages).
    pub name: String,
    /// `H_i`, `m_i x N`.
    pub h: DMatrix<f64>,
    /// `R_i`, `m_i x m_i`, symmetric positive definite.
    pub r: DMatrix<f64>,
}

/// A centralized KF over the stacked measurements of several sensors, with the
/// stacked dimension `M = sum m_i` fixed at compile time (all-fixed-size, no
/// allocation per step).
///
/// Each [`MeasurementFusion::step`]: predict with `F`, `Q`; one update with the
/// stacked `z`, `H`, block-diagonal `R` (Joseph form). For independent sensor noises
/// this equals the information-form combination
/// `P+^-1 = P-^-1 + sum H_i^T R_i^-1 H_i`, `x+ = P+ (P-^-1 x- + sum H_i^T R_i^-1 z_i)`.
///
/// Bad input: a non-finite measurement is an [`ArchitectureError::Filter`] naming the
/// sensor, the index inside its block and the step time; loss of positive
/// definiteness is a filter error with the time; unchanged on error.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurementFusion<const N: usize, const M: usize> {
    kf: KalmanFilter<N>,
    f: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    h: SMatrix<f64, M, N>,
    r: SMatrix<f64, M, M>,
    block_sizes: Vec<usize>,
    names: Vec<String>,
}

impl<const N: usize, const M: usize> MeasurementFusion<N, M> {
    /// A filter starting from `prior` at `t0` with the motion model `F`, `Q` and the
    /// sensors `blocks` (in the order their measurements are stacked).
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] when there is no sensor, a block's `H` is
    /// not `m_i x N` or its `R` not `m_i x m_i` SPD, the `m_i` do not sum to `M`, or
    /// `F`/`Q` are not finite; [`ArchitectureError::Filter`] for an invalid prior.
    pub fn new(
        prior: Gaussian<N>,
        t0: Time,
        f: SMatrix<f64, N, N>,
        q: SMatrix<f64, N, N>,
        blocks: &[SensorBlock],
    ) -> Result<Self, ArchitectureError> {
        let invalid =
            |what: String, reason: String| ArchitectureError::InvalidConfig { what, reason };
        if blocks.is_empty() {
            return Err(invalid(
                "measurement fusion".into(),
                "needs at least one sensor".into(),
            ));
        }
        for (what, m) in [("transition matrix F", &f), ("process noise Q", &q)] {
            ensure_finite(what, m.iter())
                .map_err(|e| invalid("measurement fusion".into(), e.to_string()))?;
        }
        let total: usize = blocks.iter().map(|b| b.h.nrows()).sum();
        if total != M {
            return Err(invalid(
                "measurement fusion".into(),
                format!("sensor blocks stack to {total} rows, the filter is built for {M}"),
            ));
        }
        let mut h = SMatrix::<f64, M, N>::zeros();
        let mut r = SMatrix::<f64, M, M>::zeros();
        let mut row = 0;
        for b in blocks {
            let m = b.h.nrows();
            let what = format!("sensor `{}`", b.name);
            if m == 0 || b.h.ncols() != N {
                return Err(invalid(
                    what,
                    format!("H is {}x{}, expected m x {N} with m >= 1", m, b.h.ncols()),
                ));
            }
            if b.r.nrows() != m || b.r.ncols() != m {
                return Err(invalid(
                    what,
                    format!("R is {}x{}, expected {m}x{m}", b.r.nrows(), b.r.ncols()),
                ));
            }
            ensure_finite("H", b.h.iter()).map_err(|e| invalid(what.clone(), e.to_string()))?;
            check_covariance_dyn(&b.r).map_err(|reason| invalid(what.clone(), reason))?;
            h.view_mut((row, 0), (m, N)).copy_from(&b.h);
            r.view_mut((row, row), (m, m)).copy_from(&b.r);
            row += m;
        }
        check_covariance("stacked R", &r)
            .map_err(|e| invalid("measurement fusion".into(), e.to_string()))?;
        let kf = KalmanFilter::new(prior, t0).map_err(ArchitectureError::filter("mf"))?;
        Ok(Self {
            kf,
            f,
            q,
            h,
            r,
            block_sizes: blocks.iter().map(|b| b.h.nrows()).collect(),
            names: blocks.iter().map(|b| b.name.clone()).collect(),
        })
    }

    /// One step to `time` with one measurement slice per sensor block (in block
    /// order, lengths `m_i`). Returns the estimate.
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] for a wrong number or length of slices;
    /// [`ArchitectureError::Filter`] for a failing predict/update. Unchanged on error.
    pub fn step(
        &mut self,
        time: Time,
        measurements: &[&[f64]],
    ) -> Result<Gaussian<N>, ArchitectureError> {
        if measurements.len() != self.block_sizes.len() {
            return Err(ArchitectureError::InvalidConfig {
                what: "measurement fusion step".into(),
                reason: format!(
                    "{} measurement slices for {} sensors",
                    measurements.len(),
                    self.block_sizes.len()
                ),
            });
        }
        let mut z = SVector::<f64, M>::zeros();
        let mut row = 0;
        for (k, (zi, &m)) in measurements.iter().zip(&self.block_sizes).enumerate() {
            if zi.len() != m {
                return Err(ArchitectureError::InvalidConfig {
                    what: format!("measurement of sensor `{}` (block {k})", self.names[k]),
                    reason: format!("expected {m} values, got {}", zi.len()),
                });
            }
            for (i, v) in zi.iter().enumerate() {
                if !v.is_finite() {
                    // Named per sensor (the stacked index would hide which one);
                    // stamped with the step time, like the update's own errors.
                    return Err(ArchitectureError::Filter {
                        track: "mf",
                        source: crate::EstimatorError::NonFinite {
                            what: format!("measurement of sensor `{}` (block {k})", self.names[k]),
                            index: i,
                            value: *v,
                            time,
                        },
                    });
                }
                z[row + i] = *v;
            }
            row += m;
        }
        self.step_stacked(time, &z)
    }

    /// One step to `time` with the already stacked measurement `z` (length `M`).
    ///
    /// # Errors
    /// [`ArchitectureError::Filter`] for a failing predict/update. Unchanged on error.
    pub fn step_stacked(
        &mut self,
        time: Time,
        z: &SVector<f64, M>,
    ) -> Result<Gaussian<N>, ArchitectureError> {
        let mut kf = self.kf.clone();
        kf.predict(&self.f, &self.q, time)
            .map_err(ArchitectureError::filter("mf"))?;
        kf.update(z, &self.h, &self.r)
            .map_err(ArchitectureError::filter("mf"))?;
        self.kf = kf;
        Ok(self.kf.estimate())
    }

    /// The filter.
    pub fn filter(&self) -> &KalmanFilter<N> {
        &self.kf
    }

    /// The stacked measurement matrix.
    pub fn stacked_h(&self) -> &SMatrix<f64, M, N> {
        &self.h
    }

    /// The stacked (block-diagonal) measurement noise.
    pub fn stacked_r(&self) -> &SMatrix<f64, M, M> {
        &self.r
    }
}

fn check_covariance_dyn(r: &DMatrix<f64>) -> Result<(), String> {
    ensure_finite("R", r.iter()).map_err(|e| e.to_string())?;
    let n = r.nrows();
    for i in 0..n {
        for j in 0..i {
            let tol = fathom_core::gaussian::SYMMETRY_TOLERANCE
                * (1.0 + r[(i, j)].abs().max(r[(j, i)].abs()));
            if (r[(i, j)] - r[(j, i)]).abs() > tol {
                return Err(format!("R is not symmetric at ({i}, {j})"));
            }
        }
    }
    if r.clone().cholesky().is_none() {
        return Err("R is not positive definite".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EstimatorError, models};
    use approx::assert_relative_eq;
    use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

    fn blocks() -> Vec<SensorBlock> {
        let h = DMatrix::from_fn(3, 6, |r, c| if c == 2 * r { 1.0 } else { 0.0 });
        vec![
            SensorBlock {
                name: "ins".into(),
                h: h.clone(),
                r: DMatrix::identity(3, 3) * 9.8 * 9.8,
            },
            SensorBlock {
                name: "dvl".into(),
                h,
                r: DMatrix::from_row_slice(3, 3, &[0.5, 0.1, 0.0, 0.1, 0.4, 0.05, 0.0, 0.05, 0.3]),
            },
        ]
    }

    fn prior() -> Gaussian<6> {
        let mut p = Matrix6::identity() * 2.0;
        p[(0, 1)] = 0.3;
        p[(1, 0)] = 0.3;
        Gaussian::new(Vector6::new(1.0, 0.5, -2.0, 0.1, 100.0, 0.0), p).unwrap()
    }

    #[test]
    fn equals_information_form_combination() {
        let f = models::cv_transition_3d(1.0).unwrap();
        let q = models::cv_scaled_identity_q_3d(1.0).unwrap();
        let mut mf = MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q, &blocks()).unwrap();
        let z_ins = [3.0, -1.0, 101.0];
        let z_dvl = [1.4, -1.8, 100.2];
        let est = mf.step(1.0, &[&z_ins, &z_dvl]).unwrap();
        // Information form by hand.
        let x_pred = f * prior().mean();
        let p_pred = f * prior().cov() * f.transpose() + q;
        let h = models::cv_position_h_3d();
        let r1 = Matrix3::identity() * 9.8 * 9.8;
        let r2 = Matrix3::new(0.5, 0.1, 0.0, 0.1, 0.4, 0.05, 0.0, 0.05, 0.3);
        let (r1i, r2i) = (r1.try_inverse().unwrap(), r2.try_inverse().unwrap());
        let p_pred_i = p_pred.try_inverse().unwrap();
        let info = p_pred_i + h.transpose() * r1i * h + h.transpose() * r2i * h;
        let p = info.try_inverse().unwrap();
        let x = p
            * (p_pred_i * x_pred
                + h.transpose() * r1i * Vector3::from(z_ins)
                + h.transpose() * r2i * Vector3::from(z_dvl));
        assert_relative_eq!(*est.mean(), x, epsilon = 1e-12);
        assert_relative_eq!(*est.cov(), p, epsilon = 1e-12);
        // Negative control: dropping a sensor changes the answer.
        let mut one = MeasurementFusion::<6, 3>::new(prior(), 0.0, f, q, &blocks()[1..]).unwrap();
        let e1 = one.step(1.0, &[&z_dvl]).unwrap();
        assert!((e1.mean() - x).norm() > 1e-6);
    }

    /// Bad input (crate docs): a non-finite measurement names the sensor, the index
    /// inside its block and the time; a `Q` that makes `P` indefinite is a
    /// positive-definiteness error at the step time; the filter is unchanged.
    #[test]
    fn bad_input_names_sensor_index_and_time() {
        let f = models::cv_transition_3d(1.0).unwrap();
        let q = models::cv_scaled_identity_q_3d(1.0).unwrap();
        let mut mf = MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q, &blocks()).unwrap();
        let before = mf.clone();
        for bad in [f64::NAN, f64::INFINITY] {
            match mf.step(1.0, &[&[1.0, 2.0, 3.0], &[1.0, 2.0, bad]]) {
                Err(ArchitectureError::Filter {
                    track: "mf",
                    source:
                        EstimatorError::NonFinite {
                            what, index, time, ..
                        },
                }) => {
                    assert!(what.contains("`dvl`"), "{what}");
                    assert_eq!((index, time), (2, 1.0));
                }
                other => panic!("unexpected {other:?}"),
            }
            assert_eq!(mf, before);
        }
        let mut q_bad = Matrix6::zeros();
        q_bad[(0, 1)] = 100.0;
        q_bad[(1, 0)] = 100.0;
        let mut mf = MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q_bad, &blocks()).unwrap();
        let before = mf.clone();
        let e = mf
            .step(1.0, &[&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]])
            .unwrap_err();
        assert!(
            matches!(&e, ArchitectureError::Filter { source: EstimatorError::NotPositiveDefinite { time, .. }, .. } if *time == 1.0),
            "{e}"
        );
        assert_eq!(mf, before);
    }

    #[test]
    fn configuration_and_step_errors() {
        let f = models::cv_transition_3d(1.0).unwrap();
        let q = models::cv_scaled_identity_q_3d(1.0).unwrap();
        assert!(MeasurementFusion::<6, 5>::new(prior(), 0.0, f, q, &blocks()).is_err());
        assert!(MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q, &[]).is_err());
        let mut bad = blocks();
        bad[1].r[(0, 0)] = -1.0;
        assert!(matches!(
            MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q, &bad),
            Err(ArchitectureError::InvalidConfig { what, .. }) if what == "sensor `dvl`"
        ));
        let mut mf = MeasurementFusion::<6, 6>::new(prior(), 0.0, f, q, &blocks()).unwrap();
        let before = mf.clone();
        assert!(mf.step(1.0, &[&[1.0, 2.0, 3.0]]).is_err());
        assert!(mf.step(1.0, &[&[1.0, 2.0], &[1.0, 2.0, 3.0]]).is_err());
        assert!(
            mf.step(1.0, &[&[1.0, 2.0, f64::NAN], &[1.0, 2.0, 3.0]])
                .is_err()
        );
        assert_eq!(mf, before);
    }
}
