//! Tests of the smoother: equality with batch least squares (mean and covariance) on
//! linear-Gaussian problems with gated, missing and repeated updates and a covariance
//! inflation; Monte Carlo NEES within chi-square bounds with a negative control; the
//! error-state smoother against the total-state one; the fixed-lag variant against
//! the fixed-interval one; recording leaves the filters unchanged; misuse is an error.

use super::*;
use crate::{
    EstimatorError, GateThreshold, KalmanFilter,
    beacon_ekf::{BeaconMeasurement, DvlAhrsInput, DvlAhrsMotionParams, DvlAhrsSample},
    ekf::{Ekf, GroupItem, MotionModel, Propagation, ScalarModel},
    error_state::{ErrorCovariance, ErrorStateFilter, ErrorVector, N_ERROR_STATES},
    models,
    robust::{RecoveryParams, RobustParams},
    schemes::{Event, Observation, SchemeFilter, SchemeParams, UpdateScheme},
};
use fathom_core::Gaussian;
use nalgebra::{
    DMatrix, DVector, Matrix1, Matrix2, Matrix3, RowVector2, SMatrix, SVector, Vector1, Vector2,
    Vector3, Vector4,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use statrs::distribution::{ChiSquared, ContinuousCDF};

fn dm<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_column_slice(R, C, m.as_slice())
}

fn dv<const R: usize>(v: &SVector<f64, R>) -> DVector<f64> {
    DVector::from_column_slice(v.as_slice())
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

/// The batch least-squares problem over the stacked states `[x_0, ..., x_K]`:
/// information matrix and vector of the prior, transition and measurement factors.
struct BatchLs {
    n: usize,
    lam: DMatrix<f64>,
    eta: DVector<f64>,
}

impl BatchLs {
    fn new(n: usize, states: usize) -> Self {
        Self {
            n,
            lam: DMatrix::zeros(n * states, n * states),
            eta: DVector::zeros(n * states),
        }
    }

    /// A factor `A X - b ~ N(0, W^-1)` with `A` given by blocks `(state, matrix)`.
    fn factor(&mut self, blocks: &[(usize, DMatrix<f64>)], b: &DVector<f64>, cov: &DMatrix<f64>) {
        let w = cov.clone().try_inverse().unwrap();
        let n = self.n;
        for (i, ai) in blocks {
            let mut eta = self.eta.rows_mut(i * n, n);
            eta += ai.transpose() * (&w * b);
            for (j, aj) in blocks {
                let mut blk = self.lam.view_mut((i * n, j * n), (n, n));
                blk += ai.transpose() * (&w * aj);
            }
        }
    }

    fn prior(&mut self, mean: &DVector<f64>, cov: &DMatrix<f64>) {
        self.factor(&[(0, DMatrix::identity(self.n, self.n))], mean, cov);
    }

    /// `x_k = F x_{k-1} + offset + w`, `w ~ N(0, Q)`.
    fn transition(&mut self, k: usize, f: &DMatrix<f64>, offset: &DVector<f64>, q: &DMatrix<f64>) {
        let n = self.n;
        self.factor(&[(k, DMatrix::identity(n, n)), (k - 1, -f)], offset, q);
    }

    /// `z = H x_k + v`, `v ~ N(0, R)`.
    fn measurement(&mut self, k: usize, h: &DMatrix<f64>, z: &DVector<f64>, r: &DMatrix<f64>) {
        self.factor(&[(k, h.clone())], z, r);
    }

    /// Posterior mean and covariance of every state.
    fn solve(&self) -> (DVector<f64>, DMatrix<f64>) {
        let cov = self.lam.clone().try_inverse().unwrap();
        let cov = (&cov + cov.transpose()) * 0.5;
        (&cov * &self.eta, cov)
    }
}

/// Asserts the smoothed steps equal the batch posterior blocks to `tol`.
fn assert_matches_batch<const N: usize>(smoothed: &[SmoothedStep<N>], batch: &BatchLs, tol: f64) {
    let (mean, cov) = batch.solve();
    assert_eq!(smoothed.len() * N, mean.len());
    let mut worst = (0.0f64, 0.0f64);
    for (k, s) in smoothed.iter().enumerate() {
        for i in 0..N {
            worst.0 = worst.0.max((s.mean[i] - mean[k * N + i]).abs());
            for j in 0..N {
                worst.1 = worst
                    .1
                    .max((s.cov[(i, j)] - cov[(k * N + i, k * N + j)]).abs());
            }
        }
    }
    assert!(
        worst.0 <= tol && worst.1 <= tol,
        "worst mean / cov difference {worst:?}"
    );
}

#[test]
fn step_sizes_are_as_documented() {
    assert_eq!(ForwardStep::<4>::BYTES, 456);
    assert_eq!(ForwardStep::<5>::BYTES, 688);
    assert_eq!(ForwardStep::<9>::BYTES, 2096);
    assert_eq!(ForwardStep::<15>::BYTES, 5648);
    assert_eq!(SmoothedStep::<4>::BYTES, 168);
    assert_eq!(SmoothedStep::<5>::BYTES, 248);
    assert_eq!(SmoothedStep::<9>::BYTES, 728);
    assert_eq!(SmoothedStep::<15>::BYTES, 1928);
}

/// `[p, v, b]`: constant velocity driven by a known acceleration, a constant bias of
/// the position sensor; steps of varying length; per step none, one, a 2-vector, a
/// gated (once rejected) or two sequential updates.
#[test]
fn rts_equals_batch_least_squares_with_gated_and_missing_updates() {
    const K: usize = 40;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let m0 = SVector::<f64, 3>::new(1.0, 0.5, -0.3);
    let p0 = Matrix3::new(1.0, 0.1, 0.0, 0.1, 0.25, 0.0, 0.0, 0.0, 0.5);
    let mut kf = KalmanFilter::new(Gaussian::new(m0, p0).unwrap(), 0.0).unwrap();
    let mut pass = ForwardPass::from_filter(&kf);
    let mut batch = BatchLs::new(3, K + 1);
    batch.prior(&DVector::from_column_slice(m0.as_slice()), &dm(&p0));
    let h_pb = SMatrix::<f64, 1, 3>::new(1.0, 0.0, 1.0);
    let h_pv = SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    let h_v = SMatrix::<f64, 1, 3>::new(0.0, 1.0, 0.0);
    let r1 = Matrix1::new(0.3);
    let r2 = Matrix2::new(0.2, 0.05, 0.05, 0.1);
    let gate = GateThreshold::from_sigma_distance(3.0).unwrap();
    let mut truth = m0;
    let (mut t, mut rejected) = (0.0, 0);
    for k in 1..=K {
        let dt = 0.5 + 0.1 * (k % 3) as f64;
        let u = (k as f64).sin();
        let f = Matrix3::new(1.0, dt, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let b = SMatrix::<f64, 3, 1>::new(0.5 * dt * dt, dt, 0.0);
        let mut q = Matrix3::zeros();
        q.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&models::cv_white_accel_q_1d(dt, 0.05).unwrap());
        q[(2, 2)] = 1e-3 * dt;
        t += dt;
        truth = f * truth
            + b * u
            + q.cholesky().unwrap().l() * Vector3::from_fn(|_, _| normal(&mut rng));
        kf.predict_with_control(&f, &b, &Vector1::new(u), &q, t)
            .unwrap();
        pass.record_prediction(&f, &kf);
        batch.transition(k, &dm(&f), &dv(&(b * u)), &dm(&q));
        let z1 = Vector1::new((h_pb * truth)[0] + 0.5 * normal(&mut rng));
        match k % 5 {
            0 => {}
            1 => {
                kf.update(&z1, &h_pb, &r1).unwrap();
                batch.measurement(k, &dm(&h_pb), &dv(&z1), &dm(&r1));
            }
            2 => {
                let z = h_pv * truth + Vector2::new(0.3 * normal(&mut rng), 0.2 * normal(&mut rng));
                kf.update(&z, &h_pv, &r2).unwrap();
                batch.measurement(k, &dm(&h_pv), &dv(&z), &dm(&r2));
            }
            3 => {
                // An outlier on step 13: rejected by the gate, absent from the batch.
                let z = if k == 13 { z1 + Vector1::new(50.0) } else { z1 };
                if kf.update_gated(&z, &h_pb, &r1, gate).unwrap().is_accepted() {
                    batch.measurement(k, &dm(&h_pb), &dv(&z), &dm(&r1));
                } else {
                    rejected += 1;
                }
            }
            _ => {
                let zv = Vector1::new(truth[1] + 0.3 * normal(&mut rng));
                kf.update(&z1, &h_pb, &r1).unwrap();
                pass.record_update(&kf);
                kf.update(&zv, &h_v, &r1).unwrap();
                batch.measurement(k, &dm(&h_pb), &dv(&z1), &dm(&r1));
                batch.measurement(k, &dm(&h_v), &dv(&zv), &dm(&r1));
            }
        }
        pass.record_update(&kf);
    }
    assert_eq!(rejected, 1);
    assert_eq!(pass.len(), K + 1);
    let smoothed = pass.smooth().unwrap();
    assert_matches_batch(&smoothed, &batch, 1e-9);
    // The last smoothed step is the filtered one.
    assert_eq!(smoothed[K].mean, *kf.state());
    assert_eq!(smoothed[K].cov, *kf.covariance());
}

/// A deferred factor of a batch problem whose size is known at the end.
type Factor = Box<dyn Fn(&mut BatchLs)>;

/// A linear 1-axis constant-velocity motion model for the generic EKF.
#[derive(Debug, Clone, PartialEq)]
struct LinearCv {
    q_psd: f64,
}

impl MotionModel<2> for LinearCv {
    type Input = f64;
    type InputSample = f64;
    fn apply_sample(&self, input: &mut f64, sample: &f64) {
        *input = *sample;
    }
    fn propagate(
        &self,
        x: &Vector2<f64>,
        u: &f64,
        dt: f64,
    ) -> Result<Propagation<2>, EstimatorError> {
        let f = models::cv_transition_1d(dt)?;
        Ok(Propagation {
            x_pred: f * x + Vector2::new(0.5 * dt * dt, dt) * *u,
            f_jacobian: f,
            q: models::cv_white_accel_q_1d(dt, self.q_psd)?,
        })
    }
}

/// Position measurement `h = p`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Position;

impl ScalarModel<2> for Position {
    fn evaluate(&self, x: &Vector2<f64>) -> Result<(f64, RowVector2<f64>), EstimatorError> {
        Ok((x[0], RowVector2::new(1.0, 0.0)))
    }
}

/// The EKF records itself: predictions with the input, sequential gated updates and a
/// covariance inflation (a step with `F = I` and `Q = (c - 1) P`) match the batch
/// solution with those factors.
#[test]
fn ekf_recording_with_inflation_equals_batch_least_squares() {
    let model = LinearCv { q_psd: 0.02 };
    let p0 = Matrix2::new(2.0, 0.0, 0.0, 0.5);
    let prior = Gaussian::new(Vector2::new(0.0, 1.0), p0).unwrap();
    let mut ekf = Ekf::new(prior, 0.0, model.clone(), 0.0).unwrap();
    let plain = ekf.clone();
    ekf.start_recording();
    let mut factors: Vec<Factor> = Vec::new();
    factors.push(Box::new(move |b: &mut BatchLs| {
        b.prior(&DVector::from_vec(vec![0.0, 1.0]), &dm(&p0));
    }));
    let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
    let mut plain = plain;
    let mut rejected = 0;
    let mut k = 0;
    for i in 1..=30 {
        let t = 0.2 * i as f64;
        let u = 0.3 * (i as f64 * 0.7).cos();
        let x_before = *ekf.state();
        for e in [&mut ekf, &mut plain] {
            e.apply_input(&u);
            e.predict_to(t).unwrap();
        }
        k += 1;
        let prop = model.propagate(&x_before, &u, 0.2).unwrap();
        let off = prop.x_pred - prop.f_jacobian * x_before;
        let (kk, f, q) = (k, dm(&prop.f_jacobian), dm(&prop.q));
        factors.push(Box::new(move |b: &mut BatchLs| {
            b.transition(kk, &f, &DVector::from_column_slice(off.as_slice()), &q)
        }));
        let z = t + 0.1 * (i as f64).sin() + if i == 17 { 30.0 } else { 0.0 };
        let item = GroupItem {
            value: z,
            model: &Position,
            variance: 0.04,
            gate: Some(gate),
        };
        let out = ekf.update_sequential(&[item]).unwrap();
        plain.update_sequential(&[item]).unwrap();
        if out[0].accepted {
            factors.push(Box::new(move |b: &mut BatchLs| {
                b.measurement(
                    kk,
                    &DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
                    &DVector::from_vec(vec![z]),
                    &DMatrix::from_element(1, 1, 0.04),
                )
            }));
        } else {
            rejected += 1;
        }
        if i == 20 {
            let p_before = *ekf.covariance();
            ekf.inflate_covariance(4.0).unwrap();
            plain.inflate_covariance(4.0).unwrap();
            k += 1;
            let kk = k;
            factors.push(Box::new(move |b: &mut BatchLs| {
                b.transition(
                    kk,
                    &DMatrix::identity(2, 2),
                    &DVector::zeros(2),
                    &(dm(&p_before) * 3.0),
                )
            }));
        }
    }
    assert_eq!(rejected, 1);
    // Recording changes nothing.
    assert_eq!(ekf.state(), plain.state());
    assert_eq!(ekf.covariance(), plain.covariance());
    let pass = ekf.forward_pass().unwrap();
    assert_eq!(pass.len(), k + 1);
    let mut batch = BatchLs::new(2, k + 1);
    for f in &factors {
        f(&mut batch);
    }
    assert_matches_batch(&ekf.smooth().unwrap(), &batch, 1e-9);
    assert!(matches!(
        plain.smooth(),
        Err(EstimatorError::Smoother { .. })
    ));
}

const RUNS: usize = 50;
const STEPS: usize = 100;

/// Per-step NEES (dof 2) of the smoothed and of the filtered estimates, averaged over
/// `RUNS` runs of a constant-velocity system filtered with `Q * q_scale`.
fn monte_carlo_nees(q_scale: f64, seed: u64) -> (Vec<f64>, Vec<f64>, f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let f = models::cv_transition_1d(1.0).unwrap();
    let q_true = models::cv_white_accel_q_1d(1.0, 0.05).unwrap();
    let l_q = q_true.cholesky().unwrap().unpack();
    let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
    let r = Matrix1::new(1.0);
    let x0 = Vector2::new(0.0, 1.0);
    let p0 = Matrix2::new(4.0, 0.0, 0.0, 0.25);
    let l_p0 = p0.cholesky().unwrap().unpack();
    let (mut nees_s, mut nees_f) = (vec![0.0; STEPS + 1], vec![0.0; STEPS + 1]);
    let (mut mse_s, mut mse_f) = (0.0, 0.0);
    for _ in 0..RUNS {
        let mut truth = x0 + l_p0 * Vector2::new(normal(&mut rng), normal(&mut rng));
        let mut truths = vec![truth];
        let mut kf = KalmanFilter::new(Gaussian::new(x0, p0).unwrap(), 0.0).unwrap();
        let mut pass = ForwardPass::from_filter(&kf);
        for k in 1..=STEPS {
            truth = f * truth + l_q * Vector2::new(normal(&mut rng), normal(&mut rng));
            truths.push(truth);
            let z = Vector1::new(truth[0] + normal(&mut rng));
            kf.predict(&f, &(q_true * q_scale), k as f64).unwrap();
            pass.record_prediction(&f, &kf);
            kf.update(&z, &h, &r).unwrap();
            pass.record_update(&kf);
        }
        let smoothed = pass.smooth().unwrap();
        for (k, (s, x)) in smoothed.iter().zip(&truths).enumerate() {
            let step = &pass.steps()[k];
            let es = Gaussian::new_unchecked(s.mean, s.cov);
            let ef = Gaussian::new_unchecked(step.filtered_mean, step.filtered_cov);
            nees_s[k] += es.mahalanobis_sq(x).unwrap() / RUNS as f64;
            nees_f[k] += ef.mahalanobis_sq(x).unwrap() / RUNS as f64;
            mse_s += (s.mean[0] - x[0]).powi(2);
            mse_f += (step.filtered_mean[0] - x[0]).powi(2);
        }
    }
    (nees_s, nees_f, mse_s, mse_f)
}

/// Two-sided 95 % bounds of a run average of chi-square(2) NEES over `RUNS` runs.
fn nees_bounds() -> (f64, f64) {
    let chi2 = ChiSquared::new((RUNS * 2) as f64).unwrap();
    (
        chi2.inverse_cdf(0.025) / RUNS as f64,
        chi2.inverse_cdf(0.975) / RUNS as f64,
    )
}

fn fraction_inside(v: &[f64], (lo, hi): (f64, f64)) -> f64 {
    v.iter().filter(|&&x| x >= lo && x <= hi).count() as f64 / v.len() as f64
}

/// The smoothed NEES averaged over 50 runs lies in its 95 % chi-square interval at
/// at least 90 % of the steps (nominal 95 %; the steps are correlated, see
/// `consistency_tests`), and smoothing lowers the position error.
#[test]
fn smoothed_nees_within_chi_square_bounds() {
    let (nees_s, nees_f, mse_s, mse_f) = monte_carlo_nees(1.0, 2025);
    let b = nees_bounds();
    let (in_s, in_f) = (fraction_inside(&nees_s, b), fraction_inside(&nees_f, b));
    eprintln!(
        "smoothed NEES inside {in_s}, filtered {in_f}; MSE smoothed {mse_s}, filtered {mse_f}"
    );
    assert!(in_s >= 0.90, "smoothed NEES inside {in_s}");
    let mean = nees_s.iter().sum::<f64>() / nees_s.len() as f64;
    assert!((mean - 2.0).abs() < 0.3, "mean smoothed NEES {mean}");
    assert!(
        mse_s < 0.8 * mse_f,
        "smoothed MSE {mse_s} vs filtered {mse_f}"
    );
}

/// Negative control: a forward pass with `Q` 100x too small gives an overconfident
/// smoother, whose NEES leaves the bounds (above) at most steps.
#[test]
fn smoothed_nees_negative_control_q_too_small_fails() {
    let (nees_s, ..) = monte_carlo_nees(0.01, 2025);
    let b = nees_bounds();
    let inside = fraction_inside(&nees_s, b);
    let above = nees_s.iter().filter(|&&v| v > b.1).count();
    eprintln!("Q/100 smoother: NEES inside {inside}, above {above}");
    assert!(
        inside < 0.5 && above > STEPS / 2,
        "inside {inside}, above {above}"
    );
}

/// The 15-state feedback error-state filter on a linear system (the nominal
/// propagates with the same `Phi`): its smoothed error applied to the nominal before
/// each feedback equals the total-state smoother, mean and covariance, including a
/// gated-out velocity update.
#[test]
fn error_state_smoother_equals_total_state_smoother() {
    const N: usize = N_ERROR_STATES;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let a = SMatrix::<f64, N, N>::from_fn(|_, _| 0.1 * normal(&mut rng));
    let phi = SMatrix::<f64, N, N>::identity() + a * 0.1;
    let g = SMatrix::<f64, N, N>::from_fn(|_, _| 0.05 * normal(&mut rng));
    let qd: ErrorCovariance = g * g.transpose() + SMatrix::identity() * 1e-4;
    let p0 = ErrorStateFilter::diagonal_covariance([1.0, 0.1, 0.01, 0.01, 0.001]);
    let r = Matrix3::identity() * 0.01;
    let gate = GateThreshold::from_sigma_distance(4.0).unwrap();
    let mut eskf = ErrorStateFilter::new(&p0, 0.0).unwrap();
    eskf.start_recording();
    let mut nominal = SVector::<f64, N>::from_fn(|i, _| i as f64 * 0.1);
    let mut total = KalmanFilter::new(Gaussian::new(nominal, p0).unwrap(), 0.0).unwrap();
    let mut pass = ForwardPass::from_filter(&total);
    let mut truth =
        nominal + p0.cholesky().unwrap().l() * SVector::<f64, N>::from_fn(|_, _| normal(&mut rng));
    let l_q = qd.cholesky().unwrap().unpack();
    let mut nominal_pred = vec![nominal];
    let mut rejected = 0;
    for k in 1..=25 {
        let t = k as f64 * 0.1;
        truth = phi * truth + l_q * SVector::<f64, N>::from_fn(|_, _| normal(&mut rng));
        nominal = phi * nominal;
        nominal_pred.push(nominal);
        eskf.predict(&phi, &qd, t).unwrap();
        total.predict(&phi, &qd, t).unwrap();
        pass.record_prediction(&phi, &total);
        let mut aid = truth.fixed_rows::<3>(3) + Vector3::from_fn(|_, _| 0.1 * normal(&mut rng));
        if k == 9 {
            aid.x += 5.0; // an outlier: gated out in both filters
        }
        let ins = nominal.fixed_rows::<3>(3).into_owned();
        let ge = eskf.update_velocity(&ins, &aid, &r, Some(gate)).unwrap();
        let mut hv = SMatrix::<f64, 3, N>::zeros();
        hv.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&Matrix3::identity());
        let gt = total.update_gated(&aid, &hv, &r, gate).unwrap();
        assert_eq!(ge.is_accepted(), gt.is_accepted());
        rejected += usize::from(!ge.is_accepted());
        if k % 2 == 0 {
            let depth = truth[2] + 0.05 * normal(&mut rng);
            eskf.update_depth(nominal[2], depth, 0.0025).unwrap();
            let mut hd = SMatrix::<f64, 1, N>::zeros();
            hd[(0, 2)] = 1.0;
            total
                .update(&Vector1::new(depth), &hd, &Matrix1::new(0.0025))
                .unwrap();
        }
        pass.record_update(&total);
        // Feedback: the corrected nominal is the total-state estimate.
        let dx: ErrorVector = eskf.take_correction().unwrap();
        nominal -= dx;
        let d = (nominal - total.state()).amax();
        assert!(d < 1e-9, "nominal vs total state at step {k}: {d}");
    }
    assert_eq!(rejected, 1);
    let se = eskf.smooth().unwrap();
    let st = pass.smooth().unwrap();
    assert_eq!(se.len(), st.len());
    for (k, (e, s)) in se.iter().zip(&st).enumerate() {
        let full = nominal_pred[k] - e.mean;
        assert!(
            (full - s.mean).amax() < 1e-9,
            "mean at step {k}: {}",
            (full - s.mean).amax()
        );
        assert!((e.cov - s.cov).amax() < 1e-9, "cov at step {k}");
    }
}

/// The fixed-lag estimate equals the fixed-interval smoother of the pass recorded so
/// far, at the lagged step; the window stays bounded.
#[test]
fn fixed_lag_equals_fixed_interval_on_the_data_so_far() {
    let f = models::cv_transition_1d(0.1).unwrap();
    let q = models::cv_white_accel_q_1d(0.1, 0.1).unwrap();
    let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
    let mut kf = KalmanFilter::new(
        Gaussian::new(Vector2::zeros(), Matrix2::identity()).unwrap(),
        0.0,
    )
    .unwrap();
    let mut full = ForwardPass::from_filter(&kf);
    let mut lag = FixedLagSmoother::new(0.5, &kf).unwrap();
    assert!(FixedLagSmoother::new(-1.0, &kf).is_err());
    let mut outputs = 0;
    for k in 1..=60 {
        let t = 0.1 * k as f64;
        kf.predict(&f, &q, t).unwrap();
        full.record_prediction(&f, &kf);
        lag.record_prediction(&f, &kf);
        if k % 3 != 0 {
            kf.update(&Vector1::new((t * 0.9).sin()), &h, &Matrix1::new(0.05))
                .unwrap();
            full.record_update(&kf);
            lag.record_update(&kf);
        }
        let Some(s) = lag.lagged(&Euclidean).unwrap() else {
            assert!(t < 0.5 - 1e-9, "no output at t = {t}");
            continue;
        };
        outputs += 1;
        // The newest step at or before t - 0.5 (one step earlier when t - 0.5 rounds
        // just below a step's time).
        let age = t - s.time;
        assert!(
            (0.5 - 1e-9..0.6 + 1e-9).contains(&age),
            "lagged time {} at {t}",
            s.time
        );
        let reference = full.smooth().unwrap();
        let j = full.steps().iter().position(|x| x.time == s.time).unwrap();
        assert!((reference[j].mean - s.mean).amax() < 1e-12);
        assert!((reference[j].cov - s.cov).amax() < 1e-12);
        assert!(lag.window().len() <= 7, "window {}", lag.window().len());
    }
    assert!(outputs >= 55);
}

fn beacon_events(rng: &mut ChaCha8Rng) -> Vec<Event<DvlAhrsSample, BeaconMeasurement>> {
    let beacons = [
        Vector3::new(20.0, 0.0, 0.0),
        Vector3::new(0.0, 20.0, 10.0),
        Vector3::new(-20.0, -5.0, 5.0),
    ];
    let mut ev = Vec::new();
    for i in 0..200 {
        let t = 0.05 * (i + 1) as f64;
        let (x, y, z) = (t, 0.5 * t, 5.0);
        if i % 4 == 0 {
            ev.push(Event::Input {
                stamp: t,
                sample: DvlAhrsSample::Velocity(Vector3::new(1.118 + 0.05 * normal(rng), 0.0, 0.0)),
            });
            ev.push(Event::Input {
                stamp: t,
                sample: DvlAhrsSample::YawRate(0.01 * normal(rng)),
            });
        }
        let b = i % 3;
        let d = (Vector3::new(x, y, z) - beacons[b]).norm();
        // a run of outliers on beacon 0 (rejected, then a recovery inflation)
        let outlier = if (60..120).contains(&i) && b == 0 {
            8.0
        } else {
            0.0
        };
        ev.push(Event::Measurement(Observation {
            channel: b,
            stamp: t,
            value: d + 0.1 * normal(rng) + outlier,
            model: BeaconMeasurement::Range {
                beacon_in_nav: beacons[b],
            },
            tag: i,
        }));
    }
    ev
}

/// The beacon EKF under the AS scheme with robust recovery: recording changes no
/// decision and no estimate, covariance inflations appear as same-time steps, and the
/// smoothed position is closer to the truth than the filtered one on average.
#[test]
fn scheme_filter_recording_changes_nothing_and_smoothing_helps() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let events = beacon_events(&mut rng);
    let motion = DvlAhrsMotionParams {
        vel_sigma: [0.05, 0.05, 0.01],
        vel_hold: 0.2,
        yaw_rate_sigma: 0.01,
        yaw_rate_hold: 0.2,
    }
    .check()
    .unwrap();
    let heading = 0.5f64.atan2(1.0);
    let prior = Gaussian::new(
        Vector4::new(0.3, -0.2, 5.1, heading + 0.05),
        SMatrix::from_diagonal(&Vector4::new(0.25, 0.25, 0.25, 0.01)),
    )
    .unwrap();
    let config = SchemeParams {
        scheme: UpdateScheme::Asynchronous,
        epoch_period: 0.1,
        stale_tolerance: 0.0,
        channel_cov: DMatrix::identity(3, 3) * 0.01,
        gates: vec![Some(GateThreshold::from_sigma_distance(3.0).unwrap()); 3],
    }
    .check()
    .unwrap();
    let policy = RobustParams {
        huber_k: None,
        recovery: Some(RecoveryParams {
            after_rejections: 5,
            inflation: 4.0,
        }),
    }
    .check()
    .unwrap();
    let input = DvlAhrsInput {
        vel_in_body: Vector3::new(1.118, 0.0, 0.0),
        yaw_rate: 0.0,
    };
    let make = || {
        SchemeFilter::new(
            Ekf::new(prior.clone(), 0.0, motion, input).unwrap(),
            config.clone(),
        )
        .with_robust(policy)
    };
    let mut plain = make();
    let mut rec = make().with_recording();
    let times: Vec<f64> = (1..=20).map(|i| 0.5 * i as f64).collect();
    let mut idx = Vec::new();
    let mut filtered = Vec::new();
    for f in [&mut plain, &mut rec] {
        let mut it = events.clone().into_iter().peekable();
        f.run_to_evaluations(
            &mut it,
            times.iter().copied(),
            |e| e,
            |_, _, f| {
                if let Some(p) = f.ekf().forward_pass() {
                    idx.push(p.last_index());
                    filtered.push(*f.ekf().state());
                }
                Ok(())
            },
        )
        .unwrap();
    }
    assert_eq!(plain.ekf().state(), rec.ekf().state());
    assert_eq!(plain.decisions(), rec.decisions());
    assert!(rec.recoveries() > 0);
    let pass = rec.ekf().forward_pass().unwrap();
    assert!(
        pass.steps().windows(2).any(|w| w[0].time == w[1].time),
        "no inflation step"
    );
    let smoothed = rec.ekf().smooth().unwrap();
    let (mut err_s, mut err_f) = (0.0, 0.0);
    for ((&i, x_f), &t) in idx.iter().zip(&filtered).zip(&times) {
        assert_eq!(smoothed[i].time, t);
        let truth = Vector3::new(t, 0.5 * t, 5.0);
        err_s += (smoothed[i].mean.xyz() - truth).norm();
        err_f += (x_f.xyz() - truth).norm();
    }
    eprintln!(
        "mean 3D error: smoothed {}, filtered {}",
        err_s / 20.0,
        err_f / 20.0
    );
    assert!(err_s < err_f, "smoothed {err_s} vs filtered {err_f}");
}

#[test]
fn misuse_and_bad_records_are_errors_naming_the_step() {
    let kf = KalmanFilter::new(
        Gaussian::new(Vector2::zeros(), Matrix2::identity()).unwrap(),
        1.0,
    )
    .unwrap();
    // An update at a time without its prediction step.
    let mut p = ForwardPass::from_filter(&kf);
    p.push_update(2.0, &Vector2::zeros(), &Matrix2::identity());
    assert!(matches!(p.smooth(), Err(EstimatorError::Smoother { time, .. }) if time == 2.0));
    // Time going backwards.
    let mut p = ForwardPass::from_filter(&kf);
    p.push_prediction(
        0.5,
        &Matrix2::identity(),
        &Vector2::zeros(),
        &Matrix2::identity(),
    );
    assert!(matches!(
        p.smooth(),
        Err(EstimatorError::TimeBackwards { .. })
    ));
    // A predicted covariance that is not positive definite.
    let mut p = ForwardPass::from_filter(&kf);
    p.push_prediction(
        2.0,
        &Matrix2::identity(),
        &Vector2::zeros(),
        &Matrix2::zeros(),
    );
    let e = p.smooth().unwrap_err();
    assert!(
        e.to_string().contains("step 1") && e.time() == Some(2.0),
        "{e}"
    );
    // A non-finite recorded value.
    let mut p = ForwardPass::from_filter(&kf);
    p.push_prediction(
        2.0,
        &Matrix2::new(1.0, f64::NAN, 0.0, 1.0),
        &Vector2::zeros(),
        &Matrix2::identity(),
    );
    let e = p.smooth().unwrap_err();
    assert!(
        matches!(&e, EstimatorError::NonFinite { what, .. } if what.contains("transition F of step 1")),
        "{e}"
    );
    // Only the prior: the smoothed estimate is the prior.
    let p = ForwardPass::from_filter(&kf);
    let s = p.smooth().unwrap();
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].cov, Matrix2::identity());
}
